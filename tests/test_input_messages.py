"""Messages of bad model files found by a fuzz review: each names the place
(file:line:key) and the cause, not a consequence of it.

Duplicate names of bolts, trials and stages (they merged in the results), a
misspelt required key (reported only as missing), a file of too many values
without aliases (blamed on an alias bomb) and a block touching another only
at a corner (said to overlap it by a sliver).
"""

from __future__ import annotations

import pytest

from _cli import assert_refused
from _models import BOX, SLOPE
from rockdem.config import ModelFileError, parse_document, parse_model, yaml_read


def _refused(text: str) -> str:
    with pytest.raises(ModelFileError) as info:
        parse_model(text, source="m.yaml")
    return str(info.value)


# ------------------------------------------------------------ duplicate names
BOLTED = (
    BOX
    + """bolts:
  - {name: B1, head: [1, 2], angle: 270, length: 1.5, capacity: 50, axial_stiffness: 1.0e+4}
  - {name: B1, head: [1.5, 2], angle: 270, length: 1.5, capacity: 50, axial_stiffness: 1.0e+4}
"""
)


def test_two_bolts_of_one_name_are_refused():
    """Found by fuzzing: the bolted example with B2 renamed B1 ran, and the
    results merged the two bolts into one."""
    assert _refused(BOLTED) == (
        "m.yaml:11: bolts[1].name: 'B1' is already the name of bolts[0]; "
        "give each bolt its own name"
    )


def test_bolts_without_names_need_none():
    model, _ = parse_model(BOLTED.replace("name: B1, ", ""))
    assert [b.name for b in model.bolts] == ["bolts[0]", "bolts[1]"]
    model, _ = parse_model(BOLTED.replace("name: B1, ", 'name: "", '))
    assert [b.name for b in model.bolts] == ["bolts[0]", "bolts[1]"]


@pytest.mark.parametrize(
    ("section", "label", "line"),
    [("trials", "trial", 17), ("stages", "stage", 17)],
)
def test_two_designs_of_one_name_are_refused(section, label, line):
    text = (
        SLOPE
        + f"""stabilisation:
  {section}:
    - {{name: A, remove: {{blocks: [1]}}}}
    - {{name: A, remove: {{blocks: [2]}}}}
"""
    )
    assert _refused(text) == (
        f"m.yaml:{line}: stabilisation.{section}[1].name: 'A' is already the name of "
        f"stabilisation.{section}[0]; give each {label} its own name"
    )


# ------------------------------------------------------ a misspelt required key
@pytest.mark.parametrize(
    ("typo", "meant"),
    [
        ("friction_angel", "friction_angle"),
        ("normal_stiffnes", "normal_stiffness"),
        ("friction_angIe", "friction_angle"),  # a capital I for an l
    ],
)
def test_a_misspelt_required_key_is_named_before_the_missing_one(typo, meant):
    """Found by fuzzing: `friction_angel: 30` was reported only as
    "friction_angle: required key is missing", which hides the typo."""
    text = BOX.replace(meant, typo, 1)
    assert _refused(text) == (
        f"m.yaml:4: joints.bedding.{typo}: unknown key; did you mean `{meant}`? "
        "(1 more problem in the file)"
    )


def test_a_missing_key_without_a_typo_is_still_named():
    text = BOX.replace("friction_angle: 30", "cohesion: 1", 1)
    assert "joints.bedding.friction_angle: required key is missing" in _refused(text)


# ------------------------------------------------------------ too many values
def test_too_many_values_without_aliases_names_the_key(monkeypatch):
    """Found by fuzzing: a water table of 1.5 million points (no aliases at all)
    was blamed on "aliases that multiply (an alias bomb)"."""
    monkeypatch.setattr(yaml_read, "MAX_NODES", 1000)
    points = ", ".join(f"[{i}, 1]" for i in range(400))
    text = BOX + f"loads:\n  water_unit_weight: 9.81\n  water_table: [{points}]\n"
    with pytest.raises(ModelFileError) as info:
        parse_document(text, source="m.yaml")
    message = str(info.value)
    assert message.startswith("m.yaml:11: loads.water_table: holds more than 1,000 values")
    assert "alias" not in message


def test_too_many_values_from_aliases_is_still_an_alias_bomb(monkeypatch):
    monkeypatch.setattr(yaml_read, "MAX_NODES", 1000)
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, 5)]
    with pytest.raises(ModelFileError) as info:
        parse_document(BOX + "\n".join(lines) + "\n", source="m.yaml")
    assert "once its aliases are expanded" in str(info.value)
    assert "alias bomb" in str(info.value)


# ------------------------------------------------------- a corner-only contact
CORNER = """units: kN, m, kPa
materials: {rock: {unit_weight: 25}}
joints:
  j: {normal_stiffness: 1.0e+6, friction_angle: 30}
blocks:
  - {fixed: true, vertices: [[-5, -1], [5, -1], [5, 0], [-5, 0]]}
  - {material: rock, vertices: [[0, 0], [1, 0], [1, 1], [0, 1]]}
  - {material: rock, vertices: [[1, 1], [2, 1], [2, 2], [1, 2]]}
"""

DIAMOND = """units: kN, m, kPa
materials: {rock: {unit_weight: 25}}
joints:
  j: {normal_stiffness: 1.0e+6, friction_angle: 30}
blocks:
  - {fixed: true, vertices: [[-5, -1], [5, -1], [5, 0], [-5, 0]]}
  - {material: rock, vertices: [[0, 0], [1, 1], [0, 2], [-1, 1]]}
"""


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        (CORNER, "m.yaml:8: blocks[2]: block 2 touches block 1 only at the point (1, 1)"),
        (DIAMOND, "m.yaml:7: blocks[1]: block 1 touches block 0 only at the point (0, 0)"),
        (  # a corner within the tolerance of the other block's corner
            CORNER.replace("[[1, 1], [2, 1]", "[[1, 1.00000000001], [2, 1]"),
            "blocks[2]: block 2 touches block 1 only at the point (1, 1)",
        ),
    ],
)
def test_a_block_touching_only_at_a_corner_is_named_so(text, expected):
    """Found by fuzzing: a block standing on another's corner was said to
    overlap it "by a sliver deeper than the model's geometric tolerance"."""
    message = _refused(text)
    assert expected in message and "blocks must share an edge" in message
    assert "sliver" not in message and "overlaps" not in message


@pytest.mark.parametrize(
    ("base", "expected"),
    [
        ("[[0, -1e-6], [1, -1e-6]", "it overlaps block 0 by a sliver deeper than"),
        ("[[0, 1e-5], [1, 1e-5]", "it misses block 0 by 1e-05, more than"),
    ],
)
def test_a_block_along_the_ground_but_off_it_is_still_named_so(base, expected):
    """The messages a corner contact was confused with stay for what they
    describe: a block sunk into the ground, or one floating just above it."""
    text = DIAMOND.replace("[[0, 0], [1, 1], [0, 2], [-1, 1]]", base + ", [1, 1], [0, 1]]")
    assert f"blocks[1]: block 1 shares no edge with another block: {expected}" in _refused(text)


def test_a_corner_contact_is_one_line_and_exit_2(tmp_path):
    from typer.testing import CliRunner

    from rockdem.cli import app

    (tmp_path / "m.yaml").write_text(CORNER)
    r = CliRunner().invoke(app, ["check", str(tmp_path / "m.yaml")])
    assert_refused(r, "touches block 1 only at the point (1, 1)")


@pytest.mark.parametrize(
    ("section", "where"),
    [
        ("loads:\n  points:\n    - {at: [1, 1], force: [0, -10], name: crane}\n"
         "    - {at: [1.5, 1], force: [0, -10], name: crane}\n", "loads.points[1].name"),
        ("loads:\n  lines:\n    - {start: [0, 1], end: [1, 1], q: [0, -5], name: road}\n"
         "    - {start: [1, 1], end: [2, 1], q: [0, -5], name: road}\n", "loads.lines[1].name"),
        ("supports:\n  - {at: [2, 0.5], force: 100, angle: 180, name: prop}\n"
         "  - {at: [2, 0.7], force: 100, angle: 180, name: prop}\n", "supports[1].name"),
    ],
)  # fmt: skip
def test_two_loads_or_supports_of_one_name_are_refused(section, where):
    """Loads and supports are listed by name as bolts are (their error
    locations were kept by name too, the last one winning)."""
    message = _refused(BOX + section)
    assert where in message and "is already the name of" in message
