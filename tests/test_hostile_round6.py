"""Hostile testing, round 6: limit-equilibrium case files, `rockdem import`
destinations, stabilisation bolt patterns, study folders read back.  Each
test failed before its fix."""

from __future__ import annotations

import json
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


# ------------------------------------------------------ limit-equilibrium case files
PLANE = (
    "height: 30, face_angle: 60, plane_dip: 30, friction_angle: 30, cohesion: 48, "
    "unit_weight: 25.5, crack_distance: 9"
)


def le_case(folder: Path, inputs: str, units: str = "kN, m, kPa") -> Path:
    path = folder / "case.yaml"
    path.write_text(f"units: {units}\nlimit_equilibrium:\n  plane_failure: {{{inputs}}}\n")
    return path


def test_water_in_a_case_file_of_tonnes_is_not_weighed_in_kilonewtons(tmp_path):
    """A crack full of water in a case file in t and m, without
    water_unit_weight, was weighed at 9.81 (kN/m^3) against rock of 2.55
    t/m^3: 'factor of safety: -0.7406', exit 0.  The water's unit weight is
    required with water, as a model file's water table requires it."""
    inputs = PLANE.replace("cohesion: 48", f"cohesion: {48 / 9.81!r}")
    inputs = inputs.replace("unit_weight: 25.5", f"unit_weight: {25.5 / 9.81!r}")
    case = le_case(tmp_path, f"{inputs}, water_depth: 14.8", units="t, m, t/m^2")
    assert_refused(
        invoke("le", case),
        "case.yaml:3: limit_equilibrium.plane_failure.water_unit_weight: ",
        "is missing",
        "give water_unit_weight: 1 (water in t, m, t/m^2)",
    )
    # given, it is the kN answer (0.7945) in tonnes
    case = le_case(
        tmp_path, f"{inputs}, water_depth: 14.8, water_unit_weight: 1.0", units="t, m, t/m^2"
    )
    r = invoke("le", case)
    assert r.exit_code == 0, r.output
    assert "factor of safety: 0.794" in r.stdout
    # no water, no unit weight of water needed
    r = invoke("le", le_case(tmp_path, PLANE))
    assert r.exit_code == 0, r.output


def test_water_that_lifts_the_block_off_its_plane_gives_no_negative_factor(tmp_path):
    """A crack 29 m deep in a 30 m slope, full of water: the uplift and the
    crack's thrust exceed the block's weight across the plane, and Hoek &
    Bray's formula read 'factor of safety: -0.3441' (exit 0)."""
    inputs = PLANE.replace("crack_distance: 9", "crack_depth: 29")
    case = le_case(tmp_path, f"{inputs}, water_depth: 29, water_unit_weight: 9.81")
    assert_refused(
        invoke("le", case),
        "limit_equilibrium.plane_failure.water_depth: ",
        "lifts the block off the plane",
        "rockdem fos",
    )
    # water short of that still has its factor
    case = le_case(tmp_path, f"{inputs}, water_depth: 2, water_unit_weight: 9.81")
    r = invoke("le", case, "--json")
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["result"]["fos"] > 0


# ------------------------------------------------------------------- rockdem import
@pytest.mark.parametrize("name", ["model.toml", "model.json", "other.dxf", "model.txt"])
def test_import_writes_only_a_yaml_file(tmp_path, name):
    """`rockdem import --out model.toml` wrote YAML under a TOML name (the file
    it said loads with every command then read 'not valid TOML'), and
    `--out other.dxf --overwrite` replaced a drawing with YAML text."""
    out = tmp_path / name
    if name.endswith(".dxf"):
        out.write_text("0\nEOF\n")
    r = invoke("import", "--example", "--bolt-force", 150, "--out", out, "--overwrite")
    assert_refused(r, f"--out {out}", "give a .yaml file name")
    assert not out.exists() or out.read_text() == "0\nEOF\n"


# ------------------------------------------------------------- stabilise: bolt rows
def test_a_bolt_pattern_of_given_rows_is_not_said_to_have_tried_16(tmp_path):
    """With `stabilisation.bolts.row_spacing` the rows are the ones that
    spacing lays out (one row here), but a pattern that fell short was said
    'not reached with up to 16 rows of bolts'."""
    bolts = {"capacity": 0.01, "axial_stiffness": 1.0e4, "row_spacing": 1.0e6}
    model = sliding_wedge(tmp_path, stabilisation={"bolts": bolts})
    r = invoke("stabilise", model, "--quiet", "--no-support", "--json")
    assert r.exit_code == 0, r.output
    (row,) = [m for m in json.loads(r.stdout)["measures"] if m["kind"] == "bolts"]
    assert not row["reaches_target"]
    assert "16 rows" not in row["note"], row["note"]
    assert "rows of bolts 1e+06 apart on the face" in row["note"], row["note"]


# ----------------------------------------------------------------- study folders
def test_a_study_folder_whose_study_json_is_no_object_is_refused(tmp_path):
    """A study.json holding `[]` (valid JSON, not the study's record) ended
    in "AttributeError: 'list' object has no attribute 'get'", exit 1."""
    pytest.importorskip("pyarrow")  # rockdem[study]
    study = {
        "samples": 2,
        "inputs": {"joints.plane.friction_angle": {"distribution": "normal", "mean": 33, "sd": 1}},
    }
    model = two_blocks(tmp_path, study=study)
    out = tmp_path / "out"
    out.mkdir()
    (out / "study.json").write_text("[]\n")
    r = invoke("study", model, "--out", out, "--workers", 0, "--quiet")
    assert_refused(r, f"--out {out}", "holds the results of another study", "--overwrite")
    assert (out / "study.json").read_text() == "[]\n"


# ------------------------------------------------------------------ the units note
@pytest.mark.parametrize("units", ["kN, m,\\e[31m kPa", "kN,\\nm, kPa", "kN,\\tm, kPa"])
def test_a_units_note_with_a_control_character_is_refused(tmp_path, units):
    """Names and keys with an escape or a line break were refused (round 3),
    but the `units` note, printed in the header of every command, was not:
    its escape coloured the terminal and a line break split the header."""
    path = two_blocks(tmp_path)
    path.write_text(path.read_text().replace("units: kN, m, kPa", f'units: "{units}"', 1))
    line = assert_refused(invoke("check", path), "two.yaml:1: units: the note", "control character")
    assert "\x1b" not in line


def test_a_study_of_a_joint_whose_name_holds_a_dot_says_why_it_is_not_found(tmp_path):
    """A joint named `a.b` studied as `joints.a.b.friction_angle` read
    "`joints` has no key `a`", though the file has the joint: the message
    now says that the name holds a separator and to rename it."""
    study = {
        "samples": 2,
        "inputs": {"joints.a.b.friction_angle": {"distribution": "normal", "mean": 33, "sd": 1}},
    }
    path = two_blocks(tmp_path, study=study)
    path.write_text(path.read_text().replace("  plane:", "  a.b:", 1))
    assert_refused(
        invoke("study", path, "--out", tmp_path / "out", "--workers", 0),
        "study.inputs.joints.a.b.friction_angle",
        "the key `a.b` holds a `.` or `[`",
        "rename it to vary it",
    )


# ------------------------------------------------------------------ removal regions
SLOPE = {
    "units": "kN, m, kPa",
    "materials": {"rock": {"unit_weight": 25}},
    "joints": {"bedding": {"normal_stiffness": 1.0e6, "friction_angle": 35, "cohesion": 10}},
    "slope": {
        "profile": {"height": 10, "face_angle": 60},
        "depth": 6,
        "joint_sets": {"bedding": {"dip": 30, "spacing": 2.5}},
    },
}


def test_a_crossed_removal_region_of_a_generated_slope_is_named_at_its_key(tmp_path):
    """A self-crossing `remove.regions[1]` of a generated slope was reported
    at `slope:` as "excavation region is not a valid polygon" (which one, and
    where?); it is named at its key and line, as on explicit blocks."""
    regions = [[[-5, 5], [0, 5], [0, 8]], [[0, 0], [1, 1], [1, 0], [0, 1]]]
    path = tmp_path / "slope.yaml"
    path.write_text(yaml.safe_dump({**SLOPE, "remove": {"regions": regions}}, sort_keys=False))
    line = assert_refused(invoke("check", path), "remove.regions[1]: is not a valid polygon")
    assert "slope.yaml:" in line and ": slope:" not in line
