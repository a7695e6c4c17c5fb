"""Toppling on a stepped base: the DEM against Goodman & Bray's limit equilibrium.

Source: R. E. Goodman and J. W. Bray (1976), "Toppling of rock slopes",
Proc. ASCE Specialty Conference on Rock Engineering for Foundations and
Slopes, Boulder, vol. 2, 201-234; the worked example of E. Hoek and
J. W. Bray (1981), Rock Slope Engineering, 3rd ed., ch. 10 (also Wyllie &
Mah 2004, section 9.4): 16 blocks 10 m wide on treads dipping 30 degrees,
a1 = 5.0 m, a2 = 5.2 m, step b = 1.0 m, crest at block 10, gamma = 2.5
t/m^3.  Limiting equilibrium (P0 = 0) at phi = 38.15 degrees on bases and
faces: blocks 1-3 slide, 4-13 topple, 14-16 stand (tests/test_limit_equilibrium.py
checks the closed form against these published values).

Here the same blocks are rigid DEM blocks (x up the dip in the base frame,
the slope facing +x) on a fixed ground block below the stepped base.
"""

from __future__ import annotations

import numpy as np
import pytest

import rockdem as rd
from rockdem import verification as V
from rockdem.limit_equilibrium.closed_forms import stepped_heights, toppling, toppling_fos
from rockdem.modes import failure_modes

PHI = 38.15  # the published limiting friction angle
DX, PSI, STEP, GAMMA = 10.0, 30.0, 1.0, 2.5


def staircase(phi: float = PHI, kn: float = 1e6) -> rd.Model:
    """The 16 blocks of the worked example; ids 1 (toe) to 16, ground 0."""
    return V.toppling_staircase(
        stepped_heights(16, 10, 5.0, 5.2, STEP),
        width=DX,
        step=STEP,
        base_dip=PSI,
        joint=rd.Joint(normal_stiffness=kn, friction_angle=phi),
        unit_weight=GAMMA,
    )


def _le_factor(phi: float = PHI) -> float:
    y = stepped_heights(16, 10, 5.0, 5.2, STEP)
    return toppling_fos(y, width=DX, step=STEP, base_dip=PSI, base_friction=phi, unit_weight=GAMMA)


def _limit(fos) -> float:
    return float(np.degrees(np.arctan(np.tan(np.radians(PHI)) / fos)))


@pytest.fixture(scope="module")
def limit():
    return rd.factor_of_safety(staircase(), width=0.002)


def test_dem_limiting_friction_is_goodman_and_brays(limit):
    """The DEM's limiting friction angle is within 0.75 degrees of Goodman &
    Bray's 38.15 (FS within 3%; measured 37.6 degrees, FS 1.0206 against
    1.0006).  The difference is systematic, not the springs' deformability:
    the bracket is the same for kn = 1e5 and 1e7 (c = 0: the limit does not
    depend on the stiffness).  It comes from where the LE fixes the forces:
    each block in one mode (the larger of P_t and P_s), forces at the
    corners, Q = P tan phi on every face.  The DEM finds one distribution:
    above the crest its face forces are the LE's P_n (checked to 1%), below
    it the toppling blocks pass more force down and block 4 slides on its
    base instead of toppling, so the toe needs less: the DEM is the less
    conservative by 2%."""
    F_le = _le_factor()
    assert abs(F_le - 1.0) < 0.002  # the published limit
    assert limit.mode == "strength"
    assert abs(limit.value - F_le) / F_le < 0.03
    assert abs(_limit(limit.value) - PHI) < 0.75
    assert limit.value >= F_le  # the direction of the difference explained above
    for kn in (1e5, 1e7):
        other = rd.factor_of_safety(staircase(kn=kn), width=0.002)
        assert other.bracket == pytest.approx(limit.bracket, abs=1e-9)
    # the forces between blocks 10-13 (above the crest) are Goodman & Bray's
    a = limit.stable_analysis
    le = toppling(
        stepped_heights(16, 10, 5.0, 5.2, STEP),
        width=DX,
        step=STEP,
        base_dip=PSI,
        base_friction=_limit(a.strength_factor),
        unit_weight=GAMMA,
    )
    faces = a.interfaces
    for n in range(10, 16):  # the face between blocks n and n + 1 carries P_n
        k = np.flatnonzero((faces.block_a == n) & (faces.block_b == n + 1))
        assert len(k) == 1
        P = le.p_upper[n - 1]
        assert faces.normal_force[k[0]] == pytest.approx(P, abs=0.01 * le.p_lower.max())


def test_dem_limit_state_has_the_classic_pattern(limit):
    """The last equilibrium before the limit: the toe blocks slide on their
    whole base, the middle blocks stand on their toe corners with the base
    open behind and its friction not exhausted, the upper blocks carry no
    force from their neighbours."""
    a = limit.stable_analysis
    faces = a.interfaces
    base = {
        int(b): k
        for k, (g, b) in enumerate(zip(faces.block_a, faces.block_b, strict=True))
        if g == 0 and faces.length[k] > 5
    }
    tan_phi = np.tan(np.radians(_limit(a.strength_factor)))
    mobilised = {
        n: abs(faces.shear_force[base[n]]) / (faces.normal_force[base[n]] * tan_phi)
        for n in range(1, 17)
    }
    assert all(faces.current_name[base[n]] == "sliding" for n in (1, 2, 3))
    assert all(faces.current_name[base[n]] == "open" for n in range(5, 14))
    assert all(mobilised[n] < 0.95 for n in range(5, 14))
    for n in (13, 14, 15):
        k = np.flatnonzero((faces.block_a == n) & (faces.block_b == n + 1))[0]
        assert faces.normal_force[k] < 1e-6 * GAMMA * DX * 40


def _modes(limit) -> tuple[dict[int, str], set[int]]:
    """Mode of every block, and the blocks whose mode the limit state decided."""
    modes = failure_modes(limit.failed_analysis)
    names = dict(zip(modes.ids.tolist(), modes.name.tolist(), strict=True))
    return names, set(modes.ids[modes.decided].tolist())


def _ground_base(analysis, n: int) -> int:
    """Position of block n's base on the ground (the 10 m tread, not the riser)."""
    faces = analysis.system.interfaces
    k = np.flatnonzero(
        ((faces.block_a == 0) & (faces.block_b == n))
        | ((faces.block_b == 0) & (faces.block_a == n))
    )
    return int(k[np.argmax(faces.length[k])])


@pytest.mark.parametrize("grow", [1.3, 1.5, 2.0])
def test_failure_modes_show_the_classic_toppling_pattern(grow):
    """Goodman & Bray's staircase (Goodman & Bray 1976; Wyllie & Mah 2004,
    ch. 9): the toe blocks slide, a middle group topples, the upper blocks
    stand, for three trial schedules.  The modes are read at the limit, block
    by block, from its base at the last equilibrium: the mechanism 2% beyond
    it slips the toppling blocks' toe corners by ~5% of their speed, and is
    chaotic in its detail (test_modes_do_not_depend_on_the_relaxation_round_off).
    Block 4 slides in the DEM where the LE has it topple (see
    test_dem_limiting_friction_is_goodman_and_brays).  The 1.3 schedule
    reaches its limit on another path (FS 1.0147, not 1.0204): there blocks
    5, 6 and 10 stand on a base 1/6 open and 2/3 at its strength, at the
    transition; their mode is the motion's (not decided by the limit)."""
    limit = rd.factor_of_safety(staircase(), grow=grow, width=0.002)
    names, decided = _modes(limit)
    said = (limit, limit.failed_analysis.evidence.relaxation, names, decided)
    expected = {n: "slides" for n in range(1, 5)} | {n: "topples" for n in range(5, 14)}
    assert {n: names[n] for n in decided} == {n: expected[n] for n in decided}, said
    assert [n for n in range(1, 17) if names[n] == "stable"] == [14, 15, 16], said
    assert set(range(1, 5)) <= decided and len(decided & set(range(5, 14))) >= 6, said
    # an undecided block stood on a base partly open and partly at its strength
    a = limit.failed_analysis
    for n in set(range(1, 14)) - decided:
        k = _ground_base(a, n)
        opened = a.limit_interfaces.open_fraction[k]
        slid = a.limit_interfaces.sliding_fraction[k]
        assert 0 < opened < 0.5 and 0 < slid < 0.99 * (1 - opened), (n, opened, slid)


def test_modes_do_not_depend_on_the_relaxation_round_off(monkeypatch):
    """The run beyond the limit is chaotic: its start moved by 1e-9 (relative)
    made blocks 5, 6 and 10 of Goodman & Bray's staircase slide instead of
    topple, and block 4 hop off its base (a CI machine's BLAS kernels did the
    same).  The modes the limit state decides stay put."""
    import rockdem.confirmation as confirmation

    relax = confirmation.relax
    seen = []
    for eps in (0.0, 1e-12, 1e-9):

        def moved(system, state, f0, f1, start, *args, eps=eps, **kw):
            return relax(system, state, f0, f1, start * (1 + eps), *args, **kw)

        monkeypatch.setattr(confirmation, "relax", moved)
        names, decided = _modes(rd.factor_of_safety(staircase(), grow=1.3, width=0.002))
        seen.append(({n: names[n] for n in decided}, decided))
    assert seen[0][1] >= set(range(1, 5)) | {7, 8, 9, 11, 12, 13}, seen[0]
    assert seen[1] == seen[0] and seen[2] == seen[0], seen


@pytest.mark.xfail(
    strict=True,
    reason="the DEM's block 4 slides on its base at the limit (1-4 slide, 5-13 topple, "
    "14-16 stand: test_failure_modes_show_the_classic_toppling_pattern); Goodman & Bray's "
    "limit equilibrium, with the forces at the block corners, has it topple "
    "(test_dem_limiting_friction_is_goodman_and_brays)",
)
def test_dem_mechanism_is_goodman_and_brays_classes(limit):
    """Goodman & Bray's classes exactly: 1-3 slide, 4-13 topple, 14-16 stand."""
    modes = failure_modes(limit.failed_analysis)
    names = dict(zip(modes.ids.tolist(), modes.name.tolist(), strict=True))
    assert [n for n in range(1, 17) if names[n] == "slides"] == [1, 2, 3]
    assert [n for n in range(1, 17) if names[n] == "topples"] == list(range(4, 14))
    assert [n for n in range(1, 17) if names[n] == "stable"] == [14, 15, 16]


SCHEDULES = [(1.3, 0.005), (1.5, 0.005), (2.0, 0.01)]


def test_relaxation_mechanism_does_not_depend_on_round_off():
    """Damped explicit dynamics is chaotic in its detail: started from the last
    equilibrium moved by 1e-15 (relative), the run 2% beyond the limit moves
    Goodman & Bray's toe blocks by 3% or by 53% of the leading block over its
    last quarter (they stick and slip).  Read window by window over the last
    half, the moving blocks are 1-13 for every start, from the limit states
    of two schedules (the last quarter alone, or the last half as one
    stretch, each lost block 1 for one of these starts)."""
    from rockdem.mechanism import relaxation_mechanism
    from rockdem.relaxation import relax

    system = rd.build_system(staircase())
    free = ~system.blocks.fixed
    for grow, width in [(1.5, 0.002), (2.0, 0.01)]:
        limit = rd.factor_of_safety(system, grow=grow, width=width)
        lo = limit.stable_analysis
        q0 = np.zeros(system.assembly.n_dof)
        q0[system.assembly.dof[free].ravel()] = lo.displacement[free].ravel()
        beyond = 1.02 * limit.bracket[1]
        for eps in (0.0, 1e-15, 1e-12, 1e-9):
            start = q0 * (1 + eps)
            run = relax(system, lo.state.without_slip(), 1.0, beyond, start, extend=True)
            assert run.status == "mechanism", run
            moving = relaxation_mechanism(system, limit.failed_analysis, run).unstable_blocks
            assert sorted(moving.tolist()) == list(range(1, 14)), (grow, eps, moving)


def test_staircase_mechanism_is_the_same_for_any_schedule():
    """Issue 10: the moving blocks of the limit do not depend on the trial
    schedule (blocks 1-13 for grow 1.3, 1.5 and 2.0; the brackets differ
    slightly, 1.0137-1.0156, the continuation losing equilibrium where its
    path takes it)."""
    system = rd.build_system(staircase())
    sets = []
    for grow, width in SCHEDULES:
        fos = rd.factor_of_safety(system, grow=grow, width=width)
        sets.append(frozenset(fos.failed_analysis.unstable_blocks.tolist()))
    assert len(set(sets)) == 1, sets
    assert sets[0] == frozenset(range(1, 14))


def test_toppling_example_mechanism_is_the_same_for_any_schedule():
    """The bundled toppling example (Goodman & Bray columns at the paper's
    scale): the same moving blocks, the same mode per block and brackets that
    overlap, whatever the growth of the trial factor."""
    from rockdem.config import load_model
    from rockdem.examples import example_path

    system = rd.build_system(load_model(example_path("toppling"))[0])
    sets, codes, brackets = [], [], []
    for grow, width in SCHEDULES:
        fos = rd.factor_of_safety(system, grow=grow, width=width)
        failed = fos.failed_analysis
        sets.append(frozenset(failed.unstable_blocks.tolist()))
        codes.append(tuple(failure_modes(failed).code.tolist()))
        brackets.append(fos.bracket)
    assert len(set(sets)) == 1 and len(sets[0]) >= 10
    assert len(set(codes)) == 1
    assert max(b[0] for b in brackets) <= min(b[1] for b in brackets)


def columns(face: float, phi: float = 30.0) -> tuple[rd.Model, np.ndarray]:
    """The bundled example's toppling columns (20 columns 0.6 m wide, treads
    dipping 15 degrees, overall base 23, crest at column 7) with another face
    angle, built from Goodman & Bray's a1, a2, b; ids 1 (toe) to 20."""
    dx, psi, n = 0.6, 15.0, 20
    a1 = dx * np.tan(np.radians(face - psi))
    a2 = dx * np.tan(np.radians(psi))
    b = dx * np.tan(np.radians(23.0 - psi))
    y = stepped_heights(n, 7, a1, a2, b)
    joint = rd.Joint(normal_stiffness=1e5, friction_angle=phi)
    model = V.toppling_staircase(y, width=dx, step=b, base_dip=psi, joint=joint, unit_weight=2.6)
    le = toppling_fos(y, width=dx, step=b, base_dip=psi, base_friction=phi, unit_weight=2.6)
    return model, le


@pytest.mark.parametrize("grow", [1.5, 2.0])
def test_the_search_does_not_stop_at_a_newton_stall(grow):
    """With a 68-degree face Newton's method stalls at F = 0.449 although the
    columns are in equilibrium up to Goodman & Bray's 0.521: dynamic
    relaxation, continued while its unbalanced force keeps falling, finds
    the equilibria and the search goes on (it had reported 0.449, with a
    'confirmed' mechanism after 4,000 relaxation steps that were still
    settling)."""
    model, le = columns(68.0)
    fos = rd.factor_of_safety(model, grow=grow)
    assert fos.value == pytest.approx(le, rel=0.02)
    assert fos.failed_analysis.evidence.proof in {"lp-certificate", "dynamic-relaxation"}


def test_steep_face_columns_match_goodman_and_bray():
    """The columns with a 70, 72, 74 and 75 degree face: within 3% of Goodman &
    Bray (measured 0.474 / 0.4308 / 0.3923 / 0.374 against 0.4736 / 0.4310 /
    0.3924 / 0.3743).

    Path-sensitive, so watched: these verdicts were wrong by 17-33% at the
    last stop (the search stopped at a Newton stall and took the relaxation
    beyond it for the mechanism) and moved with round-off and with a weaker
    relaxation motion test (1x elastic: 70 degrees gave 0.319).  72 degrees
    came right when a from-scratch release that cannot reach zero at F
    resumes at F/2 from its last released state instead of starting again;
    74 degrees (0.316, -20%, "undecided") when a confirmation run that is
    undecided beyond the stall, like one that finds equilibrium there, sends
    the search on from where that run ended."""
    for face in (70.0, 72.0, 74.0, 75.0):
        model, le = columns(face)
        assert rd.factor_of_safety(model).value == pytest.approx(le, rel=0.03), face


@pytest.mark.parametrize(
    "face, flip, scale", [(70.0, -1.0, 1.0), (75.0, -1.0, 1.0), (75.0, 1.0, 10.0)]
)
def test_steep_face_columns_mirrored_or_ten_times_larger(face, flip, scale):
    """The same columns mirrored left to right, or ten times larger (kn / 10:
    the same limit, c = 0), so that only round-off and the search's path
    differ: still within 3% of Goodman & Bray.

    With a relaxation that took one segment of motion for a mechanism, a
    change of round-off in the stiffness sum moved 72 and 75 degrees to -17%
    and -21%, and the mirrored 70 degrees to -16%: the columns rocked 4x
    then 14x their elastic response and settled into equilibrium over five
    more segments.  Ten times larger, 75 degrees read 0.294 (-21%,
    "undecided") until an equilibrium found beyond a stall stopped counting
    against the search's three restarts: it stalls five times on the way up."""
    model, le = columns(face)
    b = model.blocks
    blocks = rd.Blocks.from_polygons(
        [b.outline(i) * np.array([flip * scale, scale]) for i in range(b.n_blocks)],
        fixed=b.fixed,
        unit_weight=2.6,
        ids=b.ids,
    )
    joint = rd.Joint(normal_stiffness=1e5 / scale, friction_angle=30)
    fos = rd.factor_of_safety(rd.Model(blocks, joint, settings=model.settings))
    assert fos.value == pytest.approx(le, rel=0.03)


def test_a_failure_confirmed_below_the_bracket_top_ends_the_bracket():
    """Goodman & Bray's staircase held at the toe by a 500 t/m strut parallel
    to the treads (at mid-height of the toe block's lower face), width 0.002.
    Dynamic relaxation, 2% beyond Newton's limit, neither settled nor moved;
    at 5% it moved.  The search went on from the 2% run, and the restart's
    own check found the blocks moving at that nearer factor: the bracket
    must end there.  It ended at the 5% factor, FS 1.4953 in [1.4587,
    1.5319], a value above a factor where failure was confirmed.  No trial
    with a failure that is proven or confirmed at its own factor may lie
    below the bracket's top; a bracket wider than the search's width ends
    where failure was confirmed, a narrow one below it.  (Since the
    relaxation's mass is the same in every unit system, the run 2% beyond
    Newton's limit moves: the bracket is Newton's, [1.4587, 1.4589], the
    failure confirmed at 1.4881.)"""
    from rockdem.stabilisation.measures import with_support

    p = np.radians(PSI)
    toe_height = stepped_heights(16, 10, 5.0, 5.2, STEP)[0]
    at = 0.5 * toe_height * np.array([np.sin(p), np.cos(p)])
    model = with_support(staircase(), at, 180.0 - PSI, 500.0)
    fos = rd.factor_of_safety(model, width=0.002)
    lo, hi = fos.bracket
    assert fos.proof in {"lp-certificate", "dynamic-relaxation"}
    top = fos.confirmed_upper_bound
    if hi - lo > 0.002 * (1 + 1e-9):  # widened to where the blocks moved
        assert top == hi, fos
    else:
        assert top is None or top >= hi, fos
    for trial in fos.trials:
        if trial.stable:
            assert trial.factor <= lo
        elif trial.evidence.proof in {"lp-certificate", "dynamic-relaxation"}:
            # a failure confirmed where the trial's own solve lost equilibrium
            at_factor = trial.evidence.confirmed_at or trial.evidence.failed_at or trial.factor
            assert at_factor >= hi * (1 - 1e-12), (trial, fos)


def test_an_unproven_toppling_limit_says_it_depends_on_the_spring_points(limit):
    """With friction and no dilatancy a toppling limit is not unique: on a
    14-column Goodman & Bray staircase (treads 25, base 30, face 55, phi 35;
    Goodman & Bray 0.9289) the DEM read 0.8593 to 0.9681 with 2 to 5 spring
    points of either rule, each confirmed by relaxation, none proven.  So the
    result says so wherever the limit is not proven and blocks topple (the
    JSON's warnings, printed by `rockdem fos`, and the trust statements); a
    proven sliding limit does not."""
    from rockdem.result_tables import fos_summary
    from rockdem.trust import trust_statements
    from rockdem.verification import block_on_plane

    assert limit.proof != "lp-certificate"
    doc = fos_summary(limit)
    caution = [w for w in doc["warnings"] if "a toppling limit is not unique" in w]
    assert len(caution) == 1 and "3 lobatto points" in caution[0]
    assert caution[0] in trust_statements(limit.stable_analysis, limit)
    sliding = rd.factor_of_safety(block_on_plane(35.0, rd.Joint(1e6, 30.0)))
    assert sliding.proof == "lp-certificate"
    assert not any("toppling" in w for w in fos_summary(sliding)["warnings"])
