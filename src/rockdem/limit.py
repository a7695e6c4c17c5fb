"""The limit state in one solve: strength reduction under control of the work.

A strength trial that is solved at a prescribed factor ``F`` has no
equilibrium beyond the limit, and Newton's method stalls near it, so a
bracket search on ``F`` spends most of its solves at the limit, failing or
creeping up to it (a 9,638-block brick slope: 354 of 431 factorisations).
A laboratory test meets the same difficulty at a peak load and avoids it by
controlling a displacement instead of the load.  Here the strength
multiplier ``t = 1 / F`` becomes an unknown and the external work
``lambda f . q`` is prescribed:

    r(q, t) = lambda f - B^T W p(B q; t) = 0,      lambda f . q = work.

Beyond the limit the slope slides at a constant ``F`` while the work grows,
so a work a little beyond the limit's lands on that plateau: the solution's
``F`` is the limit, found by one Newton solve, and its ``q`` is an
equilibrium there (a 1,021-, 2,952- and 9,638-block brick slope: 1.9238044
in 31, 28 and 44 factorisations; tan 35 / tan 20 = 1.9238044).  The
bordered Newton system

    [K_T  g] [dq]   [r]          g = d(B^T W p) / dt  (the springs at their
    [f^T  0] [dt] = [work - f.q]     strength: tau and the tensile force
                                     scale with t)

is solved with the factorised tangent, two solves each iteration; it stays
regular where ``K_T`` has the mechanism as a null vector (``f`` does work
on it, ``g`` drives it).  From an equilibrium below the limit the work is
nearly flat in ``F`` until the mechanism forms, so the start is a
prediction of the limit state: the equilibrium displaced along the
mechanism of a failed solve by about its elastic displacement
(:func:`pushed`), at the factor that mechanism predicts
(:func:`predicted_limit`).

The plateau is the limit of the holonomic law of one trial (the strengths
of its failure flags): where committing the failures sheds strength
(brittle cohesion) the caller settles the state and searches on.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .linalg import norm
from .mechanism import MECHANISM_SHARE, block_motion
from .solver import STALL_RATIO, STALL_WINDOW, Solve, System, newton, residual, tangent
from .spring_law import Response, SpringState, strength

#: Newton iterations of one work-controlled solve (a 1,212-block slope
#: reached its plateau, 2.6e-4 of the loads, in 16; then crept over kinks of
#: the spring law to 2.6e-7 in 60) ...
MAX_ITERATIONS = 80
#: ... and on, up to CREEP_ITERATIONS, while the out-of-balance force still
#: falls by CREEP_RATIO over CREEP_WINDOW iterations: the creep grows with
#: the model (a 28,556-block brick slope: on the plateau, F = 1.923804, at
#: 2e-2 of the loads after 26 iterations, 1.6e-5 after 80, 6.9-fold over the
#: last 20, converged in 101; stopped at 80, the search bisected: 712
#: factorisations, 428 s, instead of 192, 146 s).  Not 4-fold: from another
#: start the same slope fell 7.7-, 4.8- and 4.3-fold over the 20 iterations
#: to 85, 90 and 95 (6.2e-6 of the loads, the Levenberg-Marquardt shift
#: still 1e-5 after steps halved by the line search), then, 2-fold allowed,
#: took full steps and converged at 101; stopped at 95 the search bisected:
#: 727 factorisations, FS 1.9230 in a bracket of the search's width
CREEP_ITERATIONS = 240
CREEP_WINDOW = 20
CREEP_RATIO = 0.5
#: the predicted limit state moves the mechanism this many times its elastic
#: displacement (0.3 landed below the plateau on a 1,021-block brick slope,
#: 1.9139 for 1.9238, after 112 iterations; 1.0 on it in 31), and where that
#: lands below the plateau (a column with water in its back crack: 1.077 for
#: 1.221), this many more each time
MECHANISM_REACH = (1.0, 4.0)
#: the shift of the tangent, as in rockdem.solver.newton
BETA_START = 1e-6
BETA_MAX = 0.1
LINE_SEARCH_HALVINGS = 10
#: Newton iterations of the polish at a fixed factor
POLISH_ITERATIONS = 25
#: the equilibrium LP is tried at these shares of the search's width above
#: the limit that work control found (the nearest first: the bracket it
#: settles is that narrow; at an eighth the wedge's 0.9786 read 0.9789)
LIMIT_PROOF_SHARES = (1 / 64, 1 / 8, 1 / 2, 1.0)
#: the equilibrium at the limit work control found is taken this share below
#: its factor (the plateau's factor is exact to about round-off: a block at
#: phi 24.6 on a 25 degree plane 2.5e-9 above tan(phi) / tan(dip), so the
#: stable end is an equilibrium to the tolerance, 1.3e-9 above the limit).
#: Not more: below the plateau the sliding springs must find their elastic
#: displacements again, which the polish cannot (one tolerance, 1e-8: it
#: stalled on that kink at 1e-7, and the next trial from there failed)
LIMIT_MARGIN = 1e-9
#: the solve stops where it stalls this close to equilibrium (share of the
#: loads), as rockdem.solver.newton does at a kink of the spring law; the
#: caller polishes at a fixed factor (from 2.6e-7: Newton within 1e-7 in 10
#: iterations; from 6e-5 it stalled)
STALL_BELOW = 1e-6


@dataclass(frozen=True)
class LimitState:
    """Outcome of a work-controlled solve."""

    converged: bool
    factor: float  # the strength factor of the last iterate (the limit, converged)
    q: np.ndarray
    iterations: int
    residuals: list[float]
    reason: str


def mechanism_slip(system: System, q_from: np.ndarray, q_failed: np.ndarray) -> np.ndarray | None:
    """The way the blocks went in a failed solve from ``q_from`` (the loads do
    positive work on it), or None if they did not move."""
    d = q_failed - q_from
    if not np.any(d):
        return None
    return d if np.dot(d, system.f_ext) >= 0 else -d


def predicted_limit(resp: Response, factor: float, slip: np.ndarray, weight) -> float | None:
    """The strength factor at which a mechanism whose spring points slip by
    ``slip`` would be at its limit, from an equilibrium at ``factor`` with
    the response ``resp``: its springs mobilise ``g = sum w tau ds / sum w
    capacity |ds|`` of their strength there, and capacities scale as ``1 /
    F``, so ``F / g`` if the stresses did not redistribute.  Exact for a
    plane slide from any equilibrium (tan(phi) / tan(dip)); for others it
    improves as the equilibrium nears the limit.  None where the
    mechanism's springs carry no shear in its direction."""
    work = float(np.sum(weight * resp.tau * slip))
    capacity = float(np.sum(weight * resp.capacity * np.abs(slip)))
    if work <= 0.0 or capacity <= 0.0:
        return None
    return factor * capacity / work


def strength_derivative(system: System, resp: Response, t: float) -> np.ndarray:
    """``g = d(B^T W p) / dt`` at fixed displacements: the shear of the
    springs at their strength and the tension of those at their (reduced)
    tensile strength are proportional to ``t = 1 / F``."""
    dp = np.zeros((len(resp.tau), 2))
    dp[:, 1] = np.where(resp.sliding, resp.tau / t, 0.0)
    if system.model.settings.reduce_tensile:
        dp[:, 0] = np.where(resp.open, -resp.sigma / t, 0.0)
    return system.assembly.internal_force(dp)


def work_controlled(
    system: System,
    state: SpringState,
    load_factor: float,
    q0: np.ndarray,
    factor0: float,
    work: float,
    max_it: int | None = None,
) -> LimitState:
    """Equilibrium with the strength factor as an unknown and the external
    work ``load_factor f . q`` equal to ``work``, from ``(q0, factor0)``.

    Newton's method on the bordered system (module docstring) with the
    tangent shifted by ``beta K0`` and a backtracking line search on the
    scaled residual and the relative work error, as :func:`rockdem.solver.newton`
    does for a fixed factor.  ``max_it`` iterations, and on while the
    out-of-balance force still falls (``CREEP_*``).
    """
    asm = system.assembly
    scale = asm.dof_scale
    f = load_factor * system.f_ext
    f_norm = norm(f * scale)
    tol = system.model.settings.tolerance
    reduce = system.model.settings.reduce_tensile
    springs = system.springs
    ref = state.bolt_reference

    def evaluate_at(q, t):
        F = 1.0 / t
        resp, r = residual(system, q, state, load_factor, F, strength(springs, state, F, reduce))
        force = norm(r * scale) / f_norm
        return resp, r, force, abs(work - float(f @ q)) / abs(work)

    q, t = q0.copy(), 1.0 / factor0
    resp, r, force, gap = evaluate_at(q, t)
    merit = float(np.hypot(force, gap))
    history, beta = [merit], BETA_START
    max_it = MAX_ITERATIONS if max_it is None else max_it
    for it in range(1, max(max_it, CREEP_ITERATIONS) + 1):
        if force <= tol and gap <= tol:
            return LimitState(True, 1.0 / t, q, it - 1, history, "converged")
        if it > max_it and not still_converging(history):
            return LimitState(False, 1.0 / t, q, it - 1, history, "iteration limit")
        try:
            lu = system.factorizer.factorize(tangent(system, resp, q, beta, ref))
            a = lu.solve(r)
            b = lu.solve(strength_derivative(system, resp, t))
        except RuntimeError:  # exactly singular
            beta *= 10.0
            if beta > BETA_MAX:
                return LimitState(False, 1.0 / t, q, it, history, "singular tangent")
            continue
        fb = float(f @ b)
        if fb == 0.0 or not np.isfinite(fb):  # no spring at its strength: F does no work
            return LimitState(False, 1.0 / t, q, it, history, "the strength does no work")
        dt = (float(f @ a) - (work - float(f @ q))) / fb
        dq = a - b * dt
        alpha, accepted = 1.0, False
        for _ in range(LINE_SEARCH_HALVINGS):
            t_try = t + alpha * dt
            if t_try > 0.0:
                trial = evaluate_at(q + alpha * dq, t_try)
                merit_try = float(np.hypot(trial[2], trial[3]))
                if merit_try <= (1.0 - 1e-4 * alpha) * merit:
                    accepted = True
                    break
            alpha *= 0.5
        if not accepted:
            beta *= 10.0
            if beta > BETA_MAX:
                return LimitState(False, 1.0 / t, q, it, history, "no descent")
            continue
        q, t = q + alpha * dq, t_try
        resp, r, force, gap = trial
        merit = merit_try
        history.append(merit)
        if alpha == 1.0:
            beta = max(beta / 10.0, BETA_START)
        if (
            merit <= STALL_BELOW
            and len(history) > STALL_WINDOW
            and merit > STALL_RATIO * history[-1 - STALL_WINDOW]
        ):  # (a kink of the spring law: the caller polishes at a fixed factor)
            converged = force <= tol and gap <= tol
            return LimitState(converged, 1.0 / t, q, it, history, "stalled")
    converged = force <= tol and gap <= tol
    return LimitState(converged, 1.0 / t, q, it, history, "iteration limit")


def still_converging(history: list[float]) -> bool:
    """Has the out-of-balance force (``history``, one entry per accepted
    iteration) fallen by CREEP_RATIO over the last CREEP_WINDOW iterations?"""
    return len(history) > CREEP_WINDOW and history[-1] <= CREEP_RATIO * history[-1 - CREEP_WINDOW]


def pushed(system: System, load_factor: float, q: np.ndarray, slip_q: np.ndarray, reach: float):
    """``q`` moved along the mechanism ``slip_q`` by ``reach`` times the
    elastic displacement, and the external work there; None where the
    mechanism does not move or the loads do no work."""
    size = float(np.max(np.abs(slip_q / system.assembly.dof_scale)))
    if not size > 0.0:
        return None
    start = q + (reach * system.elastic_scale * load_factor / size) * slip_q
    work = float(load_factor * (system.f_ext @ start))
    return (start, work) if work > 0.0 else None


@dataclass(frozen=True)
class LimitProof:
    """How the factor-of-safety search settles its bracket: ``proves(F,
    moving)`` is True when the equilibrium LP proves that no equilibrium
    exists at ``F`` (``moving``: the blocks of the mechanism, bool per block,
    whose equations alone may prove it on models too large for the whole
    LP), None where that LP was too large to be solved; ``width`` is the
    bracket the search accepts."""

    proves: Callable[[float, np.ndarray | None], bool | None]
    width: float


class LimitStep:
    """The factor-of-safety search's step to the limit: once a
    failed solve shows the mechanism, one work-controlled solve from the last
    equilibrium; then the equilibrium LP at a little above the factor it
    found, which settles the bracket where the LP is tight (planar sliding;
    not toppling, where the homotopy goes on from there)."""

    def __init__(self, system: System, state: SpringState, lam: float, proof: LimitProof):
        self.system, self.state, self.lam, self.proof = system, state, lam, proof
        self.slip: np.ndarray | None = None  # the mechanism of the last failure
        self.moving: np.ndarray | None = None  # ... and its blocks (bool per block)
        self.done = False

    @property
    def ready(self) -> bool:
        return self.slip is not None and not self.done

    def beyond_proven(self, bad) -> bool:
        """Does the LP prove the failure ``bad`` (factor, distance)?  The work
        control goes only where it does: else the failure may be a stall
        below the limit, or the LP not tight there (a near-flat benched
        slope that stands up to F = 100: five work-controlled solves of
        50-80 iterations for nothing).  Where the LP was too large to solve
        (a stall far below the limit moved nearly every block: 92,562 of
        94,534 at F = 1.5, limit 1.92) a later failure is asked again."""
        if bad is None:
            return False
        proven = self.proof.proves(bad[0], self.moving)
        self.done = self.done or proven is False
        return bool(proven)

    def failed(self, trial: Solve, q_from: np.ndarray) -> None:
        """Take note of a failed solve that started from ``q_from``."""
        slip = mechanism_slip(self.system, q_from, trial.q)
        if slip is not None:
            self.slip = slip
            motion = block_motion(self.system, slip)[1]
            self.moving = motion > MECHANISM_SHARE * motion.max()

    def solve(self, F_ok: float, q_ok: np.ndarray):
        """``(limit, iterations)`` from the equilibrium at ``F_ok``: ``limit``
        is ``(factor, q, top)``, an equilibrium at ``factor`` and the factor
        ``top`` (at most the search's width above) where the LP proves
        failure, or None.

        Where the work lands below the plateau (the LP does not prove
        failure just above), the mechanism is pushed further, while that
        raises the factor.  Where the work-controlled solve stalls on a kink
        close to the plateau (a 1,212-block slope: 2.6e-7 of the loads at
        F = 1.46954, its exact limit), Newton at the fixed factor polishes
        it."""
        self.done = True
        system, state, lam = self.system, self.state, self.lam
        resp = residual(system, q_ok, state, lam, F_ok)[0]
        ds = system.assembly.relative_displacement(self.slip)[1]
        predicted = predicted_limit(resp, F_ok, ds, system.springs.weight)
        if predicted is None or predicted <= F_ok:
            return None, 0
        q, factor, total = q_ok, predicted, 0
        for reach in MECHANISM_REACH:
            start = pushed(system, lam, q, self.slip, reach)
            if start is None:
                break
            found = work_controlled(system, state, lam, start[0], factor, start[1])
            total += found.iterations
            near = found.converged or found.residuals[-1] <= STALL_BELOW
            if found.factor <= max(F_ok, factor if q is not q_ok else F_ok) or not near:
                break  # (no higher than before: a plateau where the LP is not tight)
            # the plateau's factor is the limit to round-off: the equilibrium is
            # taken a hair below it, checked by Newton at that fixed factor
            at = found.factor * (1.0 - LIMIT_MARGIN)
            polish = newton(system, state, lam, at, found.q, POLISH_ITERATIONS)
            total += polish.iterations
            if not polish.converged:
                break
            top = self.prove(at)
            if top is not None:
                return (at, polish.q, top), total
            q, factor = polish.q, found.factor
        return None, total

    def prove(self, F_ok: float) -> float | None:
        """The nearest factor above ``F_ok`` (by a share of the search's width,
        ``LIMIT_PROOF_SHARES``) at which the LP proves failure, or None.  Below
        F = 1 the width is taken relative to F (a block at phi 1 on a 20
        degree plane, FS 0.048: an eighth of the absolute 0.005 is 1.3%)."""
        width = self.proof.width * min(1.0, F_ok)
        for share in LIMIT_PROOF_SHARES:
            top = F_ok + share * width
            if self.proof.proves(top, self.moving):  # (None: not solved, no proof)
                return top
        return None
