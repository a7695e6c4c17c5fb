"""Which blocks move at a failure, and how: the failure mechanism.

Two readings of the same failure: the lightly shifted Newton step from the
failed solve (always available) and the late motion of dynamic relaxation
from the last equilibrium (used wherever it finds a mechanism: one state, one
factor, so independent of the trial schedule).  Also the blocks that the
last equilibrium still holds to the ground, and the slip surface.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components

from .results import Analysis
from .solver import Solve, System, residual, tangent

#: a block moves in the mechanism if its motion exceeds this share of the largest
MECHANISM_SHARE = 0.01
#: dynamic relaxation: blocks moving less than this share of the fastest are
#: never in the mechanism (the cut is at the widest gap above it)
RELAXATION_SHARE = 0.01
#: gaps in the ranked motion of the blocks within this factor of the widest
#: are as good a cut as the widest (the lowest of them is taken)
AMBIGUOUS_GAP = 1.5
#: a relaxation mechanism smaller than this share of Newton's, and inside
#: it, is only its first movers on a large model (see :func:`first_movers`)
FIRST_MOVERS = 0.1
#: a spring point holds when its strength exceeds its shear stress by this factor
HOLD_MARGIN = 1.01


def newton_mechanism(system: System, sol: Solve, state, load_factor, factor):
    """Direction of the failure mechanism: the lightly shifted Newton step.

    Where the tangent is (nearly) singular the step is dominated by the
    free motion; elsewhere it is elastic and orders of magnitude smaller.
    """
    asm = system.assembly
    n_blocks = system.blocks.n_blocks
    out = np.zeros((n_blocks, 3))
    if asm.n_dof == 0:
        return out, np.zeros(n_blocks, dtype=bool)
    resp, r = residual(system, sol.q, state, load_factor, factor)
    J = tangent(system, resp, sol.q, 1e-6, state.bolt_reference)
    try:
        d = system.factorizer.factorize(J).solve(r)  # (the pattern analysed once)
    except RuntimeError:
        d = sol.direction
    if np.dot(d, system.f_ext) < 0:  # the loads do positive work on the mechanism
        d = -d
    out, motion = block_motion(system, d)
    top = motion.max()
    if top <= 0 or not np.isfinite(top):
        return out, np.zeros(n_blocks, dtype=bool)
    return out / top, motion > MECHANISM_SHARE * top


def block_motion(system: System, d: np.ndarray):
    """Per block: the displacements ``(n_blocks, 3)`` of the dof vector ``d``
    and the size of its motion (translation plus rotation x block size)."""
    asm = system.assembly
    free = ~system.blocks.fixed
    per_block = np.zeros((system.blocks.n_blocks, 3))
    per_block[free] = d[asm.dof[free]]
    size = np.sqrt(np.abs(system.blocks.area))
    return per_block, np.hypot(per_block[:, 0], per_block[:, 1]) + np.abs(per_block[:, 2]) * size


def slip_surface(system: System, unstable: np.ndarray, if_res) -> np.ndarray:
    """Interfaces of the slip surface: failed or separating ones at moving blocks."""
    faces = system.interfaces
    moving = unstable[faces.block_a] | unstable[faces.block_b]
    separating = unstable[faces.block_a] != unstable[faces.block_b]
    return np.flatnonzero(moving & ((if_res.state > 0) | separating))


def relaxation_mechanism(system: System, failed: Analysis, run) -> Analysis:
    """The mechanism as dynamic relaxation shows it, where it found one.

    Beyond the limit the blocks of the mechanism keep moving while the rest
    settle.  From the last equilibrium at one factor, so it does not depend
    on the trial schedule or on where a Newton solve stopped.  Each block's
    share is the most it moved, in any window of the run's last half, as a
    share of the block that moved most in that window; the moving blocks are
    those above the widest gap (in log scale) among the shares above
    ``RELAXATION_SHARE``, or above the lowest of the gaps nearly as wide.
    The mechanism drawn is the motion over that half.

    Damped explicit dynamics is chaotic in its detail: a 1e-15 change of the
    start changed the last-quarter motion of Goodman & Bray's toe blocks
    from 3% to 53% of the largest (they stick and slip), and a block dragged
    along at 3-5% of the speed of the others fell on either side of a fixed
    5% threshold as the lengths were scaled.  Windows catch the slips; the
    widest gap (measured: 0.8-12 decades between the moving and the
    settling blocks on six slopes, x1.5 or more wider than the next one)
    stays put under round-off where a fixed threshold does not.
    """
    if run is None or run.status != "mechanism" or not run.windows:
        return failed
    share = np.zeros(system.blocks.n_blocks)
    for d in run.windows:
        _, m = block_motion(system, d)
        if 0 < m.max() < np.inf:
            share = np.maximum(share, m / m.max())
    half = np.sum(run.windows, axis=0)
    mech, motion = block_motion(system, half if np.dot(half, system.f_ext) >= 0 else -half)
    top = motion.max()
    if not 0 < top < np.inf:
        return failed
    free = ~system.blocks.fixed
    floor = 1e-12
    ranked = np.concatenate([[floor], np.sort(np.maximum(share[free], floor))])
    gaps = np.diff(np.log10(ranked))
    gaps[ranked[1:] < RELAXATION_SHARE] = -np.inf
    # where another gap is nearly as wide, the lowest of them: a block dragged
    # along at a few percent of the others' motion is in the mechanism (a
    # 462-block bedded slope: one block at 7% fell on either side of the
    # widest gap, 0.78 / 0.45 and 0.57 / 0.68 decades, as the search's
    # schedule changed the state the run started from)
    near = np.flatnonzero(gaps >= np.max(gaps) / AMBIGUOUS_GAP)
    cut = ranked[1 + int(near[0])]
    unstable = free & (share >= cut)
    if first_movers(system, unstable, failed.unstable):
        return failed
    mech = np.where(unstable[:, None], mech / top, 0.0)
    slip = slip_surface(system, unstable, failed.interfaces)
    return replace(failed, mechanism=mech, unstable=unstable, slip_surface=slip)


def first_movers(system: System, moving: np.ndarray, newton: np.ndarray) -> bool:
    """Did dynamic relaxation move only the first few blocks of Newton's
    mechanism ``newton``: fewer than FIRST_MOVERS of them and none outside,
    on a model too large for its runs (where no stall check runs, above
    20,000 unknowns)?  Then the mechanism shown is Newton's.

    A run that shows a proven mechanism is 2,000 explicit steps whatever
    the size: on brick slopes of 28,556 and 94,533 blocks only 6 and 5
    blocks at the face had moved clearly (the widest gap of the shares
    falls after them), while the whole mass above a bedding plane slides
    (Newton's mechanism: 13,703 of 28,556 blocks; at 9,638 blocks the run
    showed 5,222 and Newton 4,697)."""
    from .continuation import stall_checked

    if stall_checked(system.assembly.n_dof) or not newton.any():
        return False
    return not (moving & ~newton).any() and moving.sum() < FIRST_MOVERS * newton.sum()


def held_blocks(system: System, resp) -> np.ndarray:
    """Blocks joined to the fixed ground through holding interfaces.

    An interface holds when at least two of its spring points are closed and
    sticking with a margin (two points restrain all three relative motions;
    one point is a hinge).  Blocks that no chain of holding interfaces ties
    to the ground are free to move: the candidates of the mechanism.
    """
    faces, springs = system.interfaces, system.springs
    m = springs.points_per_interface
    margin = resp.capacity > HOLD_MARGIN * np.abs(resp.tau)
    sticking = (~resp.open & ~resp.sliding & margin).reshape(-1, m)
    holds = sticking.sum(axis=1) >= min(2, m)
    n = system.blocks.n_blocks
    ground = n  # all fixed blocks are one node
    a = np.where(system.blocks.fixed[faces.block_a], ground, faces.block_a)[holds]
    b = np.where(system.blocks.fixed[faces.block_b], ground, faces.block_b)[holds]
    graph = coo_array((np.ones(len(a)), (a, b)), shape=(n + 1, n + 1))
    _, label = connected_components(graph, directed=False)
    return (label[:n] == label[ground]) | system.blocks.fixed


def slip_polylines(analysis: Analysis) -> list[dict]:
    """The slip surface as ordered polylines, each segment with its stresses.

    The slip interfaces are chained end to end (endpoints within ten times the
    geometric tolerance are one node), walking from a loose end where there
    is one; a branch starts a new polyline.  Per segment: the interface, the
    mean normal and shear stress and the mobilised share of the strength
    (|tau| / strength at the factor of the stresses).
    """
    faces, idx = analysis.system.interfaces, np.asarray(analysis.slip_surface)
    if not len(idx):
        return []
    tol = 10 * analysis.system.blocks.tolerance
    ends = np.vstack([faces.start[idx], faces.end[idx]])
    _, node = np.unique(np.round(ends / tol).astype(np.int64), axis=0, return_inverse=True)
    node = node.ravel()
    k = len(idx)
    seg_nodes = np.column_stack([node[:k], node[k:]])
    xy = np.zeros((node.max() + 1, 2))
    xy[node] = ends
    touching: dict[int, list[int]] = {}
    for s, (p, q) in enumerate(seg_nodes):
        touching.setdefault(int(p), []).append(s)
        touching.setdefault(int(q), []).append(s)
    springs, m = analysis.springs, analysis.system.springs.points_per_interface
    strength = springs.strength if springs.strength is not None else springs.capacity
    point_strength = np.asarray(strength).reshape(-1, m).mean(axis=1)
    sigma, tau = analysis.interfaces.normal_stress, analysis.interfaces.shear_stress
    used = np.zeros(k, dtype=bool)
    lines = []
    while not used.all():
        loose = [n for n, segs in touching.items() if sum(not used[s] for s in segs) == 1]
        here = loose[0] if loose else int(seg_nodes[np.flatnonzero(~used)[0], 0])
        points, segs = [here], []
        while True:
            nxt = [s for s in touching[here] if not used[s]]
            if not nxt:
                break
            s = nxt[0]
            used[s] = True
            here = int(seg_nodes[s, 1] if seg_nodes[s, 0] == here else seg_nodes[s, 0])
            points.append(here)
            segs.append(int(idx[s]))
        segs_arr = np.asarray(segs)
        with np.errstate(divide="ignore", invalid="ignore"):
            mobilised = np.abs(tau[segs_arr]) / point_strength[segs_arr]
        lines.append(
            {
                "points": xy[points].tolist(),
                "interfaces": segs,
                "normal_stress": sigma[segs_arr].tolist(),
                "shear_stress": tau[segs_arr].tolist(),
                "mobilised": [float(v) if np.isfinite(v) else None for v in mobilised],
            }
        )
    return lines
