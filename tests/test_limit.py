"""The limit state by work control (rockdem.limit): the strength factor as
an unknown, the external work prescribed.

Closed forms: a block on a plane (Hoek & Bray 1981, ch. 7: FS = tan(phi) /
tan(dip)); generated slopes whose bedding daylights (the same, Hoek & Bray
planar sliding); a brick slope of 1,021 blocks (tan 35 / tan 20).
"""

from __future__ import annotations

import numpy as np
import pytest

import rockdem as rd
from rockdem import limit
from rockdem import verification as V
from rockdem.linalg import norm
from rockdem.solver import residual
from rockdem.spring_law import SpringState


def _free_q(system, analysis):
    """The free-dof displacement vector of an analysis."""
    asm = system.assembly
    free = ~system.blocks.fixed
    q = np.zeros(asm.n_dof)
    q[asm.dof[free].ravel()] = analysis.displacement[free].ravel()
    return q


def _block(dip=20.0, phi=30.0, **joint):
    joint = rd.Joint(normal_stiffness=1e6, friction_angle=phi, **joint)
    return rd.build_system(V.block_on_plane(dip, joint))


def _down_the_dip(system, dip):
    """The block sliding down the plane: (ux, uy, w) = (cos d, -sin d, 0)."""
    d = np.radians(dip)
    return np.array([np.cos(d), -np.sin(d), 0.0])


@pytest.mark.parametrize(("dip", "phi"), [(20, 30), (35, 40), (10, 12)])
def test_a_block_on_a_plane_reaches_tan_phi_over_tan_dip_in_one_solve(dip, phi):
    """From the equilibrium at F = 1, the block pushed down the dip by its
    elastic displacement: the work-controlled solve lands on the plateau at
    tan(phi) / tan(dip) (Hoek & Bray), to 1e-9, in a few iterations, and its
    displacements are an equilibrium there."""
    system = _block(dip, phi)
    base = rd.analyse(system)
    q0 = _free_q(system, base)
    exact = V.sliding_fos(dip, phi)
    state = base.state.without_slip()
    start, work = limit.pushed(system, 1.0, q0, _down_the_dip(system, dip), 1.0)
    found = limit.work_controlled(system, state, 1.0, start, 1.0, work)
    assert found.converged and found.iterations <= 10
    assert found.factor == pytest.approx(exact, rel=1e-9)
    _, r = residual(system, found.q, state, 1.0, found.factor)
    scale = system.assembly.dof_scale
    assert norm(r * scale) <= 1e-8 * norm(system.f_ext * scale)
    assert float(system.f_ext @ found.q) == pytest.approx(work, rel=1e-8)


@pytest.mark.parametrize("share", [0.5, 0.9])
def test_the_mechanism_predicts_a_plane_slide_from_any_equilibrium(share):
    """A plane slide's springs carry the driving force wherever the factor
    is: the share of their strength they mobilise predicts the limit
    exactly (tan(phi) / tan(dip)) from an equilibrium at half or 0.9 of it."""
    dip, phi = 25.0, 40.0
    system = _block(dip, phi)
    exact = V.sliding_fos(dip, phi)
    at = rd.analyse(system, strength_factor=share * exact)
    resp, _ = residual(system, _free_q(system, at), at.state, 1.0, share * exact)
    ds = system.assembly.relative_displacement(_down_the_dip(system, dip))[1]
    predicted = limit.predicted_limit(resp, share * exact, ds, system.springs.weight)
    assert predicted == pytest.approx(exact, rel=1e-9)


def test_the_strength_derivative_is_that_of_the_internal_force():
    """g = d(B^T W p)/dt at fixed displacements (t = 1/F) against a central
    difference, on a block whose springs slide (c, phi) and one whose joint
    opens at its reduced tensile strength (a block hanging under a ledge)."""
    dip = 30.0
    system = _block(dip, 20.0, cohesion=5.0, residual_cohesion=5.0)
    base = rd.analyse(system, strength_factor=0.5)
    state = base.state.without_slip()
    q = _free_q(system, base) + 1e-3 * _down_the_dip(system, dip)  # sliding
    t, h = 1.0 / 1.2, 1e-6
    resp, _ = residual(system, q, state, 1.0, 1.0 / t)
    assert resp.sliding.any()
    g = limit.strength_derivative(system, resp, t)

    def internal(t_):
        r = residual(system, q, state, 1.0, 1.0 / t_)[1]
        return system.f_ext - r

    fd = (internal(t + h) - internal(t - h)) / (2 * h)
    assert g == pytest.approx(fd, rel=1e-5, abs=1e-9 * np.abs(fd).max())
    # a joint open at its tensile strength: the tension scales with t too
    ledge = rd.Blocks.from_polygons(
        [[(-3, 0), (3, 0), (3, 2), (-3, 2)], [(-1, -1), (1, -1), (1, 0), (-1, 0)]],
        fixed=[True, False],
        unit_weight=25.0,
    )
    joint = rd.Joint(normal_stiffness=1e6, friction_angle=30, cohesion=50, tensile_strength=10)
    hanging = rd.build_system(rd.Model(ledge, joint))
    st = SpringState.initial(hanging.springs.n_springs)
    q = np.array([0.0, -1.0, 0.0])  # pulled off the ledge: open
    resp, _ = residual(hanging, q, st, 1.0, 1.0 / t)
    assert resp.open.all()
    g = limit.strength_derivative(hanging, resp, t)
    fd = (
        (hanging.f_ext - residual(hanging, q, st, 1.0, 1.0 / (t + h))[1])
        - (hanging.f_ext - residual(hanging, q, st, 1.0, 1.0 / (t - h))[1])
    ) / (2 * h)
    assert g == pytest.approx(fd, rel=1e-5, abs=1e-9 * np.abs(fd).max())


def test_the_brick_slope_search_takes_the_step_to_the_limit():
    """The 1,021-block brick slope (tan 35 / tan 20 = 1.92380, bedding
    daylighting, staggered cross joints): the search lands on the limit by
    work control and the LP proves failure a 64th of the width above, so
    the bracket is width / 64 wide and holds the closed form; the whole
    search, gravity included, takes at most 120 factorisations (264 with
    the bisection alone: stop 33)."""
    system = rd.build_system(V.brick_slope(1000))
    exact = np.tan(np.radians(35)) / np.tan(np.radians(20))
    before = system.factorizer.count
    fos = rd.factor_of_safety(system)
    lo, hi = fos.bracket
    assert fos.proof == "lp-certificate"
    assert lo <= exact <= hi and hi - lo == pytest.approx(0.005 / 64)
    assert fos.value == pytest.approx(exact, abs=0.005 / 128 + 1e-9)
    assert system.factorizer.count - before <= 120
    assert "found by work control" in fos.failed_analysis.evidence.reason


def test_a_model_too_large_for_the_whole_lp_is_proven_on_its_moving_blocks(monkeypatch):
    """Above CERTIFY_MAX_SPRINGS the whole-model LP is not solved (a
    94,533-block slope: 19-21 s and 1.5 GB each); the step to the limit is
    proven by the LP of the mechanism's blocks alone, a relaxation of the
    whole LP.  Here the 1,021-block brick slope (tan 35 / tan 20) is made
    "too large": the search takes the same step to the limit, the bracket is
    as narrow and holds the closed form, and no whole-model LP is solved.
    (Before, such models bisected: 264 factorisations at this size.)"""
    from rockdem import certificate

    system = rd.build_system(V.brick_slope(1000))
    monkeypatch.setattr(certificate, "CERTIFY_MAX_SPRINGS", system.springs.n_springs - 1)
    regions, real = [], certificate.admissible_load

    def spy(system, state, load_factor, factor, region=None, quick=False):
        regions.append(region)
        return real(system, state, load_factor, factor, region, quick)

    monkeypatch.setattr(certificate, "admissible_load", spy)
    exact = np.tan(np.radians(35)) / np.tan(np.radians(20))
    fos = rd.factor_of_safety(system)
    lo, hi = fos.bracket
    assert fos.proof == "lp-certificate"
    assert lo <= exact <= hi and hi - lo == pytest.approx(0.005 / 64)
    assert system.factorizer.count <= 120
    assert regions and all(r is not None and 0 < r.sum() < r.size for r in regions)
    assert "found by work control" in fos.failed_analysis.evidence.reason
    assert "moving blocks" in fos.failed_analysis.evidence.certificate


@pytest.mark.parametrize("creep", [True, False])
def test_a_solve_still_converging_at_its_iteration_limit_goes_on(monkeypatch, creep):
    """The creep over the spring law's kinks near the plateau grows with the
    model (a 28,556-block brick slope: 1.6e-5 of the loads after 80
    iterations, converged in 101; stopped at 80 its search bisected, 712
    factorisations instead of 192).  A solve still converging at its limit
    goes on.  Here the 1,021-block brick slope's solve (31 iterations) is
    given 20: it goes on and the search lands on tan 35 / tan 20; with
    the creep switched off it stops there and the search bisects."""
    monkeypatch.setattr(limit, "MAX_ITERATIONS", 20)
    if not creep:
        monkeypatch.setattr(limit, "CREEP_ITERATIONS", 0)
    solves, real = [], limit.work_controlled

    def spy(*args, **kw):
        solves.append(real(*args, **kw))
        return solves[-1]

    monkeypatch.setattr(limit, "work_controlled", spy)
    system = rd.build_system(V.brick_slope(1000))
    fos = rd.factor_of_safety(system)
    exact = np.tan(np.radians(35)) / np.tan(np.radians(20))
    assert solves
    assert solves[0].converged is creep
    assert (solves[0].iterations > 20) is creep
    assert ("found by work control" in fos.failed_analysis.evidence.reason) is creep
    assert fos.bracket[0] <= exact <= fos.bracket[1] + 1e-9


#: the out-of-balance force (share of the loads) of a 28,556-block brick
#: slope's work-controlled solve over its iterations 75-95 (one accepted
#: entry each), on the plateau F = 1.923804: 3.6-fold over the window
CREEPING_28556 = [2.22e-05, 1.96e-05, 1.86e-05, 1.73e-05, 1.68e-05, 1.57e-05, 1.48e-05]
CREEPING_28556 += [1.39e-05, 1.33e-05, 1.27e-05, 1.24e-05, 1.2e-05, 1.15e-05, 1.1e-05]
CREEPING_28556 += [1.05e-05, 9.46e-06, 9.12e-06, 8.44e-06, 8.34e-06, 6.66e-06, 6.16e-06]


def test_a_solve_falling_two_fold_over_the_window_is_still_converging():
    """The 28,556-block solve above went on to converge at iteration 101
    (the shift fell, full steps); stopped at 95 (the rule was 4-fold) the
    search bisected: 727 factorisations instead of about 200.  A force that
    stays put, or falls less than 2-fold, stops the solve."""
    assert limit.still_converging(CREEPING_28556)
    assert not limit.still_converging([*CREEPING_28556[:-1], 1.2e-5])  # 1.85-fold
    assert not limit.still_converging([1e-5] * 21)
    assert not limit.still_converging(CREEPING_28556[-20:])  # not a whole window yet


@pytest.mark.parametrize(("answer", "done"), [(False, True), (None, False)])
def test_the_step_is_given_up_only_where_the_lp_answered(answer, done):
    """A failure the LP does not prove may be a stall below the limit: the
    step to the limit is given up (a near-flat benched slope: work control
    found nothing to settle).  Where the LP was too large to solve (None:
    a 94,533-block slope's trial at F = 1.5 stalled and moved 92,562 of its
    blocks, 832,461 spring points), a later failure is asked again."""
    system = _block(20.0, 30.0)
    step = limit.LimitStep(system, None, 1.0, limit.LimitProof(lambda F, moving: answer, 0.005))
    step.slip = np.ones(system.assembly.n_dof)
    assert step.ready and not step.beyond_proven((1.5, 0.5))
    assert step.done is done and step.ready is not done


def test_brittle_joints_keep_the_bisection(monkeypatch):
    """Where committing the failures sheds strength (brittle cohesion), the
    limit of a trial's strengths is not the slope's: no step to the limit
    is taken (the bedded-slope example keeps its factor, 1.1958)."""
    from rockdem.config import load_model
    from rockdem.examples import example_path

    model, _ = load_model(example_path("bedded-slope"))
    system = rd.build_system(model)
    assert system.sheds_strength
    called = []
    real = limit.work_controlled

    def spy(*args, **kw):
        called.append(args)
        return real(*args, **kw)

    monkeypatch.setattr(limit, "work_controlled", spy)
    fos = rd.factor_of_safety(system)
    assert called == [] and fos.value == pytest.approx(1.1958, abs=5e-4)


def test_a_plateau_the_lp_does_not_prove_is_not_taken(monkeypatch):
    """Where the LP does not prove failure just above the factor work
    control found (non-associated friction: toppling), that equilibrium,
    reached with the mechanism pushed along, is not on the trials' path: the
    search goes on by bisection as it would without it.  Here the LP is made
    to prove nothing near a brick slope's limit."""
    system = rd.build_system(V.brick_slope(1000))
    monkeypatch.setattr(limit.LimitStep, "prove", lambda self, F: None)
    steps, real = [], limit.LimitStep.solve

    def counted(self, F_ok, q_ok):
        steps.append(real(self, F_ok, q_ok))
        return steps[-1]

    monkeypatch.setattr(limit.LimitStep, "solve", counted)
    fos = rd.factor_of_safety(system)
    assert steps and all(found is None for found, _ in steps)
    assert "found by work control" not in fos.failed_analysis.evidence.reason
    exact = np.tan(np.radians(35)) / np.tan(np.radians(20))
    assert fos.bracket[0] <= exact <= fos.bracket[1] + 1e-9


def _column_with_crack_water():
    """Literature round 4's column with water in its back crack (mean block
    size 32.6 m with the ground: the case that found the LP's scaling)."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from test_literature_round4 import _column, _critical_depth

    return _column(0.8 * _critical_depth(), 40.0)


@pytest.mark.parametrize(
    "case", ["bedded-slope", "bolted-slope", "plane-failure-water", "toppling", "column"]
)
def test_an_equilibrium_is_admissible_to_the_lp(case):
    """Any equilibrium the solver finds is a statically admissible force
    field at its factor (METHOD.md section 4), so the LP must never prove
    failure there.  It did on the water-filled column: the loads' moments
    were divided by the mean block size twice, and at 32.6 m the LP read no
    admissible field even at F = 1 (Hoek & Bray's sliding factor 1.2213).
    Checked at F = 1 and at the lower end of each search's bracket."""
    from rockdem.certificate import admissible_load
    from rockdem.config import load_model
    from rockdem.examples import example_path

    if case == "column":
        model = _column_with_crack_water()
    else:
        model, _ = load_model(example_path(case))
    system = rd.build_system(model)
    fos = rd.factor_of_safety(system)
    standing = [fos.stable_analysis]
    at_one = rd.analyse(system)
    if at_one.stable:
        standing.append(at_one)
    for a in standing:
        cert = admissible_load(system, a.state, a.load_factor, a.strength_factor)
        assert not cert.proves_failure, (case, a.strength_factor, str(cert))
    if case == "column":
        assert fos.value == pytest.approx(1.2213, abs=5e-4)
