"""Passive bolts and cables (rockdem.bolts) against closed forms.

Block on a plane held by one bolt at angle theta to the plane (Hoek & Bray,
Rock Slope Engineering, 3rd ed. 1981, ch. 7, reinforced plane failure; Wyllie
& Mah 2004, section 6.5): once the bolt carries T,

    FS = (c A + (W cos psi + T sin theta) tan phi) / (W sin psi - T cos theta).

At the limit the block slides, the bolt stretches and yields, so T is its
capacity: the steel's, or the grout bond beyond the joint when that is less.
"""

from __future__ import annotations

import numpy as np
import pytest

import rockdem as rd
from rockdem import verification as V
from rockdem.bolts import Bolt, bolt_results
from rockdem.errors import InputError
from rockdem.joints import Joint

PSI, PHI = 35.0, 30.0  # plane dip and friction: unbolted FS = tan30/tan35 = 0.8245
WIDTH, HEIGHT, GAMMA = 4.0, 1.0, 25.0
W = WIDTH * HEIGHT * GAMMA


def bolted_fos(T, theta, cohesion=0.0, psi=PSI, phi=PHI):
    p, s, t = np.radians([phi, psi, theta])
    resist = cohesion * WIDTH + (W * np.cos(s) + T * np.sin(t)) * np.tan(p)
    return resist / (W * np.sin(s) - T * np.cos(t))


def block_with_bolt(theta=30.0, cohesion=0.0, shift=(0.0, 0.0), **bolt):
    """The block's bolt runs from its top face, through the middle of its base,
    2 m into the plane, at ``theta`` to the plane and pointing up-dip."""
    # ductile cohesion (kept after yield), as limit equilibrium assumes
    joint = Joint(
        normal_stiffness=1e6, friction_angle=PHI, cohesion=cohesion, residual_cohesion=cohesion
    )
    m = V.block_on_plane(PSI, joint, width=WIDTH, height=HEIGHT, unit_weight=GAMMA)
    R = V._rot(-PSI)
    t = np.radians(theta)
    head = R @ np.array([WIDTH / 2 + HEIGHT * np.cos(t) / np.sin(t), HEIGHT]) + shift
    blocks = m.blocks
    if any(shift):
        blocks = rd.Blocks.from_polygons(
            [blocks.outline(i) + shift for i in range(blocks.n_blocks)],
            fixed=blocks.fixed,
            unit_weight=GAMMA,
        )
    args = dict(
        head=tuple(head),
        angle=180.0 + theta - PSI,
        length=HEIGHT / np.sin(t) + 2.0,
        capacity=30.0,
        axial_stiffness=1e4,
    )
    args.update(bolt)
    return m.replace(blocks=blocks, bolts=[Bolt(**args)])


@pytest.mark.parametrize(
    ("theta", "T", "cohesion"), [(30.0, 30.0, 0.0), (60.0, 30.0, 0.0), (40.0, 15.0, 2.0)]
)
def test_bolted_block_on_plane_matches_closed_form(theta, T, cohesion):
    fos = rd.factor_of_safety(block_with_bolt(theta, cohesion, capacity=T))
    exact = bolted_fos(T, theta, cohesion)
    assert fos.value == pytest.approx(exact, rel=0.005)
    # the failure beyond it is proven with the bolt at its capacity in the LP
    assert fos.failed_analysis.evidence.proof == "lp-certificate"


def test_bond_limits_the_capacity_by_the_length_beyond_the_joint():
    """2 m beyond the joint at 6 per unit length: 12 < the steel's 30."""
    fos = rd.factor_of_safety(block_with_bolt(30.0, bond_strength=6.0))
    assert fos.value == pytest.approx(bolted_fos(12.0, 30.0), rel=0.005)


def test_bolt_carries_what_equilibrium_needs_below_its_capacity():
    """At F = 1 the unbolted block slides (FS 0.82): the stretched bolt holds it
    with exactly the force limit equilibrium needs, and is not yielded."""
    model = block_with_bolt(30.0)
    an = rd.analyse(model)
    assert an.stable
    p, s, t = np.radians([PHI, PSI, 30.0])
    need = W * (np.sin(s) - np.cos(s) * np.tan(p)) / (np.cos(t) + np.sin(t) * np.tan(p))
    res = an.bolts
    assert res.n == 1
    assert res.axial_force[0] == pytest.approx(need, rel=1e-3)
    assert not res.yielded[0]
    assert res.utilisation[0] == pytest.approx(need / 30.0, rel=1e-3)


def test_pretension_acts_at_once_like_an_anchor_force():
    """A stiff-less pre-tensioned cable is a constant force: FS with T = P0."""
    model = block_with_bolt(30.0, pretension=20.0, axial_stiffness=1e-6, kind="cable")
    fos = rd.factor_of_safety(model)
    assert fos.value == pytest.approx(bolted_fos(20.0, 30.0), rel=0.005)


def _pointing_down_dip(model):
    """``block_with_bolt``'s model (theta 30) with its bolt line turned to
    point down-dip: through the base from the other side."""
    b = model.bolts[0]
    R = V._rot(-PSI)
    t = np.radians(30.0)
    head = R @ np.array([WIDTH / 2 - HEIGHT * np.cos(t) / np.sin(t), HEIGHT])
    return model.replace(bolts=[Bolt(**{**b.__dict__, "head": tuple(head), "angle": -30.0 - PSI})])


def test_cable_carries_no_compression():
    """Pointing down-dip, sliding shortens the cable: it adds nothing, FS = tan phi / tan psi."""
    fos = rd.factor_of_safety(_pointing_down_dip(block_with_bolt(30.0, kind="cable")))
    exact = np.tan(np.radians(PHI)) / np.tan(np.radians(PSI))
    assert fos.value == pytest.approx(exact, rel=0.005)


def test_spacing_divides_the_force_per_unit_width():
    """A 60-capacity bolt every 2 m equals a 30-capacity bolt every metre."""
    fos = rd.factor_of_safety(block_with_bolt(30.0, capacity=60.0, spacing=2.0))
    assert fos.value == pytest.approx(bolted_fos(30.0, 30.0), rel=0.005)


def test_translation_changes_nothing():
    """Moving the model and the bolt together by (1e5, -3e4) gives the same FS and force."""
    a = rd.factor_of_safety(block_with_bolt(30.0))
    b = rd.factor_of_safety(block_with_bolt(30.0, shift=(1e5, -3e4)))
    assert b.value == pytest.approx(a.value, rel=1e-6)
    fa = rd.analyse(block_with_bolt(30.0)).bolts.axial_force
    fb = rd.analyse(block_with_bolt(30.0, shift=(1e5, -3e4))).bolts.axial_force
    np.testing.assert_allclose(fb, fa, rtol=1e-6)


def test_bolt_results_report_every_crossing():
    model = block_with_bolt(30.0)
    system = rd.build_system(model)
    res = bolt_results(system.bolts, np.zeros(system.assembly.n_dof))
    assert res.n == 1
    assert res.depth[0] == pytest.approx(HEIGHT / np.sin(np.radians(30.0)), rel=1e-9)
    assert res.axial_force[0] == 0.0


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (dict(head=(50.0, 50.0)), "is not on the rock"),
        (dict(length=0.5), "crosses no joint"),
        (dict(capacity=-1.0), "capacity -1.0 is not positive"),
        (dict(pretension=40.0), "exceeds the capacity"),
        (dict(kind="rope"), "kind 'rope' is unknown"),
    ],
)
def test_bad_bolts_are_refused_with_a_reason(change, message):
    with pytest.raises(InputError, match=message):
        rd.build_system(block_with_bolt(30.0, **change))


# ------------------------------------------------- model file, command line
def test_bolted_example_holds_the_toppling_columns():
    """examples/bolted-slope.yaml states: stable, bolts below 20% of capacity,
    FS ~ 1.24 = tan30/tan25 (planar sliding of crest blocks 40, 45, 50), proven."""
    from rockdem.config import load_model
    from rockdem.examples import example_path

    model, _ = load_model(example_path("bolted-slope"))
    assert len(model.bolts) == 4
    an = rd.analyse(model)
    assert an.stable
    assert an.bolts.utilisation.max() < 0.2
    assert set(np.unique(an.bolts.name)) == {"B1", "B2", "B3", "B4"}
    fos = rd.factor_of_safety(model)
    planar = np.tan(np.radians(30)) / np.tan(np.radians(25))
    assert 1.22 < fos.value < 1.26
    assert fos.value == pytest.approx(planar, rel=0.005)
    assert fos.failed_analysis.evidence.proof == "lp-certificate"
    assert set(fos.failed_analysis.unstable_blocks) == {40, 45, 50}


def test_run_writes_the_bolt_table(tmp_path):
    import csv
    import json

    from typer.testing import CliRunner

    from rockdem.cli import app

    out = tmp_path / "res"
    res = CliRunner().invoke(app, ["run", "--example", "bolted-slope", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert "B1: crosses 8 joints" in res.output
    with (out / "bolts.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 29
    assert "axial_force [t]" in rows[0]
    doc = json.loads((out / "result.json").read_text())
    assert [b["bolt"] for b in doc["bolt_summary"]] == ["B1", "B2", "B3", "B4"]
    assert len(doc["bolts"]) == 29
    assert doc["column_units"]["bolts"]["axial_force"] == "t"


BOLTED_BOX = """
units: kN, m, kPa
joints:
  rock: {normal_stiffness: 1.0e+6, friction_angle: 30}
blocks:
  - {vertices: [[-5, -1], [5, -1], [5, 0], [-5, 0]], fixed: true}
  - {vertices: [[0, 0], [1, 0], [1, 1], [0, 1]], unit_weight: 25}
bolts:
  - {head: [0.5, 1.0], angle: 270, length: 2, capacity: 50, axial_stiffness: 1.0e+4}
"""


@pytest.mark.parametrize(
    ("change", "where", "message"),
    [
        ("length: 2", "bolts[0]:", "crosses no joint"),
        ("head: [0.5, 1.0]", "bolts[0]:", "is not on the rock"),
        ("capacity: 50", "bolts[0].capacity:", "-5 is out of range"),
        ("angle: 270", "bolts[0].kind:", "use 'bolt' or 'cable'"),
        # 1e-9 made the bolts 1e9 x stiffer than the joints: "no failure at any factor"
        ("axial_stiffness: 1.0e+4", "spacing", "far below the size of the blocks"),
    ],
)
def test_bad_bolt_in_a_file_is_one_line_and_exit_2(tmp_path, change, where, message):
    from typer.testing import CliRunner

    from rockdem.cli import EXIT_INPUT, app

    bad = {
        "length: 2": "length: 0.5",
        "head: [0.5, 1.0]": "head: [3.0, 4.0]",
        "capacity: 50": "capacity: -5",
        "angle: 270": "angle: 270, kind: rope",
        "axial_stiffness: 1.0e+4": "axial_stiffness: 1.0e+4, spacing: 1.0e-9",
    }[change]
    path = tmp_path / "m.yaml"
    path.write_text(BOLTED_BOX.replace(change, bad))
    res = CliRunner().invoke(app, ["run", str(path)])
    assert res.exit_code == EXIT_INPUT
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1, res.output
    assert where in lines[0] and message in lines[0]


def test_pictures_and_report_show_the_bolts(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from rockdem import plots
    from rockdem.report import write_report

    an = rd.analyse(block_with_bolt(30.0))
    ax = plots.plot_failure(an)
    assert any(c.get_gid() == "bolts" for c in ax.collections)
    dots = [c for c in ax.collections if c.get_gid() == "bolt-crossings"]
    assert len(dots) == 1 and len(dots[0].get_offsets()) == 1
    model_ax = plots.plot_model(an.system.model)
    assert any(c.get_gid() == "bolts" for c in model_ax.collections)
    path = write_report(an.system.model, tmp_path, analysis=an, compute_fos=False, animation=False)
    html = path.read_text()
    assert "<h3>Bolts at F = 1</h3>" in html and 'class="bolts"' in html


# ------------------------------------------------------------ bolt pattern design
def test_bolt_pattern_reaches_the_target_with_the_widest_spacing():
    """perpendicular-joints (FS 0.90): rows on the mechanism's face reach 1.1;
    the spacing found holds at the target and the next wider one tried does not."""
    from rockdem.config import load_model
    from rockdem.examples import example_path
    from rockdem.stabilisation.bolting import bolt_pattern
    from rockdem.stabilisation.removal import stable_at

    model, _ = load_model(example_path("perpendicular-joints"))
    p = bolt_pattern(model, 1.1, capacity=2.0, axial_stiffness=1e4)
    assert p.spacing is not None and p.fos.value >= 1.1
    assert stable_at(p.model, 1.1)
    lo_bad = p.bracket[0]
    if np.isfinite(lo_bad):  # a wider spacing was tried and fell short
        wider = model.replace(bolts=[Bolt(**{**b.__dict__, "spacing": lo_bad}) for b in p.bolts])
        assert not stable_at(wider, 1.1)
    # every bolt passes through the moving rock and anchors beyond it
    assert all(b.length > 1.0 for b in p.bolts)


def test_measures_compare_a_bolt_pattern():
    from rockdem.config import load_model
    from rockdem.examples import example_path
    from rockdem.stabilisation import compare_measures

    model, _ = load_model(example_path("perpendicular-joints"))
    c = compare_measures(
        model, 1.1, bolting=dict(capacity=20, axial_stiffness=1e4), support=False, removal=False
    )
    kinds = [r["kind"] for r in c.rows()]
    assert kinds == ["none", "bolts"]
    bolt_row = c.rows()[1]
    assert bolt_row["reaches_target"] and bolt_row["factor_of_safety"] >= 1.1
    assert "rows of bolts" in bolt_row["note"]


def test_the_load_step_a_bolt_first_yields_is_recorded(tmp_path):
    """Two bolts side by side, capacities 3 and 30: they share the force the
    block needs, 8.71 x the load factor (4.36 each) until the weak one yields
    at load factor 3 / 4.36 = 0.69, in load step 4 of 5; the strong one
    holds.  The bolt table (bolts.csv) carries the step."""

    from rockdem.result_tables import analysis_tables

    model = block_with_bolt(30.0, capacity=3.0, name="weak")
    strong = Bolt(**{**model.bolts[0].__dict__, "capacity": 30.0, "name": "strong"})
    model = model.replace(bolts=[*model.bolts, strong], settings=rd.Settings(load_steps=5))
    an = rd.analyse(model)
    assert an.stable
    res = an.bolts
    assert list(res.name) == ["weak", "strong"]
    assert list(res.first_yield) == [4, -1]
    rows = analysis_tables(an)["bolts"]
    assert [r["first_yield"] for r in rows] == [4, -1]


def test_a_bolt_longer_than_the_model_is_cut_at_the_model():
    """A 1e9-long bolt (the file format's largest length) behaves as one that
    passes through everything below its head."""
    short = rd.factor_of_safety(block_with_bolt(30.0))
    long = rd.factor_of_safety(block_with_bolt(30.0, length=1e9))
    assert long.value == pytest.approx(short.value, rel=1e-3)


def test_a_row_spacing_that_would_put_millions_of_bolts_on_the_face_is_refused():
    """stabilise ran for minutes on row_spacing 1e-6 (4.8 million rows)."""
    from rockdem.config import load_model
    from rockdem.examples import example_path
    from rockdem.stabilisation.bolting import MAX_ROWS, face_rows

    model, _ = load_model(example_path("inclined-layers"))
    free = [int(i) for i in model.blocks.ids[~model.blocks.fixed]]
    assert 1 <= len(face_rows(model, free, row_spacing=1.0)) <= MAX_ROWS
    with pytest.raises(rd.InputError, match="row_spacing"):
        face_rows(model, free, row_spacing=1e-6)


def test_a_bolt_key_the_engine_refuses_is_named_by_its_path():
    """Found by fuzzing: an unnamed bolt's tiny spacing was reported as
    "slope: bolts bolts[0] spacing ..."; it is `bolts[0].spacing`."""
    from rockdem.config import ModelFileError, parse_model
    from rockdem.examples import example_path

    text = example_path("bolted-slope").read_text()
    text = text.replace("{name: B1, ", "{", 1).replace("spacing: 1.5}", "spacing: 1.0e-9}", 1)
    with pytest.raises(ModelFileError) as info:
        parse_model(text, source="b.yaml")
    assert info.value.key == "bolts[0].spacing"
    assert "is far below the size of the blocks" in str(info.value)


def test_a_bolt_far_stiffer_than_the_joint_it_crosses_is_refused(tmp_path):
    """Found by fuzzing: a bolt of axial stiffness 1e13 across 1e6-stiff
    joints (5e6 x) on a flat two-block stack, which cannot fail, read
    "strength-independent failure"; on the block on a plane 2.5e5 x read
    1.771 and 2.5e6 x 1.50 against the closed form 1.7833.  Up to the limit,
    1e4 x, the closed form holds."""
    from rockdem.bolt_placement import BOLT_STIFFNESS_CONTRAST_MAX
    from rockdem.config import ModelFileError, parse_model

    stiff = 2.5e3 * 1e6 * WIDTH  # 2,500 x the 4 m base's kn x length
    fos = rd.factor_of_safety(block_with_bolt(30.0, axial_stiffness=stiff, shear_stiffness=stiff))
    assert fos.value == pytest.approx(bolted_fos(30.0, 30.0), rel=0.005)
    for key in ("axial_stiffness", "shear_stiffness"):
        too_stiff = 2 * BOLT_STIFFNESS_CONTRAST_MAX * 1e6 * WIDTH
        with pytest.raises(InputError, match=f"bolts {key}: .* times as stiff as the joint"):
            rd.factor_of_safety(block_with_bolt(30.0, **{key: too_stiff}))
    text = BOLTED_BOX.replace("1.0e+4}", "1.0e+13}")
    with pytest.raises(ModelFileError) as info:
        parse_model(text, source="b.yaml")
    assert info.value.key == "bolts[0].axial_stiffness"
    # the limit: 1e4 x kn x the interface's length, at least the blocks' mean size
    # (here sqrt((10 + 1) / 2) = 2.35 m, over the 1 m interface)
    assert "give axial_stiffness: 2.35e+10 or less" in str(info.value)


def _stack(*bolts):
    """Two 4 x 2 blocks stacked on fixed ground, kh 0.3 (found by fuzzing)."""
    blocks = rd.Blocks.from_polygons(
        [
            [(-5, -1), (9, -1), (9, 0), (-5, 0)],
            [(0, 0), (4, 0), (4, 2), (0, 2)],
            [(0, 2), (4, 2), (4, 4), (0, 4)],
        ],
        fixed=[True, False, False],
        unit_weight=25.0,
    )
    joint = Joint(normal_stiffness=1e6, friction_angle=20)
    return rd.Model(blocks, joint, loads=rd.Loads(seismic_h=0.3), bolts=list(bolts))


@pytest.mark.parametrize(
    ("bolt", "words"),
    [
        # from the top, out through the corner (4, 2) into the air: it held
        # the upper block as if anchored in the lower one, FS 2.797 for 1.213
        (dict(head=(2, 4), angle=-45, length=np.hypot(2, 2) * 1.5), "crosses no joint"),
        # down the free face x = 4, in no rock: it pushed, FS 1.173
        (dict(head=(4, 3), angle=270, length=2.0), "crosses no joint"),
        # the head 1 m inside the upper block, not on a face: FS 1.184
        (dict(head=(2, 3), angle=270, length=2.0), "inside the rock"),
    ],
)
def test_a_bolt_out_of_the_rock_or_headed_inside_it_is_refused(bolt, words):
    plain = rd.factor_of_safety(_stack())
    assert plain.value == pytest.approx(np.tan(np.radians(20)) / 0.3, rel=0.005)
    model = _stack(Bolt(capacity=100.0, axial_stiffness=1e5, **bolt))
    with pytest.raises(rd.InputError, match=words):
        rd.factor_of_safety(model)
    # a bolt from the top through both joints into the ground is taken
    down = _stack(Bolt(head=(2, 4), angle=270, length=5.0, capacity=100.0, axial_stiffness=1e5))
    assert rd.factor_of_safety(down).value is not None


def test_a_bolt_shortened_by_the_sliding_is_reported_in_compression():
    """A bolt pointing down-dip (the flipped bolt of the cable test) is
    shortened as the block slides: its force is compression, reported with
    its magnitude and the word, not as the "largest" of signed forces (a
    compression at capacity read as the largest force -99 kN)."""
    from rockdem.result_tables import bolt_summary

    model = _pointing_down_dip(block_with_bolt(30.0))
    b = model.bolts[0]
    fos = rd.factor_of_safety(model)
    (row,) = bolt_summary(fos.stable_analysis)
    assert row["max_axial_force"] < -0.5 * b.capacity  # near its capacity, pushing
    # of a bolt's crossings, the force of largest magnitude, with its sign
    from types import SimpleNamespace

    crossings = SimpleNamespace(
        name=np.array(["B", "B"]),
        axial_force=np.array([3.0, -29.0]),
        utilisation=np.array([0.1, 0.97]),
        yielded=np.array([False, False]),
        first_yield=np.array([-1, -1]),
    )
    (row,) = bolt_summary(SimpleNamespace(bolts=crossings))
    assert row["max_axial_force"] == -29.0 and row["max_utilisation"] == 0.97


def test_the_bolt_line_says_tension_or_compression(capsys):
    from rockdem.cli.analyses import _print_bolts

    doc = {
        "unit_system": {"force": "kN"},
        "bolt_summary": [
            dict(bolt="P", crossings=2, max_axial_force=-99.28, max_utilisation=0.99,
                 yielded_crossings=0, first_yield=None),
            dict(bolt="T", crossings=1, max_axial_force=12.5, max_utilisation=0.125,
                 yielded_crossings=0, first_yield=None),
            dict(bolt="Z", crossings=1, max_axial_force=0.0, max_utilisation=0.0,
                 yielded_crossings=0, first_yield=None),
        ],
    }  # fmt: skip
    _print_bolts(doc, "bolt_summary", "bolts")
    said = capsys.readouterr().out
    assert "P: crosses 2 joints, largest axial force 99.28 kN compression (99% of capacity)" in said
    assert "T: crosses 1 joint, largest axial force 12.5 kN tension (12% of capacity)" in said
    assert "Z: crosses 1 joint, no axial force (0% of capacity)" in said


# ------------------------------------------------- installed after the loads
def _stable_block_with_bolt(**bolt):
    """The bolted block of ``block_with_bolt`` on a 20 degree plane (phi 30:
    stable unbolted, FS = tan30/tan20 = 1.586), its bolt at 30 degrees to it."""
    joint = Joint(normal_stiffness=1e6, friction_angle=PHI)
    m = V.block_on_plane(20.0, joint, width=WIDTH, height=HEIGHT, unit_weight=GAMMA)
    R, t = V._rot(-20.0), np.radians(30.0)
    head = R @ np.array([WIDTH / 2 + HEIGHT * np.cos(t) / np.sin(t), HEIGHT])
    args = dict(
        head=tuple(head),
        angle=180.0 + 30.0 - 20.0,
        length=HEIGHT / np.sin(t) + 2.0,
        capacity=30.0,
        axial_stiffness=1e4,
    )
    return m.replace(bolts=[Bolt(**{**args, **bolt})])  # fmt: skip


def test_a_bolt_installed_after_the_loads_carries_none_of_them():
    """In from the start, the bolt shares the block's settlement under its
    weight; installed in the slope standing under it, it carries nothing
    (only a pretension it is locked off at), and resists only what moves
    after: at the limit it reaches its capacity either way, so the factor
    of safety is Hoek & Bray's with T = 30 (Wyllie & Mah 2004, eq. 6.23)."""
    before = rd.analyse(_stable_block_with_bolt())
    after = rd.analyse(_stable_block_with_bolt(installed="after_loads"))
    assert before.stable and after.stable
    assert np.max(np.abs(before.bolts.axial_force)) > 1e-3  # the settlement loads it
    assert np.all(after.bolts.axial_force == 0) and np.all(after.bolts.shear_force == 0)
    assert np.all(after.bolts.extension == 0)
    locked = rd.analyse(_stable_block_with_bolt(installed="after_loads", pretension=10.0))
    assert locked.bolts.axial_force == pytest.approx([10.0], rel=0.02)
    p, s, t = np.radians([PHI, 20.0, 30.0])
    exact = (W * np.cos(s) + 30 * np.sin(t)) * np.tan(p) / (W * np.sin(s) - 30 * np.cos(t))
    fos = rd.factor_of_safety(_stable_block_with_bolt(installed="after_loads"))
    assert fos.value == pytest.approx(exact, rel=0.005)


def test_a_bolt_to_go_in_after_loads_the_slope_cannot_carry_is_never_installed():
    """The block on 35 degrees (phi 30) slides under its weight before the
    bolt goes in: the analysis says so, naming the bolt."""
    model = block_with_bolt(30.0, installed="after_loads", name="B7")
    with pytest.warns(rd.ModelWarning, match=r"bolts B7 \(installed: after_loads\) were never"):
        a = rd.analyse(model)
    assert not a.stable
    assert rd.analyse(block_with_bolt(30.0, name="B7")).stable  # in from the start, it holds
    # the factor of safety is the unbolted slope's, and says why (it read 0.9986:
    # the bolt installed in a stronger trial slope that stands, found in review)
    with pytest.warns(rd.ModelWarning, match="B7 .* were never installed"):
        fos = rd.factor_of_safety(model)
    unbolted = np.tan(np.radians(PHI)) / np.tan(np.radians(PSI))
    assert fos.value == pytest.approx(unbolted, rel=0.005)
    # nor do Sarma's bodies carry it, or its pretension (they read 1.527)
    from rockdem.limit_equilibrium import sarma

    tensioned = block_with_bolt(30.0, installed="after_loads", name="B7", pretension=25.0)
    with pytest.warns(rd.ModelWarning, match="never installed"):
        failed = rd.analyse(tensioned)
    assert sarma(failed).fos == pytest.approx(unbolted, rel=0.005)


def test_the_failure_picture_of_a_search_shows_the_bolts_at_the_limit():
    """The factor of safety's failure picture coloured the bolt crossings by
    the failed trial's own start (the gravity state: a bolt at 99% of its
    capacity at the limit was drawn at 14%); it shows them at the last
    equilibrium below the limit, as `rockdem fos` lists them."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import colormaps

    from rockdem import plots
    from rockdem.plots.bolts import UTILISATION_CMAP

    fos = rd.factor_of_safety(block_with_bolt(30.0))
    at_limit = fos.stable_analysis.bolts.utilisation
    assert at_limit[0] > 0.9 and fos.failed_analysis.bolts.utilisation[0] < 0.9 * at_limit[0]
    ax = plots.plot_failure(fos)
    (dots,) = [c for c in ax.collections if c.get_gid() == "bolt-crossings"]
    expected = colormaps[UTILISATION_CMAP](np.clip(at_limit, 0, 1))
    assert dots.get_facecolors()[:, :3] == pytest.approx(expected[:, :3])


def test_a_pretension_that_leaves_no_equilibrium_leaves_the_bolt_out(monkeypatch):
    """Locking off the pretension of a bolt put in after the loads re-solves
    the equilibrium; where there is none (forced here), the bolt is not
    installed and the analysis says so, instead of reporting the bolt at
    its pretension on blocks that are not in equilibrium with it."""
    from dataclasses import replace

    from rockdem import analysis

    settle = analysis.settle

    def no_equilibrium_once_installed(system, state, *args, **kwargs):
        sol, new = settle(system, state, *args, **kwargs)
        if state.bolt_reference is not None and not state.bolts_waiting:
            return replace(sol, converged=False), state
        return sol, new

    monkeypatch.setattr(analysis, "settle", no_equilibrium_once_installed)
    model = _stable_block_with_bolt(installed="after_loads", pretension=10.0, name="P1")
    with pytest.warns(rd.ModelWarning, match="bolts P1 .* were not installed: locking off"):
        a = rd.analyse(model)
    assert a.stable and a.state.bolts_waiting and np.all(a.bolts.axial_force == 0)
