"""Line numbers in the errors of TOML model files, as in those of YAML files.

The locator (:mod:`rockdem.config.toml_lines`) on each construct of TOML, then
broken TOML models whose one-line message from ``rockdem run`` names
``file.toml:N:`` at the right line (and the same key path, problem and fix as
the YAML file of the same model, where the fix is not in the file's syntax).
"""

from __future__ import annotations

import tomllib

import pytest
import yaml
from typer.testing import CliRunner

from _cli import assert_refused
from rockdem.cli import app
from rockdem.config import ModelFileError, parse_model
from rockdem.config.toml_lines import TomlLines, toml_lines

# ------------------------------------------------------------------ locator
TRICKY = r"""# a comment [not.a.table] = 1
title = "a [b] # c = d"  # a trailing [comment] = "x"
"quoted key" = 'C:\dir [x] # y'
'lit.key' = 1
a.b . c = 2
text = QQQ
[not.a.table]
x = "1" "" \QQQ = [
QQQ
lit = '''
[[nor.this]] '' # = '''
arr = [
  1,   # one, [two]
  [2, 3],
  { k = "}", m = [4,
    5] },
]
ends = QQQquoteQQQ"

[tab.le]
x = 1
[[aot]]
name = "first"
[aot.sub]
y = 2
[[aot.items]]
z = 3
[[aot.items]]
z = 4
[[aot]]
[[aot.items]]
z = 5
inline = {p = 1, q = {r = 2}, s . t = 3}
pts = [{at = [1, 2]}, {at = [3, 4]}]
[  "sp ace" . 'x' ]
"a\"b" = 1
"\u0041" = [
  {n = 1},

  {n = 2},
]
""".replace("QQQ", '"' * 3)

CASES = [
    (("title",), 2),
    (("quoted key",), 3),
    (("lit.key",), 4),
    (("a",), 5),
    (("a", "b", "c"), 5),
    (("text",), 6),
    (("lit",), 10),
    (("arr",), 12),
    (("arr", 0), 13),
    (("arr", 1), 14),
    (("arr", 1, 1), 14),
    (("arr", 2), 15),
    (("arr", 2, "k"), 15),
    (("arr", 2, "m", 1), 16),
    (("arr", 3), 12),  # past the end: the array's line
    (("ends",), 18),
    (("tab",), 20),
    (("tab", "le", "x"), 21),
    (("tab", "le", "missing"), 20),  # a missing key: its table's header
    (("aot",), 22),
    (("aot", 0), 22),
    (("aot", 0, "name"), 23),
    (("aot", 0, "sub", "y"), 25),
    (("aot", 0, "items"), 26),
    (("aot", 0, "items", 0, "z"), 27),
    (("aot", 0, "items", 1), 28),
    (("aot", 0, "items", 1, "z"), 29),
    (("aot", 1), 30),
    (("aot", 1, "items", 0, "z"), 32),
    (("aot", 1, "items", 0, "inline", "q", "r"), 33),
    (("aot", 1, "items", 0, "inline", "s", "t"), 33),
    (("aot", 1, "items", 0, "pts", 1, "at", 0), 34),
    (("aot", 2, "name"), 22),  # no third table: the array's line
    (("sp ace",), 35),
    (("sp ace", "x", 'a"b'), 36),
    (("sp ace", "x", "A", 0, "n"), 38),
    (("sp ace", "x", "A", 1, "n"), 40),
    (("missing",), 2),  # the document: its first key
]


@pytest.mark.parametrize("newline", ["\n", "\r\n"])
def test_every_construct_has_its_line(newline):
    text = TRICKY.replace("\n", newline)
    data = tomllib.loads(text)  # valid TOML, and what it holds:
    assert "not" not in data and "nor" not in data
    assert data["ends"] == 'quote"' and data["sp ace"]["x"]["A"][1] == {"n": 2}
    assert data["aot"][1]["items"][0]["inline"]["s"] == {"t": 3}
    where = TomlLines(text)
    got = {loc: where.line(loc) for loc, _ in CASES}
    assert got == dict(CASES)
    assert not any(loc[0] in ("not", "nor", "x", "y") for loc in toml_lines(text) if loc)


def _paths(data, loc=()):
    if isinstance(data, dict):
        for k, v in data.items():
            yield (*loc, k)
            yield from _paths(v, (*loc, k))
    elif isinstance(data, list):
        for i, v in enumerate(data):
            yield from _paths(v, (*loc, i))


def test_every_key_is_on_its_line():
    """Every key of the data is found, on a line naming it."""
    lines = TRICKY.splitlines()
    where = toml_lines(TRICKY)
    raw = {'a"b': r"a\"b", "A": r"\u0041"}
    for loc in _paths(tomllib.loads(TRICKY)):
        if isinstance(loc[-1], str):
            assert raw.get(loc[-1], loc[-1]) in lines[where[loc] - 1], loc


def test_lines_are_scanned_only_when_asked_for():
    where = TomlLines("x = 1\n")
    assert where._lines is None
    assert where.line(("x",)) == 1 and where._lines == {(): 1, ("x",): 1}


# ------------------------------------------------------- messages of models
BOX = """units = "kN, m, kPa"

[materials.rock]
unit_weight = 25

[joints.bedding]
normal_stiffness = 1.0e6
friction_angle = 30

[[blocks]]
fixed = true
vertices = [[-5, -1], [5, -1], [5, 0], [-5, 0]]

[[blocks]]
material = "rock"
vertices = [
  [0, 0],
  [2, 0],
  [2, 1],
  [0, 1],
]

[[blocks]]
material = "rock"
vertices = [[0, 1], [2, 1], [2, 2], [0, 2]]
"""


def _line_of(text: str, fragment: str) -> int:
    (n,) = [i for i, t in enumerate(text.splitlines(), 1) if fragment in t]
    return n


def _run(tmp_path, text: str, name: str = "m.toml") -> str:
    """``rockdem run`` of ``text``: refused in one line; the line."""
    (tmp_path / name).write_text(text)
    r = CliRunner().invoke(app, ["run", str(tmp_path / name), "--quiet"])
    return assert_refused(r, f"error: {tmp_path / name}:")


def _as_yaml(toml_text: str) -> str:
    return yaml.safe_dump(tomllib.loads(toml_text), sort_keys=False)


def test_the_box_runs(tmp_path):
    (tmp_path / "m.toml").write_text(BOX)
    r = CliRunner().invoke(app, ["check", str(tmp_path / "m.toml")])
    assert r.exit_code == 0, r.output


#: (old, new, the text on the line named, the message after it, same in YAML)
BROKEN = [
    (  # out of range in a [joints.x] table
        "friction_angle = 30",
        "friction_angle = 135",
        "friction_angle = 135",
        "joints.bedding.friction_angle: 135 is out of range; give a value >= 0 and < 90",
        True,
    ),
    (  # a missing key: its table's header
        "friction_angle = 30\n",
        "",
        "[joints.bedding]",
        "joints.bedding.friction_angle: required key is missing",
        False,
    ),
    (  # an unknown key
        "friction_angle = 30",
        "friction_angle = 30\nfriction = 30",
        "friction = 30",
        "joints.bedding.friction: unknown key",
        True,
    ),
    (  # a wrong value in the second [[blocks]], in an element of a multi-line array
        "  [2, 1],",
        "  [2, true],",
        "[2, true]",
        "blocks[1].vertices[2][1]: expected a number",
        True,
    ),
    (  # a bad reference: the material of the third block
        'material = "rock"\nvertices = [[0, 1]',
        'material = "granite"\nvertices = [[0, 1]',
        'material = "granite"',
        "blocks[2].material: material 'granite' is not defined in `materials`",
        True,
    ),
    (  # a value in an inline table in an array
        "[[blocks]]\nfixed",
        "[loads]\npoints = [\n  {at = [1, 1], force = [0, -10]},\n"
        "  {at = [1, 1], force = [0, -10], name = 7},\n]\n\n[[blocks]]\nfixed",
        "name = 7",
        "loads.points[1].name: expected text, got 7",
        True,
    ),
    (  # from building the model: a load that misses every block
        "[[blocks]]\nfixed",
        "[loads]\npoints = [\n  {at = [1, 1], force = [0, -10]},\n"
        "  {at = [20, 20], force = [0, -10]},\n]\n\n[[blocks]]\nfixed",
        "{at = [20, 20]",
        "loads.points[1]: ",
        True,
    ),
    (  # from building the model: the third block overlaps the second
        "vertices = [[0, 1], [2, 1], [2, 2], [0, 2]]",
        "vertices = [[0, 0.5], [2, 0.5], [2, 2], [0, 2]]",
        "[[blocks]]",  # the second (see below)
        "blocks[1]: blocks 1 and 2 overlap",
        True,
    ),
]


@pytest.mark.parametrize(
    ("old", "new", "at", "message", "as_yaml"), BROKEN, ids=lambda v: str(v)[:24]
)
def test_a_toml_error_names_its_line(tmp_path, old, new, at, message, as_yaml):
    assert old in BOX
    text = BOX.replace(old, new, 1)
    said = _run(tmp_path, text)
    lines = [i for i, t in enumerate(text.splitlines(), 1) if at in t]
    line = lines[1] if at == "[[blocks]]" else lines[-1]
    assert said.startswith(f"error: {tmp_path / 'm.toml'}:{line}: {message}"), said
    if as_yaml:  # the same key path, problem and fix as the YAML of the model
        yaml_said = _run(tmp_path, _as_yaml(text), "m.yaml")
        assert yaml_said.split(": ", 2)[2] == said.split(": ", 2)[2]


def test_two_bolts_of_one_name_in_an_array_of_tables(tmp_path):
    bolt = (
        '[[bolts]]\nname = "B1"\nhead = [1, 2]\nangle = 270\nlength = 1.5\n'
        "capacity = 50\naxial_stiffness = 1.0e4\n\n"
    )
    text = BOX + "\n" + bolt + bolt.replace("[1, 2]", "[1.5, 2]")
    line = [i for i, t in enumerate(text.splitlines(), 1) if t == 'name = "B1"'][1]
    said = _run(tmp_path, text)
    assert f"m.toml:{line}: bolts[1].name: 'B1' is already the name of bolts[0]" in said


def test_an_error_from_a_slope_names_its_line(tmp_path):
    """An engine error mapped back to a key of a generated slope."""
    text = """units = "kN, m, kPa"
ground_joint = "base"
materials = {rock = {unit_weight = 25}}

[joints]
bedding = {normal_stiffness = 1.0e6, friction_angle = 35}
base = {normal_stiffness = 1.0e6, friction_angle = 45}

[slope]
depth = 3
profile = {height = 6, face_angle = 60}
joint_sets.bedding = {dip = 0, spacing = 2, origin = [0, 1]}
joint_sets.cross = {dip = 90, spacing = 3, origin = [0.5, 0]}
"""
    said = _run(tmp_path, text)
    line = _line_of(text, "joint_sets.cross")
    assert f"m.toml:{line}: slope.joint_sets.cross" in said


def test_a_toml_model_file_error_has_the_line_in_the_api():
    text = BOX.replace("friction_angle = 30", "friction_angle = -1")
    with pytest.raises(ModelFileError) as info:
        parse_model(text, fmt="toml", source="m.toml")
    assert info.value.line == _line_of(text, "friction_angle = -1")


def test_a_study_in_a_toml_model_names_its_line(tmp_path):
    """The study's inputs are quoted keys (a key path holds dots)."""
    text = (
        BOX
        + "\n[study]\nsamples = 10\n\n[study.inputs]\n"
        + '"joints.bedding.friction_angle" = {distribution = "normal", mean = 35, sd = 2}\n'
        + '"joints.bedding.nope" = {distribution = "normal", mean = 35, sd = 2}\n'
    )
    (tmp_path / "m.toml").write_text(text)
    r = CliRunner().invoke(app, ["study", str(tmp_path / "m.toml"), "-o", str(tmp_path / "out")])
    line = _line_of(text, "nope")
    assert_refused(r, f"m.toml:{line}: study.inputs.joints.bedding.nope: no such number")


def test_a_warning_about_a_toml_model_names_its_line(tmp_path):
    import warnings

    from rockdem.config import load_model
    from rockdem.errors import ModelWarning

    text = BOX + "\n[loads]\ngravity = false\nseismic_h = 0.1\n"
    (tmp_path / "m.toml").write_text(text)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ModelWarning)
        load_model(tmp_path / "m.toml")
    said = [str(w.message) for w in caught if issubclass(w.category, ModelWarning)]
    line = _line_of(text, "seismic_h")
    assert len(said) == 1 and f"m.toml:{line}: loads.seismic_h with gravity off" in said[0]


def test_a_cross_check_words_its_fix_in_toml(tmp_path):
    """The checks between sections (a free block with no unit weight when
    two materials are defined) said "give `material:` or `unit_weight:`" in
    a .toml file; they say `material = ...`, as validation errors do, and
    the YAML of the model keeps its own syntax."""
    last = 'material = "rock"\nvertices = [[0, 1]'
    text = BOX.replace(last, "vertices = [[0, 1]") + "\n[materials.clay]\nunit_weight = 20\n"
    said = _run(tmp_path, text)
    assert "give `material = ...` or `unit_weight = ...`" in said
    yaml_said = _run(tmp_path, _as_yaml(text), "m.yaml")
    assert "give `material:` or `unit_weight:`" in yaml_said
