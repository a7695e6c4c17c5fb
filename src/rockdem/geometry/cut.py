"""Cutting a slope section into blocks with joint sets.

The section is bounded by the profile on top, a horizontal base at
``min(profile y) - depth`` and vertical sides at the profile's first and
last x.  Every joint line of every set (traces *and* rock bridges) is
clipped to the section; the faces of the planar arrangement of the section
outline and all these lines (``shapely.node`` + ``shapely.polygonize``, no
loop per block) are the blocks.  Trace ends are nodes of the arrangement, so
no interface straddles the end of a trace.

Fixed ground
------------
By default the ground is a boundary of the model: fixed strips of
thickness ``ground_thickness`` below the base, behind the back side and in
front of the front side (choose with ``boundary``), outside the section, so
the joints cut the section only.  A ``fixed_region`` polygon adds ground
inside the section: the blocks lying entirely in it (and any block it
encloses) are merged into fixed ground blocks that follow the joints.
Ground outlines carry a vertex wherever a block corner meets them.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
import shapely

from ..blocks import GEOMETRY_RTOL, Blocks
from ..errors import InputError
from ..joints import Joint
from . import _topology as topo
from .joint_sets import JointSet
from .profile import Profile
from .size import MAX_BLOCKS, check_size, estimate_size
from .slope import Sliver, SlopeGeometry

__all__ = ["generate_slope", "section_polygon"]

log = logging.getLogger(__name__)

BOUNDARY_SIDES = ("base", "back", "front")


def section_polygon(profile: Profile, depth: float) -> shapely.Polygon:
    """The section below ``profile`` down to ``min(y) - depth`` (vertical sides).

    Examples
    --------
    >>> sec = section_polygon(Profile([(0, 10), (10, 0)]), 5)
    >>> sec.area, sec.bounds
    (100.0, (0.0, -5.0, 10.0, 10.0))
    """
    pts = profile.points
    yb = float(pts[:, 1].min()) - depth
    ring = np.vstack([pts, [[pts[-1, 0], yb], [pts[0, 0], yb]]])
    poly = shapely.Polygon(ring)
    return shapely.orient_polygons(poly)


def generate_slope(
    profile: Profile | Sequence,
    joint_sets: Sequence[JointSet] = (),
    *,
    depth: float,
    behind: float | None = None,
    unit_weight: float = 1.0,
    ground_joint: Joint | None = None,
    bridge_joint: Joint | None = None,
    boundary: Sequence[str] = BOUNDARY_SIDES,
    ground_thickness: float | None = None,
    fixed_region=None,
    min_block_fraction: float = 0.05,
    slivers: str = "merge",
    seed: int = 0,
    max_blocks: int | None = MAX_BLOCKS,
) -> SlopeGeometry:
    """Cut a slope section into blocks with joint sets.

    Parameters
    ----------
    profile : Profile or sequence of (x, y)
        Ground surface, left (crest side) to right (toe side).
    joint_sets : sequence of JointSet
        Any number of sets (names unique).
    depth : float
        Depth of the model below the lowest profile point (> 0).
    behind : float, optional
        Horizontal ground added to the left of the profile's first point
        (behind the crest, when the profile starts at the crest).
    unit_weight : float
        Unit weight of all blocks.
    ground_joint : Joint, optional
        Properties of every contact with the fixed ground (named
        ``"ground"``).  None: such contacts take the joint of the trace they
        lie on, else the first set's joint.
    bridge_joint : Joint, optional
        Intact-rock properties of the rock bridges (cohesion, tensile
        strength, friction), named ``"bridge"``; required if a set has gaps.
    boundary : sequence of {"base", "back", "front"}
        Sides of the section backed by a fixed strip; ``()`` for none.
    ground_thickness : float, optional
        Thickness of those strips (default 10% of the larger section size).
    fixed_region : shapely Polygon or sequence of (x, y), optional
        Region of the section that is fixed ground.
    min_block_fraction : float
        Blocks smaller than this fraction of the median block area are slivers.
    slivers : {"merge", "report"}
        Merge each sliver into the neighbour sharing the longest edge, or keep
        and only report them (``SlopeGeometry.slivers``).
    seed : int
        Seed of the random variation of sets without their own seed.
    max_blocks : int or None
        Refuse, before cutting anything, a slope estimated to make more
        blocks than this (see :mod:`rockdem.geometry.size`); None: no limit.

    Returns
    -------
    SlopeGeometry

    Raises
    ------
    InputError
        Bad profile, depth, set names, a set that misses the section, a
        missing ``bridge_joint``, an unknown boundary side, a slope estimated
        larger than ``max_blocks``.

    Examples
    --------
    >>> from rockdem import Joint
    >>> j = Joint(normal_stiffness=1e6, friction_angle=35)
    >>> box = Profile([(0, 10), (10, 10)])
    >>> g = generate_slope(box, [JointSet("A", 0, 2.5, j, origin=(0, 0.5)),
    ...                          JointSet("B", 90, 2.5, j, origin=(0.5, 0))], depth=10)
    >>> int((~g.blocks.fixed).sum()), [jt.name for jt in g.joints]
    (25, ['A', 'B'])
    """
    if not isinstance(profile, Profile):
        profile = Profile(profile)
    depth = _positive("generate_slope depth", depth)
    if behind is not None and float(behind) > 0:
        profile = profile.extended(left=_positive("generate_slope behind", behind))
    gamma = float(unit_weight)
    if not (math.isfinite(gamma) and gamma >= 0):
        raise InputError(
            "generate_slope unit_weight",
            f"{unit_weight} is out of range",
            "give a unit weight >= 0",
        )
    if isinstance(joint_sets, JointSet):  # (found by fuzzing: a TypeError)
        raise InputError(
            "generate_slope joint_sets", "is one JointSet, not a list", "give [JointSet(...)]"
        )
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise InputError(
            "generate_slope seed", f"{seed!r} is not a whole number >= 0", "give 0, 1, 2, ..."
        )
    sets = tuple(joint_sets)
    names = []
    for k, s in enumerate(sets):
        if not isinstance(s, JointSet):
            raise InputError(f"joint set {k}", f"{s!r} is not a JointSet", "give JointSet(...)")
        if s.name in names:
            raise InputError(f"joint set {s.name!r}", "is named twice", "give unique names")
        names.append(s.name)
    sides = tuple(boundary)
    for side in sides:
        if side not in BOUNDARY_SIDES:
            raise InputError(
                f"generate_slope boundary {side!r}",
                "is not a side",
                f"use some of {BOUNDARY_SIDES}",
            )
    if slivers not in ("merge", "report"):
        raise InputError(
            "generate_slope slivers", f"{slivers!r} is not an option", "use 'merge' or 'report'"
        )
    frac = float(min_block_fraction)
    if not (math.isfinite(frac) and 0 <= frac < 1):
        raise InputError(
            "generate_slope min_block_fraction",
            f"{frac} is out of range",
            "give a fraction in [0, 1)",
        )
    if not sets and ground_joint is None:
        raise InputError(
            "generate_slope",
            "no joint properties (no joint sets, no ground joint)",
            "give at least one JointSet or a ground_joint",
        )

    whole = section_polygon(profile, depth)
    check_size(estimate_size(whole, sets), max_blocks, whole)
    xmin, ymin, xmax, ymax = whole.bounds  # the messages give model coordinates
    extent = math.hypot(xmax - xmin, ymax - ymin)
    tol = GEOMETRY_RTOL * extent
    # The slope is cut in coordinates relative to the lower left corner of the
    # profile's bounding box and moved back at the end (as a DXF section is):
    # the blocks do not depend on where the model lies.
    ref = profile.points.min(axis=0)
    rel_profile = Profile(profile.points - ref)
    section = section_polygon(rel_profile, depth)
    rel_sets = [replace(s, origin=(s.origin[0] - ref[0], s.origin[1] - ref[1])) for s in sets]

    # ---------------------------------------------------------- joint lines
    seg_list, trace_list, set_list = [], [], []
    for k, s in enumerate(rel_sets):
        rng = np.random.default_rng(s.seed if s.seed is not None else [seed, k])
        seg, is_trace, _ = s.segments(section.bounds, rng)
        lines = shapely.linestrings(seg) if len(seg) else np.zeros(0, dtype=object)
        hits = shapely.intersects(lines, section) & ~shapely.touches(lines, section)
        if not hits.any():
            raise InputError(
                f"joint set {s.name!r}",
                f"misses the section (x {xmin:g} to {xmax:g}, y {ymin:g} to {ymax:g})",
                "move its origin into the section or reduce its spacing",
            )
        if not (hits & is_trace).any():
            raise InputError(
                f"joint set {s.name!r}",
                "has no trace in the section (all of it falls in rock bridges)",
                "move its origin, or lengthen trace_length / shorten gap",
            )
        if (~is_trace & hits).any() and bridge_joint is None:
            raise InputError(
                f"joint set {s.name!r}",
                "has rock bridges (gap > 0) but no bridge properties were given",
                "give the intact rock's strength as the bridge joint (in a model file "
                "`slope: {bridge_joint: NAME}` naming a joint with cohesion and "
                "tensile_strength; in Python generate_slope(..., bridge_joint=Joint(...)))",
            )
        seg_list.append(seg[hits])
        trace_list.append(is_trace[hits])
        set_list.append(np.full(int(hits.sum()), k))
    if seg_list:
        segs = np.concatenate(seg_list)
        is_trace = np.concatenate(trace_list)
        set_of = np.concatenate(set_list)
    else:
        segs, is_trace, set_of = np.zeros((0, 2, 2)), np.zeros(0, bool), np.zeros(0, np.int64)

    # ----------------------------------------------------------- arrangement
    faces = _arrangement(section, segs, extent)
    log.debug("arrangement: %d faces", len(faces))

    # -------------------------------------------------------------- ground
    in_ground = np.zeros(len(faces), dtype=bool)
    region = None
    if fixed_region is not None:
        region = _move(topo.as_region(fixed_region, "generate_slope fixed_region"), -ref)
        if (
            not shapely.intersects(region, section)
            or shapely.area(shapely.intersection(region, section)) <= tol * extent
        ):
            raise InputError(
                "generate_slope fixed_region",
                "does not overlap the section",
                f"give a region within x {xmin:g} to {xmax:g}, y {ymin:g} to {ymax:g}",
            )
        in_ground = shapely.covered_by(faces, shapely.buffer(region, 10 * tol, join_style="mitre"))

    # -------------------------------------------------------------- slivers
    free_area = shapely.area(faces[~in_ground])
    typical = float(np.median(free_area)) if free_area.size else float("nan")
    report: list = []
    # faces thinner than the engine's tolerance are always merged (they cannot be analysed)
    thin = 2 * tol
    if len(faces) > 1:
        fa = shapely.area(faces)
        if (fa <= thin * shapely.length(faces)).any():
            faces, origin, _ = topo.merge_slivers(faces, 0.0, movable=~in_ground, thin=thin)
            gnew = np.zeros(len(faces), dtype=bool)
            gnew[origin[in_ground]] = True
            in_ground = gnew
    if frac > 0 and free_area.size > 1:
        small = frac * typical
        if slivers == "merge":
            faces, origin, report = topo.merge_slivers(faces, small, movable=~in_ground)
            gnew = np.zeros(len(faces), dtype=bool)
            gnew[origin[in_ground]] = True
            in_ground = gnew
        else:
            area = shapely.area(faces)
            cent = shapely.get_coordinates(shapely.centroid(faces))
            report = [
                (int(i), float(area[i]), tuple(cent[i]), False)
                for i in np.flatnonzero((area < small) & ~in_ground)
            ]
    if region is not None and in_ground.any():
        ground_polys, in_ground = _merge_ground(faces, in_ground)
    else:
        ground_polys = np.zeros(0, dtype=object)

    # ------------------------------------------------------------ blocks
    free_idx = np.flatnonzero(~in_ground)
    free = faces[free_idx]
    order = topo.reading_order(shapely.get_coordinates(shapely.centroid(free)), 10 * tol)
    free, free_idx = free[order], free_idx[order]
    fid = np.full(len(faces), -1)
    fid[free_idx] = np.arange(len(free))
    fxy, _ = topo.to_arrays(free, tol)
    strips = _boundary_strips(section, rel_profile, sides, ground_thickness, fxy, tol)
    ground_polys = np.array(
        [topo.insert_vertices(g, fxy, 10 * tol) for g in ground_polys] + list(strips),
        dtype=object,
    )
    allpolys = np.concatenate([free, ground_polys])
    xy, offsets = topo.to_arrays(allpolys, tol)
    _check_outlines(allpolys, offsets, tol, ref)
    xy = xy + ref
    n_free = len(free)
    fixed = np.zeros(len(allpolys), dtype=bool)
    fixed[n_free:] = True
    blocks = Blocks(xy, offsets, fixed, np.full(len(allpolys), gamma), np.arange(len(allpolys)))

    # sliver report with block ids (ground faces map to the first ground block)
    gface = np.flatnonzero(in_ground)
    sl = []
    for j, area, c, merged in report:
        blk = (
            int(fid[j])
            if fid[j] >= 0
            else (_ground_block(faces[j], ground_polys, n_free) if gface.size else None)
        )
        at = (float(c[0] + ref[0]), float(c[1] + ref[1]))
        sl.append(Sliver(area, at, "merged" if merged else "kept", blk))

    # ---------------------------------------------------------- joint table
    table = [replace(s.joint, name=s.name) for s in sets]
    if (~is_trace).any():
        table.append(replace(bridge_joint, name="bridge"))
        bridge_index = len(table) - 1
    else:
        bridge_index = -1
    ground_index = None
    if ground_joint is not None:
        table.append(replace(ground_joint, name="ground"))
        ground_index = len(table) - 1
    order = np.argsort(~is_trace, kind="stable")  # traces first, then bridges
    lines = segs[order] + ref
    line_joint = np.where(is_trace[order], set_of[order], bridge_index).astype(np.int64)
    return SlopeGeometry(
        blocks=blocks,
        joints=tuple(table),
        joint_lines=lines,
        line_joint=line_joint,
        ground=ground_index,
        section=_move(section, ref),
        slivers=tuple(sl),
        profile=profile,
        joint_sets=sets,
        typical_area=typical,
        min_block_fraction=frac,
    )


# ---------------------------------------------------------------- helpers
def _move(geom, by):
    """``geom`` translated by ``by`` (x, y)."""
    return shapely.transform(geom, lambda xy: xy + np.asarray(by, dtype=float))


def _arrangement(section: shapely.Polygon, segs: np.ndarray, extent: float) -> np.ndarray:
    """Faces of the planar arrangement of the section outline and the segments.

    A joint passing within the geometric tolerance of a corner of the section
    is made to pass through it (see :func:`._topology.through_corners`).
    """
    if len(segs) == 0:
        return np.array([section], dtype=object)
    margin = 1e-4 * extent
    big = shapely.buffer(section, margin, join_style="mitre")
    shapely.prepare(big)
    lines = shapely.linestrings(segs)
    clipped = shapely.intersection(lines, big)
    parts = shapely.get_parts(clipped)
    # keep non-empty line pieces only (GEOS node crashes on empty parts)
    parts = parts[(shapely.get_type_id(parts) == 1) & ~shapely.is_empty(parts)]
    corners = shapely.get_coordinates(section.exterior)[:-1]
    parts = topo.through_corners(parts, corners, GEOMETRY_RTOL * extent)
    allg = shapely.multilinestrings(np.concatenate([parts, [section.exterior]]))
    noded = shapely.node(allg)
    faces = shapely.get_parts(shapely.polygonize(shapely.get_parts(noded)))
    # faces of the section lie within it (up to round-off); those in the margin do not
    tight = shapely.buffer(section, GEOMETRY_RTOL * extent, join_style="mitre")
    shapely.prepare(tight)
    inside = shapely.contains(tight, faces)
    # near-coincident lines (a joint within round-off of the outline or of
    # another joint) leave faces of no area: drop them
    solid = shapely.area(faces) > 1e-12 * extent**2
    if (inside & ~solid).any():
        log.info("dropped %d faces of no area", int((inside & ~solid).sum()))
    return faces[inside & solid]


def _merge_ground(faces: np.ndarray, in_ground: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Union of the ground faces, holes filled (enclosed faces join the ground)."""
    merged = shapely.coverage_union_all(faces[in_ground])
    parts = shapely.get_parts(merged)
    filled = shapely.polygons(shapely.get_exterior_ring(parts))
    tree = shapely.STRtree(filled)
    pts = shapely.point_on_surface(faces)
    fi, _ = tree.query(pts, predicate="within")
    in_ground = in_ground.copy()
    in_ground[fi] = True
    return filled, in_ground


def _ground_block(face, ground_polys, n_free) -> int | None:
    pt = shapely.point_on_surface(face)
    for k, g in enumerate(ground_polys):
        if shapely.contains(g, pt):
            return n_free + k
    return None


#: thickest fixed strip, as a multiple of the section's size
MAX_GROUND = 10.0


def _boundary_strips(section, profile, sides, thickness, free_xy, tol) -> list:
    """Fixed strips along the chosen sides, with a vertex at every block corner on them."""
    if not sides:
        return []
    xmin, ymin, xmax, ymax = section.bounds
    size = max(xmax - xmin, ymax - ymin)
    t = 0.1 * size if thickness is None else _positive("generate_slope ground_thickness", thickness)
    if t > MAX_GROUND * size:  # the tolerances follow the extent: the slope would vanish
        raise InputError(
            "generate_slope ground_thickness",
            f"{t:g} is more than {MAX_GROUND:g} x the section's size {size:.3g}",
            f"give at most {MAX_GROUND * size:.3g} (the ground only has to hold the blocks)",
        )
    yb = ymin
    y_back, y_front = float(profile.points[0, 1]), float(profile.points[-1, 1])
    x, y = free_xy[:, 0], free_xy[:, 1]
    out = []
    if "base" in sides:
        xs = np.unique(x[np.abs(y - yb) <= tol])
        xs = xs[(xs > xmin + tol) & (xs < xmax - tol)]
        x0 = xmin - (t if "back" in sides else 0.0)
        x1 = xmax + (t if "front" in sides else 0.0)
        top = [(x0, yb), (xmin, yb), *[(v, yb) for v in xs], (xmax, yb), (x1, yb)]
        top = [p for k, p in enumerate(top) if k == 0 or p[0] > top[k - 1][0] + tol]
        out.append(shapely.Polygon([*top, (x1, yb - t), (x0, yb - t)]))
    if "back" in sides:
        ys = np.unique(y[np.abs(x - xmin) <= tol])
        ys = ys[(ys > yb + tol) & (ys < y_back - tol)]
        edge = [(xmin, yb), *[(xmin, v) for v in ys], (xmin, y_back)]
        out.append(shapely.Polygon([*edge, (xmin - t, y_back), (xmin - t, yb)]))
    if "front" in sides:
        ys = np.unique(y[np.abs(x - xmax) <= tol])
        ys = ys[(ys > yb + tol) & (ys < y_front - tol)]
        edge = [(xmax, yb), *[(xmax, v) for v in ys], (xmax, y_front)]
        out.append(shapely.Polygon([*edge, (xmax + t, y_front), (xmax + t, yb)]))
    return out


def _check_outlines(polys: np.ndarray, offsets: np.ndarray, tol: float, ref=(0.0, 0.0)) -> None:
    """Every block keeps at least three corners once corners closer than the
    tolerance merge.  (Found by fuzzing: a profile spike 1e-6 m wide and
    990 m high left blocks with two corners, and the analysis stopped on a
    shapely error.)"""
    flat = np.flatnonzero(np.diff(offsets) < 3)
    if flat.size:
        x, y = shapely.get_coordinates(shapely.centroid(polys[flat[0]]))[0] + ref
        raise InputError(
            "profile",
            f"makes blocks thinner than the geometric tolerance ({tol:.3g}) near "
            f"({x:.6g}, {y:.6g}): {flat.size} of them collapse to lines",
            "widen or remove the narrow part of the profile (a spike or a slot)",
        )


def _positive(where: str, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise InputError(where, f"{value!r} is not a number", "give a number") from exc
    if not (math.isfinite(v) and v > 0):
        raise InputError(where, f"{value} is not positive", "give a value > 0")
    return v
