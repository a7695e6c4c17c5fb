"""Hostile testing, round 5: bolts put in after the loads, stabilisation
plans, line and point loads at odd places, study outputs.  Each test failed
before its fix."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from _cli import assert_refused
from rockdem.cli import app

runner = CliRunner()


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


def two_blocks(folder: Path, **extra) -> Path:
    """Two 2 x 1 blocks stacked on a horizontal fixed plane, with ``extra``
    top-level keys."""
    doc = {
        "units": "kN, m, kPa",
        "materials": {"rock": {"unit_weight": 25}},
        "joints": {"plane": {"normal_stiffness": 1.0e6, "friction_angle": 33}},
        "blocks": [
            {"fixed": True, "vertices": [[-8, -1], [8, -1], [8, 0], [-8, 0]]},
            {"material": "rock", "vertices": [[0, 0], [2, 0], [2, 1], [0, 1]]},
            {"material": "rock", "vertices": [[0, 1], [2, 1], [2, 2], [0, 2]]},
        ],
        **extra,
    }
    path = folder / "two.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def sliding_wedge(folder: Path, **extra) -> Path:
    """A block on a plane dipping 26.6 degrees with friction 20 (FS 0.73)
    above a block on the ground, with ``extra`` top-level keys."""
    doc = {
        "units": "kN, m, kPa",
        "materials": {"rock": {"unit_weight": 25}},
        "joints": {
            "j": {"normal_stiffness": 1.0e6, "friction_angle": 20},
            "g": {"normal_stiffness": 1.0e6, "friction_angle": 45},
        },
        "ground_joint": "g",
        "blocks": [
            {"id": 0, "fixed": True, "vertices": [[-10, -2], [10, -2], [10, 0], [-10, 0]]},
            {"id": 1, "material": "rock", "vertices": [[0, 0], [4, 0], [4, 1], [0, 3]]},
            {"id": 2, "material": "rock", "vertices": [[0, 3], [4, 1], [4, 2], [0, 4]]},
        ],
        **extra,
    }
    path = folder / "wedge.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def late_bolt(capacity: float = 100) -> dict:
    """Bolt B of the sliding wedge, put in after the loads (angle 200 from
    its head on the upper block, 5 long, axial stiffness 1e4)."""
    return {
        "name": "B",
        "head": [4, 1.5],
        "angle": 200,
        "length": 5,
        "capacity": capacity,
        "axial_stiffness": 1.0e4,
        "installed": "after_loads",
    }


def test_a_warning_is_printed_once_per_command(tmp_path):
    """A bolt put in after the loads on a slope that never stands was warned
    about at every support force stabilise tried (11 identical lines)."""
    bolt = late_bolt()
    model = sliding_wedge(tmp_path, bolts=[bolt], stabilisation={"target_fos": 1.2})
    r = invoke("stabilise", model, "--out", tmp_path / "o")
    assert r.exit_code == 0, r.output
    lines = [s for s in r.stderr.splitlines() if s.startswith("warning: bolts B")]
    assert len(lines) == 1, r.stderr


def test_a_trapezoid_that_turns_from_pushing_to_pulling_about_its_middle_is_named_so(tmp_path):
    """q_end = -q averages to nothing: the side it pushes was read from that
    mean, and the error named a Gauss point "that does not act on any block"."""
    line = {"start": [0, 2], "end": [2, 2], "q": [0, 10], "q_end": [0, -10]}
    r = invoke("check", two_blocks(tmp_path, loads={"lines": [line]}))
    assert_refused(r, "loads.lines[0]", "turns from pushing to pulling", "split it")


def test_a_point_force_of_nought_on_a_joint_is_no_error(tmp_path):
    """A zero force (the first point of a sweep of a load, say) on a joint
    was refused as one that "points along the boundary between blocks"."""
    points = [{"at": [2, 1], "force": [0, 0]}, {"at": [1, 0], "force": [0, 0]}]
    r = invoke("run", two_blocks(tmp_path, loads={"points": points}))
    assert r.exit_code == 0, r.output
    assert "STABLE" in r.stdout


def test_a_study_error_a_spreadsheet_would_run_as_a_formula_is_quoted(tmp_path, monkeypatch):
    """samples.csv wrote its text columns as they stand: the `error` of a
    sample of the model file `=x.yaml` begins with its name, and a
    spreadsheet runs it; it is written `'=x.yaml ...` and read back as it was
    (a rerun into the folder continues the study)."""
    pytest.importorskip("pyarrow")  # rockdem[study]
    import csv

    points = [{"at": [1, 2], "force": [0, -10]}]
    study = {
        "samples": 4,
        "seed": 0,
        "inputs": {"loads.points[0].at[0]": {"distribution": "uniform", "min": 0.5, "max": 3}},
    }
    model = two_blocks(tmp_path, loads={"points": points}, study=study)
    model.rename(tmp_path / "=x.yaml")
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "o"
    for _ in range(2):  # the second reads the rows back
        r = invoke("study", "=x.yaml", "--out", out, "--workers", 0)
        assert r.exit_code == 0, r.output
        with (out / "samples.csv").open(newline="") as fh:
            errors = [row["error"] for row in csv.DictReader(fh) if row["error"]]
        assert errors and all(e.startswith("'=x.yaml (sample ") for e in errors), errors


def four_blocks(folder: Path, bolt: dict) -> Path:
    """Four 2 x 1 blocks in two columns on a fixed plane, and ``bolt``."""
    doc = yaml.safe_load(two_blocks(folder).read_text())
    doc["blocks"][1:] = [
        {"material": "rock", "vertices": [[x, y], [x + 2, y], [x + 2, y + 1], [x, y + 1]]}
        for y in (0, 1)
        for x in (0, 2)
    ]
    doc["bolts"] = [{"capacity": 10, "axial_stiffness": 1.0e4, **bolt}]
    path = folder / "four.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def test_a_bolt_through_the_grounds_corner_ties_the_block_to_the_ground(tmp_path):
    """A bolt from block 4 through the corner (2, 0), where blocks 1, 2 and
    the ground meet, was tied across the joint 1-2 ending there (the first
    interface found at that depth), not to the ground it goes into."""
    import csv

    bolt = {"head": [4, 2], "angle": 225, "length": 4}
    out = tmp_path / "o"
    r = invoke("run", four_blocks(tmp_path, bolt), "--out", out)
    assert r.exit_code == 0, r.output
    with (out / "bolts.csv").open() as fh:
        crossed = [int(row["interface"]) for row in csv.DictReader(fh)]
    with (out / "interfaces.csv").open() as fh:
        pairs = {
            int(row["interface"]): {row["block_a"], row["block_b"]} for row in csv.DictReader(fh)
        }
    assert [pairs[k] for k in crossed] == [{"2", "4"}, {"0", "2"}]


def test_a_bolt_through_a_corner_between_blocks_that_share_no_joint_is_refused(tmp_path):
    """From block 4 into block 1 through the corner (2, 1) of all four: they
    share no joint to tie, and the bolt was tied across the joint 1-2."""
    bolt = {"head": [4, 2], "angle": 206.565051177, "length": 4.4}
    r = invoke("check", four_blocks(tmp_path, bolt))
    assert_refused(
        r,
        "bolts[0]",
        "from block 4 to block 1 through the corner at (2, 1)",
        "move or turn the bolt a little",
    )


def test_a_stage_removing_only_excavated_rock_names_the_stages_by_key(tmp_path):
    """A second stage over the block the first took was said to remove "only
    rock that stage 0 already excavated": the report's stage 0 is the slope
    before excavation, and stages[0] is its stage 1."""
    stages = [
        {"name": "first", "remove": {"blocks": [2]}},
        {"name": "second", "remove": {"regions": [[[0, 3], [4, 1], [4, 5], [0, 5]]]}},
    ]
    r = invoke("check", sliding_wedge(tmp_path, stabilisation={"stages": stages}))
    assert_refused(
        r,
        "stabilisation.stages[1].remove",
        "removes only rock that stages[0] (`first`) already excavated",
    )


def test_a_bolt_of_a_slope_that_stands_is_not_said_never_installed_by_stabilise(tmp_path):
    """The slope stands (FS 1.1) and its after_loads bolt goes in; stabilise's
    support search tried it at the target 1.3, where it fails, and printed
    that the bolt "was never installed: the slope finds no equilibrium under
    its loads" (of the model, as it read)."""
    bolt = late_bolt(capacity=1)
    model = sliding_wedge(tmp_path, bolts=[bolt], stabilisation={"target_fos": 1.3})
    doc = yaml.safe_load(model.read_text())
    doc["joints"]["j"]["friction_angle"] = 29
    model.write_text(yaml.safe_dump(doc, sort_keys=False))
    r = invoke("run", model)
    assert r.exit_code == 0 and "STABLE" in r.stdout and "never installed" not in r.stderr
    r = invoke("stabilise", model, "--out", tmp_path / "o")
    assert r.exit_code == 0, r.output
    assert "never installed" not in r.stderr


def test_a_bolt_never_installed_is_reported_so_not_as_carrying_nothing(tmp_path):
    """An after_loads bolt of a slope that never stands was listed as
    "crosses 1 joint, no axial force (0% of capacity)", and in the JSON
    like a bolt in place that carries nothing."""
    import json

    bolt = late_bolt()
    model = sliding_wedge(tmp_path, bolts=[bolt])
    r = invoke("run", model)
    assert r.exit_code == 0, r.output
    assert "  B: not installed (installed: after_loads)" in r.stdout
    r = invoke("run", model, "--json")
    (summary,) = json.loads(r.stdout)["bolt_summary"]
    assert summary["installed"] is False
    bolt["installed"] = "before_loads"
    r = invoke("run", sliding_wedge(tmp_path, bolts=[bolt]), "--json")
    (summary,) = json.loads(r.stdout)["bolt_summary"]
    assert summary["installed"] is True


def test_a_bolt_row_that_leaves_the_rock_is_left_out_of_the_pattern(tmp_path):
    """The row nearest the crest of the wedge, drilled at 195 degrees, runs
    out of the block's back face into the air before it crosses a joint:
    the whole bolt pattern failed with "crosses no joint between a free
    block and another block"; the other rows hold the wedge."""
    import csv

    bolts = {"capacity": 100, "axial_stiffness": 1.0e4}
    model = sliding_wedge(tmp_path, stabilisation={"bolts": bolts})
    r = invoke("stabilise", model, "--out", tmp_path / "o")
    assert r.exit_code == 0, r.output
    with (tmp_path / "o" / "measures.csv").open() as fh:
        (row,) = [row for row in csv.DictReader(fh) if row["kind"] == "bolts"]
    assert row["reaches_target"] == "True", row
    assert row["note"].startswith("3 rows of bolts"), row


def test_a_pore_pressure_ratio_without_gravity_is_warned_about(tmp_path):
    """r_u x the overburden of weightless rock lifted the blocks off:
    "UNSTABLE: statically admissible forces carry none of the loads", with
    nothing to say why (as a seismic coefficient without gravity is)."""
    r = invoke("run", two_blocks(tmp_path, loads={"gravity": False, "pore_pressure_ratio": 0.5}))
    assert r.exit_code == 0, r.output
    (line,) = [s for s in r.stderr.splitlines() if s.startswith("warning:")]
    assert "two.yaml:42: loads.pore_pressure_ratio with gravity off" in line, line


def test_an_error_of_a_drawn_bolt_names_geometry_bolt_and_the_bolt(tmp_path):
    """The bolts of a DXF section take `geometry.bolt`; an error of theirs
    was put at `bolts[0]`, a key the file does not have, on line 1."""
    import shutil

    from rockdem.exchange.dxf_in import example_dxf

    shutil.copy(example_dxf(), tmp_path / "section.dxf")
    path = tmp_path / "drawn.yaml"
    path.write_text(
        "units: kN, m, kPa\n"
        "materials: {rock: {unit_weight: 26}}\n"
        "joints:\n"
        "  bedding: {normal_stiffness: 1.0e+6, friction_angle: 30}\n"
        "  cross: {normal_stiffness: 1.0e+6, friction_angle: 35}\n"
        "geometry:\n"
        "  dxf: section.dxf\n"
        "  bolt: {capacity: 200, axial_stiffness: 1.0e+5, pretension: 500}\n"
        "loads: {water_unit_weight: 9.81}\n"
    )
    r = invoke("check", path)
    assert_refused(r, "drawn.yaml:8: geometry.bolt: drawn bolt 1: pretension 500 exceeds")
    path.write_text(path.read_text().replace("pretension: 500", "spacing: 1.0e-9"))
    r = invoke("check", path)
    assert_refused(r, "drawn.yaml:8: geometry.bolt.spacing: drawn bolt 1: 1e-09 is far below")


def test_the_reports_bolt_table_says_a_bolt_never_went_in(tmp_path):
    """The report's table listed a never-installed bolt with force 0 and
    utilisation 0%, as a bolt in place that carries nothing."""
    import warnings

    from rockdem import analyse
    from rockdem.config import load_model
    from rockdem.report_tables import bolts_table

    bolt = late_bolt()
    model, *_ = load_model(sliding_wedge(tmp_path, bolts=[bolt]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        html = bolts_table(analyse(model))
    assert "not installed" in html


def test_stabilise_overwrite_leaves_no_stage_results_of_the_earlier_model(tmp_path):
    """Replacing the results of a stabilisation with stages by one of a model
    without them kept the old stages.csv and stage pictures beside the new
    stabilisation.json, as this model's; other files stay."""
    stages = [{"name": "cut", "remove": {"blocks": [2]}}]
    staged = sliding_wedge(tmp_path, stabilisation={"stages": stages, "target_fos": 0.5})
    out = tmp_path / "o"
    r = invoke("stabilise", staged, "--out", out)
    assert r.exit_code == 0, r.output
    assert (out / "stages.csv").exists() and (out / "stage-00.png").exists()
    (out / "notes.txt").write_text("mine")
    plain = sliding_wedge(tmp_path, stabilisation={"target_fos": 0.5})
    r = invoke("stabilise", plain, "--out", out, "--overwrite")
    assert r.exit_code == 0, r.output
    assert not list(out.glob("stage*")), sorted(p.name for p in out.iterdir())
    assert (out / "notes.txt").read_text() == "mine" and (out / "stabilisation.json").exists()


def test_a_bolt_pattern_that_cannot_be_laid_out_says_the_key_and_the_fix(tmp_path):
    """A row spacing of 1e-6 noted only "1e-06 puts 5,472,135 rows on the
    5.47 of face to bolt": not which key, nor the spacing to give."""
    import csv

    bolts = {"capacity": 100, "axial_stiffness": 1.0e4, "row_spacing": 1.0e-6}
    model = sliding_wedge(tmp_path, stabilisation={"bolts": bolts})
    r = invoke("stabilise", model, "--out", tmp_path / "o")
    assert r.exit_code == 0, r.output
    with (tmp_path / "o" / "measures.csv").open() as fh:
        (row,) = [row for row in csv.DictReader(fh) if row["kind"] == "bolts"]
    assert row["note"].startswith("stabilisation.bolts.row_spacing: 1e-06 puts"), row
    assert "give a row spacing of at least" in row["note"], row


def test_a_water_table_below_every_joint_is_warned_about(tmp_path):
    """A water table at y = -100 under blocks from y = 0 to 2 (elevations in
    another datum, say) loaded no joint and was accepted without a word."""
    loads = {"water_table": [[-8, -100], [8, -100]], "water_unit_weight": 9.81}
    r = invoke("run", two_blocks(tmp_path, loads=loads))
    assert r.exit_code == 0, r.output
    (line,) = [s for s in r.stderr.splitlines() if s.startswith("warning:")]
    assert "loads.water_table lies at or below every joint" in line, line
    assert "check its levels" in line, line
    loads["water_table"] = [[-8, -1], [0, 0], [1, 0.5], [2, 0], [8, -1]]  # wets the base
    r = invoke("run", two_blocks(tmp_path, loads=loads))
    assert r.exit_code == 0, r.output
    assert "warning" not in r.stderr, r.stderr


def test_bolts_put_in_after_the_loads_are_rated_whatever_the_search_starts_at(tmp_path):
    """With strength_reduction.start 3 the first trial failed the unbolted
    slope at F = 3, its after_loads bolt was "never installed" (the slope
    stands at F = 1 and takes it) and the factor was the unbolted one, 1.109
    for > 86."""
    import json

    bolt = late_bolt()
    search = {"strength_reduction": {"start": 3}}
    model = sliding_wedge(tmp_path, bolts=[bolt], analysis=search)
    doc = yaml.safe_load(model.read_text())
    doc["joints"]["j"]["friction_angle"] = 29  # FS 1.109 unbolted
    model.write_text(yaml.safe_dump(doc, sort_keys=False))
    r = invoke("fos", model, "--json")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["factor_of_safety"] is None and doc["mode"] == "no-failure", doc["bracket"]
    assert not any("never installed" in w for w in doc["warnings"]), doc["warnings"]


def test_a_cable_given_a_dowel_stiffness_is_refused(tmp_path):
    """A cable has no dowel action: its shear_stiffness and shear_capacity
    were dropped without a word."""
    bolt = {
        "head": [2, 1.5],
        "angle": 225,
        "length": 3,
        "capacity": 10,
        "axial_stiffness": 1.0e4,
        "kind": "cable",
        "shear_stiffness": 1.0e4,
    }
    r = invoke("check", two_blocks(tmp_path, bolts=[bolt]))
    assert_refused(r, "bolts[0].shear_stiffness: 10000 is given for a cable", "kind: bolt")
    del bolt["shear_stiffness"]
    r = invoke("check", two_blocks(tmp_path, bolts=[bolt]))
    assert r.exit_code == 0, r.output


def test_a_study_sample_whose_bolt_never_went_in_has_no_bolt_utilisation(tmp_path):
    """A sample whose after_loads bolt never went in (the slope never stood)
    read bolt_utilisation 0, as a bolt in place carrying nothing."""
    pytest.importorskip("pyarrow")  # rockdem[study]
    import csv

    bolt = late_bolt()
    study = {"sweep": {"joints.j.friction_angle": {"values": [20, 40]}}, "compute": "verdict"}
    out = tmp_path / "o"
    r = invoke(
        "study", sliding_wedge(tmp_path, bolts=[bolt], study=study), "--out", out, "--workers", 0
    )
    assert r.exit_code == 0, r.output
    with (out / "samples.csv").open() as fh:
        use = [row["bolt_utilisation"] for row in csv.DictReader(fh)]
    assert use[0] == "" and use[1] != "", use


def test_a_contact_off_by_less_than_the_tolerance_is_found_in_either_block_order(tmp_path):
    """The top of a block bent up 1e-7 at its middle (the tolerance is 1.6e-7)
    under a flat block: listed first, it was refused ("overlaps block 2 by a
    sliver deeper than the tolerance", its short edge's line missing the far
    end of the long edge by 2e-7); listed second, the two rested on each other."""
    bent = {"material": "rock", "vertices": [[0, 0], [2, 0], [2, 1], [1, 1.0000001], [0, 1]]}
    flat = {"material": "rock", "vertices": [[0, 1], [2, 1], [2, 2], [0, 2]]}
    doc = yaml.safe_load(two_blocks(tmp_path).read_text())
    ground = doc["blocks"][0]
    for order in ([bent, flat], [flat, bent]):
        doc["blocks"] = [ground, *order]
        path = tmp_path / "bent.yaml"
        path.write_text(yaml.safe_dump(doc, sort_keys=False))
        r = invoke("run", path)
        assert r.exit_code == 0, r.output
        assert "STABLE" in r.stdout


def test_the_next_command_after_example_copy_runs_in_a_shell(tmp_path):
    """Copied into a folder with a space, the hint `next: rockdem check
    my models/x.yaml` ran `check` on `my`: the path is quoted for the shell."""
    import shlex

    r = invoke("example", "copy", "bolted-slope", tmp_path / "my models")
    assert r.exit_code == 0, r.output
    (line,) = [s for s in r.stdout.splitlines() if s.startswith("next: ")]
    args = shlex.split(line.removeprefix("next: "))
    assert args == ["rockdem", "check", str(tmp_path / "my models" / "bolted-slope.yaml")]


def test_digging_below_the_water_table_is_refused_by_check_and_stops_removal(tmp_path):
    """A stage, or stabilise's own removal round, that digs below the water
    table (water on the new face is not modelled) passed `check` and then
    stopped stabilise mid-run with "loads water_table: is 0.312 above ...",
    naming no file or key and reporting no other measure."""
    import csv

    loads = {
        "water_table": [[-10, -1], [0, 0], [2, 2.5], [4, 0], [10, -1]],
        "water_unit_weight": 9.81,
    }
    stages = [{"name": "dig", "remove": {"blocks": [2]}}]
    r = invoke("check", sliding_wedge(tmp_path, loads=loads, stabilisation={"stages": stages}))
    assert_refused(
        r, "stabilisation.stages[0].remove: loads.water_table: is 0.312 above", "drained"
    )
    model = sliding_wedge(tmp_path, loads=loads, stabilisation={"max_removal": 0.9})
    r = invoke("stabilise", model, "--out", tmp_path / "o")
    assert r.exit_code == 0, r.output
    with (tmp_path / "o" / "measures.csv").open() as fh:
        rows = {row["kind"]: row for row in csv.DictReader(fh)}
    assert rows["support"]["reaches_target"] == "True", rows
    assert "would dig below the water table" in rows["removal"]["note"], rows


def test_a_load_on_rock_that_remove_takes_says_so(tmp_path):
    """A point load on the top block, which the file's `remove` takes out:
    the error said only "does not act on any block"; its fix now names
    `remove` as well (found in round 5, fixed after it)."""
    path = two_blocks(
        tmp_path,
        remove={"blocks": [2]},
        loads={"points": [{"at": [1, 2], "force": [0, -10], "name": "P"}]},
    )
    assert_refused(
        invoke("check", path), "loads.points[0]", "does not act on any block", "`remove` takes out"
    )
    # without the removal the same load is fine
    doc = yaml.safe_load(path.read_text())
    del doc["remove"]
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    assert invoke("check", path).exit_code == 0


def test_a_support_the_slope_does_not_need_says_so(tmp_path):
    """A block on a 20 degree plane (phi 35: FS 1.92) against a target of
    1.3: the support row read "force bracket 0-0 kN"; it says none is needed."""
    import numpy as np

    d = np.radians(20)
    R = np.array([[np.cos(d), -np.sin(d)], [np.sin(d), np.cos(d)]])
    ground = np.array([(-10, 0), (10, 0), (10, -3), (-10, -3)]) @ R.T
    block = np.array([(0, 0), (2, 0), (2, 1), (0, 1)]) @ R.T
    doc = {
        "units": "kN, m, kPa",
        "joints": {"j": {"normal_stiffness": 1.0e6, "friction_angle": 35}},
        "blocks": [
            {"fixed": True, "vertices": ground.tolist()},
            {"unit_weight": 25, "vertices": block.tolist()},
        ],
        "stabilisation": {"support": {"angle": 10}},
    }
    path = tmp_path / "met.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    r = invoke("stabilise", path, "--out", tmp_path / "out")
    assert r.exit_code == 0, r.output
    text = (tmp_path / "out" / "measures.csv").read_text()
    assert "none needed: the slope meets the target without it" in text
    assert "force bracket 0-0" not in text


def test_bolts_csv_says_which_bolts_are_in(tmp_path):
    """An after_loads bolt that never went in: bolts.csv showed its rows with
    force 0 and nothing to say why; its rows now read installed false."""
    import csv

    bolt = late_bolt()
    r = invoke("run", sliding_wedge(tmp_path, bolts=[bolt]), "--out", tmp_path / "o")
    assert r.exit_code == 0, r.output
    text = (tmp_path / "o" / "bolts.csv").read_text().splitlines()
    rows = list(csv.DictReader(text))
    assert rows and all(row["installed"] == "false" for row in rows)


def test_a_bolt_along_a_joint_is_refused(tmp_path):
    """A bolt drilled along the joint between the two stacked blocks (head on
    the face at that joint, pointing along it) was tied to whichever side
    round-off put it on; it is refused.  One through the lower block into the
    ground holds."""
    bolt = {"head": [2, 1], "angle": 180, "length": 1.5, "capacity": 10, "axial_stiffness": 1e4}
    r = invoke("check", two_blocks(tmp_path, bolts=[bolt]))
    assert_refused(r, "bolts[0]", "runs along the joint between blocks", "turn it a little")
    bolt.update(head=[2, 0.6], angle=210, length=3)  # through the lower block into the ground
    r = invoke("check", two_blocks(tmp_path, bolts=[bolt]))
    assert r.exit_code == 0, r.output


def test_a_confidence_just_below_one_is_not_printed_as_100_percent():
    """confidence: 0.999999999 printed "100% interval"."""
    from rockdem.studies.stats import level_text

    assert level_text(0.95) == "95" and level_text(0.5) == "50"
    assert level_text(0.999999999) == "99.9999999"


def test_a_sweep_range_that_starts_where_it_stops_is_refused(tmp_path):
    """`{start: 0, stop: 0, steps: 3}` ran the same sample three times without
    a word; the spec is refused at the key, with the fix."""
    sweep = {"joints.plane.friction_angle": {"start": 30, "stop": 30, "steps": 3}}
    r = invoke("check", two_blocks(tmp_path, study={"sweep": sweep}))
    assert_refused(r, "study.sweep", "start and stop are both 30", "give a stop other than")
