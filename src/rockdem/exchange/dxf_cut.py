"""A drawn section (:func:`rockdem.exchange.dxf_in.read_section`) cut into
blocks along its joint traces, about a local origin so that site
coordinates keep every digit."""

from __future__ import annotations

import math

import numpy as np

from .dxf_entities import _fail
from .dxf_in import Section, SectionBlocks

__all__ = ["cut_section"]


def cut_section(section: Section, *, max_blocks: int | None = None) -> SectionBlocks:
    """Cut the section into blocks along its joint traces.

    The faces of the arrangement of the outline, the fixed regions and the
    traces are the blocks; faces in fixed regions are merged into one ground
    block per connected region.  The cut is made about a local origin (the
    outline's lowest-left corner) and moved back.

    Raises
    ------
    DxfError
        A fixed region apart from the section, a section left with no free
        block, more blocks than ``max_blocks``.
    """
    import shapely

    from ..blocks import GEOMETRY_RTOL
    from ..config.build import MAX_VERTICES
    from ..geometry import _topology as topo

    source = section.source
    origin = section.outline.min(axis=0)
    outline = shapely.Polygon(section.outline - origin)
    fixed = [shapely.Polygon(f - origin) for f in section.fixed]
    domain = shapely.union_all([outline, *fixed])
    if domain.geom_type != "Polygon":
        areas = [(k, shapely.intersection(f, outline).area) for k, f in enumerate(fixed)]
        apart = [k for k, a in areas if a <= 0 and not shapely.touches(fixed[k], outline)]
        which = f"fixed region {apart[0] + 1}" if apart else "the fixed ground"
        raise _fail(
            source,
            f"{which} lies apart from the outline",
            "draw the fixed ground inside the outline or along its edge",
            "layers.fixed",
        )
    xmin, ymin, xmax, ymax = domain.bounds
    extent = math.hypot(xmax - xmin, ymax - ymin)
    tol = GEOMETRY_RTOL * extent
    traces = np.array([shapely.LineString(t.points - origin) for t in section.traces], object)
    if max_blocks is not None:
        _check_crossings(traces, domain, max_blocks, source)
    # a trace through a corner of the outline or of a fixed region (a bedding
    # line drawn through the toe) is split there, whatever the round-off
    corners = np.concatenate([shapely.get_coordinates(p.exterior)[:-1] for p in (outline, *fixed)])
    traces = topo.through_corners(traces, corners, tol)
    lines = [shapely.LinearRing(outline.exterior), *(f.exterior for f in fixed), *traces]
    noded = shapely.node(shapely.multilinestrings(shapely.get_parts(np.array(lines, object))))
    faces = shapely.get_parts(shapely.polygonize(shapely.get_parts(noded)))
    inside = shapely.buffer(domain, tol, join_style="mitre")
    shapely.prepare(inside)
    keep = shapely.contains(inside, faces) & (shapely.area(faces) > 1e-12 * extent**2)
    faces = faces[keep]
    ground_area = shapely.union_all(fixed)
    shapely.prepare(ground_area)
    in_ground = shapely.contains(ground_area, shapely.point_on_surface(faces))
    thin = 2 * tol
    if ((shapely.area(faces) <= thin * shapely.length(faces)) & ~in_ground).any():
        faces, where, _ = topo.merge_slivers(faces, 0.0, movable=~in_ground, thin=thin)
        moved = np.zeros(len(faces), dtype=bool)
        moved[where[in_ground]] = True
        in_ground = moved
    free = faces[~in_ground]
    if len(free) == 0:
        raise _fail(
            source,
            "the fixed ground covers the whole section: no free block",
            "draw the fixed regions around the ground only",
            "layers.fixed",
        )
    if max_blocks is not None and len(free) > max_blocks:
        raise _fail(
            source,
            f"the traces cut {len(free):,} blocks, more than the limit of {max_blocks:,}",
            "raise the limit with `rockdem --max-blocks N ...` or draw fewer traces",
        )
    # columns left to right, each bottom to top, x equal within the tolerance
    # (rounding to a grid split ties that straddled a grid line)
    free = free[topo.reading_order(shapely.get_coordinates(shapely.centroid(free)), 10 * tol)]
    fxy, foff = topo.to_arrays(free, tol)
    corners = np.diff(foff)

    def centre(k: int) -> tuple[float, float]:  # of free block k, for an error
        return tuple(shapely.get_coordinates(shapely.centroid(free[k]))[0] + origin)

    if (corners < 3).any():  # found by fuzzing: a 1e9 m wide section, blocks 10 m high
        x, y = centre(int(np.argmax(corners < 3)))
        raise _fail(
            source,
            f"the block at ({x:.6g}, {y:.6g}) collapses: it is thinner than the drawing's "
            f"tolerance ({tol:.3g}, {GEOMETRY_RTOL:g} of the section's size {extent:.3g})",
            "clip the outline closer to the slope, so that every block is wider than that",
        )
    if corners.max() > MAX_VERTICES:
        # refused here, not by the model file read back after writing it (a
        # 200,000-vertex outline took 37 s of YAML before that said so)
        k = int(np.argmax(corners))
        x, y = centre(k)
        raise _fail(
            source,
            f"the block at ({x:.6g}, {y:.6g}) has {int(corners[k]):,} vertices, more than "
            f"the limit of {MAX_VERTICES:,} for one block (every edge is an interface of its own)",
            "draw the outline and the traces with fewer vertices (merge collinear points)",
        )
    polygons = [fxy[foff[i] : foff[i + 1]] + origin for i in range(len(free))]
    ground = shapely.get_parts(shapely.coverage_union_all(faces[in_ground]))
    for g in ground:
        # the traces' nodes on the ground's outline are no corners: drop them (simplify
        # within the tolerance), then make every free block's corner on it a vertex
        g = shapely.simplify(shapely.polygons(shapely.get_exterior_ring(g)), tol)
        g = topo.insert_vertices(g, fxy, 10 * tol)
        gxy, _ = topo.to_arrays(np.array([g], dtype=object), tol)
        polygons.append(gxy + origin)
    flags = np.zeros(len(polygons), dtype=bool)
    flags[len(free) :] = True
    segs = tuple(
        (t.joint, t.points[k].copy(), t.points[k + 1].copy())
        for t in section.traces
        for k in range(len(t.points) - 1)
    )
    return SectionBlocks(polygons=tuple(polygons), fixed=flags, lines=segs)


#: traces are checked for crossings in chunks of this many (memory: ~16 bytes per pair)
CROSSING_CHUNK = 256


def _check_crossings(traces, domain, max_blocks: int, source: str) -> None:
    """Refuse, before the cut, traces that cross too often for ``max_blocks``.

    Found by fuzzing: 1,500 x 1,500 crossing traces (3,000 segments, within
    the segment limit) would cut 2.25 million blocks; noding them ran out of
    memory (5.6 GB) before the block limit was checked.  An arrangement of
    ``n`` pieces with ``X`` crossings (each pair of traces counted once) and
    ``C`` connected parts has ``X - n + C`` bounded faces (Euler), so at
    least ``X - n`` blocks: the count stops as soon as that exceeds the limit.
    """
    import shapely

    pieces = shapely.get_parts(shapely.intersection(traces, domain))
    pieces = pieces[(shapely.get_type_id(pieces) == 1) & ~shapely.is_empty(pieces)]
    n = len(pieces)
    if n < 2:
        return
    tree = shapely.STRtree(pieces)
    crossings = 0
    for start in range(0, n, CROSSING_CHUNK):
        chunk = pieces[start : start + CROSSING_CHUNK]
        _, other = tree.query(chunk, predicate="crosses")
        crossings += len(other)
        if crossings // 2 - n > max_blocks:
            raise _fail(
                source,
                f"the traces cross each other at least {crossings // 2:,} times: they would "
                f"cut at least {crossings // 2 - n:,} blocks, more than the limit of "
                f"{max_blocks:,}",
                "raise the limit with `rockdem --max-blocks N ...` or draw fewer traces",
            )
