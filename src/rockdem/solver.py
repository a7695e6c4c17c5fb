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
* a trust radius: a step longer than the larger of the elastic displacement
  and the distance already travelled is solved again with ``beta`` raised to
  fit (a block whose springs all slide or open has no tangent stiffness, and
  the unshifted step throws it far; shrinking ``beta``'s x10 ladder one
  failed line search at a time cost ~4 factorisations per such step);
* a backtracking line search on the scaled residual norm.

Convergence is scale-free: moments are divided by the mean block size and
the out-of-balance force is compared with the external force.  A solve that
does not converge returns its evidence; deciding that the slope has failed
is the caller's job (:mod:`rockdem.analysis`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp

from .assembly import Assembly, build_assembly
from .blocks import Blocks
from .bolts import Crossings, place_bolts
from .errors import InputError
from .interfaces import Interfaces, assign_joints, check_held, find_interfaces
from .linalg import Factorizer, factorize, norm
from .loads import block_loads, check_water_table, joint_water, water_loads
from .model import Model
from .relaxation import relax
from .spring_law import Response, SpringState, evaluate
from .springs import Springs, place_springs

log = logging.getLogger(__name__)

BETA_START = 1e-6
#: a Newton step may move no dof by more than this multiple of the larger of
#: the elastic displacement and the distance already travelled in the solve
#: (scaled); a longer step is re-solved with the shift raised to fit
TRUST_RADIUS = 1.0
BETA_MAX = 0.1
LINE_SEARCH_HALVINGS = 8
#: displacements beyond this multiple of the elastic response are a mechanism
BLOWUP = 1e6
#: fresh starts of the strength homotopy: halve the factor up to this many times
HOMOTOPY_TRIES = 5
#: fictitious-strength release from scratch: s -> s * ratio, then 0 below RELEASE_LAST
RELEASE_RATIO = 0.3
#: a Newton solve has stalled when the residual fell less than x STALL_RATIO
#: over the last STALL_WINDOW accepted steps
STALL_WINDOW = 6
STALL_RATIO = 0.5
#: Newton iterations tried from scratch before releasing fictitious strength
DIRECT_FROM_SCRATCH = 20
#: Newton iterations per step of the strength homotopy (a step that needs more is halved)
HOMOTOPY_ITERATIONS = 25
RELEASE_LAST = 1e-3
#: smallest relative step of the homotopy before equilibrium is declared lost
HOMOTOPY_MIN_STEP = 1e-4
#: a check for a stall at the limit relaxes in segments of at most about
#: this many dof-steps (4,000 steps up to 10,000 dof) ...
STALL_CHECK_WORK = 4e7
#: ... and is not run where a segment would be shorter than this (above
#: 20,000 dof)
STALL_CHECK_MIN = 2_000
#: a stall at the limit is first checked with the equilibrium LP on models of
#: up to this many spring points (a two-block wedge: 8 ms, where relaxation
#: took 28,000 steps, 0.5 s, to stay undecided; 2,769 points: 1.3 s)
LP_FIRST_SPRINGS = 500
#: the reason of an equilibrium found by dynamic relaxation that Newton could
#: not polish (out-of-balance force within rockdem.relaxation.TOLERANCE)
RELAXED = "converged by dynamic relaxation"


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
    #: one factorisation handle for all tangents (symbolic analysis reused)
    factorizer: Factorizer = field(default_factory=Factorizer)
    #: bolt and cable crossings of the joints (rockdem.bolts), None without bolts
    bolts: Crossings | None = None

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
    # every free block must reach a fixed one (a factorisation of the singular
    # stiffness need not fail: SuperLU factorised 59 blocks and no ground)
    check_held(blocks, faces)
    s = model.settings
    springs = place_springs(faces, model.joints, s.quadrature, s.points_per_interface)
    asm = build_assembly(blocks, faces, springs)
    n = springs.n_springs
    K0 = asm.stiffness(springs.kn, np.zeros(n), springs.ks)
    bolts = place_bolts(model.bolts, blocks, faces, asm)
    if bolts is not None:
        K0.data += bolts.stiffness_data(np.column_stack([bolts.k_axial, bolts.k_shear]))
    if f_block is None:
        f_block = block_loads(blocks, model.loads)
    check_water_table(blocks, faces, model.loads)
    f_block = f_block + water_loads(blocks, faces, joint_water(blocks, model.loads))
    free = ~blocks.fixed
    f_ext = np.zeros(asm.n_dof)
    f_ext[asm.dof[free].ravel()] = f_block[free].ravel()
    if asm.n_dof and not np.any(f_ext) and bolts is None:
        raise InputError(
            "the free blocks",
            "carry no load (no unit weight, or gravity off, and no other load): there is "
            "nothing to analyse",
            "give the blocks a unit weight, or apply a load",
        )
    lu0 = None
    elastic = 1.0
    if asm.n_dof:
        try:
            lu0 = factorize(K0)
        except RuntimeError as exc:
            check_held(blocks, faces)  # a group of blocks nothing holds: name it
            raise InputError(
                "model",
                "the elastic stiffness is singular: some block is not held against "
                f"rotation ({s.points_per_interface}-point {s.quadrature} rule)",
                "use 2 or more spring points per interface",
            ) from exc
        u = lu0.solve(f_ext)
        elastic = float(np.max(np.abs(u / asm.dof_scale))) or 1.0
    return System(model, blocks, faces, springs, asm, K0, f_block, f_ext, elastic, lu0, bolts=bolts)


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
    #: the second method's statement on the failure (rockdem.relaxation)
    relaxation: str | None = None


def residual(system: System, q, state, load_factor, factor):
    """Response and out-of-balance force at displacements q."""
    asm = system.assembly
    dn, ds = asm.relative_displacement(q)
    resp = evaluate(system.springs, state, dn, ds, factor, system.model.settings.reduce_tensile)
    r = load_factor * system.f_ext - asm.internal_force(resp.force)
    if system.bolts is not None:
        r -= system.bolts.internal_force(q)
    return resp, r


def tangent(system: System, resp: Response, q, shift: float = 0.0) -> sp.csc_array:
    """Consistent tangent of the springs (and bolts) at ``q``, plus ``shift x K0``."""
    J = system.assembly.stiffness(resp.d_nn, resp.d_sn, resp.d_ss, shift, system.K0)
    if system.bolts is not None:
        _, d_bolt, _ = system.bolts.forces(q)
        J.data += system.bolts.stiffness_data(d_bolt)
    return J


def _lu(system, J):
    try:
        return system.factorizer.factorize(J)
    except RuntimeError:  # exactly singular
        return None


class _Tangents:
    """The factorised tangent of one Newton solve, refactorised only when it changed.

    The spring law is piecewise linear: the tangent depends only on which
    springs are elastic, sliding (and which way) or open, and on the shift.
    Near a limit Newton often creeps towards the next switch of one spring in
    several damped steps under the same tangent (measured: 30-40% of the
    iterations of a creeping solve); those steps reuse the factor.
    """

    def __init__(self, system: System) -> None:
        self.system = system
        self.key: tuple | None = None
        self.lu = None
        self.reused = 0

    def factor(self, resp: Response, q, beta: float):
        system = self.system
        parts = [resp.d_nn, resp.d_sn, resp.d_ss]
        if system.bolts is not None:
            parts.append(system.bolts.forces(q)[1].ravel())
        key = (beta, np.concatenate(parts))
        if (
            self.key is not None
            and self.lu is not None
            and key[0] == self.key[0]
            and np.array_equal(key[1], self.key[1])
            and getattr(self.lu, "generation", 0) in (0, system.factorizer.generation)
        ):  # (a PARDISO factor is valid until its handle factorises another matrix)
            self.reused += 1
            return self.lu
        self.key, self.lu = key, _lu(system, tangent(system, resp, q, beta))
        return self.lu


def _newton(system, state, load_factor, factor, q, max_it):
    """Semismooth Newton with an adaptive Levenberg-Marquardt shift and a
    backtracking line search on the scaled out-of-balance force.

    The step solves ``(J + beta K0) dq = r`` with ``J`` the consistent tangent.
    Where sliding and open springs leave a block nearly free ``J`` is nearly
    singular; the shift ``beta K0`` (``K0`` the elastic stiffness) bounds the
    step.  ``beta`` rises x10 when the line search fails and falls /10 after
    a full step; the solve gives up when ``beta`` exceeds ``BETA_MAX``.
    A step that would move a dof farther than ``TRUST_RADIUS`` x the larger
    of the elastic displacement and the distance travelled since the start
    is re-solved with ``beta`` scaled up by the excess (the free mode's step
    is ~ 1 / beta).
    """
    asm = system.assembly
    scale = asm.dof_scale
    tol = system.model.settings.tolerance
    f_norm = norm(load_factor * system.f_ext * scale)
    resp, r = residual(system, q, state, load_factor, factor)
    merit = norm(r * scale) / f_norm
    history = [merit]
    beta = BETA_START
    bound = BLOWUP * system.elastic_scale * max(load_factor, 1e-12)
    direction = np.zeros_like(q)
    q_start, reach = q, system.elastic_scale * load_factor
    tangents = _Tangents(system)
    for it in range(1, max_it + 1):
        if merit <= tol:
            return Solve(True, q, resp, it - 1, history, "converged", direction)
        lu = tangents.factor(resp, q, beta)
        if lu is None:
            beta *= 10.0
            if beta > BETA_MAX:
                return Solve(False, q, resp, it, history, "singular tangent", direction)
            continue
        step = lu.solve(r)
        size = np.max(np.abs(step / scale))
        radius = TRUST_RADIUS * max(reach, np.max(np.abs((q - q_start) / scale)))
        if size > radius:  # a near-free mode of the tangent: raise the shift to fit
            beta = min(beta * size / radius, BETA_MAX)
            lu = tangents.factor(resp, q, beta)
            if lu is None:
                continue
            step = lu.solve(r)
        direction = step
        alpha, accepted = 1.0, False
        for _ in range(LINE_SEARCH_HALVINGS):
            q_try = q + alpha * step
            resp_try, r_try = residual(system, q_try, state, load_factor, factor)
            merit_try = norm(r_try * scale) / f_norm
            if merit_try <= (1.0 - 1e-4 * alpha) * merit:
                accepted = True
                break
            alpha *= 0.5
        if accepted:
            q, resp, r, merit = q_try, resp_try, r_try, merit_try
            history.append(merit)
            if alpha == 1.0:
                beta = max(beta / 10.0, BETA_START)
            if len(history) > STALL_WINDOW and merit > STALL_RATIO * history[-1 - STALL_WINDOW]:
                return Solve(False, q, resp, it, history, "stalled", direction)
        else:
            beta *= 10.0
            if beta > BETA_MAX:
                return Solve(False, q, resp, it, history, "no descent", direction)
        if np.max(np.abs(q / scale)) > bound:
            return Solve(False, q, resp, it, history, "displacements unbounded", direction)
    if merit <= tol:
        return Solve(True, q, resp, max_it, history, "converged", direction)
    return Solve(False, q, resp, max_it, history, "iteration limit", direction)


def _release(system, state, load_factor, factor, max_it, resume=None) -> Solve:
    """Solve from scratch by releasing fictitious strength.

    At zero displacement every spring sits on the apex of its Coulomb cone
    (no stress, no strength), the worst place to start Newton.  So add a
    fictitious cohesion and tensile strength ``s * ref`` (``ref`` the largest
    elastic spring stress: at ``s = 1`` nothing fails and the elastic solution
    is exact) and release it, ``s -> 0`` geometrically, each solve starting
    from the last.  ``reached`` reports the smallest ``s`` that converged.
    ``resume = (s, q)``: start from a release that got down to ``s`` (at
    another strength factor) instead of from ``s = 1``.
    """
    asm = system.assembly
    springs = system.springs
    u = system.lu0.solve(load_factor * system.f_ext)
    dn, ds = asm.relative_displacement(u)
    ref = float(max(np.max(np.abs(springs.kn * dn)), np.max(np.abs(springs.ks * ds)), 1e-300))
    q = np.zeros(asm.n_dof)
    total, history = 0, []
    s_ok, ratio = None, RELEASE_RATIO
    s = 1.0
    if resume is not None:
        s, q = resume
    while True:
        fict = s * ref
        relaxed = replace(
            springs,
            cohesion=springs.cohesion + fict,
            cohesion_residual=springs.cohesion_residual + fict,
            tensile=springs.tensile + fict,
            tensile_residual=springs.tensile_residual + fict,
        )
        sol = _newton(replace(system, springs=relaxed), state, load_factor, factor, q, max_it)
        total += sol.iterations
        history += sol.residuals
        if sol.converged:
            q, s_ok = sol.q, s
            if s == 0.0:
                resp, _ = residual(system, q, state, load_factor, factor)
                return Solve(True, q, resp, total, history, "converged", sol.direction, 0.0)
            s = s * ratio if s * ratio > RELEASE_LAST else 0.0
        else:
            if s_ok is None:
                return Solve(False, sol.q, sol.response, total, history, "no start", sol.direction)
            ratio = np.sqrt(ratio)
            if ratio > 0.9:
                reason = f"fictitious strength could not be released below {s_ok:.3g}"
                resp, _ = residual(system, q, state, load_factor, factor)
                return Solve(False, q, resp, total, history, reason, sol.direction, s_ok)
            s = s_ok * ratio if s_ok * ratio > RELEASE_LAST else 0.0


def solve_equilibrium(
    system: System,
    state: SpringState,
    *,
    load_factor: float = 1.0,
    strength_factor: float = 1.0,
    q0: np.ndarray | None = None,
    base_factor: float | None = None,
    max_iterations: int | None = None,
    resolution: float | None = None,
) -> Solve:
    """Displacements in equilibrium with the loads, from the committed state.

    1. A direct Newton solve from ``q0`` (a short one from scratch).
    2. From scratch, if that fails: release a fictitious strength
       (:func:`_release`).
    3. A homotopy in the strength factor, from ``q0`` if it is in equilibrium
       at ``base_factor`` (or from a released state at a smaller factor): the
       strength is reduced step by step to the requested factor, each solve
       starting from the previous one (the step grows x1.5 after a success and
       is halved after a failure).  Equilibrium is declared lost only when a
       step smaller than ``resolution`` (default ``HOMOTOPY_MIN_STEP`` x the
       factor) fails; the result then reports the largest factor reached and
       the one that failed.

    No state is committed on the way.
    """
    asm = system.assembly
    max_it = max_iterations or system.model.settings.max_iterations
    q = np.zeros(asm.n_dof) if q0 is None else q0.copy()
    f_norm = norm(load_factor * system.f_ext * asm.dof_scale)
    if asm.n_dof == 0 or f_norm == 0.0:
        resp, _ = residual(system, q, state, load_factor, strength_factor)
        return Solve(True, q, resp, 0, [0.0], "no load", np.zeros_like(q))
    fresh = base_factor is None and not np.any(q)
    sol = _newton(
        system,
        state,
        load_factor,
        strength_factor,
        q,
        min(max_it, DIRECT_FROM_SCRATCH) if fresh else max_it,
    )
    if sol.converged:
        return sol
    total, history = sol.iterations, list(sol.residuals)
    target = strength_factor
    if base_factor is not None and q0 is not None:
        F_ok, q_ok = base_factor, q0
    else:
        start = _release(system, state, load_factor, target, max_it)
        total += start.iterations
        history += start.residuals
        if start.converged:
            return Solve(
                True, start.q, start.response, total, history, "converged", start.direction
            )
        if start.reached is None:
            return Solve(
                False, start.q, start.response, total, history, start.reason, start.direction
            )
        # the strengths could not all be released: try the strength homotopy from
        # the weakest fully released state we can find
        F_ok, q_ok = None, None
        F_try = target
        for _ in range(HOMOTOPY_TRIES):
            F_try *= 0.5
            # from the last released state (stronger joints hold it), else afresh
            weak = _release(system, state, load_factor, F_try, max_it, (start.reached, start.q))
            if weak.reached is None:
                total += weak.iterations
                weak = _release(system, state, load_factor, F_try, max_it)
            total += weak.iterations
            if weak.converged:
                F_ok, q_ok = F_try, weak.q
                break
        if q_ok is None:
            return Solve(
                False, start.q, start.response, total, history, "no start", start.direction
            )
    return _strength_homotopy(
        system,
        state,
        load_factor,
        target,
        F_ok,
        q_ok,
        # the direct attempt at the target failed from q0: the first bracket
        (target, abs(target - F_ok)) if F_ok == base_factor else None,
        resolution if resolution is not None else HOMOTOPY_MIN_STEP * abs(target),
        max_it,
        (total, history, sol),
    )


def _strength_homotopy(system, state, lam, target, F_ok, q_ok, bad, smallest, max_it, so_far):
    """Reduce the strength from ``F_ok`` (in equilibrium at ``q_ok``) to ``target``.

    A bracket search on the strength factor: the step grows x1.5 after a
    success and never reaches the smallest factor that failed (``bad``: the
    factor and the distance from which it was tried), so near the limit the
    search is a bisection.  Each solve starts from the last equilibrium.
    (A secant predictor and a shorter stall window while exploring were
    measured: no fewer factorisations, and a less stable mechanism.)  A
    failure is only taken as the limit once it is confirmed from an
    equilibrium within ``smallest`` of it; a failure from farther away that
    later converges is forgotten.
    """
    total, history, last = so_far
    step = target - F_ok
    if bad is not None:
        step *= 0.5
    if step == 0:  # re-solving at the equilibrium's own factor: one more fresh attempt
        bad = (target, np.inf)
    while True:
        F_try = F_ok + step
        if bad is not None and abs(bad[0] - F_ok) < smallest:
            if bad[1] <= smallest * (1 + 1e-9):  # Newton failed from close by
                # ... the LP (small models) or a second, independent method
                # looks for equilibrium there
                dr = _stall_check(system, state, lam, bad[0], q_ok)
                polish = None
                if dr is not None and dr.status != "mechanism":
                    # Newton from where relaxation got to (an undecided run may have
                    # come within 1e-6 of the loads, not its 1e-7, and stopped moving)
                    polish = _newton(system, state, lam, bad[0], dr.q, HOMOTOPY_ITERATIONS)
                    total += polish.iterations
                if polish is not None and (dr.status == "equilibrium" or polish.converged):
                    # a stall, not the limit: go on from there
                    if not polish.converged:  # relaxation's equilibrium, to its tolerance
                        resp_dr, _ = residual(system, dr.q, state, lam, bad[0])
                        polish = Solve(True, dr.q, resp_dr, 0, [], RELAXED, np.zeros_like(dr.q))
                    if bad[0] == target:
                        return replace(polish, iterations=total, residuals=history)
                    F_ok, q_ok, step = bad[0], polish.q, bad[1]
                    bad = None
                    continue
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
                    bad[0],
                    _stall_text(dr),
                )
            F_try = bad[0]  # tried from afar: try again from here
        elif bad is not None and (F_try - bad[0]) * step >= 0:  # never past a failure
            F_try = 0.5 * (F_ok + bad[0])
        trial = _newton(system, state, lam, F_try, q_ok, min(max_it, HOMOTOPY_ITERATIONS))
        total += trial.iterations
        history += trial.residuals
        if trial.converged:
            if F_try == target:
                return Solve(
                    True, trial.q, trial.response, total, history, "converged", trial.direction
                )
            distance = abs(F_try - F_ok)
            F_ok, q_ok = F_try, trial.q
            if bad is not None and F_try == bad[0]:  # a failure from afar was not the limit
                bad, step = None, 0.5 * bad[1]
            step = np.sign(target - F_ok) * max(1.5 * abs(step), distance)
            if (target - F_ok) * (target - F_ok - step) <= 0:  # do not overshoot
                step = target - F_ok
        else:
            last = trial
            bad = (F_try, abs(F_try - F_ok))
            step = 0.5 * (F_try - F_ok)


def _stall_check(system: System, state: SpringState, lam: float, factor: float, q0):
    """Is the Newton failure at ``factor`` (from an equilibrium ``q0`` just
    below it) a stall?  None when nothing was run or the LP proved that no
    force field carries the loads there; else the dynamic relaxation's run
    (a segment, continued while its unbalanced force keeps falling).

    On small models the LP (:mod:`rockdem.certificate`) comes first.  On
    large ones (a segment of under STALL_CHECK_MIN steps) nothing runs:
    such short runs were undecided (9,638 blocks: 1,383 steps, 3.8 s), and
    the confirmation beyond the bracket, which sends the search on when it
    finds equilibrium there, is run anyway.
    """
    if system.springs.n_springs <= LP_FIRST_SPRINGS:
        from .certificate import admissible_load

        if admissible_load(system, state, lam, factor).proves_failure:
            return None
    segment = int(min(STALL_CHECK_WORK / system.assembly.n_dof, 4_000))
    if segment < STALL_CHECK_MIN:
        return None
    return relax(system, state, lam, factor, q0, max_steps=segment, extend=True)


def _stall_text(run) -> str | None:
    """What the stall check said, for the evidence."""
    if run is None:
        return None
    return str(run) if run.status != "equilibrium" else f"{run}; Newton could not polish it"
