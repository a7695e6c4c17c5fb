"""Load stepping: from a model to a verdict at one strength factor.

``analyse`` applies the loads in steps (the paper's staged gravity), solves
each step to equilibrium, and after every converged step commits the spring
state; where springs failed and lost strength, the same load is solved
again until no more strength is lost (the progressive redistribution of
excess force, :mod:`rockdem.redistribution`).  The factor of safety
(strength reduction) builds on it: :mod:`rockdem.strength_reduction`.
"""

from __future__ import annotations

import logging
import warnings
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from .certificate import certificate_for, lp_limit_proof, prove_in_region, with_certificate
from .confirmation import confirm_failed_analysis
from .continuation import RELAXED
from .errors import ModelWarning, check_number
from .mechanism import held_blocks, newton_mechanism, relaxation_mechanism, slip_surface
from .model import MAX_LOAD_STEPS, Model, check_count
from .redistribution import settle
from .results import Analysis, Evidence, Step, tabulate
from .solver import Solve, System, build_system, newton, residual
from .spring_law import SpringState, commit
from .trust import large_displacement

log = logging.getLogger(__name__)

#: a failed load step is retried in up to this many equal sub-steps (halving)
MAX_SUBSTEPS = 8


def _evidence(sol: Solve) -> Evidence:
    return Evidence(
        sol.reason,
        sol.iterations,
        tuple(sol.residuals),
        None,
        sol.reached,
        sol.failed_at,
        relaxation=sol.relaxation,
    )


def _load_step(
    system, state, q, lam_prev, lam, factor, stage, start=None, prove_first=False, width=None
):
    """Settle the load at ``lam`` from equilibrium at ``lam_prev``; where the
    whole increment fails and the equilibrium LP does not prove the load
    beyond every admissible force field, retry it in smaller sub-steps
    (halving, down to 1/MAX_SUBSTEPS of it), committing the state after each.

    A Newton failure on a large increment is not yet a verdict: with brittle
    strength the state jumps at each commit, and smaller increments follow
    the loading path.  Not from the unloaded state of a scale-free model
    (:attr:`rockdem.solver.System.scale_free`), whose sub-steps repeat the
    same search scaled down (a 1,021-block frictional slope, unstable under
    gravity: four identical searches, 1,400 factorisations).  ``start``: an
    ``Analysis.unloaded_limit`` at this load, where the whole step's search
    starts.  Returns ``(solve, state, q,
    lam_reached, certificate, unloaded_limit)`` (the certificate of the load
    ``lam`` when it was computed, else None; the limit when the whole step
    failed from the unloaded state, else None).  ``prove_first``: where
    Newton cannot release the fictitious strength, solve the equilibrium LP
    before the strength homotopy, and stop if it proves the load beyond
    every admissible force field (a 2,952-block slope failing under
    gravity: the LP in 0.3 s, where the homotopy took 430 iterations).
    ``width``: the factor-of-safety search's bracket width; the whole step
    from the unloaded state climbs to its limit by work control (see
    ``analyse(limit_width=...)``).
    """
    full = lam - lam_prev
    inc = full
    iterations, history = 0, []
    cert = limit = None
    if start is not None and not (lam_prev == 0.0 and start[0] == lam):
        start = None

    def proven() -> bool:
        nonlocal cert
        if cert is None:
            cert = certificate_for(system, state, 1.0, factor)
        return bool(cert.proves_failure and cert.mu < lam)

    while True:
        target = min(lam, lam_prev + inc)
        q0 = q * (target / lam_prev) if lam_prev > 0 else q
        base = None
        if start is not None and target == lam:  # at an equilibrium of a weaker factor
            base, q0 = start[1], start[2]
        limit_proof = None
        if width is not None and lam_prev == 0.0 and target == lam:
            limit_proof = lp_limit_proof(system, state, target, width)
        sol, new_state = settle(
            system,
            state,
            q0,
            target,
            factor,
            stage,
            base,
            proven=proven if prove_first else None,
            limit_proof=limit_proof,
        )
        iterations += sol.iterations
        history += sol.residuals
        if sol.converged:
            state, q, lam_prev = new_state, sol.q, target
            if lam_prev >= lam * (1 - 1e-12):
                break
            continue
        if (
            lam_prev == 0.0
            and target == lam
            and new_state is state  # the failed search ran from the unloaded state
            and sol.reached is not None
            and sol.reached_q is not None
        ):
            limit = (lam, sol.reached, sol.reached_q)
        if cert is None:
            cert = certificate_for(system, state, 1.0, factor)
            if cert.proves_failure and cert.mu < lam:
                break  # proven: no sub-step can carry this load
        if lam_prev == 0.0 and system.scale_free:
            break  # from the unloaded state, every sub-step is this solve scaled down
        if inc <= full / MAX_SUBSTEPS * (1 + 1e-9):
            break
        inc *= 0.5
    sol = replace(sol, iterations=iterations, residuals=history)
    return sol, state, q, lam_prev, cert, limit


def _limit_contacts(system, failed, state, q, lam_prev):
    """``failed`` with how the contacts stood at the last load carried (if any)."""
    if lam_prev <= 0:
        return failed
    factor = failed.strength_factor
    resp, _ = residual(system, q, state, lam_prev, factor)
    _, carried = tabulate(system, state, resp, factor, system.model.settings.reduce_tensile)
    return replace(failed, limit_interfaces=carried)


def show_mechanism(system: System, failed: Analysis) -> Analysis:
    """A proven failure of ``analyse(show_mechanism=False)`` with the
    mechanism that dynamic relaxation shows (as ``analyse`` would have)."""
    if failed.failure_start is None:
        return failed
    state, q, lam = failed.failure_start
    failed, run = confirm_failed_analysis(system, failed, state, q, lam)
    return replace(relaxation_mechanism(system, failed, run), failure_start=None)


def _package(
    system, sol, state, load_factor, factor, stable, steps, q_ok, near_limit=False, drive=None
):
    """Assemble an :class:`Analysis` from the last solve.

    ``near_limit``: the failed solve continued from an equilibrium just below
    the limit (a strength trial); the blocks that state no longer holds
    narrow the moving blocks down to the mechanism.  ``drive``: the factor
    whose out-of-balance drives the Newton-step mechanism (the trial's
    target), where it differs from the state's ``factor``.
    """
    asm = system.assembly
    free = ~system.blocks.fixed
    disp = np.zeros((system.blocks.n_blocks, 3))
    disp[free] = q_ok[asm.dof[free]]
    if stable:
        resp, _ = residual(system, q_ok, state, load_factor, factor)
        mech = np.zeros_like(disp)
        unstable = np.zeros(system.blocks.n_blocks, dtype=bool)
    else:
        resp = sol.response
        lam_fail = steps[-1].load_factor if steps else load_factor
        drive = factor if drive is None else drive
        mech, unstable = newton_mechanism(system, sol, state, lam_fail, drive)
        if near_limit and sol.reached_q is not None:
            resp_limit, _ = residual(system, sol.reached_q, state, lam_fail, sol.reached)
            free = unstable & ~held_blocks(system, resp_limit)
            if free.any():
                unstable = free
                mech[~unstable] = 0.0
        # show the springs failing in the mechanism (not committed: no equilibrium)
        _, ds = system.assembly.relative_displacement(sol.q)
        stage = steps[-1].stage if steps else 0
        state = commit(system.springs, state, resp, ds, stage)
    sp_res, if_res = tabulate(system, state, resp, factor, system.model.settings.reduce_tensile)
    slip = np.zeros(0, dtype=np.int64) if stable else slip_surface(system, unstable, if_res)
    return Analysis(
        system,
        bool(stable),
        float(load_factor),
        float(factor),
        disp,
        mech,
        unstable,
        sp_res,
        if_res,
        slip,
        tuple(steps),
        state,
    )


def analyse(
    model: Model | System,
    *,
    strength_factor: float = 1.0,
    load_steps: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    start: tuple[float, float, np.ndarray] | None = None,
    prove_first: bool = True,
    show_mechanism: bool = True,
    install_bolts: bool = True,
    limit_width: float | None = None,
) -> Analysis:
    """Apply the loads in steps and find equilibrium, or the failure mechanism.

    Parameters
    ----------
    model : Model or System
    strength_factor : float
        Divide c, tan(phi) (and the tensile strength) by this factor.
    load_steps : int, optional
        Overrides ``model.settings.load_steps``.
    progress : callable, optional
        Called as ``progress(step, n_steps)`` after each load step.
    start : tuple, optional
        The ``unloaded_limit`` of a failed analysis of the same system at a
        larger strength factor: the first load step starts from its
        equilibrium (at ``start[1]``), not from scratch.
    prove_first : bool
        Where Newton cannot find a first equilibrium, ask the equilibrium LP
        before climbing to the limit strength by a homotopy: a proven
        failure ends the step at once.  The factor-of-safety search turns it
        off: there the homotopy's limit state is where its next trials start.
    show_mechanism : bool
        Where the LP proved the failure, run dynamic relaxation to show how
        the blocks move (:func:`show_mechanism` does it later otherwise).
        The factor-of-safety search defers it: it shows the mechanism of its
        last failed trial, which is rarely this analysis (a 2,952-block
        slope failing under gravity: 1.6 s of a 9.4 s search).
    install_bolts : bool
        Put the bolts that go in after the loads (``installed: after_loads``)
        into the slope once it stands under them.  The factor-of-safety
        search turns it off where the slope did not stand at the factor
        asked: there the bolts never go in (a stronger trial slope that
        stands is not the slope they would be installed in).
    limit_width : float, optional
        The factor-of-safety search's bracket width: a first load step that
        fails from the unloaded state goes to its limit strength by work
        control (:mod:`rockdem.limit`), settled by the equilibrium LP within
        this width, instead of by bisection (a 1,021-block slope failing
        under gravity: ~280 factorisations).

    Returns
    -------
    Analysis
        Verdict, displacements, stresses, failed interfaces (with the step of
        first failure), unstable blocks and slip surface.

    Examples
    --------
    >>> from rockdem import Blocks, Joint, Model, analyse
    >>> ground = [(-5, -1), (5, -1), (5, 0), (-5, 0)]
    >>> m = Model(Blocks.from_polygons([ground, [(0, 0), (1, 0), (1, 1), (0, 1)]],
    ...                                fixed=[True, False], unit_weight=25),
    ...           Joint(normal_stiffness=1e6, friction_angle=30))
    >>> analyse(m).stable
    True
    """
    check_number("analyse", "strength_factor", strength_factor, lo=1e-6, hi=1e6 + 1e-6)
    if load_steps is not None:
        check_count("analyse load_steps", load_steps, MAX_LOAD_STEPS)
    system = model if isinstance(model, System) else build_system(model)
    n_steps = load_steps or system.model.settings.load_steps
    bolts = system.bolts
    state = SpringState.initial(
        system.springs.n_springs, None if bolts is None else bolts.initial_reference()
    )
    q = np.zeros(system.assembly.n_dof)
    steps: list[Step] = []
    lam_prev = 0.0
    sol = None
    for k in range(1, n_steps + 1):
        lam = k / n_steps
        sol, state, q, lam_prev, cert, limit = _load_step(
            system,
            state,
            q,
            lam_prev,
            lam,
            strength_factor,
            k,
            start if k == 1 else None,
            prove_first,
            limit_width,
        )
        ev = _evidence(sol)
        if not sol.converged:  # is the full load beyond every admissible force field?
            ev = with_certificate(system, ev, state, 1.0, strength_factor, cert)
        n_failed = int((state.yielded | state.broken).sum())
        steps.append(Step(k, lam, strength_factor, sol.converged, ev, n_failed))
        if progress is not None:
            progress(k, n_steps)
        if not sol.converged:
            log.info("load step %d/%d: no equilibrium (%s)", k, n_steps, ev)
            if state.bolts_waiting and show_mechanism:
                _warn_bolts_not_installed(system, state)
            failed = _package(system, sol, state, lam_prev, strength_factor, False, steps, q)
            failed = prove_in_region(system, failed, state, strength_factor)
            if failed.evidence.certified and not show_mechanism:
                failed = replace(failed, failure_start=(state, q, lam))
                return replace(
                    _limit_contacts(system, failed, state, q, lam_prev), unloaded_limit=limit
                )
            failed, run = confirm_failed_analysis(system, failed, state, q, lam)
            if run.status == "equilibrium" and not failed.evidence.certified:
                # Newton stalled where the second method found equilibrium (its
                # failures committed, see rockdem.relaxation): a stall, not a
                # verdict; go on from there
                held = state if run.slip is None else replace(state, slip=run.slip)
                rescued, new_state = _from_relaxed(system, held, run.q, lam, strength_factor, k)
                if rescued.converged:
                    ev = replace(_evidence(rescued), relaxation=failed.evidence.relaxation)
                    n_failed = int((new_state.yielded | new_state.broken).sum())
                    steps[-1] = Step(k, lam, strength_factor, True, ev, n_failed)
                    sol, state, q, lam_prev = rescued, new_state, rescued.q, lam
                    continue
            failed = relaxation_mechanism(system, failed, run)
            return replace(
                _limit_contacts(system, failed, state, q, lam_prev), unloaded_limit=limit
            )
    if state.bolts_waiting and install_bolts:  # the slope stands: the late bolts go in
        sol, state, q = _install_bolts(system, sol, state, q, lam_prev, strength_factor, k)
    done = _package(system, sol, state, lam_prev, strength_factor, True, steps, q)
    text = large_displacement(done)
    if text is not None:
        warnings.warn(ModelWarning(text), stacklevel=2)
    return done


def _install_bolts(system, sol, state, q, load_factor, factor, stage):
    """The bolts to go in after the loads installed at ``q``, and the
    equilibrium their pretension moves the slope to; where it has none, the
    slope as it was, without them (said in a warning)."""
    bolts = system.bolts
    waiting = np.isnan(state.bolt_reference[:, 0])
    installed = state.with_bolts_installed(bolts.displacement(q))
    if not np.any(bolts.pretension[waiting]):
        return sol, installed, q
    locked, new_state = settle(system, installed, q, load_factor, factor, stage)
    if not locked.converged:
        names = dict.fromkeys(np.asarray(bolts.names)[bolts.bolt[waiting]])
        warnings.warn(
            ModelWarning(
                f"bolts {', '.join(map(str, names))} (installed: after_loads) were not "
                "installed: locking off their pretension leaves no equilibrium; lower the "
                "pretension"
            ),
            stacklevel=3,
        )
        return sol, state, q
    return locked, new_state, locked.q


def _warn_bolts_not_installed(system, state) -> None:
    """The bolts to be installed after the loads never went in: the slope
    found no equilibrium under the loads without them."""
    waiting = np.isnan(state.bolt_reference[:, 0])
    names = dict.fromkeys(np.asarray(system.bolts.names)[system.bolts.bolt[waiting]])
    warnings.warn(
        ModelWarning(
            f"bolts {', '.join(map(str, names))} (installed: after_loads) were never installed: "
            "the slope finds no equilibrium under its loads without them; to hold the slope "
            "as the loads come on, install them before the loads (installed: before_loads)"
        ),
        stacklevel=3,
    )


def _from_relaxed(system, state, q, load_factor, factor, stage):
    """Equilibrium at ``load_factor`` from a state the dynamic relaxation
    brought within its tolerance: polished by Newton where it can be, else
    taken as it is (:data:`~rockdem.continuation.RELAXED`), then settled
    (committed, and re-solved while failures shed strength).  Returns
    ``(solve, state)`` as :func:`rockdem.redistribution.settle`."""
    max_it = system.model.settings.max_iterations
    first = newton(system, state, load_factor, factor, q, max_it)
    if not first.converged:
        resp, _ = residual(system, q, state, load_factor, factor)
        first = Solve(True, q, resp, first.iterations, first.residuals, RELAXED, np.zeros_like(q))
    return settle(system, state, first.q, load_factor, factor, stage, first=first)


def analyse_from(
    model: Model | System,
    state: SpringState,
    q0: np.ndarray,
    *,
    stage: int = 1,
    strength_factor: float = 1.0,
) -> Analysis:
    """Solve the full load once, from a given spring state and displacements.

    For sequences of models that carry the state forward (excavation in
    stages): ``state`` and ``q0`` (free-dof displacements) describe this
    model's springs and blocks, mapped from the previous stage.  Failures
    found here are recorded with ``stage``.
    """
    system = model if isinstance(model, System) else build_system(model)
    sol, new_state = settle(system, state, q0, 1.0, strength_factor, stage)
    n_failed = int((new_state.yielded | new_state.broken).sum())
    steps = (Step(stage, 1.0, strength_factor, sol.converged, _evidence(sol), n_failed),)
    if sol.converged:
        return _package(system, sol, new_state, 1.0, strength_factor, True, steps, sol.q)
    return _package(system, sol, state, 0.0, strength_factor, False, steps, q0)
