"""From a state to equilibrium at a target: the strategies around one Newton solve.

:func:`solve_equilibrium` tries Newton (:mod:`rockdem.solver`) directly;
from scratch it releases a fictitious strength first (every spring starts
on the apex of its Coulomb cone, the worst place for Newton); where the
target is beyond reach it climbs by a homotopy in the strength factor, a
bracket search whose failures count only when confirmed from close by.
A Newton failure at the top of that bracket is checked before it is taken
for the limit: by the equilibrium LP on small models
(:mod:`rockdem.certificate`), else by dynamic relaxation
(:mod:`rockdem.relaxation`), whose equilibrium sends the climb on.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from .confirmation import look_keeping_slip
from .limit import LimitProof, LimitStep
from .linalg import norm
from .relaxation import relax
from .solver import Solve, System, newton, residual
from .spring_law import SpringState

#: fresh starts of the strength homotopy: halve the factor up to this many times
HOMOTOPY_TRIES = 5
#: fictitious-strength release from scratch: s -> s * ratio, then 0 below RELEASE_LAST
RELEASE_RATIO = 0.3
#: ... each solve with fictitious strength left stops this close to equilibrium
#: (share of the loads): it is only the next one's start.  Gravity analyses,
#: factorisations (model tolerance 1e-8 -> 5e-3): brick slopes of 1,021 /
#: 2,952 / 9,638 blocks 37 / 48 / 60 -> 31 / 43 / 52, generated slopes of
#: 1,000-3,000 blocks 81 / 95 / 90 -> 74 / 64 / 76, the toppling and
#: perpendicular-joints examples 259 / 329 -> 229 / 295; the same
#: equilibrium to 7 digits.  (1e-4: 35 / 46 / -, 1e-2 or looser: some more, some
#: fewer: 1e-1 took 171 on one generated slope)
RELEASE_TOLERANCE = 5e-3
#: Newton iterations tried from scratch before releasing fictitious strength
DIRECT_FROM_SCRATCH = 20
#: Newton iterations per step of the strength homotopy (a step that needs more is halved)
#: (40 measured: 10-17% fewer factorisations on the brick slopes, but a
#: 2,322-block family slope then stalled 3.7% below its limit, not 0.6%)
HOMOTOPY_ITERATIONS = 25
RELEASE_LAST = 1e-3
#: ... down to this when the jump to zero fails (x RELEASE_RATIO^2 per failure)
RELEASE_FLOOR = 1e-8
#: smallest relative step of the homotopy before equilibrium is declared lost
#: (1.25e-3, the factor-of-safety search's own, was measured: a failing
#: 2,952-block brick slope's search 10.8 -> 8.7 s, but the toppling columns
#: ten times larger, 75 degree face, then stopped at an undecided 0.143
#: instead of Goodman & Bray's 0.374)
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
#: ... and on models of any size at this many resolutions of the search
#: beyond the last equilibrium (the factor of safety's bracket width)
PROOF_WIDTH = 4
#: the reason of an equilibrium found by dynamic relaxation that Newton could
#: not polish (out-of-balance force within rockdem.relaxation.TOLERANCE)
RELAXED = "converged by dynamic relaxation"


def _release(system, state, load_factor, factor, max_it, resume=None, proven=None) -> Solve:
    """Solve from scratch by releasing fictitious strength.

    At zero displacement every spring sits on the apex of its Coulomb cone
    (no stress, no strength), the worst place to start Newton.  So add a
    fictitious cohesion and tensile strength ``s * ref`` (``ref`` the largest
    elastic spring stress: at ``s = 1`` nothing fails and the elastic solution
    is exact) and release it, ``s -> 0`` geometrically, each solve starting
    from the last; below ``RELEASE_LAST`` it jumps to zero, and where that
    jump fails it releases further first (a 94,533-block slope: ``ref``, the
    deepest spring's stress, is far above the strength of the shallow
    springs; the jump from 1.3e-3 failed, the release gave up and the
    gravity state was searched again from half the strength factor, 988 s;
    releasing on to 1.2e-4 first: 256 s, 124 factorisations).  ``reached``
    reports the smallest ``s`` that converged.
    ``resume = (s, q)``: start from a release that got down to ``s`` (at
    another strength factor) instead of from ``s = 1``.  ``proven()``: asked
    at the first failure; True (no equilibrium exists) ends the release.
    """
    asm = system.assembly
    springs = system.springs
    u = load_factor * system.u_elastic  # (linear: the elastic solution at this load)
    dn, ds = asm.relative_displacement(u)
    ref = float(max(np.max(np.abs(springs.kn * dn)), np.max(np.abs(springs.ks * ds)), 1e-300))
    q = np.zeros(asm.n_dof)
    total, history = 0, []
    s_ok, ratio = None, RELEASE_RATIO
    last = RELEASE_LAST  # the smallest s before the jump to zero
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
        tol = RELEASE_TOLERANCE if s > 0.0 else None
        sol = newton(replace(system, springs=relaxed), state, load_factor, factor, q, max_it, tol)
        total += sol.iterations
        history += sol.residuals
        if sol.converged:
            q, s_ok = sol.q, s
            if s == 0.0:
                resp, _ = residual(system, q, state, load_factor, factor)
                return Solve(True, q, resp, total, history, "converged", sol.direction, 0.0)
            s = s * ratio if s * ratio > last else 0.0
        else:
            if s_ok is None:
                return Solve(False, sol.q, sol.response, total, history, "no start", sol.direction)
            if proven is not None and proven():
                reason = f"fictitious strength could not be released below {s_ok:.3g}"
                resp, _ = residual(system, q, state, load_factor, factor)
                return Solve(False, q, resp, total, history, reason, sol.direction, s_ok)
            if s == 0.0 and last > RELEASE_FLOOR:
                # the jump to zero was too long (ref, the largest stress, is far
                # above the strength of shallow springs): release further first
                last *= RELEASE_RATIO**2
            else:
                ratio = np.sqrt(ratio)
            if ratio > 0.9:
                reason = f"fictitious strength could not be released below {s_ok:.3g}"
                resp, _ = residual(system, q, state, load_factor, factor)
                return Solve(False, q, resp, total, history, reason, sol.direction, s_ok)
            s = s_ok * ratio if s_ok * ratio > last else 0.0


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
    proven: Callable[[], bool] | None = None,
    limit_proof: LimitProof | None = None,
) -> Solve:
    """Displacements in equilibrium with the loads, from the committed state.

    1. A direct Newton solve from ``q0`` (a short one from scratch).
    2. From scratch, if that fails: release a fictitious strength
       (:func:`_release`).  Where it cannot all be released and ``proven()``
       says that no equilibrium exists (the equilibrium LP), stop there: the
       homotopy below would only find how much weaker the joints must be.
    3. A homotopy in the strength factor, from ``q0`` if it is in equilibrium
       at ``base_factor`` (or from a released state at a smaller factor): the
       strength is reduced step by step to the requested factor, each solve
       starting from the previous one (the step grows x1.5 after a success and
       is halved after a failure).  Equilibrium is declared lost only when a
       step smaller than ``resolution`` (default ``HOMOTOPY_MIN_STEP`` x the
       factor) fails; the result then reports the largest factor reached and
       the one that failed.  With ``limit_proof`` (the factor-of-safety
       search) the homotopy stops as soon as the equilibrium LP proves
       failure within ``limit_proof.width`` of its last equilibrium.

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
    sol = newton(
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
        start = _release(system, state, load_factor, target, max_it, proven=proven)
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
        if proven is not None and proven():
            reason = f"{start.reason}; the equilibrium LP proves that none exists"
            return Solve(False, start.q, start.response, total, history, reason, start.direction)
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
        limit_proof,
    )


def _strength_homotopy(
    system, state, lam, target, F_ok, q_ok, bad, smallest, max_it, so_far, limit_proof=None
):
    """Reduce the strength from ``F_ok`` (in equilibrium at ``q_ok``) to ``target``.

    A bracket search on the strength factor: the step grows x1.5 after a
    success and never reaches the smallest factor that failed (``bad``: the
    factor and the distance from which it was tried), so near the limit the
    search is a bisection.  Each solve starts from the last equilibrium.
    (A secant predictor and a shorter stall window while exploring were
    measured: no fewer factorisations, and a less stable mechanism.  So was
    retrying a failure from afar once within a quarter of its distance,
    instead of halving the way to it: 2-7% fewer factorisations on brick
    slopes, but Goodman & Bray's staircase then stopped short of its limit
    state, block 5 sliding.)  A
    failure is only taken as the limit once it is confirmed from an
    equilibrium within ``smallest`` of it; a failure from farther away that
    later converges is forgotten.  Past a stall (the check found equilibrium
    there) the climb resumes at the pace it had before that failure, not at
    the resolution it was confirmed with (a near-flat benched slope stalled
    every 0.5-1 in F above F = 17 and regrew its step x1.5 from 0.00125
    after each).
    """
    total, history, last = so_far
    pace = 0.0  # the last step that succeeded with no failure ahead
    step = target - F_ok
    if bad is not None:
        step *= 0.5
    if step == 0:  # re-solving at the equilibrium's own factor: one more fresh attempt
        bad = (target, np.inf)
    # the search for a factor of safety goes to the limit by work control
    # once a failure shows the mechanism (rockdem.limit); not where committing
    # the failures sheds strength (brittle joints: the limit of the trial's
    # strengths is not the slope's), and the homotopies of a staged analysis
    # keep their bisection alone
    limit = None
    if limit_proof is not None and target > F_ok and not system.sheds_strength:
        limit = LimitStep(system, state, lam, limit_proof)
        if bad is not None and not last.converged:
            limit.failed(last, q_ok)  # the caller's failed attempt at the target
    while True:
        if limit is not None and limit.ready and limit.beyond_proven(bad):
            found, iterations = limit.solve(F_ok, q_ok)
            total += iterations
            if found is not None:
                F_lim, q_lim, top = found
                reason = (
                    f"no equilibrium beyond strength factor {F_lim:.6g} (the strengths divided "
                    f"by it; found by work control); the equilibrium LP proves that none "
                    f"exists at {top:.6g}"
                )
                resp = residual(system, q_lim, state, lam, F_lim)[0]
                direction = last.direction
                return Solve(
                    False, q_lim, resp, total, history, reason, direction, F_lim, q_lim, top
                )
            # no proof there (toppling, non-associated friction: the LP's limit lies
            # above the DEM's, and the equilibrium work control found, with the
            # mechanism pushed along, is not on the trials' path): the homotopy goes
            # on as it would have
        F_try = F_ok + step
        if bad is not None and abs(bad[0] - F_ok) < smallest:
            if bad[1] <= smallest * (1 + 1e-9):  # Newton failed from close by
                # ... the LP (small models) or a second, independent method
                # looks for equilibrium there
                within = F_ok + PROOF_WIDTH * smallest * np.sign(bad[0] - F_ok)
                dr = _stall_check(system, state, lam, bad[0], q_ok, within)
                polish = None
                if dr is not None and dr.status != "mechanism":
                    # Newton from where relaxation got to (an undecided run may have
                    # come within 1e-6 of the loads, not its 1e-7, and stopped moving)
                    polish = newton(system, state, lam, bad[0], dr.q, HOMOTOPY_ITERATIONS)
                    total += polish.iterations
                    if dr.status != "equilibrium" and not polish.converged:
                        dr, by_slip = look_keeping_slip(system, state, lam, bad[0], q_ok, dr)
                        total += by_slip.iterations if by_slip is not None else 0
                        polish = by_slip if dr.status == "equilibrium" else polish
                if polish is not None and (dr.status == "equilibrium" or polish.converged):
                    # a stall, not the limit: go on from there
                    if not polish.converged:  # relaxation's equilibrium, to its tolerance
                        resp_dr, _ = residual(system, dr.q, state, lam, bad[0])
                        polish = Solve(True, dr.q, resp_dr, 0, [], RELAXED, np.zeros_like(dr.q))
                    if bad[0] == target:
                        return replace(polish, iterations=total, residuals=history)
                    F_ok, q_ok, bad = bad[0], polish.q, None
                    step = np.sign(target - F_ok) * max(smallest, pace)
                    if (target - F_ok) * (target - F_ok - step) <= 0:  # do not overshoot
                        step = target - F_ok
                    continue
                reason = (
                    f"no equilibrium beyond strength factor {F_ok:.6g} "
                    f"(the strengths divided by it; {last.reason})"
                )
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
        trial = newton(system, state, lam, F_try, q_ok, min(max_it, HOMOTOPY_ITERATIONS))
        total += trial.iterations
        history += trial.residuals
        if limit is not None and not trial.converged:
            limit.failed(trial, q_ok)
        if trial.converged:
            if F_try == target:
                return Solve(
                    True, trial.q, trial.response, total, history, trial.reason, trial.direction
                )
            distance = abs(F_try - F_ok)
            F_ok, q_ok = F_try, trial.q
            if bad is None:
                pace = distance
            if bad is not None and F_try == bad[0]:  # a failure from afar was not the limit
                bad, step = None, 0.5 * bad[1]
            step = np.sign(target - F_ok) * max(1.5 * abs(step), distance)
            if (target - F_ok) * (target - F_ok - step) <= 0:  # do not overshoot
                step = target - F_ok
        else:
            last = trial
            bad = (F_try, abs(F_try - F_ok))
            step = 0.5 * (F_try - F_ok)


def _stall_check(system: System, state: SpringState, lam: float, factor: float, q0, within=None):
    """Is the Newton failure at ``factor`` (from an equilibrium ``q0`` just
    below it) a stall?  None when nothing was run or the LP proved that no
    force field carries the loads there or at ``within`` (a factor close
    enough to the equilibrium that a limit below it settles the search);
    else the dynamic relaxation's run (a segment, continued while its
    unbalanced force keeps falling).

    On small models the LP (:mod:`rockdem.certificate`) comes first at
    ``factor``; then, before a relaxation, at ``within`` (a cohesionless
    slope's failure there is proven in the time of about fifteen
    factorisations, where the relaxation took 8,000 explicit steps: 2,952
    blocks, 0.3 s against 5 s; an LP that would take longer gives up).  On
    large models (a segment of under STALL_CHECK_MIN steps) nothing runs:
    such short runs were undecided (9,638 blocks: 1,383 steps, 3.8 s), and
    the confirmation beyond the bracket, which sends the search on when it
    finds equilibrium there, is run anyway.
    """
    from .certificate import admissible_load, certificate_for

    if system.springs.n_springs <= LP_FIRST_SPRINGS:
        if admissible_load(system, state, lam, factor).proves_failure:
            return None
    if not stall_checked(system.assembly.n_dof):
        return None  # (the search's end proves or confirms the failure anyway)
    if within is not None and certificate_for(system, state, lam, within).proves_failure:
        return None
    segment = int(min(STALL_CHECK_WORK / system.assembly.n_dof, 4_000))
    return relax(system, state, lam, factor, q0, max_steps=segment, extend=True)


def stall_checked(n_dof: int) -> bool:
    """Is a Newton failure at the top of a bracket checked for a stall on a
    model of ``n_dof`` unknowns?  (Not above 20,000: see :func:`_stall_check`.)"""
    return STALL_CHECK_WORK / max(n_dof, 1) >= STALL_CHECK_MIN


def _stall_text(run) -> str | None:
    """What the stall check said, for the evidence."""
    if run is None:
        return None
    return str(run) if run.status != "equilibrium" else f"{run}; Newton could not polish it"
