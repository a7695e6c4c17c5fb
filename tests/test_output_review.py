"""What an engineer reads off the outputs: the same number the same everywhere,
units stated, words that say what they mean (an output review, round ux6)."""

from __future__ import annotations

import re

import matplotlib

matplotlib.use("Agg")

import pytest

import rockdem as rd
from rockdem import plots
from rockdem.config import load_model
from rockdem.examples import example_path

# rockdem.loads calls shapely.line_interpolate_point(g, 0.5, True): deprecated in
# shapely 2.1 (as in tests/test_plots.py)
pytestmark = pytest.mark.filterwarnings(
    "ignore:positional argument `normalized`:DeprecationWarning"
)


@pytest.fixture(scope="module")
def water_model():
    return load_model(example_path("plane-failure-water"))[0]


@pytest.fixture(scope="module")
def water_fos(water_model):
    return rd.factor_of_safety(water_model)


def test_fos_plot_title_shows_the_bracket_apart(water_fos):
    """The search picture's title read "Factor of safety 1.107 in [1.107,
    1.107]": a bracket of width 0.0005 at three decimals.  It now has the
    decimals `rockdem fos` prints (1.10693, 1.10742)."""
    lo, hi = water_fos.bracket
    assert hi - lo < 1e-3
    title = plots.plot_fos(water_fos, recompute=False).get_title()
    assert f"{lo:.5f}" in title and f"{hi:.5f}" in title
    assert f"{water_fos.value:.4f}" in title


def test_fos_plot_legend_names_the_factor_of_safety(water_fos):
    ax = plots.plot_fos(water_fos, recompute=False)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "factor of safety" in labels and "F of S" not in labels


def test_fos_plot_title_of_an_undecided_top_says_at_least(water_fos):
    """Where nothing proved or confirmed the failure above the stable end,
    `rockdem fos` says "at least"; the picture said a plain value in a bracket."""
    from dataclasses import replace

    from rockdem.results import Evidence

    stall = Evidence(reason="stalled", iterations=40, residuals=(1e-3,))
    failed = water_fos.failed_analysis
    steps = (*failed.steps[:-1], replace(failed.steps[-1], evidence=stall))
    undecided = replace(water_fos, failed_analysis=replace(failed, steps=steps))
    assert undecided.proof == "undecided"
    title = plots.plot_fos(undecided, recompute=False).get_title()
    assert "at least" in title and "undecided" in title


def test_report_says_the_stresses_of_a_failed_gravity_step_are_at_its_load_factor(tmp_path):
    """inclined-layers fails in the first of 5 load steps: the report's table
    "Joints at F = 1" showed the last iterate's stresses at load factor 0.2
    (a fifth of the gravity stresses) and did not say so."""
    import re

    from rockdem.report import write_report

    model = load_model(example_path("inclined-layers"))[0]
    a = rd.analyse(model)
    assert not a.stable and a.steps[-1].load_factor == pytest.approx(0.2)
    path = write_report(model, tmp_path, analysis=a, compute_fos=False, animation=False)
    text = re.sub(r"\s+", " ", path.read_text(encoding="utf-8"))
    head = text.index("<h3>Joints at F = 1: state now")
    note = text[head : text.index("<table", head)]
    assert "last iterate of the failed step (at load factor 0.2, not the full load" in note


def test_report_inputs_state_units_water_and_per_metre(tmp_path, water_model, water_fos):
    """The report's input tables gave kn, ks, c, tensile strength without a
    unit, left out the water table of a model with water, and nowhere said
    that a 2-D section's forces are per metre of slope."""
    import re

    from rockdem.report import write_report

    path = write_report(
        water_model,
        tmp_path,
        fos=water_fos,
        units="kN, m, kPa (angles in degrees)",
        animation=False,
    )
    text = re.sub(r"\s+", " ", path.read_text(encoding="utf-8"))
    inputs = text[text.index('id="inputs"') :]
    for head in ("kn (kPa/m)", "ks (kPa/m)", "c (kPa)", "tensile (kPa)", "c res. (kPa)"):
        assert head in inputs, head
    assert "water table" in inputs and "(-12, 10) - (0, 0)" in inputs
    assert "9.81 kN/m^3" in inputs
    assert "per m of slope perpendicular to the section" in inputs


def test_le_prints_the_bracket_apart_and_the_face_length_unit():
    """`rockdem le` printed the wedge's bracket as "0.9786 - 0.9786" and the
    faces' length column without its unit (N and S had theirs)."""
    from typer.testing import CliRunner

    from rockdem.cli import app

    r = CliRunner().invoke(app, ["le", "--example", "wedge-verification"])
    assert r.exit_code == 0, r.output
    model, cfg = load_model(example_path("wedge-verification"))
    lo, hi = rd.factor_of_safety(model, width=cfg.analysis.strength_reduction.width).bracket
    # (the case: a bracket of 1e-4 or less, four decimals barely tell apart)
    assert hi - lo < 1e-4 and f"{lo:.6f}" != f"{hi:.6f}"
    assert f"(bracket {lo:.6f} - {hi:.6f})" in r.stdout
    assert "length m" in r.stdout and "N t" in r.stdout


def test_report_le_faces_table_has_units(water_fos):
    """The report's Sarma face table headed length, N and S with no unit."""
    from rockdem.limit_equilibrium.report import html_section
    from rockdem.units import parse_units

    text = "".join(html_section(water_fos, parse_units("kN, m, kPa")))
    for head in ("length (m)", "N (kN)", "S (kN)"):
        assert f"<th>{head}</th>" in text, head


def test_trust_statement_shows_the_bracket_ends_apart(water_model, water_fos):
    """The report's first trust line read "equilibrium was found at F = 0.7299
    and lost at F = 0.7299 ... (+-0.0000)" for the toppling example's bracket
    0.729858 - 0.729919: four decimals whatever the width."""
    from rockdem.results import bracket_decimals
    from rockdem.trust import trust_statements

    lo, hi = water_fos.bracket
    d = bracket_decimals(lo, hi)
    assert f"{lo:.{d}f}" != f"{hi:.{d}f}" and f"{lo:.{d - 1}f}" != f"{hi:.{d - 1}f}"
    first = trust_statements(rd.analyse(water_model), water_fos)[0]
    assert f"found at F = {lo:.{d}f} and lost at F = {hi:.{d}f}" in first, first
    assert f"(+-{(hi - lo) / 2:.1g})" in first


def test_unstable_blocks_table_explains_the_mechanism_columns():
    from rockdem.report_tables import unstable_table

    a = rd.analyse(load_model(example_path("wedge-verification"))[0])
    text = unstable_table(a, 10)
    assert "mech. ux" in text and "largest block motion is 1" in text
    assert "counter-clockwise positive" in text


def test_stabilise_table_says_accepted_is_not_an_approval(monkeypatch):
    """`rockdem stabilise` marked "slope as it is" (FS 1.106, target 1.3)
    "design: accepted" with no word on what that means."""
    import io

    from rich.console import Console

    import rockdem.cli
    from rockdem.cli_stabilise import print_summary
    from rockdem.units import parse_units

    doc = {
        "model_name": "slope",
        "model_file": "slope.yaml",
        "target_fos": 1.3,
        "reached": False,
        "message": "block removal stopped",
        "needs": "",
        "removal": [
            {
                "trial": 0,
                "label": "slope as it is",
                "blocks_removed": [],
                "area_removed": 0.0,
                "fos_text": "1.106",
                "reaches_target": False,
                "accepted": True,
            }
        ],
        "measures": [],
        "designs": [],
    }
    buf = io.StringIO()
    monkeypatch.setattr(
        rockdem.cli, "out", Console(file=buf, width=200, highlight=False, soft_wrap=True)
    )
    print_summary(doc, parse_units("kN, m, kPa"))
    assert "accepted = the next round starts from it" in buf.getvalue()


def test_stabilise_says_its_fos_bracket_is_coarser_than_rockdem_fos():
    """plane-failure-water: `rockdem stabilise` printed "slope as it is ...
    1.106" and `rockdem fos` 1.1072 for the same slope, with no word on why
    (the study rates every design to a bracket 0.01 wide, the file asks 0.002)."""
    from typer.testing import CliRunner

    from rockdem.cli import app

    r = CliRunner().invoke(
        app, ["stabilise", "--example", "plane-failure-water", "--no-support", "-q"]
    )
    assert r.exit_code == 0, r.output
    text = " ".join(r.stdout.split())
    # the slope as it is, rated to the study's bracket: Hoek & Bray's 1.107
    # within half of it
    as_it_is = re.search(r"slope as it is 0 0 (\d\.\d+)", text)
    assert as_it_is and abs(float(as_it_is.group(1)) - 1.107) <= 0.005
    assert "bracket 0.01 wide; `rockdem fos` narrows it to 0.002" in text


def test_with_water_the_normal_stress_is_labelled_effective(water_fos):
    """plane-failure-water: the springs carry the effective stress (interface 0:
    884 kN = W cos psi - U - V sin psi, Hoek & Bray's N'), but the stress
    picture and the report's joint table said "normal stress" / "σ"."""
    from html import unescape

    from rockdem.report_tables import failed_table

    a = water_fos.stable_analysis
    ax = plots.plot_joint_stress(a, stress_unit="kPa").axes[1]
    assert ax.get_ylabel() == "σ' (kPa)"
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "effective normal stress (compression +)" in labels
    assert "σ' mean (kPa)" in unescape(failed_table(a, "kPa", 10))
    dry = rd.analyse(load_model(example_path("wedge-verification"))[0])
    assert "σ mean (t/m^2)" in failed_table(dry, "t/m^2", 10)


def test_stabilise_warns_where_a_design_s_mechanism_reaches_the_model_boundary():
    """perpendicular-joints: round 2 reads FS 13.777 ("REACHED") for the whole
    remaining mass sliding along the fixed back and base of the model; the
    trial's picture marked it, the console and stabilisation.json did not."""
    import json

    from typer.testing import CliRunner

    from rockdem.cli import app

    args = ["stabilise", "--example", "perpendicular-joints", "--no-support", "-q"]
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 0, r.output
    text = " ".join(r.stdout.split())
    assert "warning: trial 2 (FS 13.777): the mechanism reaches the fixed" in text
    doc = json.loads(CliRunner().invoke(app, [*args, "--json"]).stdout)
    rows = {row["trial"]: row for row in doc["removal"]}
    assert "base boundary" in rows[2]["boundary"]
    assert rows[0]["boundary"] == ""


def test_stabilise_one_moving_block_is_not_plural():
    """plane-failure-water: "removing the 1 moving blocks would take 100% of
    the rock"."""
    from typer.testing import CliRunner

    from rockdem.cli import app

    r = CliRunner().invoke(
        app, ["stabilise", "--example", "plane-failure-water", "--no-support", "-q"]
    )
    text = " ".join(r.stdout.split())
    assert "removing the moving block would take 100% of the rock" in text
    assert "the 1 moving blocks" not in text


@pytest.mark.parametrize("draw", ["plot_failure", "plot_model", "plot_deformed"])
def test_map_pictures_keep_their_axis_labels_inside_the_figure(draw):
    """The wedge's failure picture (legend outside on the right, a tall
    equal-aspect map) had "y (m)" cut off at its left edge (x0 = -3.9 px)."""
    a = rd.analyse(load_model(example_path("wedge-verification"))[0])
    ax = getattr(plots, draw)(a)
    import io

    fig = ax.figure
    fig.savefig(io.BytesIO(), format="png", dpi=100)  # lays it out as the report does
    r = fig._get_renderer()
    width, height = fig.bbox.width, fig.bbox.height
    for label in (ax.yaxis.label, ax.xaxis.label, ax.title):
        bb = label.get_window_extent(r)
        assert bb.x0 >= 0 and bb.y0 >= 0, (label.get_text(), bb)
        assert bb.x1 <= width and bb.y1 <= height, (label.get_text(), bb)


def test_report_stress_picture_follows_the_slip_surface_of_the_failure(
    tmp_path, water_model, water_fos
):
    """plane-failure-water: the stress picture at F = 1 drew the only joint
    failed there, the open tension crack (all zeros), not the plane the block
    slides on at the factor of safety."""
    import re

    from rockdem.report import write_report

    path = write_report(water_model, tmp_path, fos=water_fos, units="kN, m, kPa", animation=False)
    text = re.sub(r"\s+", " ", path.read_text(encoding="utf-8"))
    F = rd.results.format_factor(water_fos.failed_analysis.strength_factor)
    assert f"along the slip surface of the failure (found at F = {F}), stresses at F = 1;" in text


def test_progressive_frame_of_a_failed_trial_says_where_equilibrium_was_lost(water_fos):
    """plane-failure-water: the last progressive frame read "F = 1.5000 (no
    equilibrium)" and drew the state at F = 1.1074, where the trial lost it."""
    last = plots.frames(water_fos)[-1]
    lost = rd.results.format_factor(water_fos.failed_analysis.strength_factor)
    # (equilibrium is lost at the top of the search's bracket, not at 1.5)
    assert not last.converged and lost == rd.results.format_factor(water_fos.bracket[1])
    assert last.label == f"step 2: load x1, F = 1.5000 tried (no equilibrium; lost at {lost})"


def test_run_says_the_written_stresses_of_a_failed_step_are_its_last_iterate(tmp_path):
    """inclined-layers fails in load step 1 of 5: `rockdem run --out` wrote the
    last iterate's stresses (load factor 0.2) to interfaces.csv and springs.csv
    with nothing saying so."""
    import json

    from typer.testing import CliRunner

    from rockdem.cli import app

    r = CliRunner().invoke(app, ["run", "--example", "inclined-layers", "--out", str(tmp_path)])
    assert r.exit_code == 0, r.output
    said = "the last iterate of the failed step (load factor 0.2, not the full load)"
    assert said in " ".join(r.stderr.split())
    assert said in json.loads((tmp_path / "result.json").read_text())["stresses_note"]


def test_check_says_forces_are_per_metre_of_slope():
    from typer.testing import CliRunner

    from rockdem.cli import app

    r = CliRunner().invoke(app, ["check", "--example", "plane-failure-water"])
    assert r.exit_code == 0, r.output
    assert "2-D section: forces and weights per m of slope" in " ".join(r.stdout.split())


def test_le_explains_a_negative_critical_acceleration():
    """inclined-layers: "Kc = -0.0875 g" (= tan(30 - 35), the layers slide at
    full strength) was printed without a word on what negative means.  (Its
    mechanism is now the limit state's, two rigid bodies on two sliding
    faces, where Sarma's method has no single factor; the wedge, FS 0.9786
    < 1, has a negative Kc as well.)"""
    from typer.testing import CliRunner

    from rockdem.cli import app

    r = CliRunner().invoke(app, ["le", "--example", "wedge-verification"])
    assert r.exit_code == 0, r.output
    text = " ".join(r.stdout.split())
    assert re.search(r"Kc = -0\.0\d\d\d g", text), text
    assert "negative: the blocks slide at full strength even without one" in text


def test_trust_does_not_say_not_proven_after_giving_the_lp_proof():
    """bedded-slope: the trust list said "proven from F = 1.2097 (LP)" and two
    lines on "The failure is confirmed, not proven": it is the top of the
    bracket (1.1963) that is only confirmed."""
    from rockdem.trust import trust_statements

    fos = rd.factor_of_safety(load_model(example_path("bedded-slope"))[0])
    assert fos.proof == "dynamic-relaxation" and fos.certified_upper_bound is not None
    lines = trust_statements(fos.stable_analysis, fos)
    assert not any(line.startswith("The failure is confirmed, not proven") for line in lines)
    top = f"At the top of the bracket (F = {fos.bracket[1]:.4f}) the failure is confirmed, not"
    assert any(line.startswith(top) for line in lines), lines


def test_le_names_a_block_that_slides_and_topples_as_the_dem_does():
    """bolted-slope: the DEM's tables say block 45 "slides and topples"; `rockdem
    le` said "block(s) 45 topple"."""
    from typer.testing import CliRunner

    from rockdem.cli import app

    r = CliRunner().invoke(app, ["le", "--example", "bolted-slope"])
    assert r.exit_code == 0, r.output
    text = " ".join(r.stdout.split())
    assert "the mechanism rotates: block(s) 45 slide and topple;" in text


def test_report_joint_stiffness_unit_in_force_length_units(tmp_path):
    """A "t, m, t/m^2" model's stiffness header read "kn (t/m^2/m)"."""
    from rockdem.report import write_report

    model = load_model(example_path("wedge-verification"))[0]
    path = write_report(model, tmp_path, units="t, m, t/m^2", compute_fos=False, animation=False)
    text = path.read_text(encoding="utf-8")
    assert "kn (t/m^3)" in text and "c (t/m^2)" in text and "t/m^2/m" not in text


def test_fos_tables_give_the_mechanism_beside_its_failure_mode(water_fos):
    """`fos --out` writes the stresses of the last equilibrium; its failure
    columns once came from there too: every block ``unstable`` false and
    every ``slip_surface`` false beside ``failure_mode`` "slides".  They are
    the limit's now, as the mode is."""
    from rockdem.result_tables import analysis_tables

    tables = analysis_tables(water_fos.stable_analysis, water_fos.failed_analysis)
    moving = [r for r in tables["blocks"] if r["failure_mode"] not in ("stable", "fixed")]
    assert moving and all(r["unstable"] for r in moving)
    assert all(
        r["failure_mode"] in ("stable", "fixed") for r in tables["blocks"] if not r["unstable"]
    )
    slip = [r["interface"] for r in tables["interfaces"] if r["slip_surface"]]
    assert slip == sorted(int(i) for i in water_fos.failed_analysis.slip_surface)
    # the stresses stay those of the last equilibrium
    stable = water_fos.stable_analysis.interfaces.normal_stress
    assert [r["normal_stress"] for r in tables["interfaces"]] == [float(v) for v in stable]


def test_fos_drawing_has_the_slip_surface_of_the_limit(water_fos, tmp_path):
    """`fos --out --format dxf` drew the last equilibrium's slip surface (none)
    on SLIP_SURFACE: the drawing of a search carries the limit's."""
    import ezdxf

    from rockdem.exchange.dxf_out import write_dxf

    a, failed = water_fos.stable_analysis, water_fos.failed_analysis
    path = write_dxf(tmp_path / "r.dxf", a.system.model, a, failed=failed)
    lines = ezdxf.readfile(path).modelspace().query('LINE[layer=="SLIP_SURFACE"]')
    assert len(failed.slip_surface) > 0 and len(lines) == len(failed.slip_surface)


def test_the_stress_plot_of_a_standing_slope_is_not_the_open_crack(water_model):
    """plane-failure-water stands at F = 1 (no slip surface): `rockdem plot
    --what stress` drew its only failed interface, the tension crack, wholly
    open: zeros.  The default now passes over failed interfaces that carry
    nothing and takes the joint closest to failure: the sliding plane."""
    from rockdem.plots.stress import select_interfaces

    a = rd.analyse(water_model)
    assert a.stable and not len(a.slip_surface)
    chosen = select_interfaces(a)
    stress = a.interfaces.normal_stress[chosen]
    assert (stress > 1.0).any()  # the plane carries the block (63.8 kPa mean)


#: two wedges on a bilinear surface with a cohesive joint between them rising
#: into the slope (literature round 5): under gravity an end of that joint
#: opens and its point loses its cohesion, so the factor depends on the number
#: of spring points (1.605 / 1.595 / 1.581 with 2 / 3 / 5 points)
TWO_WEDGES = """\
name: two wedges, cohesive joint between
materials:
  rock: {unit_weight: 26}
joints:
  between: {normal_stiffness: 1.0e+6, friction_angle: 25, cohesion: 30, residual_cohesion: 30}
  upper: {normal_stiffness: 1.0e+6, friction_angle: 30, cohesion: 10, residual_cohesion: 10}
  lower: {normal_stiffness: 1.0e+6, friction_angle: 35, cohesion: 5, residual_cohesion: 5}
joint_lines:
  - {joint: upper, start: [-8.39099631, 10], end: [0, 0]}
  - {joint: lower, start: [0, 0], end: [10.9899097, -4]}
analysis: {load_steps: 1}
blocks:
  - {id: 0, fixed: true, vertices: [[-40, 10], [-8.39099631, 10], [0, 0], [10.9899097, -4],
     [40, -4], [40, -30], [-40, -30]]}
  - {id: 1, material: rock, vertices: [[-8.39099631, 10], [0, 0], [-3.63970234, 10]]}
  - {id: 2, material: rock, vertices: [[0, 0], [10.9899097, -4], [5.8943264, 10],
     [-3.63970234, 10]]}
"""


@pytest.mark.parametrize("command", ["run", "fos"])
def test_a_bond_lost_at_a_spring_point_is_a_warning_on_the_terminal(tmp_path, command):
    """The sentence that the result depends on the number of spring points
    (a point of a cohesive joint failed in tension) was only in the JSON's
    trust list and the report; `rockdem fos` printed 1.5957 without it."""
    import json

    from typer.testing import CliRunner

    from rockdem.cli import app

    path = tmp_path / "wedges.yaml"
    path.write_text(TWO_WEDGES)
    runner = CliRunner()
    r = runner.invoke(app, [command, str(path)])
    assert r.exit_code == 0, r.output
    lines = [ln for ln in r.stdout.splitlines() if ln.startswith("warning:")]
    assert any("failed in tension" in ln and "number of spring points" in ln for ln in lines)
    data = json.loads(runner.invoke(app, [command, str(path), "--json"]).stdout)
    assert any("failed in tension" in w for w in data["warnings"]), data["warnings"]


def test_le_labels_the_effective_normal_force_with_water():
    """`rockdem le` on a wet slope printed "N kN" beside the effective force
    (884.1 of the 1,288.6 kN block, the water's taken off); dry it stays N
    (literature round 7)."""
    from typer.testing import CliRunner

    from rockdem.cli import app

    runner = CliRunner()
    wet = runner.invoke(app, ["le", "-e", "plane-failure-water"])
    assert wet.exit_code == 0, wet.output
    header = next(ln for ln in wet.stdout.splitlines() if ln.startswith("face"))
    assert "N' kN" in header.split("length")[1]
    assert "N': the effective normal force" in wet.stdout
    dry = runner.invoke(app, ["le", "-e", "wedge-verification"])
    header = next(ln for ln in dry.stdout.splitlines() if ln.startswith("face"))
    assert "N'" not in header and " N " in f" {header} "
