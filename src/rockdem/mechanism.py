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

from .linalg import factorize
from .results import Analysis
from .solver import Solve, System, residual

#: a block moves in the mechanism if its motion exceeds this share of the largest
MECHANISM_SHARE = 0.01
#: ... in the late motion of dynamic relaxation (the settling blocks still creep)
RELAXATION_SHARE = 0.05
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
    J = asm.stiffness(resp.d_nn, resp.d_sn, resp.d_ss, 1e-6, system.K0)
    try:
        d = factorize(J).solve(r)
    except RuntimeError:
        d = sol.direction
    if np.dot(d, system.f_ext) < 0:  # the loads do positive work on the mechanism
        d = -d
    free = ~system.blocks.fixed
    out[free] = d[asm.dof[free]]
    size = np.sqrt(np.abs(system.blocks.area))
    motion = np.hypot(out[:, 0], out[:, 1]) + np.abs(out[:, 2]) * size
    top = motion.max()
    if top <= 0 or not np.isfinite(top):
        return out, np.zeros(n_blocks, dtype=bool)
    return out / top, motion > MECHANISM_SHARE * top


def slip_surface(system: System, unstable: np.ndarray, if_res) -> np.ndarray:
    """Interfaces of the slip surface: failed or separating ones at moving blocks."""
    faces = system.interfaces
    moving = unstable[faces.block_a] | unstable[faces.block_b]
    separating = unstable[faces.block_a] != unstable[faces.block_b]
    return np.flatnonzero(moving & ((if_res.state > 0) | separating))


def relaxation_mechanism(system: System, failed: Analysis, run) -> Analysis:
    """The mechanism as dynamic relaxation shows it, where it found one.

    Beyond the limit the blocks of the mechanism keep moving while the rest
    settle: the late motion of the run (its last quarter) is the failure
    mechanism as UDEC draws it (velocities), computed from one state
    (the last equilibrium) at one factor, so it does not depend on the
    trial schedule or on where a Newton solve stopped.
    """
    if run is None or run.status != "mechanism" or run.late is None:
        return failed
    asm = system.assembly
    late = run.late if np.dot(run.late, system.f_ext) >= 0 else -run.late
    mech = np.zeros((system.blocks.n_blocks, 3))
    free = ~system.blocks.fixed
    mech[free] = late[asm.dof[free]]
    size = np.sqrt(np.abs(system.blocks.area))
    motion = np.hypot(mech[:, 0], mech[:, 1]) + np.abs(mech[:, 2]) * size
    top = motion.max()
    if not 0 < top < np.inf:
        return failed
    unstable = motion > RELAXATION_SHARE * top
    mech = np.where(unstable[:, None], mech / top, 0.0)
    slip = slip_surface(system, unstable, failed.interfaces)
    return replace(failed, mechanism=mech, unstable=unstable, slip_surface=slip)


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
