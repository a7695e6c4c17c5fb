"""External loads as forces and moments on the block centroids."""

from __future__ import annotations

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
        _add_forces(f, blocks, xy, force * scale[:, None], names)
    if loads.lines:
        pieces_xy, pieces_f, names = _split_line_loads(blocks, loads)
        if len(pieces_xy):
            _add_forces(f, blocks, pieces_xy, pieces_f, names)
    return f


def _locate(blocks: Blocks, xy: np.ndarray, direction: np.ndarray, names) -> np.ndarray:
    """The block each force at ``xy`` pushes into."""
    polys = blocks.polygons()
    tree = shapely.STRtree(polys)
    unit = direction / np.maximum(np.hypot(*direction.T), 1e-300)[:, None]
    probe = shapely.points(xy + 10 * blocks.tolerance * unit)
    idx_pt, idx_block = tree.query(probe, predicate="intersects")
    owner = np.full(len(xy), -1)
    owner[idx_pt] = idx_block
    missing = np.flatnonzero(owner < 0)
    if missing.size:
        k = int(missing[0])
        raise InputError(
            names[k],
            f"at ({xy[k, 0]:g}, {xy[k, 1]:g}) does not act on any block",
            "place it on a block boundary, pointing into the block",
        )
    return owner


def _add_forces(f, blocks, xy, force, names) -> None:
    owner = _locate(blocks, xy, force, names)
    r = xy - blocks.centroid[owner]
    moment = r[:, 0] * force[:, 1] - r[:, 1] * force[:, 0]
    np.add.at(f, (owner, 0), force[:, 0])
    np.add.at(f, (owner, 1), force[:, 1])
    np.add.at(f, (owner, 2), moment)


def _split_line_loads(blocks: Blocks, loads: Loads):
    """Cut each line load at the block boundaries: (midpoint, force) pieces."""
    polys = blocks.polygons()
    tree = shapely.STRtree(polys)
    xy, forces, names = [], [], []
    for i, line in enumerate(loads.lines):
        name = line.name or f"line load {i}"
        p0, p1 = np.asarray(line.start, float), np.asarray(line.end, float)
        q = np.array([line.qx, line.qy], float)
        length = float(np.hypot(*(p1 - p0)))
        if length <= blocks.tolerance:
            raise InputError(name, "has zero length", "give two different end points")
        unit = q / max(np.hypot(*q), 1e-300)
        shift = 10 * blocks.tolerance * unit
        seg = shapely.LineString([p0 + shift, p1 + shift])
        hit = tree.query(seg, predicate="intersects")
        pieces = shapely.intersection(polys[hit], seg)
        lengths = shapely.length(pieces)
        ok = lengths > blocks.tolerance
        if lengths.sum() < 0.999 * length:
            raise InputError(
                name, "does not lie on block boundaries all along", "move it onto the surface"
            )
        mids = shapely.get_coordinates(
            shapely.line_interpolate_point(pieces[ok], 0.5, normalized=True)
        )
        xy.append(mids - shift)
        forces.append(np.outer(lengths[ok], q))
        names += [name] * int(ok.sum())
    return np.concatenate(xy), np.concatenate(forces), names
