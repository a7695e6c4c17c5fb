"""A failure confirmed by the second solver: dynamic relaxation
(:mod:`rockdem.relaxation`) run a little beyond a failed trial or load step.

Newton's loss of equilibrium is no verdict; where the equilibrium LP
(:mod:`rockdem.certificate`) does not prove failure, runs from the last
equilibrium at ``CONFIRM_MARGINS`` beyond the bracket confirm it (the blocks
keep moving) or show a stall (they settle: the search goes on from there).
Where the LP proved it, a shorter run only shows the mechanism.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .relaxation import MAX_STEPS, Relaxation, relax, step_budget
from .spring_law import strength

#: a failed strength trial is confirmed this far beyond the top of its bracket
#: (the next margin only if the first leaves it undecided)
CONFIRM_MARGINS = (0.02, 0.05)


def shows_mechanism(n_dof: int) -> bool:
    """Is a failure the LP proved shown by a run on a model of ``n_dof``
    unknowns?  Not where a run is too short to show it (the models whose
    stalls are not checked either: see rockdem.continuation.stall_checked)."""
    from .continuation import stall_checked

    return stall_checked(n_dof)


#: a run keeping the slip goes on while its unbalanced force falls by this
#: over two segments
SLIP_RUN_FALL = 0.5


def look_keeping_slip(
    system, state, load_factor: float, factor: float, q0, run, with_slip: bool = False
):
    """A second look where a run under the solve's law (``run``, from ``q0``)
    did not settle: a run from ``q0`` keeping each spring's plastic slip
    (UDEC's incremental law).  Returns ``(verdict, Newton's solve or None)``:

    * ``"equilibrium"``: that run settled and Newton's method at ``factor``
      converged from its end (the run marked so, at Newton's displacements);
    * ``"mechanism"``: that run moved as a mechanism (two segments), the
      confirmation the issue asks of a second method (UDEC's own test);
    * else ``run`` itself; where the slip-keeping run settled but Newton
      under the caller's law found nothing from there, the run says whether
      Newton *with that run's slip* converged (the slope stands there with
      that slip history, not under a law without one).

    The solve's law (the shear following the total relative displacement,
    the strength the normal force) is not dissipative, and near a limit its
    explicit dynamics can keep the blocks vibrating with the unbalanced
    force at half the loads or more, never settling, where equilibrium
    exists; the incremental law of UDEC dissipates and settles.  Its
    equilibrium is not the solve's (its springs keep a plastic slip), but
    it is close to one, and Newton from there is the proof: two
    perpendicular joint sets, c = 0 (315 blocks), whose search stalled at
    0.921 with 1 load step and read 1.0247 with 5: the solve's-law runs at
    0.9-1.0 ended at 50-90% of the loads after 80,000 steps; the
    slip-keeping run settled at 0.9 in 2,748 steps.  Only a settled run:
    from one that creeps Newton converges or not by the run's rounding (the
    paper's slope at 0.9025, creeping at 1e-5 of the loads: converged in
    kN, stalled in t).  Where the solve's law boils and the slip-keeping
    run keeps moving, that run confirms the mechanism (two perpendicular
    sets with brittle cohesion and a water table, 162 blocks: 'undecided'
    at 0.7236, the solve's-law runs at 2% and 5% beyond ending at 32-39%
    of the loads after 80,000 steps; the slip-keeping run moved).

    ``with_slip``: where the caller's law keeps the plastic slip between
    solves (a staged analysis commits it at each load step; a strength
    trial does not), a run whose end Newton cannot polish under the caller's
    slip is polished with its own: the returned run's ``slip``
    (the same slope from scratch, 1 of 5 load steps: the slip-keeping run
    settled in 16,737 steps, Newton under the unloaded slip stalled)."""
    from .continuation import HOMOTOPY_ITERATIONS
    from .solver import newton

    kept = run.slip_check
    if kept is None:
        kept = relax(
            system, state, load_factor, factor, q0, max_steps=MAX_STEPS, extend=True, keep_slip=True
        )
    # on while undecided and its unbalanced force still falls (SLIP_RUN_FALL
    # over two segments), with the slip it got to (the same slope in 1 load
    # step: 3.5e-4 of the loads at 16,000 steps, 1e-7 at 56,931; the paper's
    # slope at 0.9025 crept at 1e-5 for 80,000)
    kept = _go_on(system, state, load_factor, factor, kept, MAX_STEPS, True, keep_slip=True)
    if kept.status == "mechanism" and run.status == "undecided":
        return replace(kept, law_run=replace(run, slip_check=None)), None
    if kept.status != "equilibrium":
        return run, None
    sol = newton(system, state, load_factor, factor, kept.q, HOMOTOPY_ITERATIONS)
    slip = None
    if not sol.converged:
        iterations = sol.iterations
        own = newton(
            system, replace(state, slip=kept.slip), load_factor, factor, kept.q, HOMOTOPY_ITERATIONS
        )
        if not with_slip:  # the caller's law has no slip history: a statement only
            stands = own.iterations if own.converged else None
            sol = replace(sol, iterations=iterations + own.iterations)
            if stands is None and run.slip_check is None:
                return run, sol
            return replace(run, slip_check=kept, newton_with_slip=stands), sol
        sol, slip = replace(own, iterations=iterations + own.iterations), kept.slip
    if not sol.converged:
        return run, sol
    found = replace(
        run,
        status="equilibrium",
        q=sol.q,
        slip_check=kept,
        newton_from_slip=sol.iterations,
        slip=slip,
    )
    return found, sol


#: a run after a proof only shows the mechanism: segments of this many steps
#: (the brick slopes' moving blocks were the same as with MAX_STEPS: 533 of
#: 1,021 and 1,547 of 2,952; 2,952 blocks: search 9.5 -> 8.2 s)
SHOW_STEPS = MAX_STEPS // 2


def confirm_failed_analysis(system, failed, state, q, load_factor: float):
    """A failed staged analysis checked by dynamic relaxation at the load it
    failed to carry, from its last equilibrium (``state``, ``q``): the
    statement goes into its evidence.  Returns ``(analysis, run)``; the
    run's late motion is the mechanism (also where the LP proved failure)."""
    proven = bool(failed.evidence.certified)
    factor = failed.strength_factor
    run = _run(system, state, load_factor, factor, q, MAX_STEPS, not proven)
    if not proven and run.status != "equilibrium":
        run, _ = look_keeping_slip(system, state, load_factor, factor, q, run, True)
    if run.slip is not None:  # (its equilibrium holds with the slip it kept)
        state = replace(state, slip=run.slip)
    run, shed = _shedding(system, state, load_factor, factor, run, MAX_STEPS, not proven)
    return with_relaxation(failed, f"{run} at load factor {load_factor:.4g}{shed}"), run


def _run(system, state, load_factor, factor, q, steps, look):
    """A run from ``q`` in segments of ``steps``, gone on while undecided."""
    run = relax(
        system, state, load_factor, factor, q, max_steps=steps, extend=True, second_look=look
    )
    return _go_on(system, state, load_factor, factor, run, steps, look)


def _go_on(system, state, load_factor, factor, run, steps, look, keep_slip=False):
    """A run still undecided (neither settling nor moving clearly) goes on
    from where it stopped while :func:`step_budget` allows.  (A 1e-4 m high
    slope's run stopped undecided at 8e-7 of the loads after 12,000 steps with
    one CPU's BLAS kernels, where another's found it settling and went on to
    equilibrium at 13,193.)  ``keep_slip``: a run keeping the plastic slip
    goes on with the slip it got to, while its unbalanced force still falls
    by SLIP_RUN_FALL over two segments."""
    done, ratios = run.steps, [run.ratio]
    budget = step_budget(system.assembly.n_dof)
    while run.status == "undecided" and done + MAX_STEPS <= budget:
        if keep_slip and len(ratios) > 2 and ratios[-1] > SLIP_RUN_FALL * ratios[-3]:
            break
        run = relax(
            system,
            replace(state, slip=run.slip) if keep_slip else state,
            load_factor,
            factor,
            run.q,
            max_steps=steps,
            extend=True,
            second_look=look,
            keep_slip=keep_slip,
        )
        done += run.steps
        run = replace(run, steps=done)
        ratios.append(run.ratio)
    return run


def confirm_failed_trial(system, failed, base, factor: float, trials):
    """A failed strength trial checked by dynamic relaxation a little beyond
    the limit (``factor x (1 + margin)``), from the last stable trial
    ``base``: a mechanism there is stated in the failed trial's evidence
    (proof ``"dynamic-relaxation"`` unless the LP proved it).  Right at the
    limit the excess force is too small for the blocks to move visibly.
    A run still undecided at the last margin (neither settling nor moving
    clearly) goes on from where it stopped while :func:`step_budget` allows
    (small models; one segment from 25,000 dof): toppling columns ten
    times larger than Goodman & Bray's, stopped there, read 0.293 instead
    of 0.374, after a change in how the gravity state is released.
    Returns ``(analysis, trials, run, factor of the run, first run)``; a run
    that found equilibrium there shows that the limit was a stall of
    Newton's method.  The first run, at the first margin, is returned as
    well: undecided there and a mechanism farther on does not confirm the
    bracket (the caller may go on from it)."""
    asm = system.assembly
    q0 = base.q
    state = base.state.without_slip()
    look = not failed.evidence.certified  # proven: the run only shows the mechanism
    if not look and not shows_mechanism(asm.n_dof):
        # (its few blocks at the face would be discarded for Newton's mechanism
        # anyway: rockdem.mechanism.first_movers; 9,638 blocks: 7.7 s of 75)
        idle = Relaxation("undecided", q0, 0, float("nan"), 0.0)
        return failed, list(trials), idle, factor * (1.0 + CONFIRM_MARGINS[0]), idle
    steps = MAX_STEPS if look else SHOW_STEPS
    first = None
    for margin in CONFIRM_MARGINS:
        beyond = factor * (1.0 + margin)
        run = relax(
            system,
            state,
            base.load_factor,
            beyond,
            q0,
            max_steps=steps,
            extend=True,
            second_look=look,
        )
        if look and run.status == "undecided":
            # (not settling under the solve's law: see look_keeping_slip)
            run, _ = look_keeping_slip(system, state, base.load_factor, beyond, q0, run)
        first = run if first is None else first
        if run.status != "undecided":  # a mechanism, or equilibrium: the limit was a stall
            break
    shed = ""
    if look:  # (a proven failure's run only shows the mechanism: no more runs for it)
        looked = run
        run = _go_on(system, state, base.load_factor, beyond, run, steps, look)
        if run.status == "undecided" and looked.slip_check is not None:
            # what the slip-keeping look found stays in the statement
            run = replace(
                run, slip_check=looked.slip_check, newton_with_slip=looked.newton_with_slip
            )
        run, shed = _shedding(system, state, base.load_factor, beyond, run, steps, look)
    text = f"{run} at F = {beyond:.6g} ({margin:.0%} beyond the bracket)" + shed
    failed = with_relaxation(failed, text, beyond if run.status == "mechanism" else None)
    trials = list(trials)
    last_failed = max(i for i, t in enumerate(trials) if not t.stable)
    trials[last_failed] = replace(trials[last_failed], evidence=failed.evidence)
    return failed, trials, run, beyond, first


#: rounds of (relaxed equilibrium -> its failures committed -> relaxed again)
#: while the committed failures shed strength (brittle cohesion, tension)
SHED_ROUNDS = 3


def _shedding(system, state, load_factor, factor, run, steps, look):
    """A run's equilibrium with its failures committed, relaxed again while
    they shed strength: a run keeps its strengths fixed, so a failure that
    follows the loss of brittle cohesion (springs at their peak in the
    equilibrium, at their residual strength once committed) was never seen:
    the search restarted from the equilibrium and lost it again, and ended
    undecided (a plane failure with c 25, residual 0: every run, at 2, 3
    and 5 spring points).  Returns the last run and a note on the rounds."""
    from .solver import residual
    from .spring_law import commit

    reduce = system.model.settings.reduce_tensile
    rounds = 0
    while run.status == "equilibrium" and rounds < SHED_ROUNDS:
        resp, _ = residual(system, run.q, state, load_factor, factor)
        _, ds = system.assembly.relative_displacement(run.q)
        after = commit(system.springs, state, resp, ds, 0).without_slip()
        before = strength(system.springs, state, factor, reduce)
        if all(
            np.array_equal(a, b)
            for a, b in zip(before, strength(system.springs, after, factor, reduce), strict=True)
        ):
            break  # nothing shed: the equilibrium stands
        state, rounds = after, rounds + 1
        run = _run(system, state, load_factor, factor, run.q, steps, look)
    lost = "an equilibrium" if rounds == 1 else f"{rounds} equilibria"
    if not rounds:
        return run, ""
    return run, f" (after {lost} lost as the joints failing in each shed their strength)"


def with_relaxation(failed, text: str, confirmed_at: float | None = None):
    """``failed`` (an Analysis) with ``text`` as its last step's relaxation
    evidence (and the strength factor where it confirmed a mechanism)."""
    last = failed.steps[-1]
    ev = replace(last.evidence, relaxation=text, confirmed_at=confirmed_at)
    return replace(failed, steps=(*failed.steps[:-1], replace(last, evidence=ev)))
