"""One equilibrium solve: semismooth Newton with an adaptive shift.

Given the committed spring state, the load factor and the strength factor,
find block displacements ``q`` where the internal spring forces balance the
external loads.  The residual is non-smooth (springs switch between
elastic, sliding and open), so plain Newton may cycle; we use

* the consistent tangent (non-symmetric where friction couples shear to
  normal stress), assembled on the fixed sparsity pattern, LU-factorised;
* a Levenberg-Marquardt shift ``beta K0`` (``K0`` the elastic stiffness):
  ``beta`` grows x10 when the line search fails and shrinks /10 after a
  full step; beyond ``BETA_MAX`` the solve gives up;
* a backtracking line search on the scaled residual norm.

Convergence is scale-free: moments are divided by the mean block size and
the out-of-balance force is compared with the external force.  A solve that
does not converge returns its evidence; deciding that the slope has failed
is the caller's job (:mod:`rockdem.analysis`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .assembly import Assembly, build_assembly
from .blocks import Blocks
from .errors import InputError
from .interfaces import Interfaces, assign_joints, find_interfaces
from .loads import block_loads
from .model import Model
from .spring_law import Response, SpringState, evaluate
from .springs import Springs, place_springs

log = logging.getLogger(__name__)

BETA_START = 1e-6
BETA_MAX = 0.1
LINE_SEARCH_HALVINGS = 8
#: displacements beyond this multiple of the elastic response are a mechanism
BLOWUP = 1e6
#: fresh starts of the strength homotopy: halve the factor up to this many times
HOMOTOPY_TRIES = 5
#: smallest relative step of the homotopy before equilibrium is declared lost
HOMOTOPY_MIN_STEP = 1e-4


@dataclass(frozen=True, eq=False, repr=False)
class System:
    """A model turned into arrays: built once, reused by every solve."""

    model: Model
    blocks: Blocks
    interfaces: Interfaces
    springs: Springs
    assembly: Assembly
    K0: sp.csc_array
    f_block: np.ndarray  # (n_blocks, 3) external loads at full load factor
    f_ext: np.ndarray  # (n_dof,)
    elastic_scale: float  # scaled size of the elastic displacement under f_ext
    lu0: object = field(default=None)

    def __repr__(self) -> str:
        return (
            f"<System: {self.blocks.n_blocks:,} blocks, {self.interfaces.n_interfaces:,} "
            f"interfaces, {self.springs.n_springs:,} springs, {self.assembly.n_dof:,} dof>"
        )


def build_system(model: Model, f_block: np.ndarray | None = None) -> System:
    """Interfaces, springs, assembly and loads of a model."""
    blocks = model.blocks
    faces = find_interfaces(blocks)
    faces = assign_joints(
        faces,
        blocks,
        default=0,
        ground=model.ground,
        lines=model.joint_lines,
        line_joint=model.line_joint,
    )
    s = model.settings
    springs = place_springs(faces, model.joints, s.quadrature, s.points_per_interface)
    asm = build_assembly(blocks, faces, springs)
    n = springs.n_springs
    K0 = asm.stiffness(springs.kn, np.zeros(n), springs.ks)
    if f_block is None:
        f_block = block_loads(blocks, model.loads)
    free = ~blocks.fixed
    f_ext = np.zeros(asm.n_dof)
    f_ext[asm.dof[free].ravel()] = f_block[free].ravel()
    lu0 = None
    elastic = 1.0
    if asm.n_dof:
        try:
            lu0 = spla.splu(K0, permc_spec="COLAMD")
        except RuntimeError as exc:
            raise InputError(
                "model",
                "the elastic stiffness is singular: some block is not held against "
                f"rotation ({s.points_per_interface}-point {s.quadrature} rule)",
                "use 2 or more spring points per interface",
            ) from exc
        u = lu0.solve(f_ext)
        elastic = float(np.max(np.abs(u / asm.dof_scale))) or 1.0
    return System(model, blocks, faces, springs, asm, K0, f_block, f_ext, elastic, lu0)


@dataclass(frozen=True, eq=False)
class Solve:
    """Outcome of one equilibrium solve, with its evidence."""

    converged: bool
    q: np.ndarray
    response: Response
    iterations: int
    residuals: list[float]
    reason: str
    direction: np.ndarray  # last Newton direction (the mechanism if it failed)
    #: strength homotopy: the largest factor reached in equilibrium, its
    #: displacements, and the factor just beyond it that failed
    reached: float | None = None
    reached_q: np.ndarray | None = None
    failed_at: float | None = None


def residual(system: System, q, state, load_factor, factor):
    """Response and out-of-balance force at displacements q."""
    asm = system.assembly
    dn, ds = asm.relative_displacement(q)
    resp = evaluate(system.springs, state, dn, ds, factor, system.model.settings.reduce_tensile)
    r = load_factor * system.f_ext - asm.internal_force(resp.force)
    return resp, r


def _lu(J):
    try:
        return spla.splu(J, permc_spec="COLAMD")
    except RuntimeError:  # exactly singular
        return None


def _newton(system, state, load_factor, factor, q, max_it):
    """Semismooth Newton with an adaptive Levenberg-Marquardt shift and a
    backtracking line search on the scaled out-of-balance force.

    The step solves ``(J + beta K0) dq = r`` with ``J`` the consistent tangent.
    Where sliding and open springs leave a block nearly free ``J`` is nearly
    singular; the shift ``beta K0`` (``K0`` the elastic stiffness) bounds the
    step.  ``beta`` rises x10 when the line search fails and falls /10 after
    a full step; the solve gives up when ``beta`` exceeds ``BETA_MAX``.
    """
    asm = system.assembly
    scale = asm.dof_scale
    tol = system.model.settings.tolerance
    f_norm = np.linalg.norm(load_factor * system.f_ext * scale)
    resp, r = residual(system, q, state, load_factor, factor)
    merit = np.linalg.norm(r * scale) / f_norm
    history = [merit]
    beta = BETA_START
    bound = BLOWUP * system.elastic_scale * max(load_factor, 1e-12)
    direction = np.zeros_like(q)
    for it in range(1, max_it + 1):
        if merit <= tol:
            return Solve(True, q, resp, it - 1, history, "converged", direction)
        lu = _lu(asm.stiffness(resp.d_nn, resp.d_sn, resp.d_ss, beta, system.K0))
        if lu is None:
            beta *= 10.0
            if beta > BETA_MAX:
                return Solve(False, q, resp, it, history, "singular tangent", direction)
            continue
        step = lu.solve(r)
        direction = step
        alpha, accepted = 1.0, False
        for _ in range(LINE_SEARCH_HALVINGS):
            q_try = q + alpha * step
            resp_try, r_try = residual(system, q_try, state, load_factor, factor)
            merit_try = np.linalg.norm(r_try * scale) / f_norm
            if merit_try <= (1.0 - 1e-4 * alpha) * merit:
                accepted = True
                break
            alpha *= 0.5
        if accepted:
            q, resp, r, merit = q_try, resp_try, r_try, merit_try
            history.append(merit)
            if alpha == 1.0:
                beta = max(beta / 10.0, BETA_START)
        else:
            beta *= 10.0
            if beta > BETA_MAX:
                return Solve(False, q, resp, it, history, "no descent", direction)
        if np.max(np.abs(q / scale)) > bound:
            return Solve(False, q, resp, it, history, "displacements unbounded", direction)
    if merit <= tol:
        return Solve(True, q, resp, max_it, history, "converged", direction)
    return Solve(False, q, resp, max_it, history, "iteration limit", direction)


def solve_equilibrium(
    system: System,
    state: SpringState,
    *,
    load_factor: float = 1.0,
    strength_factor: float = 1.0,
    q0: np.ndarray | None = None,
    base_factor: float | None = None,
    max_iterations: int | None = None,
) -> Solve:
    """Displacements in equilibrium with the loads, from the committed state.

    First a direct Newton solve from ``q0``.  If that fails, a homotopy in
    the strength factor: from ``q0`` if it is in equilibrium at
    ``base_factor``, otherwise from a fresh solve at a smaller factor
    (stronger joints: fewer springs slide, Newton converges), the strength
    is reduced step by step to the requested factor, each solve starting from
    the previous one (the step grows x1.5 after a success and is halved after
    a failure).  No state is committed on the way.  Equilibrium is declared
    lost only when a step smaller than ``HOMOTOPY_MIN_STEP`` (relative) fails.
    """
    asm = system.assembly
    max_it = max_iterations or system.model.settings.max_iterations
    q = np.zeros(asm.n_dof) if q0 is None else q0.copy()
    f_norm = np.linalg.norm(load_factor * system.f_ext * asm.dof_scale)
    if asm.n_dof == 0 or f_norm == 0.0:
        resp, _ = residual(system, q, state, load_factor, strength_factor)
        return Solve(True, q, resp, 0, [0.0], "no load", np.zeros_like(q))
    sol = _newton(system, state, load_factor, strength_factor, q, max_it)
    if sol.converged:
        return sol
    total, history = sol.iterations, list(sol.residuals)
    target = strength_factor
    if base_factor is not None and q0 is not None:
        F_ok, q_ok = base_factor, q0
    else:
        F_ok, q_ok = target, None
        for _ in range(HOMOTOPY_TRIES):
            F_ok *= 0.5
            start = _newton(system, state, load_factor, F_ok, np.zeros(asm.n_dof), max_it)
            total += start.iterations
            if start.converged:
                q_ok = start.q
                break
        if q_ok is None:
            return Solve(False, sol.q, sol.response, total, history, "no start", sol.direction)
    step = target - F_ok
    last = sol
    while True:
        F_try = F_ok + step
        trial = _newton(system, state, load_factor, F_try, q_ok, max_it)
        total += trial.iterations
        history += trial.residuals
        if trial.converged:
            if F_try == target:
                return Solve(
                    True, trial.q, trial.response, total, history, "converged", trial.direction
                )
            F_ok, q_ok = F_try, trial.q
            step = 1.5 * step
            if (target - F_ok) * (target - F_ok - step) <= 0:  # do not overshoot
                step = target - F_ok
        else:
            last = trial
            step = 0.5 * step
            if abs(step) < HOMOTOPY_MIN_STEP * abs(target):
                reason = f"no equilibrium beyond strength factor {F_ok:.6g} ({last.reason})"
                return Solve(
                    False,
                    last.q,
                    last.response,
                    total,
                    history,
                    reason,
                    last.direction,
                    F_ok,
                    q_ok,
                    F_try,
                )
