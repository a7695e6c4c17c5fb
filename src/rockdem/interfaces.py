"""Interfaces: the stretches of boundary that two blocks share.

Two blocks meet wherever an edge of one and an edge of the other are
collinear, run in opposite directions (both outlines are counter-clockwise)
and overlap by a positive length.  Each such overlap is one interface
``P0 -> P1`` with unit tangent ``t`` and unit normal ``n`` pointing from block
``a`` into block ``b``.  Found with one spatial query over all edges.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from .blocks import Blocks
from .errors import InputError


@dataclass(frozen=True, eq=False, repr=False)
class Interfaces:
    """One row per interface segment (struct of arrays).

    Attributes
    ----------
    block_a, block_b : ndarray of int
        The two blocks (positions in :class:`Blocks`); ``n`` points a -> b.
    start, end : ndarray, shape (n, 2)
        End points ``P0`` and ``P1``.
    joint : ndarray of int
        Index into the model's joint table.
    """

    block_a: np.ndarray
    block_b: np.ndarray
    start: np.ndarray
    end: np.ndarray
    joint: np.ndarray

    @property
    def n_interfaces(self) -> int:
        return len(self.block_a)

    @property
    def length(self) -> np.ndarray:
        return np.hypot(*(self.end - self.start).T)

    @property
    def tangent(self) -> np.ndarray:
        return (self.end - self.start) / self.length[:, None]

    @property
    def normal(self) -> np.ndarray:
        """Unit normal from block a into block b (outward normal of a)."""
        t = self.tangent
        return np.column_stack([t[:, 1], -t[:, 0]])

    @property
    def midpoint(self) -> np.ndarray:
        return 0.5 * (self.start + self.end)

    def __repr__(self) -> str:
        return f"<Interfaces: {self.n_interfaces:,} segments>"


def find_interfaces(blocks: Blocks) -> Interfaces:
    """All interfaces between the blocks (none between two fixed blocks).

    Tolerances are relative to the model's extent, so the result does not
    depend on the unit of length or on where the origin is.

    Raises
    ------
    InputError
        If a free block touches no other block (see also :func:`check_held`).
    """
    p, q, owner = blocks.edges()
    tol = blocks.tolerance
    i, j = _edge_pairs(p, q, tol)
    keep = (owner[i] < owner[j]) & ~(blocks.fixed[owner[i]] & blocks.fixed[owner[j]])
    i, j = i[keep], j[keep]
    d_i = q[i] - p[i]
    len_i = np.hypot(*d_i.T)
    t_i = d_i / len_i[:, None]
    n_i = np.column_stack([t_i[:, 1], -t_i[:, 0]])
    # distance of j's end points from i's line, and their position along it
    off0 = np.einsum("ij,ij->i", p[j] - p[i], n_i)
    off1 = np.einsum("ij,ij->i", q[j] - p[i], n_i)
    s0 = np.einsum("ij,ij->i", p[j] - p[i], t_i)
    s1 = np.einsum("ij,ij->i", q[j] - p[i], t_i)
    # or i's end points within tol of j's line: a short edge lying on a long
    # one that is off its line at its far end (2e-7 off for a vertex 1e-7
    # up) was refused with one block order and an interface with the other
    # (found by hostile testing)
    d_j = q[j] - p[j]
    n_j = np.column_stack([d_j[:, 1], -d_j[:, 0]]) / np.hypot(*d_j.T)[:, None]
    back0 = np.einsum("ij,ij->i", p[i] - p[j], n_j)
    back1 = np.einsum("ij,ij->i", q[i] - p[j], n_j)
    on_i = (np.abs(off0) <= tol) & (np.abs(off1) <= tol)
    on_j = (np.abs(back0) <= tol) & (np.abs(back1) <= tol)
    collinear = (on_i | on_j) & (s1 < s0)
    lo = np.maximum(0.0, np.minimum(s0, s1))
    hi = np.minimum(len_i, np.maximum(s0, s1))
    ok = collinear & (hi - lo > 10 * tol)
    i, t_i, lo, hi = i[ok], t_i[ok], lo[ok], hi[ok]
    j = j[ok]
    start = p[i] + lo[:, None] * t_i
    end = p[i] + hi[:, None] * t_i
    a, b = owner[i], owner[j]
    order = np.lexsort((start[:, 1], start[:, 0], b, a))
    faces = Interfaces(
        a[order], b[order], start[order], end[order], np.zeros(len(order), dtype=np.int64)
    )
    _check_connected(blocks, faces)
    return faces


#: edges whose directions differ by more than this (radians) are searched apart
DIRECTION_GAP = 1e-3


def _direction_groups(d: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Segments (direction vectors ``d``) grouped by the direction of their line,
    gaps wider than DIRECTION_GAP splitting the groups (0 and 180 degrees
    are one direction): ``(indices, rotation)`` per group, the rotation turning
    the group's lines level.

    Segments on one line have one direction (to round-off); turned level, a
    long inclined segment's bounding box is thin, where it would hold
    hundreds of thin blocks' edges in an R-tree (measured: 5,000 blocks
    0.01 m thick, 6.9 s in one query over all edges).
    """
    theta = np.mod(np.arctan2(d[:, 1], d[:, 0]), np.pi)
    order = np.argsort(theta)
    gaps = np.flatnonzero(np.diff(theta[order]) > DIRECTION_GAP)
    groups = np.split(order, gaps + 1)
    if len(groups) > 1 and theta[order[0]] + np.pi - theta[order[-1]] <= DIRECTION_GAP:
        groups[0] = np.concatenate([groups.pop(), groups[0]])  # across 0 = pi
    out = []
    for g in groups:
        angle = np.arctan2(np.sin(2 * theta[g]).mean(), np.cos(2 * theta[g]).mean()) / 2
        c, s = np.cos(angle), np.sin(angle)
        out.append((g, np.array([[c, s], [-s, c]])))  # by -angle
    return out


def _edge_pairs(p: np.ndarray, q: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of edges within ``tol`` of each other that may lie on one line
    (an R-tree query per direction group, :func:`_direction_groups`)."""
    centre = 0.5 * (p.min(axis=0) + p.max(axis=0))
    pairs_i, pairs_j = [np.zeros(0, dtype=np.int64)], [np.zeros(0, dtype=np.int64)]
    for g, turn in _direction_groups(q - p):
        ends = np.stack([(p[g] - centre) @ turn.T, (q[g] - centre) @ turn.T], axis=1)
        lines = shapely.linestrings(ends)
        a, b = shapely.STRtree(lines).query(lines, predicate="dwithin", distance=tol)
        pairs_i.append(g[a])
        pairs_j.append(g[b])
    return np.concatenate(pairs_i), np.concatenate(pairs_j)


def _on_lines(faces: Interfaces, lines: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """(interface, line) pairs whose interface midpoint is within ``tol`` of the
    line, searched per direction group (an interface lies on a line only if
    parallel to it)."""
    n = len(lines)
    d = np.concatenate([lines[:, 1] - lines[:, 0], faces.end - faces.start])
    centre = 0.5 * (lines.reshape(-1, 2).min(axis=0) + lines.reshape(-1, 2).max(axis=0))
    found_f, found_g = [np.zeros(0, dtype=np.int64)], [np.zeros(0, dtype=np.int64)]
    for g, turn in _direction_groups(d):
        on, at = g[g < n], g[g >= n] - n
        if not (on.size and at.size):
            continue
        geoms = shapely.linestrings((lines[on] - centre) @ turn.T)
        mids = shapely.points((faces.midpoint[at] - centre) @ turn.T)
        f, k = shapely.STRtree(geoms).query(mids, predicate="dwithin", distance=tol)
        found_f.append(at[f])
        found_g.append(on[k])
    return np.concatenate(found_f), np.concatenate(found_g)


def _check_connected(blocks: Blocks, faces: Interfaces) -> None:
    touched = np.zeros(blocks.n_blocks, dtype=bool)
    touched[faces.block_a] = True
    touched[faces.block_b] = True
    lonely = np.flatnonzero(~touched & ~blocks.fixed)
    if lonely.size:
        k = int(lonely[0])
        polys = blocks.polygons()
        others = np.delete(np.arange(blocks.n_blocks), k)
        near = shapely.distance(polys[k], polys[others]) if others.size else np.zeros(0)
        if near.size and near.min() <= 1e-3 * blocks.extent:
            # found by fuzzing: a block sunk 1e-6 into the ground "would float"
            j = int(others[np.argmin(near)])
            gap = float(near.min())
            point = _point_contact(polys[k], polys[j], gap, blocks.tolerance)
            if point is not None:
                # found by fuzzing: a block on another's corner was said to
                # overlap it "by a sliver deeper than the tolerance"
                raise InputError(
                    f"block {int(blocks.ids[k])}",
                    f"touches block {int(blocks.ids[j])} only at the point "
                    f"({point[0]:.6g}, {point[1]:.6g}): blocks must share an edge to "
                    "carry force between them",
                    "move it so that one of its edges rests along its neighbour's, make "
                    "it fixed, or remove it",
                )
            how = (
                f"overlaps block {int(blocks.ids[j])} by a sliver deeper than"
                if gap == 0
                else f"misses block {int(blocks.ids[j])} by {gap:.3g}, more than"
            )
            raise InputError(
                f"block {int(blocks.ids[k])}",
                f"shares no edge with another block: it {how} the model's geometric "
                f"tolerance ({blocks.tolerance:.3g})",
                "make the edges it rests on match its neighbour's within the tolerance",
            )
        raise InputError(
            f"block {int(blocks.ids[k])}",
            "touches no other block along an edge (it would float)",
            "move it onto its neighbours, make it fixed, or remove it",
        )


def _point_contact(a, b, gap: float, tol: float) -> tuple[float, float] | None:
    """The point where polygons ``a`` and ``b`` (``gap`` apart) meet, if they meet
    within ``tol`` over no more than an interface's shortest length (10 x ``tol``,
    :func:`find_interfaces`); None if they are apart or overlap more."""
    if gap > tol:
        return None
    touch = shapely.intersection(a, b) if gap == 0 else shapely.shortest_line(a, b)
    x0, y0, x1, y1 = touch.bounds
    if math.hypot(x1 - x0, y1 - y0) > 10 * tol:
        return None
    return 0.5 * (x0 + x1), 0.5 * (y0 + y1)


def check_held(blocks: Blocks, faces: Interfaces | None = None) -> None:
    """Every free block must reach a fixed block through interfaces.

    A group of free blocks touching only one another (or a model without a
    fixed block) is held by nothing: its stiffness is singular.  This names
    the blocks and the fix, where the solver could only report a singular
    matrix.

    Raises
    ------
    InputError
        Naming the free blocks that nothing holds (the first 12).
    """
    if faces is None:
        faces = find_interfaces(blocks)
    if not (~blocks.fixed).any():  # (hostile round 7: "stable", and FS "no failure")
        raise InputError(
            "blocks",
            "every block is fixed: nothing can move, there is nothing to analyse",
            "make the blocks that may move free (fixed=False)",
        )
    loose = _unheld(blocks, faces)
    if not loose.size:
        return
    ids = ", ".join(str(int(i)) for i in blocks.ids[loose[:12]])
    if loose.size > 12:
        ids += f", ... ({loose.size - 12} more)"
    if not blocks.fixed.any():
        raise InputError(
            f"blocks {ids}",
            "are held by nothing: no block is fixed",
            "make the ground blocks fixed (`fixed: true`), or give the slope a fixed boundary",
        )
    raise InputError(
        f"blocks {ids}",
        "are held by nothing: they touch one another but no fixed block",
        "connect them to the ground along an edge, make one of them fixed, or remove them",
    )


def _unheld(blocks: Blocks, faces: Interfaces) -> np.ndarray:
    """Positions of the free blocks that no chain of interfaces joins to a fixed block."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    n = blocks.n_blocks
    ground = n  # one node stands for all fixed blocks
    a = np.where(blocks.fixed[faces.block_a], ground, faces.block_a)
    b = np.where(blocks.fixed[faces.block_b], ground, faces.block_b)
    graph = sp.coo_array((np.ones(len(a)), (a, b)), shape=(n + 1, n + 1))
    _, label = connected_components(graph, directed=False)
    held = label[:n] == label[ground]
    return np.flatnonzero(~held & ~blocks.fixed)


def _along_lines(faces: Interfaces, blocks: Blocks, lines) -> tuple[np.ndarray, np.ndarray]:
    """(interface, line) pairs where the whole interface lies on the line."""
    lines = np.asarray(lines, dtype=float).reshape(-1, 2, 2)
    tol = blocks.tolerance * 10
    f, g = _on_lines(faces, lines, tol)
    if f.size:  # both ends within tol, not only the midpoint
        geoms = shapely.linestrings(lines)
        ends = shapely.distance(shapely.points(faces.start[f]), geoms[g]) <= tol
        ends &= shapely.distance(shapely.points(faces.end[f]), geoms[g]) <= tol
        f, g = f[ends], g[ends]
    return f, g


#: a joint line along no contact "nearly follows" one when both ends of some
#: interface lie within this share of the interface's length of the line
NEARLY_ALONG = 0.05


def lines_along_no_contact(faces: Interfaces, blocks: Blocks, lines) -> np.ndarray:
    """Indices of the joint ``lines`` along which no interface lies, but that
    nearly follow one, or lie on part of one: their joint is used nowhere, and
    a contact they were probably meant for keeps another (a line drawn 1 mm
    off a block's base, or over half of it).
    Lines far from every contact (a trace running on through the fixed
    ground, or into a block, in a drawn section) are not listed."""
    if lines is None or not len(lines):
        return np.zeros(0, dtype=np.int64)
    lines = np.asarray(lines, dtype=float).reshape(-1, 2, 2)
    _, g = _along_lines(faces, blocks, lines)
    unused = np.setdiff1d(np.arange(len(lines)), g)
    if not unused.size or not faces.n_interfaces:
        return unused
    length = np.linalg.norm(faces.end - faces.start, axis=1)
    reach = np.maximum(NEARLY_ALONG * length, blocks.tolerance * 10)
    geoms = shapely.linestrings(lines[unused])
    tree = shapely.STRtree(shapely.linestrings(np.stack([faces.start, faces.end], axis=1)))
    k, f = tree.query(geoms, predicate="dwithin", distance=float(reach.max()))
    close = shapely.distance(shapely.points(faces.start[f]), geoms[k]) <= reach[f]
    close &= shapely.distance(shapely.points(faces.end[f]), geoms[k]) <= reach[f]
    # ... or lies on a contact over part of its length (found by fuzzing: a
    # weak joint drawn over half of a 4 m contact was ignored, FS 2.0 for 0.728)
    segs = shapely.linestrings(np.stack([faces.start[f], faces.end[f]], axis=1))
    ends = lines[unused][k]
    part = shapely.distance(shapely.points(ends[:, 0]), segs) <= reach[f]
    part &= shapely.distance(shapely.points(ends[:, 1]), segs) <= reach[f]
    return np.unique(unused[k[close | part]])


def assign_joints(
    faces: Interfaces,
    blocks: Blocks,
    *,
    default: int = 0,
    ground: int | None = None,
    lines: np.ndarray | None = None,
    line_joint: np.ndarray | None = None,
) -> Interfaces:
    """Give every interface a joint index.

    Precedence: the contact with a fixed block takes ``ground`` (if given);
    otherwise an interface lying on one of ``lines`` (segments, shape
    ``(m, 2, 2)``) takes that line's ``line_joint``; otherwise ``default``.
    Where lines overlap, the first one listed wins.
    """
    joint = np.full(faces.n_interfaces, default, dtype=np.int64)
    if lines is not None and len(lines):
        line_joint = np.asarray(line_joint, dtype=np.int64)
        f, g = _along_lines(faces, blocks, lines)
        if f.size:
            # first listed line wins: per interface keep the smallest line index
            order = np.lexsort((g, f))
            first = np.ones(len(order), dtype=bool)
            first[1:] = f[order][1:] != f[order][:-1]
            sel = order[first]
            joint[f[sel]] = line_joint[g[sel]]
    if ground is not None:
        on_ground = blocks.fixed[faces.block_a] | blocks.fixed[faces.block_b]
        joint[on_ground] = ground
    return Interfaces(faces.block_a, faces.block_b, faces.start, faces.end, joint)
