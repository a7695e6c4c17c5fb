"""What the mechanism does: a failure mode per block, and where it meets the model's edge.

:func:`failure_modes` reads the failure mechanism of an analysis (the
direction of motion of every block, ``Analysis.mechanism``) at the contacts
of each moving block.  Blocks that move together without relative motion
form one rigid group; each group is judged at the contacts it keeps with
the rest of the model:

* **falls** - it keeps no contact closed (it separates from everything);
* **slides** - it keeps a contact closed along its whole length and moves
  along it (translation along the contact, no rotation relative to it);
* **topples** - it keeps its base closed at one corner only, the other end
  lifting, and that corner does not slip (rotation about a contact corner);
* **slides and topples** - the same, with the corner slipping along the base;
* **stable** - not part of the mechanism.

The base is the contact the loads press the group onto (its outward normal
has the largest component along the resultant load on the group).  These are
the kinematic modes of a block on a plane in Goodman & Bray (1976) and
Wyllie & Mah (2004, ch. 9), read here from the computed motion, not from
the geometry.  Where the analysis knows its last equilibrium before the
limit (``Analysis.limit_interfaces``: the failed end of a factor-of-safety
search, a load step after the first), each block's base as it stood there
decides between sliding and toppling wherever it slid or lifted: the
motion is that of a run a little beyond the limit, where toppling columns'
toe corners also slip a little and the detail is chaotic (see
:func:`_at_the_limit`; ``BlockModes.decided`` says which blocks).

:func:`boundary_contacts` finds where the moving blocks touch a fixed block
that backs the model's outer boundary (the back, the base or the front of
the section: artificial boundaries, not the ground surface): there the
mechanism is bounded by where the model was cut, and the model should be
extended.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components

__all__ = [
    "MODES",
    "BlockModes",
    "BoundaryContact",
    "boundary_contacts",
    "boundary_warnings",
    "failure_modes",
    "oriented_mechanism",
]

#: The failure modes, in the order of their codes.
MODES = ("stable", "slides", "topples", "slides and topples", "falls")
STABLE, SLIDES, TOPPLES, SLIDES_AND_TOPPLES, FALLS = range(5)
#: Relative motion below this share of a group's largest motion counts as none.
MOTION_TOL = 0.05
#: A contact whose outward normal is within this angle of the load direction
#: (cosine) carries the group; steeper contacts are its sides.
BASE_COS = 0.5
#: A contact within this angle of a side of the model runs along that side.
PARALLEL_DEG = 10.0
#: ... and within this share of the model's span from it.
BOUNDARY_SHARE = 0.25


def oriented_mechanism(a) -> np.ndarray:
    """The mechanism of an analysis signed so that the loads do positive work on
    it (a direction of motion is defined up to its sign)."""
    mech = np.asarray(a.mechanism, dtype=float)
    f = getattr(a.system, "f_block", None)
    if f is not None and np.sum(np.asarray(f) * mech) < 0:
        return -mech
    return mech


def _velocity(blocks, motion: np.ndarray, i: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Velocity of the points ``p`` (m, 2) rigidly attached to blocks ``i`` (m,)."""
    ux, uy, th = motion[i].T
    c = blocks.centroid[i]
    return np.column_stack([ux - th * (p[:, 1] - c[:, 1]), uy + th * (p[:, 0] - c[:, 0])])


def _speed_scale(blocks, motion: np.ndarray) -> np.ndarray:
    """Largest speed of any vertex of each block under ``motion``."""
    owner = np.repeat(np.arange(blocks.n_blocks), np.diff(blocks.offsets))
    v = np.hypot(*_velocity(blocks, motion, owner, blocks.vertices).T)
    out = np.zeros(blocks.n_blocks)
    np.maximum.at(out, owner, v)
    return out


@dataclass(frozen=True, eq=False, repr=False)
class BlockModes:
    """Failure mode of every block at the limit (see :data:`MODES`).

    Attributes
    ----------
    code : ndarray of int (n_blocks,)
        Index into :data:`MODES`.
    group : ndarray of int (n_blocks,)
        Rigid group of each moving block (blocks moving together), -1 if stable.
    pivot : ndarray (n_blocks, 2)
        The contact corner a toppling block turns about (NaN otherwise).
    ids : ndarray of int
        Block ids (as in ``Analysis.system.blocks.ids``).
    decided : ndarray of bool (n_blocks,)
        The mode was read from the block's base at the last equilibrium
        before the limit (sliding or lifted there); otherwise from the
        motion beyond the limit, which is chaotic in its detail for a block
        at the transition between sliding and toppling.
    carried : ndarray of bool (n_blocks,)
        Of the blocks not ``decided``: those whose base held at the limit,
        closed all along and below its strength, on moving blocks (a layer
        riding on a sliding one): they move with the blocks under them, not
        at a transition.
    """

    code: np.ndarray
    group: np.ndarray
    pivot: np.ndarray
    ids: np.ndarray
    decided: np.ndarray
    carried: np.ndarray | None = None

    @property
    def at_transition(self) -> np.ndarray:
        """Moving blocks whose mode is the motion's, at the transition between
        sliding and toppling (neither decided at the limit nor carried)."""
        carried = self.carried if self.carried is not None else np.zeros_like(self.decided)
        return (self.code > 0) & ~self.decided & ~carried

    @property
    def name(self) -> np.ndarray:
        """Mode of every block in words."""
        return np.asarray(MODES)[self.code]

    def counts(self) -> dict[str, int]:
        """Free blocks per mode, in the order of :data:`MODES` (fixed blocks excluded)."""
        n = np.bincount(self.code, minlength=len(MODES))
        return {m: int(k) for m, k in zip(MODES, n, strict=True)}

    def blocks(self, mode: str) -> np.ndarray:
        """Ids of the blocks in ``mode``."""
        return self.ids[self.code == MODES.index(mode)]

    def __repr__(self) -> str:
        moving = {m: n for m, n in self.counts().items() if n and m != "stable"}
        return f"<BlockModes: {moving or 'no mechanism'}>"


def failure_modes(a) -> BlockModes:
    """Failure mode of every block from the mechanism of an analysis.

    Parameters
    ----------
    a : Analysis
        A stable analysis gives every block ``"stable"``.

    Returns
    -------
    BlockModes
    """
    system = a.system
    blocks, faces = system.blocks, system.interfaces
    n = blocks.n_blocks
    code = np.zeros(n, dtype=np.int64)
    group = np.full(n, -1)
    pivot = np.full((n, 2), np.nan)
    moving = np.asarray(a.unstable, dtype=bool) & ~blocks.fixed
    if a.stable or not moving.any():
        return BlockModes(code, group, pivot, blocks.ids, np.zeros(n, dtype=bool))
    motion = oriented_mechanism(a).copy()
    motion[~moving] = 0.0
    scale = _speed_scale(blocks, motion)
    A, B = faces.block_a, faces.block_b
    normal, tangent = faces.normal, faces.tangent
    # relative motion of a with respect to b at both ends: opening (> 0 apart) and slip
    ends = (faces.start, faces.end)
    rel = [_velocity(blocks, motion, A, p) - _velocity(blocks, motion, B, p) for p in ends]
    opening = np.column_stack([-np.einsum("ij,ij->i", r, normal) for r in rel])
    slip = np.column_stack([np.einsum("ij,ij->i", r, tangent) for r in rel])
    size = np.maximum(scale[A], scale[B])
    still = np.hypot(opening, slip).max(1) <= MOTION_TOL * size
    # rigid groups: moving blocks joined by contacts without relative motion
    join = moving[A] & moving[B] & still
    g = coo_array((np.ones(join.sum()), (A[join], B[join])), shape=(n, n))
    _, label = connected_components(g, directed=False)
    groups = np.unique(label[moving])
    group[moving] = np.searchsorted(groups, label[moving])
    load = np.asarray(getattr(system, "f_block", np.zeros((n, 3))))[:, :2]
    limit = getattr(a, "limit_interfaces", None)
    g_code, g_pivot = _group_modes(group, len(groups), A, B, faces, opening, slip, scale, load)
    code[moving] = g_code[group[moving]]
    pivot[moving] = g_pivot[group[moving]]
    decided = carried = np.zeros(n, dtype=bool)
    if limit is not None:
        points = system.springs.points_per_interface
        code, pivot, decided, carried = _at_the_limit(
            code, pivot, moving, faces, opening, load, limit, points
        )
    return BlockModes(code, group, pivot, blocks.ids, decided, carried)


def _group_modes(group, n_groups, A, B, faces, opening, slip, scale, load):
    """Mode code and pivot of every rigid group, from its contacts with the rest.

    Each contact between a group and anything outside it is one row, seen
    from the group (outward normal, slip of the group); the rules of the
    module docstring are per-group reductions over these rows.
    """
    G = n_groups
    ga, gb = group[A], group[B]
    ext_a = (ga >= 0) & (ga != gb)
    ext_b = (gb >= 0) & (ga != gb)
    rows = np.concatenate([np.flatnonzero(ext_a), np.flatnonzero(ext_b)])
    g = np.concatenate([ga[ext_a], gb[ext_b]])
    sign = np.concatenate([np.ones(ext_a.sum()), -np.ones(ext_b.sum())])
    n_out = faces.normal[rows] * sign[:, None]
    s = np.abs(slip[rows])
    g_scale = np.zeros(G)
    moving = group >= 0
    np.maximum.at(g_scale, group[moving], scale[moving])
    tol = MOTION_TOL * g_scale
    closed = opening[rows] <= tol[g][:, None]
    touching = closed.any(1)
    # the direction the loads press each group
    f = np.column_stack([np.bincount(group[moving], load[moving, k], G) for k in (0, 1)])
    size = np.hypot(f[:, 0], f[:, 1])
    down = np.where(size[:, None] > 0, f / np.where(size > 0, size, 1.0)[:, None], [0.0, -1.0])
    press = np.einsum("ij,ij->i", n_out, down[g])
    base = touching & (press >= BASE_COS)
    # held at its sides only: judge a group at the contact it leans on most
    lean = np.full(G, -np.inf)
    np.maximum.at(lean, g[touching], press[touching])
    no_base = np.bincount(g[base], minlength=G) == 0
    base |= touching & no_base[g] & (press >= lean[g] - 1e-9)
    falls = np.bincount(g[touching], minlength=G) == 0
    slides = np.bincount(g[base & closed.all(1)], minlength=G) > 0
    # rotation about a closed corner: does the least-slipping corner slip?
    corner_slip = np.where(closed, s, np.inf).min(1)
    end = np.where(closed, s, np.inf).argmin(1)
    turn = np.flatnonzero(base & ~closed.all(1))
    least = np.full(G, np.inf)
    np.minimum.at(least, g[turn], corner_slip[turn])
    pivot = np.full((G, 2), np.nan)
    order = turn[np.lexsort((corner_slip[turn], g[turn]))]
    first = order[np.r_[True, g[order][1:] != g[order][:-1]]] if order.size else order
    pts = np.where(end[first, None] == 0, faces.start[rows[first]], faces.end[rows[first]])
    pivot[g[first]] = pts
    code = np.where(
        falls,
        FALLS,
        np.where(slides, SLIDES, np.where(least <= tol, TOPPLES, SLIDES_AND_TOPPLES)),
    )
    pivot[(code == FALLS) | (code == SLIDES)] = np.nan
    return code, pivot


#: The contacts of a group's base proper: within this (cosine) of the one it
#: leans on most (a side face of a column on a steep base can also count as
#: base, see BASE_COS)
MAIN_BASE_COS = 0.05
#: At the limit a group stood on a corner where at least this share of its
#: base was open ...
LIFTED = 0.5
#: ... and it slipped on its base where this share of the closed part was at
#: its shear strength
SLIPPING = 0.99


def _at_the_limit(code, pivot, moving, faces, opening, load, limit, points):
    """Sliding or toppling of every moving block as its base stood at the last equilibrium.

    The mechanism is a run of the blocks a little beyond the limit: there a
    toppling column's toe corner also slips a little (in Goodman & Bray's
    staircase by ~5% of the block speed although its base friction was not
    exhausted), which the motion alone reads as sliding; and the run is
    chaotic in its detail (a start moved by 1e-9 makes some columns hop off
    their base or move with a neighbour).  So the decision is made block by
    block, on the base it had at the limit: the contacts still closed there
    that its own load presses it onto most (within :data:`MAIN_BASE_COS`).
    Closed and at its strength (all along it, all but one spring point),
    the block slides; open over half its length with the closed part below
    its strength, it topples, as Goodman & Bray's limit equilibrium classes
    the blocks; open over half its length with the closed part at its
    strength, it slides and topples.  Other blocks
    keep the mode of their group's motion (``decided`` False): with no
    closed base there, or a base partly open and partly at its strength (a
    block at the transition: Goodman & Bray's staircase on one trial
    schedule, 1/6 open and 2/3 at strength, turned or slid as the run's
    round-off went; a layer sliding on bedding stands the same way), or a
    base that holds (a brittle joint may still lose it).
    """
    n = len(code)
    A, B = faces.block_a, faces.block_b
    rows = np.concatenate([np.arange(len(A)), np.arange(len(A))])
    blk = np.concatenate([A, B])
    n_out = np.concatenate([faces.normal, -faces.normal])
    keep = moving[blk]
    other = np.concatenate([B, A])[keep]
    rows, blk, n_out = rows[keep], blk[keep], n_out[keep]
    f = load[blk]
    size = np.hypot(f[:, 0], f[:, 1])
    down = np.where(size[:, None] > 0, f / np.where(size > 0, size, 1.0)[:, None], [0.0, -1.0])
    press = np.einsum("ij,ij->i", n_out, down)
    open_share = np.asarray(limit.open_fraction)[rows]
    carries = open_share < 1.0  # some of it closed at the limit
    lean = np.full(n, -np.inf)
    np.maximum.at(lean, blk[carries], press[carries])
    base = carries & (press >= lean[blk] - MAIN_BASE_COS)
    length = faces.length[rows] * base
    opened = length * open_share
    slid = length * np.asarray(limit.sliding_fraction)[rows]
    total = np.bincount(blk, length, n)
    closed = total - np.bincount(blk, opened, n)
    slid_total = np.bincount(blk, slid, n)
    # a base closed all along slips with all but its last spring point at
    # strength (the last equilibrium is the one before that point yields)
    point = np.zeros(n)
    np.maximum.at(point, blk, length / points)
    whole = (closed > 0) & (closed >= total) & (closed - slid_total <= point * (1 + 1e-9))
    slipping = (closed > 0) & ((slid_total >= SLIPPING * closed) | whole)
    lifted = (total > 0) & (total - closed >= LIFTED * total)
    # a block that hops off its base beyond the limit still slid there
    decided = moving & (slipping | lifted)
    # a base that held, closed all along, on moving blocks: carried by them
    on_moving = np.bincount(blk, length * moving[other], n)
    holds = (closed > 0) & (closed >= total) & (on_moving >= total * (1 - 1e-9))
    carried = moving & ~decided & holds
    out = code.copy()
    out[decided & slipping & ~lifted] = SLIDES
    out[decided & slipping & lifted] = SLIDES_AND_TOPPLES
    out[decided & ~slipping & lifted] = TOPPLES
    # a block read as toppling from the limit although its motion slid flat
    # turns about the corner of its longest base that the motion keeps closest
    pivot = pivot.copy()
    turns = (out == TOPPLES) | (out == SLIDES_AND_TOPPLES)
    need = np.flatnonzero(base & turns[blk] & np.isnan(pivot[blk, 0]))
    if need.size:
        need = need[np.lexsort((-faces.length[rows[need]], blk[need]))]
        first = need[np.r_[True, blk[need][1:] != blk[need][:-1]]]
        r = rows[first]
        closer = opening[r].argmin(1) == 0
        pivot[blk[first]] = np.where(closer[:, None], faces.start[r], faces.end[r])
    pivot[(out == FALLS) | (out == SLIDES) | (out == STABLE)] = np.nan
    return out, pivot, decided, carried


# ----------------------------------------------------------- model boundary
@dataclass(frozen=True, eq=False)
class BoundaryContact:
    """The mechanism touching the fixed ground along one side of the model.

    Attributes
    ----------
    side : str
        ``"back"`` (behind the crest), ``"front"`` (beyond the toe),
        ``"left"``/``"right"`` (when the ground is as high on both sides) or
        ``"base"``.
    at : float
        The x (back, front, left, right) or y (base) of the contact line.
    span : (float, float)
        Its extent along the side (y for a side, x for the base).
    interfaces : ndarray of int
        Interface positions of the contact.
    blocks : tuple of int
        Ids of the moving blocks that touch it.
    """

    side: str
    at: float
    span: tuple[float, float]
    interfaces: np.ndarray
    blocks: tuple[int, ...]

    @property
    def message(self) -> str:
        """One sentence: where, and what to do."""
        if self.side == "base":
            where = f"y = {self.at:.4g} (x {self.span[0]:.4g} to {self.span[1]:.4g})"
            fix = "deeper"
        else:
            where = f"x = {self.at:.4g} (y {self.span[0]:.4g} to {self.span[1]:.4g})"
            fix = {
                "back": "further behind the crest",
                "front": "further beyond the toe",
            }.get(self.side, f"beyond its {self.side} side")
        ids = ", ".join(str(i) for i in self.blocks[:8]) + (", ..." if len(self.blocks) > 8 else "")
        # (conditional: a fixed block drawn along a side may be a real support,
        # the footing of an arch, not a cut; found by literature round 5)
        return (
            f"the mechanism reaches the fixed {self.side} boundary at {where}, blocks {ids}: "
            f"if the model was cut there, extend it {fix} and analyse again (the mechanism "
            "is then bounded by where the model was cut, not by the rock)"
        )


def boundary_contacts(a) -> list[BoundaryContact]:
    """Where the moving blocks of an analysis touch a fixed block backing a side of the model.

    A contact counts when it runs along a side of the model's bounding box
    (back, front or base: within :data:`PARALLEL_DEG` of it and within
    :data:`BOUNDARY_SHARE` of the model's span from it) and its fixed block
    is a strip between the contact and that side (it reaches the side and
    nowhere beyond the contact): a fixed strip where the section was cut.  A
    fixed ground block that extends past the contact (rock the model
    contains) does not count, nor does the ground surface (the top).

    Returns
    -------
    list of BoundaryContact
        One per side touched (empty for a stable analysis).
    """
    system = a.system
    blocks, faces = system.blocks, system.interfaces
    moving = np.asarray(a.unstable, dtype=bool) & ~blocks.fixed
    if a.stable or not moving.any() or not faces.n_interfaces:
        return []
    A, B = faces.block_a, faces.block_b
    fixed = blocks.fixed
    cand = (moving[A] & fixed[B]) | (moving[B] & fixed[A])
    if not cand.any():
        return []
    xy = blocks.vertices
    lo, hi = xy.min(0), xy.max(0)
    span = hi - lo
    tol = 10 * blocks.tolerance
    owner = np.repeat(np.arange(blocks.n_blocks), np.diff(blocks.offsets))
    t = faces.tangent
    sin_par = np.sin(np.radians(PARALLEL_DEG))
    ground = np.where(fixed[A], A, B)
    mover = np.where(fixed[A], B, A)
    sides = _side_names(xy, lo, hi, tol)
    out = []
    for side, axis, value in sides:
        # distance of each vertex from the side: each fixed block's near and far extent
        depth = np.abs(xy[:, axis] - value)
        near_end = np.full(blocks.n_blocks, np.inf)
        far_end = np.zeros(blocks.n_blocks)
        np.minimum.at(near_end, owner, depth)
        np.maximum.at(far_end, owner, depth)
        reach = np.maximum(np.abs(faces.start[:, axis] - value), np.abs(faces.end[:, axis] - value))
        parallel = np.abs(t[:, axis]) <= sin_par
        # the fixed block is a strip between the contact and the side of the model
        strip = (near_end[ground] <= tol) & (far_end[ground] <= reach + tol)
        near = reach <= BOUNDARY_SHARE * span[axis]
        hit = np.flatnonzero(cand & parallel & near & strip & fixed[ground])
        if not hit.size:
            continue
        other = 1 - axis
        ends = np.concatenate([faces.start[hit], faces.end[hit]])
        ids = tuple(int(i) for i in np.unique(blocks.ids[mover[hit]]))
        at = float(np.mean(ends[:, axis]))
        out.append(
            BoundaryContact(
                side,
                at,
                (float(ends[:, other].min()), float(ends[:, other].max())),
                hit,
                ids,
            )
        )
    return out


def _side_names(xy, lo, hi, tol) -> list[tuple[str, int, float]]:
    """The artificial sides of the model: ``(name, axis, coordinate)``.

    The vertical side where the ground stands higher is the back (behind the
    crest), the other the front; equal heights give left and right.
    """
    top_left = xy[np.abs(xy[:, 0] - lo[0]) <= tol, 1].max()
    top_right = xy[np.abs(xy[:, 0] - hi[0]) <= tol, 1].max()
    if abs(top_left - top_right) <= tol:
        left, right = "left", "right"
    elif top_left > top_right:
        left, right = "back", "front"
    else:
        left, right = "front", "back"
    return [(left, 0, float(lo[0])), (right, 0, float(hi[0])), ("base", 1, float(lo[1]))]


def boundary_warnings(a) -> list[str]:
    """The messages of :func:`boundary_contacts` (empty when there is nothing to say)."""
    return [b.message for b in boundary_contacts(a)]
