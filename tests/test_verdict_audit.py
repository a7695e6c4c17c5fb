"""The verdict audit (audit 34): seeded random slopes, their factor of
safety against the closed form, its invariance and its evidence.

The slopes are case ``seed`` of tests/_audit_slopes.py (the generator of
benchmarks/verdict_audit.py, which runs the whole audit).  Closed form:
planar sliding on persistent daylighting bedding with vertical cross joints
whose blocks cannot topple, c = 0, dry, with a horizontal coefficient kh:
FS = tan(phi) / tan(dip + atan kh) (Hoek & Bray, Rock Slope Engineering,
ch. 6, with the resultant of W and kh W: (cos d - k sin d) / (sin d + k cos
d) = cot(d + atan k)).

What does not hold yet is marked ``xfail(strict=True)`` with the numbers
measured at this stop.
"""

from __future__ import annotations

import numpy as np
import pytest

import rockdem as rd
from _audit_slopes import G_T, build, closed_form, draw, transformed

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def _fos(model):
    return rd.factor_of_safety(model)


@pytest.mark.parametrize("seed", [0, 8])
def test_planar_sliding_reads_the_closed_form_in_every_frame(seed):
    """Seed 0 (223 blocks, dip 24.0, phi 27.2, dry) and seed 8 (152 blocks,
    dip 34.8, phi 47.3, kh 0.098): within 0.02% of the closed form, proven
    by the LP, the same to 1e-9 for 1 / 20 load steps, moved by (1e5, 1e4),
    in tonnes and with the blocks listed in reverse."""
    p = draw(seed)
    model = build(p)
    exact = closed_form(p)
    base = _fos(model)
    assert base.value == pytest.approx(exact, rel=0.01)
    assert base.proof == "lp-certificate"
    for kw in (
        dict(steps=1),
        dict(steps=20),
        dict(shift=(1e5, 1e4)),
        dict(force=1 / G_T),
        dict(reverse=True),
    ):
        other = _fos(transformed(model, **kw))
        assert other.value == pytest.approx(base.value, rel=1e-9), kw
        assert other.proof == base.proof, kw
        assert sorted(other.failed_analysis.unstable_blocks) == sorted(
            base.failed_analysis.unstable_blocks
        ), kw


def test_a_strength_independent_verdict_carries_the_proof_of_its_bracket_top():
    """Seed 4 at a height of 5 m (55 blocks; bedding 27.7 out of a 74.2
    degree face, r_u 0.274): the face columns are pushed out by their joint
    water at any strength, "strength-independent", bracket (0, 0.0585).
    The LP proves failure at F = 1, 0.667 and 0.444; from 0.296 down it
    finds an admissible field, and only dynamic relaxation confirms the
    failure.  The result said "lp-certificate" (the shown analysis at
    F = 1): a proof of what it does not state."""
    p = draw(4)
    p["height"] = 5
    fos = _fos(build(p))
    assert fos.mode == "strength-independent"
    top = [t for t in fos.trials if not t.stable and t.factor == fos.bracket[1]][-1]
    assert fos.certified_upper_bound is not None and fos.certified_upper_bound > fos.bracket[1]
    assert top.evidence.proof == "dynamic-relaxation"
    assert fos.proof == top.evidence.proof
    from rockdem.result_tables import fos_summary

    assert fos_summary(fos)["proof"] == "dynamic-relaxation"


@pytest.mark.slow
def test_planar_sliding_with_kh_reads_the_closed_form():
    """Seed 16 (368 blocks, bedding 26.46 out of a 44.6 degree face,
    vertical cross joints b/t = 1.70, phi 33.64, c = 0, dry, kh 0.130):
    closed form tan(phi) / tan(dip + atan kh) = 0.9908.  The search stalled
    at 0.6780, 'undecided' (-31.6%): dynamic relaxation under the solve's
    law never settled (its unbalanced force stayed at 20% of the loads),
    and Newton could not climb.  A run keeping each spring's plastic slip
    settles there, and Newton from its equilibrium finds the solve's:
    0.99073 [0.99041, 0.99105], proven by the LP."""
    p = draw(16)
    exact = closed_form(p)
    assert exact == pytest.approx(0.99084, rel=1e-4)
    fos = _fos(build(p))
    assert fos.value == pytest.approx(exact, rel=0.01)
    assert fos.proof == "lp-certificate"


@pytest.mark.slow
def test_stronger_joints_under_kh_are_not_read_unstable_by_the_second_solver():
    """Seed 16 (planar sliding under kh, closed form 0.9908): the staged
    analysis at strength factor 0.9 stalls after a Newton path, and dynamic
    relaxation under the solve's law, the shear following the total
    displacement, kept moving: 'unstable, confirmed' at 0.8, 0.9 and 0.95,
    while the same slope stood at 0.98.  That law is not dissipative; a run
    keeping each spring's plastic slip (UDEC's law) settles there (then it
    read 'undecided'), and Newton's method from that run's equilibrium,
    with the slip it kept, finds the solve's: the slope stands."""
    a = rd.analyse(build(draw(16)), strength_factor=0.9)
    assert a.verdict == "stable"
    assert a.stable and len(a.unstable_blocks) == 0


@pytest.mark.slow
def test_two_perpendicular_sets_without_cohesion_do_not_depend_on_load_steps():
    """Seed 14 (315 blocks, two perpendicular sets 27.2 / 117.2 degrees,
    face 68.8, phi 40.5, c = 0, dry): homogeneous in the load, yet 1 load
    step gave 0.9210 'undecided' and 5 steps 1.0247 (+11.3%).  The solve's
    law's relaxation runs at 0.92-1.0 ended at 50-90% of the loads after
    80,000 steps; a run keeping the slip settles (2,748 steps at 0.9) and
    Newton from there converges: 1.0250 / 1.0255."""
    model = build(draw(14))
    one = _fos(transformed(model, steps=1))
    five = _fos(model)
    assert one.value == pytest.approx(five.value, rel=0.005)


@pytest.mark.slow
def test_where_the_solves_law_boils_a_run_keeping_the_slip_confirms_the_mechanism():
    """Seed 2 (162 blocks, sets 26.0 / 116.0, face 72.7, phi 30.1, brittle
    c 6.38, a water table): 0.7236 'undecided' at stop 37.  The runs under
    the solve's law 2% and 5% beyond the bracket ended at 32-39% of the
    loads after 80,000 steps, neither settling nor moving clearly; a run
    from the same start keeping each spring's plastic slip (UDEC's law)
    moves in two segments: confirmed 2% beyond, and the evidence says
    which law moved."""
    fos = _fos(build(draw(2)))
    assert fos.proof == "dynamic-relaxation"
    text = fos.failed_analysis.evidence.relaxation
    assert text.startswith("dynamic relaxation: mechanism")
    assert "keeping each spring's plastic slip (UDEC's law" in text
    assert "where a run under the solve's law neither settled nor moved clearly" in text
    assert fos.confirmed_upper_bound == pytest.approx(1.02 * fos.bracket[1])
    assert fos.bracket[1] - fos.bracket[0] <= 0.005


@pytest.mark.slow
def test_an_undecided_verdict_says_where_a_slip_history_holds_the_slope():
    """Seed 10 (514 blocks, sets 24.2 / 114.2, face 73.0, phi 28.9, c = 0,
    dry): Newton under the search's law (no slip history) loses
    equilibrium at 0.5045, and 5% beyond the runs under that law end at
    39% of the loads after 64,000 steps.  A run keeping the slip settles
    there, and Newton's method *with the slip it kept* converges (at 2%,
    5% and 10% beyond; at 20% that run slides): the verdict stays
    'undecided' (the search's law found nothing) and says so."""
    fos = _fos(build(draw(10)))
    assert fos.proof == "undecided"
    top = [t for t in fos.trials if not t.stable and t.factor == fos.bracket[1]]
    assert any(
        "Newton's method with that slip found equilibrium" in (t.evidence.relaxation or "")
        for t in top
    ), [t.evidence.relaxation for t in top]


@pytest.mark.slow
def test_a_restart_that_collapses_where_the_run_found_equilibrium_confirms_the_failure():
    """Seed 13 (200 blocks, toppling: a set at 102.9 degrees into a 76.2
    degree face, cross joints 10.5, phi 26.2, brittle c 27.8, kh 0.131):
    Newton lost equilibrium at 0.4931; the run 2% beyond found equilibrium
    after three rounds of its failures shedding their cohesion, and the
    search restarted from there; the restart collapsed, its own check
    leaving the blocks moving.  The result said 'undecided' 0.4913
    [0.4896, 0.4931]; the collapse is the confirmation, at that factor."""
    fos = _fos(build(draw(13)))
    assert fos.proof == "dynamic-relaxation"
    lo, hi = fos.bracket
    assert fos.value == lo
    assert fos.confirmed_upper_bound == pytest.approx(hi)
    assert "from where the run stopped" in fos.failed_analysis.evidence.relaxation
    restart = [t for t in fos.trials if t.factor == hi]
    assert restart and not restart[-1].stable
    assert restart[-1].evidence.proof == "dynamic-relaxation"


@pytest.mark.slow
def test_the_mechanism_does_not_depend_on_the_frame():
    """Seed 3 (196 blocks, a set at 57.2 degrees behind a 54.7 degree face,
    vertical cross joints, phi 56.7, r_u 0.247, kh 0.089): FS 3.5304
    [3.5304, 3.7077], dynamic-relaxation, the same to the bit in every
    frame; until stop 37 its mechanism was block 151 alone (kN), block 162
    alone (t) and 90-93 blocks with 20 load steps, moved by (1e5, 1e4) or
    reversed.  Moved or in t, the runs under the solve's law now end
    undecided, and the run keeping each spring's plastic slip moves 93
    blocks, the same 93 as the solve's-law mechanism in kN (20 load steps
    and reversed: 92 of them)."""
    model = build(draw(3))
    base = _fos(model)
    blocks = sorted(base.failed_analysis.unstable_blocks)
    assert len(blocks) > 80
    for kw in (dict(shift=(1e5, 1e4)), dict(force=1 / G_T)):
        other = _fos(transformed(model, **kw))
        assert other.value == pytest.approx(base.value, rel=1e-9), kw
        assert sorted(other.failed_analysis.unstable_blocks) == blocks, kw


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason=(
        "seed 2 (162 blocks, sets 26.0 / 116.0, face 72.7, phi 30.1, brittle c 6.38, "
        "water table from 0.56 H at the back to the toe): since stop 38 'dynamic-relaxation' "
        "in every frame, the same 53 blocks moving, but 0.7236 [0.7233, 0.7240] (5 steps, "
        "and reversed), 0.7243 (20 steps), 0.7285 [0.7285, 0.7438] moved by (1e5, 1e4), "
        "0.7288 in t: a spread of 0.7%, more than the 0.005 width (stop 37: 'undecided' at "
        "5 steps, the proof kind changing with the frame); without cohesion 0.7307"
    ),
)
def test_a_brittle_wet_slope_keeps_its_factor_and_proof_when_moved():
    model = build(draw(2))
    base = _fos(model)
    moved = _fos(transformed(model, shift=(1e5, 1e4)))
    assert abs(moved.value - base.value) <= 0.0025
    assert moved.proof == base.proof


def test_the_audit_slopes_are_what_the_table_says():
    """The generator is seeded: the cases of the audit table."""
    counts = {s: int((~build(draw(s)).blocks.fixed).sum()) for s in (0, 3, 8)}
    assert counts == {0: 223, 3: 196, 8: 152}
    assert closed_form(draw(0)) == pytest.approx(
        np.tan(np.radians(draw(0)["phi"])) / np.tan(np.radians(draw(0)["dips"][0]))
    )
