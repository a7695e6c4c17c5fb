"""Hostile testing, round 7: the leftovers of round 6 (`check` of a study's
key paths, duplicate removal ids, empty trial names, the wedge case's line),
then the Python API with bad arguments, JSON model files, explicit blocks
with tiny features, plots and reports of every kind of result, `example`
and the environment.  Each test failed before its fix."""

from __future__ import annotations

import os
import subprocess
import sys
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


# ------------------------------------------------------------ round 6's leftovers
def test_a_wedge_case_without_a_factor_is_named_at_its_section(tmp_path):
    """'no factor of safety between 0.2 and 5' was named `w.yaml:1: wedge`
    (the function's name, the file's first line), not the case's key."""
    case = tmp_path / "w.yaml"
    case.write_text(
        "units: kN, m, kPa\nlimit_equilibrium:\n  wedge:\n    active_weight: 100\n"
        "    passive_weight: 100\n    active_dip: 1\n    passive_dip: 0.5\n"
        "    active_friction: 89\n    passive_friction: 89\n    joint_friction: 89\n"
    )
    assert_refused(
        invoke("le", case),
        "w.yaml:3: limit_equilibrium.wedge: no factor of safety between 0.2 and 5",
    )


def test_a_block_removed_twice_is_refused(tmp_path):
    """`remove.blocks: [2, 2]` (a typo for another id) was taken silently,
    in the top-level removal and in a stabilisation trial's."""
    assert_refused(
        invoke("check", two_blocks(tmp_path, remove={"blocks": [2, 2]})),
        "two.yaml:",
        "remove.blocks: id 2 is listed twice (items 0 and 1); list each block once",
    )
    trials = {"trials": [{"name": "t", "remove": {"blocks": [1, 1]}}]}
    assert_refused(
        invoke("check", two_blocks(tmp_path, stabilisation=trials)),
        "stabilisation.trials[0].remove.blocks: id 1 is listed twice",
    )
    r = invoke("check", two_blocks(tmp_path, remove={"blocks": [2]}))
    assert r.exit_code == 0, r.output


@pytest.mark.parametrize("section", ["trials", "stages"])
@pytest.mark.parametrize("name", ["", "  "])
def test_a_trial_or_stage_without_a_name_is_refused(tmp_path, section, name):
    """A stabilisation trial (or stage) of `name: ''` was accepted: a row
    without a label in the report, and two of them were not compared."""
    design = {section: [{"name": name, "remove": {"blocks": [2]}}]}
    assert_refused(
        invoke("check", two_blocks(tmp_path, stabilisation=design)),
        f"stabilisation.{section}[0].name: the {section[:-1]} has ",
        "name; give it a name",
    )


def test_check_refuses_a_study_that_rockdem_study_would(tmp_path):
    """A misspelt `study.inputs` key path passed `rockdem check` (exit 0,
    "valid"); only `rockdem study` refused it.  So did a study whose median
    is out of its key's range."""
    study = {
        "inputs": {"joints.plane.friction_angel": {"distribution": "normal", "mean": 33, "sd": 2}}
    }
    assert_refused(
        invoke("check", two_blocks(tmp_path, study=study)),
        "two.yaml:",
        "study.inputs.joints.plane.friction_angel: no such number in the model",
        "did you mean `friction_angle`?",
    )
    study = {
        "inputs": {"joints.plane.friction_angle": {"distribution": "normal", "mean": 95, "sd": 2}}
    }
    assert_refused(
        invoke("check", two_blocks(tmp_path, study=study)),
        "(study inputs at their medians): joints.plane.friction_angle: 95.0 is out of range",
    )
    study = {"sweep": {"joints.plane.friction_angle": {"values": [30, 35]}}}
    r = invoke("check", two_blocks(tmp_path, study=study))
    assert r.exit_code == 0, r.output


# ------------------------------------------------------------ the Python API
GROUND = [(-5, -1), (5, -1), (5, 0), (-5, 0)]
SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]


@pytest.mark.parametrize("ids", [[0.7, 1.2], [True, False], [2**63, 1], [float("nan"), 1]])
def test_block_ids_that_are_no_whole_numbers_are_refused(ids):
    """`ids=[0.7, 1.2]` were truncated to 0 and 1 and `[True, False]` read
    as 1 and 0, silently: results named blocks the user never numbered."""
    import rockdem as rd

    with pytest.raises(rd.InputError, match="block ids: must be whole numbers"):
        rd.Blocks.from_polygons([GROUND, SQUARE], fixed=[True, False], ids=ids)
    b = rd.Blocks.from_polygons([GROUND, SQUARE], fixed=[True, False], ids=[1.0, 2.0])
    assert b.ids.tolist() == [1, 2]


def test_a_bad_polygon_is_named_by_its_id_not_its_position():
    """With `ids=[10, 20]`, a polygon of two vertices was 'block 1: needs at
    least 3 (x, y) vertices': no block has id 1."""
    import rockdem as rd

    for bad in ([(0, 0), (1, 0)], [(0, 0), (1, float("nan")), (1, 1)]):
        with pytest.raises(rd.InputError, match=r"^block 20: "):
            rd.Blocks.from_polygons([GROUND, bad], fixed=[True, False], ids=[10, 20])


def test_vertices_written_as_text_are_refused():
    """`[("0", "0"), ("1", "0"), ("1", "1")]` was taken as numbers, where a
    Joint refuses friction_angle="30" as 'not a number'."""
    import rockdem as rd

    text = [("0", "0"), ("1", "0"), ("1", "1")]
    with pytest.raises(rd.InputError, match="block 1: vertices are not numbers"):
        rd.Blocks.from_polygons([GROUND, text], fixed=[True, False])


def test_a_model_whose_every_block_is_fixed_is_refused():
    """Built in Python, a model of fixed blocks only was analysed: 'stable',
    and its factor of safety 'none (no-failure)' (a model file refuses it:
    'every block is fixed')."""
    import rockdem as rd

    blocks = rd.Blocks.from_polygons([GROUND, SQUARE], fixed=True, unit_weight=25)
    model = rd.Model(blocks, rd.Joint(normal_stiffness=1e6, friction_angle=30))
    for run in (rd.analyse, rd.factor_of_safety):
        with pytest.raises(rd.InputError, match="every block is fixed: nothing can move"):
            run(model)


@pytest.mark.parametrize("ground", [1.5, True, "twin"])
def test_a_joint_given_by_no_index_or_by_a_shared_name_is_refused(ground):
    """`ground=1.5` and `ground=True` were joint 1 (int() of them); a name
    two joints of the table share was the first of them, silently."""
    import rockdem as rd

    blocks = rd.Blocks.from_polygons([GROUND, SQUARE], fixed=[True, False], unit_weight=25)
    joints = [
        rd.Joint(normal_stiffness=1e6, friction_angle=30),
        rd.Joint(normal_stiffness=1e6, friction_angle=20, name="twin"),
        rd.Joint(normal_stiffness=1e6, friction_angle=40, name="twin"),
    ]
    with pytest.raises(rd.InputError, match=r"^joint "):
        rd.Model(blocks, joints, ground=ground)
    assert rd.Model(blocks, joints, ground=1).ground == 1


def test_line_joint_without_joint_lines_is_refused():
    """`line_joint` without `joint_lines` was ignored, silently."""
    import rockdem as rd

    blocks = rd.Blocks.from_polygons([GROUND, SQUARE], fixed=[True, False], unit_weight=25)
    rock = rd.Joint(normal_stiffness=1e6, friction_angle=30)
    with pytest.raises(rd.InputError, match="model line_joint: is given without joint_lines"):
        rd.Model(blocks, [rock, rock.ductile], line_joint=[1])


# ------------------------------------------------------------ model files
def test_a_control_character_in_a_name_or_key_is_named_at_its_line(tmp_path):
    """A name, a key or the units note holding a control character was
    refused without its line ('k.yaml: bolts[0].name: ...')."""
    base = two_blocks(tmp_path).read_text()
    cases = [
        (base.replace("units: kN, m, kPa", 'units: "kN\\tm"'), "m.yaml:1: units: the note"),
        (base + 'name: "a\\eb"\n', f"m.yaml:{len(base.splitlines()) + 1}: name: the name"),
        (base.replace("  plane:", '  "pl\\eane":'), "m.yaml:6: the key 'pl\\x1bane'"),
    ]
    for text, fragment in cases:
        (tmp_path / "m.yaml").write_text(text)
        assert_refused(invoke("check", tmp_path / "m.yaml"), fragment, "control character")


# ------------------------------------------------------------ the environment
def test_a_misspelt_solver_refuses_the_analyses_not_the_help(monkeypatch):
    """ROCKDEM_SOLVER=bogus refused `rockdem run --help` and `rockdem example
    list` (checked in the root, before any subcommand); and `fos --json`
    printed no JSON object for scripts."""
    import json

    monkeypatch.setenv("ROCKDEM_SOLVER", "bogus")
    for args in (["run", "--help"], ["example", "list"], ["schema", "--help"]):
        r = invoke(*args)
        assert r.exit_code == 0, (args, r.output)
    r = invoke("fos", "--example", "wedge-verification", "--json")
    assert_refused(r, "error: ROCKDEM_SOLVER: 'bogus' is not a solver")
    assert json.loads(r.stdout)["exit_code"] == 2


def _child(*args, cwd: Path, **env) -> subprocess.CompletedProcess:
    """``python -m rockdem`` in a child process with ``env`` changed (None: unset);
    its output read in the encoding it was asked to write (PYTHONIOENCODING)."""
    full = {**os.environ, **{k: v for k, v in env.items() if v is not None}}
    for key in [k for k, v in env.items() if v is None]:
        full.pop(key, None)
    return subprocess.run(
        [sys.executable, "-m", "rockdem", *map(str, args)],
        cwd=cwd,
        capture_output=True,
        encoding=env.get("PYTHONIOENCODING") or "utf-8",
        timeout=300,
        env=full,
    )


@pytest.mark.skipif(not Path("/sys/kernel").is_dir(), reason="needs a read-only /sys")
def test_a_read_only_home_adds_no_lines_of_matplotlib(tmp_path):
    """With HOME on a read-only file system, `rockdem plot` wrote matplotlib's
    two lines ('mkdir -p failed ...', 'Matplotlib created a temporary cache
    directory ...') to stderr before the picture's path."""
    model = two_blocks(tmp_path)
    unset = dict.fromkeys(("MPLCONFIGDIR", "XDG_CONFIG_HOME", "XDG_CACHE_HOME"))
    r = _child(
        "plot",
        model,
        "--what",
        "model",
        "--out",
        "m.png",
        cwd=tmp_path,
        HOME="/sys/kernel",
        **unset,
    )
    assert r.returncode == 0, r.stderr
    assert r.stderr == "", r.stderr
    assert (tmp_path / "m.png").stat().st_size > 0


@pytest.mark.parametrize("encoding", ["ascii", "latin-1"])
def test_a_terminal_that_cannot_show_the_name_gets_escapes(tmp_path, encoding):
    """On an ASCII (LANG=C) or Latin-1 terminal a model named "Böschung –
    Süd" stopped `rockdem check` with 'the analysis failed:
    UnicodeEncodeError', exit 1: the model was fine."""
    model = two_blocks(tmp_path, name="Böschung – Süd")
    r = _child("check", model, cwd=tmp_path, PYTHONIOENCODING=encoding)
    assert r.returncode == 0, r.stderr
    assert "\\u2013 S" in r.stdout and "valid" in r.stdout
    r = _child("check", tmp_path / "nö.yaml", cwd=tmp_path, PYTHONIOENCODING=encoding)
    assert r.returncode == 2 and "file not found" in r.stderr, r.stderr


def test_a_narrow_terminal_cuts_no_table_cells(tmp_path):
    """With COLUMNS=20 the tables of `check` and `run` cut their cells to
    '…': 'inter…', blocks '2…' for 26-27, the numbers lost."""
    model = two_blocks(tmp_path)
    r = _child("check", model, cwd=tmp_path, COLUMNS="20")
    assert r.returncode == 0, r.stderr
    assert "…" not in r.stdout and "total length" in r.stdout
    r = _child("run", "--example", "wedge-verification", "--quiet", cwd=tmp_path, COLUMNS="20")
    assert r.returncode == 0, r.stderr
    assert "…" not in r.stdout and "first step" in r.stdout


# ------------------------------------------------------------ left to the solver
@pytest.mark.xfail(
    strict=True,
    reason="solver numerics (left, not changed here): a free sliver 1e-6 wide between two "
    "blocks on flat ground leaves the staged analysis UNDECIDED at load factor 0 (its "
    "base springs carry 1e-6 of its neighbours' stiffness); 1e-5 wide it is stable",
)
def test_a_sliver_between_two_blocks_on_flat_ground_stands():
    """Three blocks side by side on a horizontal fixed plane, the middle one
    1e-6 wide: nothing can slide, the answer is 'stable'."""
    import rockdem as rd

    w = 1e-6
    polygons = [
        GROUND,
        SQUARE,
        [(1, 0), (1 + w, 0), (1 + w, 1), (1, 1)],
        [(1 + w, 0), (2, 0), (2, 1), (1 + w, 1)],
    ]
    blocks = rd.Blocks.from_polygons(polygons, fixed=[True, False, False, False], unit_weight=25)
    model = rd.Model(blocks, rd.Joint(normal_stiffness=1e6, friction_angle=30))
    assert rd.analyse(model).stable


def test_example_copys_overwrite_says_it_replaces_the_model_file():
    """`rockdem example copy --help` said --overwrite would 'Replace result
    files that exist already'; it replaces the model file of that name, the
    user's edited copy too."""
    r = invoke("example", "copy", "--help")
    assert r.exit_code == 0
    assert "result files" not in r.stdout and "edited copy" in " ".join(r.stdout.split())


@pytest.mark.parametrize(
    ("key", "value", "problem"),
    [
        ("workers", 1.5, "workers: 1.5 is not a whole number"),
        ("workers", "2", "workers: '2' is not a whole number"),
        ("out", 5, "out: 5 is not a folder's path"),
    ],
)
def test_rockdem_study_names_a_bad_argument(tmp_path, key, value, problem):
    """`rockdem.study(..., workers=1.5)` (or "2", or out=5) was a TypeError
    from deep inside ('float' object cannot be interpreted as an integer)."""
    import rockdem as rd

    spec = {"sweep": {"joints.plane.friction_angle": {"values": [30, 35]}}}
    kw = {"out": tmp_path / "s", "workers": 0, key: value}
    with pytest.raises(rd.InputError, match=problem):
        rd.study(two_blocks(tmp_path), spec, **kw)
