"""External loads as forces and moments on the block centroids."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import shapely

from .blocks import Blocks
from .errors import InputError
from .model import Loads


def block_loads(blocks: Blocks, loads: Loads, *, support_scale: float = 1.0) -> np.ndarray:
    """Force and moment ``(fx, fy, m)`` about each block's centroid.

    Self-weight and seismic forces act at the centroid; point and line loads
    go to the block they push into (found just beyond the point of
    application in the direction of the force).
    """
    f = np.zeros((blocks.n_blocks, 3))
    W = blocks.weight
    if loads.gravity:
        f[:, 1] -= W
    f[:, 0] += loads.seismic_h * W
    f[:, 1] -= loads.seismic_v * W
    if loads.points:
        xy = np.array([(p.x, p.y) for p in loads.points], dtype=float)
        force = np.array([(p.fx, p.fy) for p in loads.points], dtype=float)
        scale = np.array([support_scale if p.support else 1.0 for p in loads.points])
        names = [p.name or f"point load {i}" for i, p in enumerate(loads.points)]
        _add_forces(f, blocks, xy, force * scale[:, None], names, on_fixed=False)
    if loads.lines:
        pieces_xy, pieces_f, names = _split_line_loads(blocks, loads)
        if len(pieces_xy):
            owner = _add_forces(f, blocks, pieces_xy, pieces_f, names)
            _check_some_free(blocks, owner, names)
    return f


def _locate(
    blocks: Blocks, xy: np.ndarray, direction: np.ndarray, names, on_fixed: bool = True
) -> np.ndarray:
    """The block each force at ``xy`` pushes into (``on_fixed=False``: a force
    on a fixed block, which would carry nothing, is an error)."""
    polys = blocks.polygons()
    tree = shapely.STRtree(polys)
    unit = direction / np.maximum(np.hypot(*direction.T), 1e-300)[:, None]
    probe = shapely.points(xy + 10 * blocks.tolerance * unit)
    idx_pt, idx_block = tree.query(probe, predicate="intersects")
    shared = np.flatnonzero(np.bincount(idx_pt, minlength=len(xy)) > 1)
    # a force of nought pushes nowhere, and either block carries nothing
    # (it was refused as one "along the boundary"; a sweep may start at 0)
    shared = shared[np.hypot(*direction[shared].T) > 0]
    if shared.size:  # along a joint: either block could take it (the order chose)
        k = int(shared[0])
        a, b = sorted(int(blocks.ids[i]) for i in idx_block[idx_pt == k][:2])
        raise InputError(
            names[k],
            f"at ({xy[k, 0]:g}, {xy[k, 1]:g}) points along the boundary between blocks "
            f"{a} and {b}, so it pushes into neither",
            "turn it a little into the block it loads, or move it onto that block's face",
        )
    owner = np.full(len(xy), -1)
    last = np.lexsort((~blocks.fixed[idx_block], idx_pt))  # on several: a free one
    owner[idx_pt[last]] = idx_block[last]
    missing = np.flatnonzero(owner < 0)
    if missing.size:
        k = int(missing[0])
        raise InputError(
            names[k],
            f"at ({xy[k, 0]:g}, {xy[k, 1]:g}) does not act on any block",
            "place it on a block boundary, pointing into the block",
        )
    if not on_fixed and blocks.fixed[owner].any():
        k = int(np.flatnonzero(blocks.fixed[owner])[0])
        raise InputError(
            names[k],
            f"at ({xy[k, 0]:g}, {xy[k, 1]:g}) acts on a fixed block "
            f"(block {blocks.ids[owner[k]]}), where it would hold or push nothing",
            "place it on a free block's boundary, pointing into that block",
        )
    return owner


def _add_forces(f, blocks, xy, force, names, on_fixed: bool = True) -> np.ndarray:
    """Add the forces to the blocks they push into; returns those blocks."""
    owner = _locate(blocks, xy, force, names, on_fixed)
    r = xy - blocks.centroid[owner]
    moment = r[:, 0] * force[:, 1] - r[:, 1] * force[:, 0]
    np.add.at(f, (owner, 0), force[:, 0])
    np.add.at(f, (owner, 1), force[:, 1])
    np.add.at(f, (owner, 2), moment)
    return owner


def _check_some_free(blocks: Blocks, owner: np.ndarray, names: list[str]) -> None:
    """A line load carried by fixed blocks alone holds or pushes nothing
    (found by fuzzing: one on the ground's surface vanished silently); one
    partly on the ground, like a surcharge across the crest, is fine."""
    for name in dict.fromkeys(names):
        mine = owner[[k for k, n in enumerate(names) if n == name]]
        if blocks.fixed[mine].all():
            raise InputError(
                name,
                f"acts only on fixed blocks (block {blocks.ids[mine[0]]}), where it "
                "would hold or push nothing",
                "place it on a free block's boundary, pushing into that block",
            )


#: two-point Gauss rule on [0, 1]: exact for the force and the moment of a
#: linearly varying traction on each piece
_GAUSS_T = 0.5 + np.array([-0.5, 0.5]) / np.sqrt(3.0)


def _split_line_loads(blocks: Blocks, loads: Loads):
    """Cut each line load at the block boundaries: (point, force) pairs, two
    per piece at its Gauss points (exact for a trapezoidal traction)."""
    polys = blocks.polygons()
    tree = shapely.STRtree(polys)
    xy, forces, names = [], [], []
    for i, line in enumerate(loads.lines):
        name = line.name or f"line load {i}"
        p0, p1 = np.asarray(line.start, float), np.asarray(line.end, float)
        q = line.traction(np.array([0.5]))[0]  # the mean: which side it pushes
        ends = line.traction(np.array([0.0, 1.0]))
        if np.hypot(*q) <= 1e-9 * np.hypot(*ends.T).max():
            q = ends[0]  # a mean of nought (q_end = -q): the ends tell the sides
        length = float(np.hypot(*(p1 - p0)))
        if length <= blocks.tolerance:
            raise InputError(name, "has zero length", "give two different end points")
        unit = q / max(np.hypot(*q), 1e-300)
        if np.any(ends @ unit < 0):  # (found by fuzzing: named a Gauss point, "acts on no block")
            raise InputError(
                name,
                "has a traction that turns from pushing to pulling along it "
                f"(({ends[0][0]:g}, {ends[0][1]:g}) to ({ends[1][0]:g}, {ends[1][1]:g}))",
                "split it where the traction changes sign and leave out the part that pulls",
            )
        shift = 10 * blocks.tolerance * unit
        seg = shapely.LineString([p0 + shift, p1 + shift])
        hit = tree.query(seg, predicate="intersects")
        pieces = shapely.intersection(polys[hit], seg)
        lengths = shapely.length(pieces)
        ok = lengths > blocks.tolerance
        if lengths.sum() < 0.999 * length:
            back = shapely.LineString([p0 - shift, p1 - shift])
            behind = shapely.length(shapely.intersection(polys, back)).sum()
            if behind >= 0.999 * length:  # on the surface, pulling away (found by fuzzing)
                raise InputError(
                    name,
                    f"pulls away from the rock (traction ({q[0]:g}, {q[1]:g}) points out of "
                    "the block it lies on)",
                    "give a traction that pushes into the rock (an uplift is not modelled)",
                )
            raise InputError(
                name, "does not lie on block boundaries all along", "move it onto the surface"
            )
        if _on_boundaries(polys, tree, p0, p1, blocks.tolerance) < 0.999 * length:
            # inside the rock all along the side it pushes: a buried line (fuzzing)
            raise InputError(
                name,
                "lies inside a block, not on its boundary",
                "move it onto the surface of the rock (or onto a joint)",
            )
        for g in _GAUSS_T:
            at = shapely.get_coordinates(
                shapely.line_interpolate_point(pieces[ok], g, normalized=True)
            )
            along = (at - shift - p0) @ (p1 - p0) / length**2  # fraction of the load's length
            xy.append(at - shift)
            forces.append(0.5 * lengths[ok][:, None] * line.traction(along))
            names += [name] * int(ok.sum())
    return np.concatenate(xy), np.concatenate(forces), names


def _on_boundaries(polys, tree, p0, p1, tol: float) -> float:
    """Length of the segment ``p0 p1`` that lies on block boundaries (within ``tol``)."""
    seg = shapely.LineString([p0, p1])
    near = polys[tree.query(seg, predicate="dwithin", distance=2 * tol)]
    if not len(near):
        return 0.0
    # about p0: in site coordinates (x ~ 1e7) the union of bands 2 tol wide
    # collapsed to nothing and a line load on the face was refused
    origin = np.asarray(p0, dtype=float)
    local = shapely.transform(shapely.boundary(near), lambda xy: xy - origin)
    band = shapely.union_all(shapely.buffer(local, 2 * tol))
    seg = shapely.LineString([(0.0, 0.0), np.asarray(p1, dtype=float) - origin])
    return float(shapely.length(shapely.intersection(seg, band)))


def joint_water(blocks: Blocks, loads: Loads) -> Loads:
    """The loads whose water table gives the joints' pore pressure.

    The user's water table as it is; for a pore-pressure ratio ``r_u`` the
    top of the rock ``s(x)`` (:func:`rock_surface`) as the table and
    ``r_u gamma`` as its unit weight (``gamma``: the free rock's mean unit
    weight), so that ``u = r_u gamma (s(x) - y)``: the overburden pressure
    times ``r_u``, integrated exactly as water is.
    """
    ru = loads.pore_pressure_ratio
    if not ru:
        return loads
    free = ~blocks.fixed
    gamma = float(blocks.weight[free].sum() / blocks.area[free].sum())
    if not gamma > 0:  # (found by fuzzing: "water_unit_weight is 0 or missing")
        raise InputError(
            "loads pore_pressure_ratio",
            "needs the weight of the rock, and the free blocks weigh nothing",
            "give the rock a unit weight, or leave the pore-pressure ratio out",
        )
    table = rock_surface(blocks)
    return replace(loads, water_table=table, water_unit_weight=ru * gamma, pore_pressure_ratio=0.0)


def rock_surface(blocks: Blocks) -> tuple[tuple[float, float], ...]:
    """The top of the rock, ``(x, s(x))`` at every vertex abscissa: the highest
    point of the blocks (free and fixed) on the vertical through it."""
    rock = shapely.union_all(blocks.polygons())
    xs = np.unique(shapely.get_coordinates(rock)[:, 0])
    _, y0, _, y1 = rock.bounds
    pad = 1.0 + (y1 - y0)
    lines = shapely.linestrings(
        np.stack([np.column_stack([xs, np.full_like(xs, y0 - pad)]),
                  np.column_stack([xs, np.full_like(xs, y1 + pad)])], axis=1)
    )  # fmt: skip
    tops = shapely.bounds(shapely.intersection(lines, rock))[:, 3]
    ok = np.isfinite(tops)
    return tuple((float(x), float(y)) for x, y in zip(xs[ok], tops[ok], strict=True))


def pore_pressure(loads: Loads, points: np.ndarray) -> np.ndarray:
    """Hydrostatic water pressure ``gamma_w (h(x) - y)`` at ``points`` (n, 2),
    zero above the water table (and everywhere without one)."""
    if not loads.water_table:
        return np.zeros(len(points))
    table = np.asarray(loads.water_table)
    head = np.interp(points[:, 0], table[:, 0], table[:, 1])
    return loads.water_unit_weight * np.maximum(head - points[:, 1], 0.0)


def water_loads(blocks: Blocks, faces, loads: Loads) -> np.ndarray:
    """Forces and moments ``(fx, fy, m)`` of joint water on each block.

    On every interface the pressure ``u`` acts on both faces: it pushes block
    b along the normal (from a to b) and block a the other way.  ``u`` is
    piecewise linear along an interface (kinks where the water table bends
    or crosses it), so it is integrated exactly piece by piece, not sampled
    at the spring points.  It is a load: strength reduction does not reduce
    it.
    """
    f = np.zeros((blocks.n_blocks, 3))
    if not loads.water_table:
        return f
    table = np.asarray(loads.water_table)
    p0, p1 = faces.start, faces.end
    d = p1 - p0
    length = np.hypot(d[:, 0], d[:, 1])
    # the table's pieces, with flat extensions beyond its ends
    xs = np.concatenate([[-np.inf], table[:, 0], [np.inf]])
    hs = np.concatenate([[table[0, 1]], table[:, 1], [table[-1, 1]]])
    # every (interface, piece) pair whose x ranges overlap: a piece per
    # interface or a few, not every piece for every interface (a table of 1.3
    # million points took 248 s to check)
    x_lo = np.minimum(p0[:, 0], p1[:, 0])
    x_hi = np.maximum(p0[:, 0], p1[:, 0])
    first = np.searchsorted(xs, x_lo, side="right") - 1
    count = np.searchsorted(xs, x_hi, side="right") - first
    i = np.repeat(np.arange(len(length)), count)
    j = np.repeat(first - np.cumsum(count) + count, count) + np.arange(count.sum())
    lo, hi = xs[j], xs[j + 1]
    x0, y0, dx, dy, L = p0[i, 0], p0[i, 1], d[i, 0], d[i, 1], length[i]
    t0, t1 = _clip_to_x(x0, dx, lo, hi)
    piece = t1 > t0
    finite = np.isfinite(lo) & np.isfinite(hi)
    with np.errstate(invalid="ignore"):
        slope = np.where(finite, (hs[j + 1] - hs[j]) / np.where(finite, hi - lo, 1.0), 0.0)
    base = np.where(np.isfinite(lo), hs[j], hs[j + 1])
    x_ref = np.where(np.isfinite(lo), lo, 0.0)
    g0, g1 = (
        base + slope * (x0 + t * dx - x_ref) - (y0 + t * dy) for t in (t0, t1)
    )  # head above each end of the piece
    F, s_bar = _positive_part(g0, g1, (t1 - t0) * L)
    wet = piece & (F > 0)
    n = len(length)
    force = np.bincount(i, weights=np.where(wet, F, 0.0), minlength=n)
    arm = np.bincount(  # force x distance from p0 along the interface
        i, weights=np.where(wet, F * (t0 * L + np.where(wet, s_bar, 0.0)), 0.0), minlength=n
    )
    force *= loads.water_unit_weight
    arm *= loads.water_unit_weight
    at = np.divide(arm, force, out=np.zeros_like(arm), where=force > 0)
    tangent = np.divide(d, length[:, None], out=np.zeros_like(d), where=length[:, None] > 0)
    point = p0 + at[:, None] * tangent
    push = force[:, None] * faces.normal  # on block b; -push on block a
    for k, sign in ((faces.block_b, 1.0), (faces.block_a, -1.0)):
        r = point - blocks.centroid[k]
        fk = sign * push
        np.add.at(f[:, 0], k, fk[:, 0])
        np.add.at(f[:, 1], k, fk[:, 1])
        np.add.at(f[:, 2], k, r[:, 0] * fk[:, 1] - r[:, 1] * fk[:, 0])
    return f


def _clip_to_x(x0, dx, lo, hi):
    """Parameter range ``[t0, t1]`` of each segment ``x0 + t dx`` (t in [0, 1])
    with ``lo <= x < hi`` (vertical segments: all or nothing)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ta = (lo - x0) / dx
        tb = (hi - x0) / dx
    t0 = np.where(dx > 0, ta, np.where(dx < 0, tb, 0.0))
    t1 = np.where(dx > 0, tb, np.where(dx < 0, ta, 1.0))
    vertical_in = (x0 >= lo) & (x0 < hi)
    t0 = np.where(dx == 0, np.where(vertical_in, 0.0, 1.0), t0)
    t1 = np.where(dx == 0, np.where(vertical_in, 1.0, 0.0), t1)
    t0, t1 = (np.clip(np.nan_to_num(t, nan=0.0), 0.0, 1.0) for t in (t0, t1))
    return t0, t1


def _positive_part(g0, g1, L):
    """Integral of ``max(g, 0)`` for ``g`` linear from ``g0`` to ``g1`` over a
    length ``L``, and the distance of its centroid from the ``g0`` end."""
    both = (g0 >= 0) & (g1 >= 0)
    first = (g0 > 0) & (g1 < 0)  # wet from the g0 end to the crossing
    last = (g0 < 0) & (g1 > 0)  # wet from the crossing to the g1 end
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        s_both = L * (g0 + 2 * g1) / (3 * (g0 + g1))
        cross = np.where(first | last, L * g0 / np.where(first | last, g0 - g1, 1.0), 0.0)
    total = np.where(both, 0.5 * (g0 + g1) * L, 0.0)
    total = np.where(first, 0.5 * g0 * cross, total)
    total = np.where(last, 0.5 * g1 * (L - cross), total)
    s_bar = np.where(both & (g0 + g1 > 0), s_both, 0.0)
    s_bar = np.where(first, cross / 3, s_bar)
    s_bar = np.where(last, cross + 2 * (L - cross) / 3, s_bar)
    return total, np.nan_to_num(s_bar)


#: samples per block edge when looking for free faces under the water table
FREE_FACE_SAMPLES = 8


def check_water_table(blocks: Blocks, faces, loads: Loads) -> None:
    """Refuse a water table above the free surface of a free block.

    Water acts on joints only; above ground (a pond, a flooded toe, a
    seepage face drawn too high) it would press on free faces, which are
    not loaded, and the joints' water would push the blocks out with
    nothing against it: a silent wrong answer.  Free faces are the parts of
    the free blocks' outlines that no interface covers.
    """
    if not loads.water_table:
        return
    check_water_unit_weight(blocks, loads)
    start, end, block = blocks.edges()
    free = ~blocks.fixed[block]
    if not free.any():
        return
    start, end, block = start[free], end[free], block[free]
    t = (np.arange(FREE_FACE_SAMPLES) + 0.5) / FREE_FACE_SAMPLES
    pts = (start[:, None, :] + t[None, :, None] * (end - start)[:, None, :]).reshape(-1, 2)
    owner = np.repeat(block, FREE_FACE_SAMPLES)
    tol = blocks.tolerance
    segments = shapely.linestrings(np.stack([faces.start, faces.end], axis=1))
    covered = np.zeros(len(pts), dtype=bool)
    if len(segments):
        hit, _ = shapely.STRtree(segments).query(
            shapely.points(pts), predicate="dwithin", distance=10 * tol
        )
        covered[hit] = True
    depth = pore_pressure(loads, pts) / loads.water_unit_weight
    wet = ~covered & (depth > 10 * tol)
    if wet.any():
        k = int(np.flatnonzero(wet)[np.argmax(depth[wet])])
        x, y = pts[k]
        raise InputError(
            "loads water_table",
            f"is {depth[k]:.3g} above the free surface of block {int(blocks.ids[owner[k]])} "
            f"at ({x:.6g}, {y:.6g}); water on free faces is not modelled",
            "keep the water table at or below the ground surface (it may meet the face, "
            "as a seepage face), or model ponded water as line loads",
        )


def check_water_unit_weight(blocks: Blocks, loads: Loads) -> None:
    """Refuse water heavier than the rock of every free block: rock is two to
    three times as heavy as water, so such a water unit weight is in other
    units than the rock's (9.81 kN/m^3 beside rock of 2.6 t/m^3 made the
    plane-failure example 'unstable, proven')."""
    rock = blocks.unit_weight[~blocks.fixed]
    if not loads.water_table or loads.pore_pressure_ratio or not rock.size:
        return
    heaviest = float(rock.max())
    if heaviest > 0 and loads.water_unit_weight > heaviest:
        raise InputError(
            "loads water_unit_weight",
            f"{loads.water_unit_weight:g} is more than the unit weight of every free block "
            f"(at most {heaviest:g}): rock is 2 to 3 times as heavy as water, so the two are "
            "in different units",
            "give water and rock in the same units (water: 9.81 kN/m^3, 1 t/m^3, "
            "0.00981 MN/m^3, 62.4 lbf/ft^3)",
        )


def loads_left_on_rock(blocks: Blocks, loads: Loads) -> tuple[Loads, tuple[str, ...]]:
    """The point and line loads after rock was removed (an excavation stage,
    a removal trial, a berm cut), and what happened to those that changed.

    A load acts on the rock beneath it, so it goes with that rock: a point
    load that no longer pushes into a block is dropped, a line load keeps
    the parts of its length that still push into the rock (each part with
    its own share of a varying traction).  (Found: the automatic removal of
    a bedded slope's mechanism blocks under a crest surcharge stopped the
    design with "surcharge: does not lie on block boundaries all along".)
    """
    if not loads.points and not loads.lines:
        return loads, ()
    polys = blocks.polygons()
    tree = shapely.STRtree(polys)
    step = 10 * blocks.tolerance
    notes: list[str] = []
    points = []
    for i, p in enumerate(loads.points):
        force = np.array([p.fx, p.fy], dtype=float)
        unit = force / max(float(np.hypot(*force)), 1e-300)
        probe = shapely.points(np.array([p.x, p.y]) + step * unit)
        if not blocks.fixed[tree.query(probe, predicate="intersects")].all():
            points.append(p)
        else:  # (on the fixed ground alone it would push nothing: refused)
            notes.append(f"{p.name or f'point load {i}'} removed with its rock")
    lines = []
    for i, line in enumerate(loads.lines):
        parts, on_free = _parts_on_rock(polys, tree, line, step, blocks)
        name = line.name or f"line load {i}"
        if parts == [(0.0, 1.0)]:
            lines.append(line)
            continue
        if not parts or not on_free:
            # (a surcharge from the fixed crest onto removed rock: what is left
            # would push only the ground, which carries nothing; found in review)
            notes.append(f"{name} removed with its rock")
            continue
        p0, p1 = np.asarray(line.start, float), np.asarray(line.end, float)
        for t0, t1 in parts:
            q0, q1 = line.traction(np.array([t0, t1]))
            lines.append(
                replace(
                    line,
                    start=tuple(p0 + t0 * (p1 - p0)),
                    end=tuple(p0 + t1 * (p1 - p0)),
                    qx=float(q0[0]),
                    qy=float(q0[1]),
                    q_end=None if line.q_end is None else (float(q1[0]), float(q1[1])),
                )
            )
        kept = sum(t1 - t0 for t0, t1 in parts)
        notes.append(f"{name} cut to the {kept:.0%} of its length still on the rock")
    return replace(loads, points=tuple(points), lines=tuple(lines)), tuple(notes)


def _parts_on_rock(polys, tree, line, step: float, blocks: Blocks):
    """The fractions ``[(t0, t1), ...]`` of a line load's length that push
    into a block (merged where they meet; ``[(0, 1)]``: all of it), and
    whether some of it pushes into a free block."""
    tol = blocks.tolerance
    p0, p1 = np.asarray(line.start, float), np.asarray(line.end, float)
    length = float(np.hypot(*(p1 - p0)))
    q = line.traction(np.array([0.5]))[0]
    shift = step * q / max(float(np.hypot(*q)), 1e-300)
    seg = shapely.LineString([p0 + shift, p1 + shift])
    hit = tree.query(seg, predicate="intersects")
    whole = shapely.intersection(polys[hit], seg)
    on_free = bool(np.any((shapely.length(whole) > tol) & ~blocks.fixed[hit]))
    pieces = shapely.get_parts(whole)  # (a concave block: in and out again)
    spans = []
    for xy in map(shapely.get_coordinates, pieces):
        if len(xy) < 2:
            continue
        t = (xy - shift - p0) @ (p1 - p0) / length**2
        spans.append((float(np.clip(t.min(), 0, 1)), float(np.clip(t.max(), 0, 1))))
    merged: list[list[float]] = []
    for t0, t1 in sorted(spans):
        if merged and t0 <= merged[-1][1] + tol / length:
            merged[-1][1] = max(merged[-1][1], t1)
        elif (t1 - t0) * length > tol:
            merged.append([t0, t1])
    if len(merged) == 1 and merged[0][0] * length <= tol and (1 - merged[0][1]) * length <= tol:
        return [(0.0, 1.0)], on_free
    return [(t0, t1) for t0, t1 in merged], on_free
