"""Hostile input: whatever a model file holds, rockdem answers in bounded time and
memory with one line and exit 2 (or a correct result), and writes nothing it was
not asked to write.

Cases whose failure would be a hang or a memory blow-up (pipes, devices, large
files, aliases, nesting, models too large to build, writing results) run
``python -m rockdem`` in a subprocess with a time limit and an address-space
limit; cases refused by validation run in-process (typer's runner) with a time
limit asserted.  Files are generated here in ``tmp_path``.  Classes: files
that are not regular or too large, encodings, YAML aliases and nesting, number
spellings, values out of their range, iteration counts, models too large to
build, what ``check`` must refuse, blocks that nothing holds, and
destinations (never over the model, never half a result set).
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import shapely

import rockdem as rd
from _cli import assert_refused
from _models import BOX, SLOPE
from rockdem.config import ModelFileError, parse_model
from rockdem.config.parse import MAX_FILE_BYTES
from rockdem.config.yaml_read import MAX_DEPTH, MAX_NODES
from rockdem.geometry import JointSet, Profile, estimate_size, generate_slope, section_polygon

TIME_LIMIT = 60  # seconds: a hang fails the test (each case takes 1-3 s)
MEMORY_LIMIT = 1536 * 2**20  # bytes of address space for the child


BOX_TOML = """units = "kN, m, kPa"
[materials.rock]
unit_weight = 25
[joints.bedding]
normal_stiffness = 1e6
friction_angle = 30
[[blocks]]
fixed = true
vertices = [[-5, -1], [5, -1], [5, 0], [-5, 0]]
[[blocks]]
material = "rock"
vertices = [[0, 0], [2, 0], [2, 1], [0, 1]]
"""


def _limit_memory() -> None:  # pragma: no cover - runs in the child
    try:
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    except (ImportError, ValueError, OSError):
        pass


def rockdem(*args, cwd: Path, timeout: float = TIME_LIMIT) -> subprocess.CompletedProcess:
    """Run the command line in a child with a time and a memory limit."""
    env = {**os.environ, "COLUMNS": "400", "ROCKDEM_MAX_BLOCKS": ""}
    env.pop("ROCKDEM_MAX_BLOCKS")
    start = time.monotonic()
    r = subprocess.run(
        [sys.executable, "-m", "rockdem", *map(str, args)],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
        preexec_fn=_limit_memory if sys.platform.startswith("linux") else None,
    )
    r.elapsed = time.monotonic() - start
    return r


class _Run:
    """What a command returned (in-process), shaped like a CompletedProcess."""

    def __init__(self, returncode: int, stdout: str, stderr: str, elapsed: float) -> None:
        self.returncode, self.stdout, self.stderr, self.elapsed = (
            returncode,
            stdout,
            stderr,
            elapsed,
        )


def inproc(*args, cwd: Path, limit: float = 10.0) -> _Run:
    """Run the command line in this process (fast) and assert it took under ``limit`` s."""
    from typer.testing import CliRunner

    from rockdem.cli import app

    old = Path.cwd()
    os.chdir(cwd)
    try:
        start = time.monotonic()
        r = CliRunner().invoke(app, [str(a) for a in args])
        elapsed = time.monotonic() - start
    finally:
        os.chdir(old)
    assert elapsed < limit, f"took {elapsed:.1f} s"
    return _Run(r.exit_code, r.stdout, r.stderr, elapsed)


def check(tmp_path: Path, text: str, name: str = "m.yaml", *extra, child: bool = False):
    """``rockdem check`` of ``text`` (in a subprocess with ``child``)."""
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    run = rockdem if child else inproc
    return run(*extra, "check", path.name, cwd=tmp_path)


# ------------------------------------------------------------ what is read
@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
def test_a_named_pipe_is_refused_not_waited_on(tmp_path):
    os.mkfifo(tmp_path / "pipe.yaml")
    assert_refused(rockdem("check", "pipe.yaml", cwd=tmp_path, timeout=20), "not a regular file")


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="no /dev/zero")
def test_a_device_is_refused_not_read(tmp_path):
    assert_refused(rockdem("check", "/dev/zero", cwd=tmp_path, timeout=20), "not a regular file")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
@pytest.mark.parametrize(
    "args, target",
    [
        (["schema", "-o", "pipe.json", "--overwrite"], "pipe.json"),
        (["plot", "m.yaml", "--what", "model", "-o", "pipe.png", "--overwrite"], "pipe.png"),
        (["run", "m.yaml", "--out", "out", "--overwrite", "--quiet"], "out/blocks.csv"),
    ],
    ids=["schema", "plot", "run-folder"],
)
def test_an_output_that_is_a_pipe_is_never_replaced(tmp_path, args, target):
    """Found by fuzzing: ``--out`` on a named pipe (or a device) with
    ``--overwrite`` replaced it with a regular file (as root, /dev/full)."""
    (tmp_path / "m.yaml").write_text(BOX, encoding="utf-8")
    (tmp_path / "out").mkdir()
    os.mkfifo(tmp_path / target)
    assert_refused(inproc(*args, cwd=tmp_path), "not a regular file", target)
    assert not (tmp_path / target).is_file()  # still the pipe
    assert (tmp_path / target).exists()


def test_a_block_of_too_many_vertices_is_refused_at_its_key(tmp_path):
    """Found by fuzzing: one block's edge split into 100,000 collinear points
    made three blocks into 43,751 interfaces (run 106 s, fos over 120 s)."""
    from rockdem.config.build import MAX_VERTICES

    xs = np.linspace(0.0, 2.0, MAX_VERTICES)  # the base, then the three other corners
    ring = [[round(float(x), 6), 0.0] for x in xs] + [[2.0, 1.0], [0.0, 1.0]]
    text = BOX.replace("[[0, 0], [2, 0], [2, 1], [0, 1]]", str(ring))
    line = assert_refused(check(tmp_path, text), "blocks[1].vertices", "more than the limit")
    assert f"{MAX_VERTICES + 2:,} vertices" in line


def test_a_file_name_with_a_line_break_stays_on_one_line(tmp_path):
    """Found by fuzzing: a file name holding a newline split the error in two."""
    name = "bad\nname.yaml"
    (tmp_path / name).write_text("x", encoding="utf-8")
    assert_refused(inproc("check", name, cwd=tmp_path), "bad\\nname.yaml")


def test_a_block_below_the_tolerance_is_called_small_not_zero_area(tmp_path):
    """Found by fuzzing: a 1 mm block beside a ground block 14,000 km wide
    (the tolerance is 1e-8 of the extent, 0.14 m) was said to have zero area."""
    text = BOX.replace(
        "[[-5, -1], [5, -1], [5, 0], [-5, 0]]", "[[-7e6, -1], [7e6, -1], [7e6, 0], [-7e6, 0]]"
    )
    text = text.replace(
        "[[0, 0], [2, 0], [2, 1], [0, 1]]", "[[0, 0], [0.001, 0], [0.001, 0.001], [0, 0.001]]"
    )
    assert_refused(
        check(tmp_path, text), "blocks[1]", "smaller than the model's geometric tolerance"
    )


def test_a_folder_is_refused(tmp_path):
    (tmp_path / "model.yaml").mkdir()
    assert_refused(rockdem("check", "model.yaml", cwd=tmp_path), "model.yaml: is a folder")


def test_a_file_over_the_size_limit_is_refused_unread(tmp_path):
    with open(tmp_path / "big.yaml", "wb") as fh:
        fh.truncate(MAX_FILE_BYTES + 1)  # sparse: costs no disk
    assert_refused(rockdem("check", "big.yaml", cwd=tmp_path), "larger than 32 MiB")


def test_text_that_is_not_utf8_is_refused(tmp_path):
    (tmp_path / "m.yaml").write_bytes(BOX.replace("kPa", "kPa \xe9").encode("latin-1"))
    assert_refused(rockdem("check", "m.yaml", cwd=tmp_path), "is not UTF-8 text")


@pytest.mark.parametrize("name,text", [("m.toml", BOX_TOML), ("m.yaml", BOX)])
def test_a_utf8_byte_order_mark_is_accepted(tmp_path, name, text):
    (tmp_path / name).write_bytes(b"\xef\xbb\xbf" + text.encode())
    r = rockdem("check", name, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "valid" in r.stdout


# ----------------------------------------------------------------- YAML
def test_an_alias_bomb_ends_at_once(tmp_path):
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, 10)]
    r = check(tmp_path, BOX + "\n".join(lines) + "\n", child=True)
    assert_refused(r, f"more than {MAX_NODES:,} values once its aliases are expanded")
    assert r.elapsed < 15


def test_an_alias_inside_its_own_anchor_is_refused(tmp_path):
    r = check(tmp_path, BOX + "description: &d [1, *d]\n", child=True)
    assert_refused(r, "alias *d refers to the node")


def test_aliases_within_the_bounds_share_properties(tmp_path):
    text = BOX.replace(
        "  bedding: {normal_stiffness: 1.0e+6, friction_angle: 30}",
        "  bedding: &j {normal_stiffness: 1.0e+6, friction_angle: 30}\n  other: *j",
    )
    r = check(tmp_path, text)
    assert r.returncode == 0, r.stderr


@pytest.mark.parametrize(
    "name,text",
    [
        ("m.yaml", BOX + "description: " + "[" * 20000 + "]" * 20000 + "\n"),
        ("m.json", '{"joints": ' + "[" * 20000 + "]" * 20000 + "}\n"),
        ("m.toml", BOX_TOML.replace('units = "kN, m, kPa"', "x = " + "[" * 20000 + "]" * 20000)),
        ("n.toml", BOX_TOML.replace('units = "kN, m, kPa"', "x = " + "[" * 100 + "]" * 100)),
    ],
)
def test_deep_nesting_is_refused_without_recursion(tmp_path, name, text):
    assert_refused(check(tmp_path, text, name, child=True), f"more than {MAX_DEPTH} deep")


# -------------------------------------------------------------- numbers
@pytest.mark.parametrize(
    "value,fragment",
    [
        ('"2_5"', "expected a number, got '2_5'"),
        ("2_5", "expected a number, got '2_5'"),  # YAML 1.2: text, not 25
        ("1:30", "expected a number, got '1:30'"),  # YAML 1.1 sexagesimal: text
        ('"0x1e"', "expected a number, got '0x1e'"),
        ('"infinity"', "expected a number, got 'infinity'"),
        (".inf", "is not a finite number"),
    ],
)
def test_numbers_are_read_as_the_format_writes_them(tmp_path, value, fragment):
    text = BOX.replace("friction_angle: 30", f"friction_angle: {value}")
    assert_refused(check(tmp_path, text), "joints.bedding.friction_angle", fragment)


def test_toml_underscores_are_toml_numbers_but_quoted_ones_are_not(tmp_path):
    ok = check(tmp_path, BOX_TOML.replace("friction_angle = 30", "friction_angle = 2_5"), "a.toml")
    assert ok.returncode == 0, ok.stderr
    r = check(tmp_path, BOX_TOML.replace("friction_angle = 30", 'friction_angle = "2_5"'), "b.toml")
    assert_refused(r, "joints.bedding.friction_angle", "expected a number")


def test_a_toml_file_gets_its_fix_in_toml(tmp_path):
    """Found by fuzzing: joints written as TOML's [[joints]] were told to
    "write `key: value` lines indented under it", YAML's syntax."""
    listed = BOX_TOML.replace("[joints.bedding]", '[[joints]]\nname = "bedding"')
    line = assert_refused(check(tmp_path, listed, "a.toml"), "joints: expected a mapping")
    assert "[joints.NAME]" in line and "`key = value`" in line and "indented" not in line
    missing = BOX_TOML.replace("friction_angle = 30\n", "")
    assert_refused(check(tmp_path, missing, "b.toml"), "add `friction_angle = ...`")
    yaml = BOX.replace(", friction_angle: 30}", "}")
    assert_refused(check(tmp_path, yaml, "c.yaml"), "add `friction_angle:`")


@pytest.mark.parametrize("name", ["m.yaml", "m.toml"])
def test_a_number_of_thousands_of_digits_is_refused_at_its_line(tmp_path, name):
    """Found by fuzzing: a 5,000-digit integer stopped the program with
    Python's "Exceeds the limit (4300 digits)" (exit 1)."""
    huge = "9" * 5000
    if name.endswith(".toml"):
        text = BOX_TOML.replace("friction_angle = 30", f"friction_angle = {huge}")
    else:
        text = BOX.replace("friction_angle: 30", f"friction_angle: {huge}")
    line = next(i for i, t in enumerate(text.splitlines(), 1) if huge in t)
    assert_refused(check(tmp_path, text, name), f"{name}:{line}:", "thousands of digits")


@pytest.mark.parametrize(
    "region,fragment",
    [
        ("[[-10, 7], [-6, 7], [-6, 12], [-10, 12]]", "holds the centroid of no listed block"),
        ("[[0, 0], [1, 1], [2, 2]]", "is not a valid polygon"),
        ("[[-10, 7], [-6, 12], [-6, 7], [-10, 12]]", "is not a valid polygon"),
    ],
)
def test_a_removal_region_that_removes_nothing_is_refused(tmp_path, region, fragment):
    """Found by fuzzing: on listed blocks (the wedge example) a region that
    holds no block's centroid, a flat one and a self-crossing one were taken
    silently (the bow tie removed a block); a generated slope refuses them."""
    from rockdem.examples import example_path

    text = example_path("wedge-verification").read_text(encoding="utf-8")
    text += f"\nremove:\n  regions:\n    - {region}\n"
    line = len(text.splitlines())
    assert_refused(check(tmp_path, text), f"m.yaml:{line}: remove.regions[0]", fragment)


def test_json_exponents_are_numbers(tmp_path):
    r = check(tmp_path, BOX.replace("normal_stiffness: 1.0e+6", "normal_stiffness: 1e6"))
    assert r.returncode == 0, r.stderr


@pytest.mark.parametrize(
    "old,new,key,fragment",
    [
        (
            "{material: rock, vertices: [[0, 0]",
            "{id: 99999999999999999999999, material: rock, vertices: [[0, 0]",
            "blocks[1].id",
            "<= 9223372036854775807",
        ),
        ("unit_weight: 25", "unit_weight: 1.0e+300", "materials.rock.unit_weight", "<= 1e+09"),
        (
            "units: kN, m, kPa",
            "units: x\nanalysis: {tolerance: 1.0e-300}",
            "analysis.tolerance",
            ">= 1e-12 and < 0.01",
        ),
        (
            "units: kN, m, kPa",
            "units: x\nanalysis: {load_steps: 1000000000}",
            "analysis.load_steps",
            "<= 1000",
        ),
        (
            "units: kN, m, kPa",
            "units: x\nanalysis: {load_steps: 9223372036854775807}",
            "analysis.load_steps",
            "<= 1000",
        ),
        (
            "units: kN, m, kPa",
            "units: x\nanalysis: {max_iterations: 100000000}",
            "analysis.max_iterations",
            "<= 1000",
        ),
        (
            "units: kN, m, kPa",
            "units: x\nanalysis: {strength_reduction: {width: 1.0e-300}}",
            "analysis.strength_reduction.width",
            ">= 1e-06",
        ),
        (
            "units: kN, m, kPa",
            "units: x\nstabilisation: {max_rounds: 100000000}",
            "stabilisation.max_rounds",
            "<= 50",
        ),
        ("[[0, 0], [2, 0]", "[[1.0e+300, 0], [2, 0]", "blocks[1].vertices[0][0]", "<= 1e+09"),
        (
            "normal_stiffness: 1.0e+6",
            "normal_stiffness: 1.0e-300",
            "joints.bedding.normal_stiffness",
            ">= 1e-06 and <= 1e+15",
        ),
    ],
)
def test_values_out_of_their_range_name_the_key_and_the_range(tmp_path, old, new, key, fragment):
    assert old in BOX
    assert_refused(check(tmp_path, BOX.replace(old, new, 1)), key, "out of range", fragment)


@pytest.mark.parametrize("key", ["shear_stiffness", "shear_capacity", "pretension"])
def test_a_bolts_dowel_and_pretension_have_the_range_of_stiffnesses_and_forces(tmp_path, key):
    """Found by fuzzing: a bolt's shear_stiffness of 1e300 (no upper bound)
    reached the solver as "the elastic stiffness is singular"."""
    bolted = BOX + (
        "bolts:\n  - {head: [1, 1], angle: 270, length: 1.5, capacity: 50, "
        f"axial_stiffness: 1.0e+4, {key}: 1.0e+300}}\n"
    )
    assert_refused(check(tmp_path, bolted), f"bolts[0].{key}", "out of range", "<= 1e+15")


@pytest.mark.parametrize(
    "units, fragment",
    [
        ("kN, m, MPa", "kN / m^2 is kPa, not MPa"),
        ("MN, mm, kPa", "MN / mm^2 is 1e+12 Pa, not kPa"),
        ("kN, MN, m", "two force units (kN and MN)"),
        ("kN, m, ft", "two length units (m and ft)"),
    ],
)
def test_contradictory_units_are_refused(tmp_path, units, fragment):
    """Fuzzing: "kN, m, MPa" was accepted and every stress computed from kN and
    m (kPa) was labelled MPa.  The note labels every number: one system."""
    r = check(tmp_path, BOX.replace("units: kN, m, kPa", f"units: {units}", 1))
    assert_refused(r, ":1: units:", fragment, "one consistent system")


@pytest.mark.parametrize(
    "units", ["MN-m-MPa", "N, mm, MPa", "t, m, t/m^2", "units in kN and m", "kip, ft, ksf"]
)
def test_consistent_units_are_accepted(tmp_path, units):
    r = check(tmp_path, BOX.replace("units: kN, m, kPa", f'units: "{units}"', 1))
    assert r.returncode == 0 and "valid" in r.stdout, r.stderr


@pytest.mark.parametrize(
    "old, new, where",
    [
        (
            "  bedding: {",
            "  null: {normal_stiffness: 1, friction_angle: 30}\n  bedding: {",
            ":4: joints:",
        ),
        ("materials: {rock:", "materials: {~: {unit_weight: 3}, rock:", ":2: materials:"),
        ("blocks:", "analysis: {12: 3}\nblocks:", ":5: analysis:"),
    ],
)
def test_a_key_that_is_no_name_is_named_as_written(tmp_path, old, new, where):
    """Fuzzing: a YAML key `null:` (or `~`, or a number) was reported as
    `joints.None: expected text, got null` or pydantic's "Keys should be
    strings"; now the mapping, the key as the file spells it, and its line."""
    assert old in BOX
    line = assert_refused(check(tmp_path, BOX.replace(old, new, 1)), where, "a key must be a name")
    assert "None" not in line
    assert ("`12`" if "12" in new else "`null`") in line


@pytest.mark.parametrize(
    "settings",
    ["{grow: 1.000000001}", "{width: 1.0e-6, grow: 1.01}", "{largest: 1.0e+6, grow: 1.05}"],
)
def test_strength_reduction_settings_that_allow_endless_trials(tmp_path, settings):
    text = BOX.replace("units: kN, m, kPa", f"analysis: {{strength_reduction: {settings}}}")
    assert_refused(check(tmp_path, text), "analysis.strength_reduction", "trials, more than 100")


def test_a_negative_seed_is_an_input_error(tmp_path):
    r = check(tmp_path, SLOPE.replace("  depth: 3", "  depth: 3\n  seed: -1"))
    assert_refused(r, "slope.seed", "out of range", ">= 0")


def test_a_spacing_of_1e_minus_300_names_the_key_and_range(tmp_path):
    r = check(tmp_path, SLOPE.replace("spacing: 2,", "spacing: 1.0e-300,"))
    assert_refused(r, "slope.joint_sets.bedding.spacing", ">= 1e-06 and <= 1e+09")


# ------------------------------------------------------ size before build
@pytest.mark.parametrize(
    "old,new,key",
    [
        ("spacing: 2,", "spacing: 1.0e-4,", "slope.joint_sets.bedding"),
        ("height: 6, face_angle: 60", "height: 1.0e+6, face_angle: 60", "slope.joint_sets"),
        ("height: 6, face_angle: 60", "height: 6, face_angle: 0.001", "slope.joint_sets"),
        (
            "{dip: 0, spacing: 2, origin: [0, 1]}",
            "{dip: 0, spacing: 2, origin: [0, 1], trace_length: 1.0e-5, gap: 1.0e-5}",
            "slope.joint_sets.bedding.trace_length",
        ),
    ],
)
def test_a_slope_too_large_to_build_is_refused_with_its_estimate(tmp_path, old, new, key):
    text = SLOPE.replace(old, new)
    if "gap" in new:
        text = text.replace("  depth: 3", "  depth: 3\n  bridge_joint: base")
    r = check(tmp_path, text, child=True)
    line = assert_refused(
        r, key, "would cut the section", "more than the limit of 100,000 blocks", "--max-blocks"
    )
    assert "about" in line and "of memory" in line
    assert r.elapsed < 20


def test_the_block_limit_is_a_flag(tmp_path):
    r = check(tmp_path, SLOPE, "m.yaml", "--max-blocks", "3")
    assert_refused(r, "slope.joint_sets", "more than the limit of 3 blocks")
    r = check(tmp_path, BOX, "b.yaml", "--max-blocks", "2")
    assert_refused(r, "blocks", "3 blocks are more than the limit of 2")
    assert check(tmp_path, SLOPE, "m.yaml", "--max-blocks", "1000").returncode == 0


@pytest.mark.parametrize(
    "sets",
    [
        [("a", 25, 1.5, None, 0.0), ("b", 115, 1.0, None, 0.0)],
        [("a", 20, 2.0, 3.0, 1.0), ("b", 100, 1.5, None, 0.0)],
        [("a", 0, 1.0, None, 0.0), ("b", 90, 2.0, None, 0.0), ("c", 45, 3.0, None, 0.0)],
    ],
)
def test_the_size_estimate_is_close_to_the_built_slope(sets):
    j = rd.Joint(1e5, 30)
    prof = Profile.simple(20, 70, crest_length=20, toe_length=10)
    js = [JointSet(n, d, s, j, trace_length=t, gap=g, origin=(0.1, 0.2)) for n, d, s, t, g in sets]
    est = estimate_size(section_polygon(prof, 8), js)
    geom = generate_slope(prof, js, depth=8, bridge_joint=j, min_block_fraction=0)
    free = int((~geom.blocks.fixed).sum())
    faces = geom.interfaces().n_interfaces
    assert est.blocks == pytest.approx(free, rel=0.25)
    assert est.interfaces == pytest.approx(faces, rel=0.3)


def test_generate_slope_refuses_before_cutting():
    j = rd.Joint(1e5, 30)
    start = time.monotonic()
    with pytest.raises(rd.InputError, match=r"joint set 'a'.*more than the limit of 100,000"):
        generate_slope(Profile.simple(10, 60), [JointSet("a", 30, 1e-5, j)], depth=5)
    assert time.monotonic() - start < 2


def test_a_profile_spike_thinner_than_the_tolerance_is_refused_at_the_profile():
    """Found by fuzzing: a spike 1e-6 wide and 990 high left blocks with two
    corners once close corners merged; the analysis stopped on a shapely error
    (exit 1) instead of naming the profile (exit 2)."""
    j = rd.Joint(1e5, 35)
    spike = Profile([(-10, 10), (0, 10), (1e-6, 1000), (2e-6, 10), (20, 0)])
    sets = [JointSet("bedding", 30, 2.5, j), JointSet("cross", 120, 3.0, j, origin=(0.5, 0))]
    with pytest.raises(rd.InputError, match=r"profile.*thinner than the geometric tolerance"):
        generate_slope(spike, sets, depth=6, unit_weight=26)
    # the same spike 1 m wide is a slope like any other
    wide = Profile([(-10, 10), (0, 10), (1, 40), (2, 10), (20, 0)])
    blocks = generate_slope(wide, sets, depth=6, unit_weight=26).blocks
    assert np.diff(blocks.offsets).min() >= 3


def test_a_model_too_small_for_its_coordinates_is_refused():
    """Found by fuzzing: the seed paper's wedge shrunk to 10 um and moved to
    x = 1e9 (174 steps of floating point across it) read FS 1.0388, not
    0.9786; the same wedge at its own size there (4e7 steps) is analysed."""
    wedge = [(0, 0), (2, 0), (2, 1), (0, 1)]
    ground = [(-1, -1), (3, -1), (3, 0), (-1, 0)]

    def moved(scale):
        return [[(1e9 + scale * x, scale * y) for x, y in p] for p in (ground, wedge)]

    with pytest.raises(rd.InputError, match=r"blocks.*floating point resolves only"):
        rd.Blocks.from_polygons(moved(1e-5), fixed=[True, False])
    assert rd.Blocks.from_polygons(moved(10.0), fixed=[True, False]).n_blocks == 2


def test_a_random_joint_set_far_from_its_origin_is_refused_at_the_origin():
    """Found by fuzzing: a 10 m slope at x = 3e8 drew its lognormal spacings
    one by one from the set's origin at (0, 0), 1.2e8 of them: 8.5 GB."""
    j = rd.Joint(1e6, 30)
    rough = JointSet("a", 30, 2.5, j, spacing_sd=0.5)
    start = time.monotonic()
    with pytest.raises(rd.InputError, match=r"joint set 'a' origin.*spacings from the section"):
        generate_slope(Profile.simple(10, 60, toe=(3e8, 0)), [rough], depth=5, unit_weight=25)
    assert time.monotonic() - start < 2
    # the same set with its origin at the slope is cut as usual
    near = JointSet("a", 30, 2.5, j, spacing_sd=0.5, origin=(3e8, 0))
    slope = generate_slope(Profile.simple(10, 60, toe=(3e8, 0)), [near], depth=5, unit_weight=25)
    assert slope.blocks.n_blocks > 3


def test_traces_are_cut_only_where_their_line_crosses_a_long_flat_section():
    """Found by fuzzing: a section 5 km long and 47 m high cut its traces over
    the whole circle around it (57 million pieces, out of memory); inside the
    section the pieces are the same as before."""
    j = rd.Joint(1e6, 30)
    broken = JointSet("a", 30, 0.5, j, trace_length=1.4, gap=1.5)
    seg, trace, _ = broken.segments((0, 0, 2000, 20))
    # the box with its margin is 2,040 x 60: at most 60 / sin 30 / 2.9 x 2 = 83
    # pieces on each of the (2,040 sin 30 + 60 cos 30) / 0.5 = 2,144 lines
    # crossing it (over the circle around it: 5,744,640 pieces)
    assert len(seg) < 2_144 * 83
    lo, hi = seg.min(axis=(0, 1)), seg.max(axis=(0, 1))
    assert lo[0] > -100 and hi[0] < 2100 and lo[1] > -100 and hi[1] < 120
    # a box inside the long one sees the same traces (the pattern is fixed by the set)
    box = shapely.box(900, 5, 950, 15)
    big = shapely.intersection(shapely.linestrings(seg[trace]), box)
    small_seg, small_trace, _ = broken.segments((900, 5, 950, 15))
    small = shapely.intersection(shapely.linestrings(small_seg[small_trace]), box)
    assert np.isclose(shapely.length(big).sum(), shapely.length(small).sum(), rtol=1e-9)


# --------------------------------------------- check refuses what the rest would
STAB = (
    BOX
    + """stabilisation:
  trials:
    - name: design
      remove: {blocks: [42]}
"""
)


def test_check_refuses_a_trial_naming_an_unknown_block(tmp_path):
    assert_refused(
        check(tmp_path, STAB), "stabilisation.trials[0].remove", "block 42", "no block has this id"
    )


@pytest.mark.parametrize(
    "section,key,fragment",
    [
        (
            "  trials:\n    - {name: nothing, remove: {}}",
            "stabilisation.trials[0].remove",
            "removes nothing",
        ),
        (
            "  stages:\n    - {name: s, remove: {profile: [[0, 0], [0, 0]]}}",
            "stabilisation.stages[0].remove",
            "profile",
        ),
        (
            "  stages:\n    - {name: s, remove: {blocks: [0]}}",
            "stabilisation.stages[0].remove",
            "fixed ground",
        ),
        (
            "  stages:\n    - {name: s, remove: {blocks: [1]}}",
            "stabilisation.stages[0].remove",
            "block 2",
        ),
        (  # a stage that takes every free block away (top-level `remove` refused it)
            "  stages:\n    - {name: s, remove: {blocks: [1, 2]}}",
            "stabilisation.stages[0].remove",
            "removes every free block",
        ),
        ("  berm: [[-10, 3], [10, 3]]", "stabilisation.berm", "does not overlap"),
        ("  berm: [[5, 3], [0, 3]]", "stabilisation.berm", "x decreases"),
        ("  support: {at: [50, 50]}", "stabilisation.support.at", ""),
    ],
)
def test_check_refuses_stabilisation_designs_that_stabilise_would(tmp_path, section, key, fragment):
    assert_refused(check(tmp_path, BOX + "stabilisation:\n" + section + "\n"), key, fragment)


def test_check_refuses_a_zero_length_joint_line(tmp_path):
    text = BOX + "joint_lines:\n  - {joint: bedding, start: [0, 1], end: [0, 1]}\n"
    assert_refused(check(tmp_path, text), "joint_lines[0]", "zero length")


@pytest.mark.parametrize(
    "text, fragments",
    [
        (  # SuperLU factorised the singular stiffness: `check` called it valid
            SLOPE.replace("  depth: 3", "  depth: 3\n  boundary: []"),
            ("slope:", "held by nothing: no block is fixed"),
        ),
        (  # nothing loads the free blocks: a factor of safety '> 86.5' was printed
            BOX.replace("unit_weight: 25", "unit_weight: 0"),
            ("free blocks carry no load", "unit weight"),
        ),
        (
            BOX.replace("units: kN, m, kPa", "units: kN, m, kPa\nloads: {gravity: false}"),
            ("free blocks carry no load", "unit weight"),
        ),
        (  # 1e-200 gave "no failure up to 86.5" where 1e-150 gave the factor of safety
            BOX.replace("unit_weight: 25", "unit_weight: 1.0e-200"),
            ("unit weight 1e-200 is out of range", "0 (weightless)"),
        ),
        (  # 1e8 made the slope vanish in the tolerances ("block 0 touches no other block")
            SLOPE.replace("  depth: 3", "  depth: 3\n  ground_thickness: 1.0e+8"),
            ("slope.ground_thickness", "more than 10 x"),
        ),
    ],
    ids=["no-fixed-boundary", "weightless", "gravity-off", "underflow", "thick-ground"],
)
def test_models_that_gave_a_silent_wrong_answer_are_refused(tmp_path, text, fragments):
    assert_refused(check(tmp_path, text), *fragments)


@pytest.mark.parametrize(
    "extra, key",
    [
        ("loads: {points: [{at: [0, -0.5], force: [100, 0]}]}", "loads.points[0]"),
        ("supports: [{at: [-5, -0.5], force: 100, angle: 0}]", "supports[0]"),
    ],
)
def test_a_load_or_support_on_the_fixed_ground_is_refused(tmp_path, extra, key):
    """A force on a fixed block carries nothing: it was dropped silently."""
    assert_refused(check(tmp_path, BOX + extra + "\n"), key, "acts on a fixed block")


@pytest.mark.parametrize(
    "joint, key",
    [
        ("cohesion: 10, residual_cohesion: 1000", "residual_cohesion"),
        ("residual_friction_angle: 60", "residual_friction_angle"),
        ("tensile_strength: 5, residual_tensile_strength: 50", "residual_tensile_strength"),
    ],
)
def test_a_residual_strength_above_the_peak_is_refused(tmp_path, joint, key):
    text = BOX.replace("friction_angle: 30}", f"friction_angle: 30, {joint}}}")
    assert_refused(check(tmp_path, text), f"joints.bedding.{key}", "above the peak")


def test_a_model_without_a_fixed_block_says_what_nothing_holds(tmp_path):
    line = assert_refused(
        check(tmp_path, BOX.replace("fixed: true", "material: rock")),
        "blocks 0, 1, 2 are held by nothing: no block is fixed",
        "fixed: true",
    )
    assert "singular" not in line and "spring points" not in line


def test_a_group_that_reaches_no_fixed_block_is_named(tmp_path):
    text = BOX + (
        "  - {material: rock, vertices: [[10, 0], [12, 0], [12, 1], [10, 1]]}\n"
        "  - {material: rock, vertices: [[10, 1], [12, 1], [12, 2], [10, 2]]}\n"
    )
    line = assert_refused(
        check(tmp_path, text),
        "blocks 3, 4 are held by nothing",
        "touch one another but no fixed block",
    )
    assert "singular" not in line


def test_engine_api_bounds():
    with pytest.raises(rd.InputError, match=r"load_steps.*use 1 to 1000"):
        rd.Settings(load_steps=10**9)
    with pytest.raises(rd.InputError, match="tolerance"):
        rd.Settings(tolerance=1e-300)
    ground = [(-5, -1), (5, -1), (5, 0), (-5, 0)]
    block = [(0, 0), (1, 0), (1, 1), (0, 1)]
    far = [(1e300, 0), (1e300 + 1e290, 0), (1e300, 1e290)]
    with pytest.raises(rd.InputError, match=r"^block 7: lies 1e\+300 from the other blocks"):
        rd.Blocks.from_polygons([ground, block, far], ids=[0, 1, 7])
    with pytest.raises(rd.InputError, match="64 bits"):
        rd.Blocks.from_polygons([ground, block], ids=[0, 10**30])
    with pytest.raises(rd.InputError, match="unit weight 1e\\+300 is out of range"):
        rd.Blocks.from_polygons([ground, block], unit_weight=1e300)


def test_parse_model_bounds_in_process():
    with pytest.raises(ModelFileError, match="refers to the node"):
        parse_model(BOX + "description: &d [*d]\n")
    model, _ = parse_model(BOX)
    assert model.blocks.n_blocks == 3 and math.isclose(model.blocks.weight[1], 50)


# --------------------------------------------------------- destinations
def test_schema_does_not_overwrite_without_overwrite(tmp_path):
    model = tmp_path / "m.yaml"
    model.write_text(BOX)
    assert_refused(
        inproc("schema", "--out", "m.yaml", cwd=tmp_path), "exists already", "--overwrite"
    )
    assert model.read_text() == BOX
    r = inproc("schema", "--out", "m.yaml", "--overwrite", cwd=tmp_path)
    assert r.returncode == 0 and model.read_text().startswith("{")


def test_results_never_overwrite_the_model(tmp_path):
    (tmp_path / "model").mkdir()
    model = tmp_path / "model" / "result.json"
    model.write_text(BOX)
    r = rockdem("run", "model/result.json", "--out", "model", "--overwrite", cwd=tmp_path)
    assert_refused(r, "--out model", "over the model file")
    assert model.read_text() == BOX
    assert sorted(p.name for p in (tmp_path / "model").iterdir()) == ["result.json"]


def test_a_plot_never_overwrites_the_model(tmp_path):
    (tmp_path / "m.png").write_text(BOX)
    r = inproc("plot", "m.png", "--what", "model", "--out", "m.png", "--overwrite", cwd=tmp_path)
    assert_refused(r, "is the model file")
    assert (tmp_path / "m.png").read_text() == BOX


def test_a_result_name_taken_by_a_folder_writes_nothing(tmp_path):
    (tmp_path / "m.yaml").write_text(BOX)
    (tmp_path / "out" / "result.json").mkdir(parents=True)
    r = rockdem("run", "m.yaml", "--out", "out", "--overwrite", cwd=tmp_path)
    assert_refused(r, "result.json is a folder")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["result.json"]


@pytest.mark.parametrize("command", ["run", "fos", "stabilise", "report"])
def test_out_under_a_file_is_refused_before_computing(tmp_path, command):
    (tmp_path / "m.yaml").write_text(BOX)
    r = rockdem(command, "m.yaml", "--out", "m.yaml/results", cwd=tmp_path)
    assert_refused(r, "--out m.yaml/results", "is a file, not a folder")


def test_stabilise_does_not_overwrite_earlier_results(tmp_path):
    (tmp_path / "m.yaml").write_text(BOX)
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "measures.csv").write_text("mine")
    assert_refused(
        rockdem("stabilise", "m.yaml", "--out", "out", cwd=tmp_path), "already holds measures.csv"
    )
    assert (tmp_path / "out" / "measures.csv").read_text() == "mine"


@pytest.mark.skipif(
    not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root may write into read-only folders"
)
def test_a_read_only_out_folder_is_refused_before_computing(tmp_path):
    (tmp_path / "m.yaml").write_text(BOX)
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        assert_refused(
            rockdem("run", "m.yaml", "--out", "ro/results", cwd=tmp_path), "not writable"
        )
    finally:
        ro.chmod(0o755)


@pytest.mark.parametrize("command", ["report", "run"])
def test_a_folder_that_refuses_files_is_refused_before_computing(tmp_path, command):
    """Found by fuzzing: /sys/kernel passes the permission check as root and
    refused the files only after the analysis (exit 1).  A file is now
    tried there first (the same folder as user: refused by its bits)."""
    kernel = Path("/sys/kernel")
    if not kernel.is_dir():
        pytest.skip("no /sys/kernel here")
    (tmp_path / "m.yaml").write_text(BOX)
    out = kernel if command == "report" else kernel / "results"
    r = inproc(command, "m.yaml", "--out", out, cwd=tmp_path)
    assert_refused(r, f"--out {out}", "not writable")


def test_example_copy_never_follows_a_link(tmp_path):
    folder = tmp_path / "copy"
    folder.mkdir()
    outside = tmp_path / "outside.yaml"
    (folder / "toppling.yaml").symlink_to(outside)  # dangling
    r = rockdem("example", "copy", "toppling", "copy", "--overwrite", cwd=tmp_path)
    assert_refused(r, "is a link")
    assert not outside.exists()


def test_bounded_reading_keeps_normal_files_working(tmp_path):
    """The stricter reader still takes YAML, JSON and TOML models as before."""
    import json

    import yaml

    data = yaml.safe_load(BOX)
    (tmp_path / "m.json").write_text(json.dumps(data))
    r = rockdem("check", "m.json", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert np.isclose(float(r.stdout.split("free weight ")[1].split()[0]), 100)


@pytest.mark.parametrize(
    "old, new, fragment",
    [
        ("bedding: {", '"bed\\nding": {', "'bed\\nding' holds a control character"),
        ("units: kN", 'name: "\\e[2J\\e[31mHACKED"\nunits: kN', "name: the name"),
        ("units: kN", "units: kN \x07", "not valid YAML: character #x0007"),
        (
            "units: kN",
            'loads: {points: [{at: [1, 1], force: [1, 0], name: "P\\nX\\e[31m"}]}\nunits: kN',
            "loads.points[0].name: the name",
        ),
    ],
)
def test_control_characters_in_keys_names_and_text_are_refused(tmp_path, old, new, fragment):
    """A line break in a joint name broke the DXF export after the analysis;
    an escape in the model's name drove the terminal; a BEL byte gave a
    two-line YAML message with no line; a bolt's or a load's name with a line
    break and an escape wrote a line of its own in `run` and coloured it."""
    line = assert_refused(check(tmp_path, BOX.replace(old, new, 1)), fragment)
    assert "\x1b" not in line


@pytest.mark.parametrize(
    "option, value, fragment",
    [
        ("--dpi", "20000", "out of range 1 to 1200"),
        ("--magnification", "inf", "out of range (0 < factor < 1e12)"),
        # found by fuzzing: 1e12 was "must be positive and finite", which it is
        ("--magnification", "1e12", "out of range (0 < factor < 1e12)"),
    ],
)
def test_plot_options_out_of_range_are_input_errors(tmp_path, option, value, fragment):
    """--dpi 20000 ran out of memory (exit 1); --magnification inf hit a math domain error."""
    what = "mechanism" if option == "--magnification" else "model"
    r = inproc(
        "plot", "-e", "wedge-verification", "-w", what, "-o", "p.png", option, value, cwd=tmp_path
    )
    assert_refused(r, option, fragment)
    assert not (tmp_path / "p.png").exists()


@pytest.mark.parametrize("address", ["not a url", "http://localhost:80"])
def test_a_scheduler_that_is_no_address_is_refused_before_anything_is_written(tmp_path, address):
    (tmp_path / "spec.yaml").write_text(
        "study: {samples: 2, inputs: {joints.lower.friction_angle: "
        "{distribution: normal, mean: 30, sd: 2}}}\n"
    )
    r = inproc(
        "study",
        "-e",
        "wedge-verification",
        "--spec",
        "spec.yaml",
        "--out",
        "o",
        "--scheduler",
        address,
        cwd=tmp_path,
    )
    assert_refused(r, "--scheduler", "not a dask scheduler address")
    assert not (tmp_path / "o").exists()


def test_a_destination_on_a_read_only_file_system_is_refused_before_work(tmp_path):
    """/proc is read-only even for root: `example copy` into it (exit 1,
    "the analysis failed: OSError") is now an input error before copying."""
    if not os.path.isdir("/proc/1") or os.access("/proc/1", os.W_OK):
        pytest.skip("no read-only /proc here")
    r = inproc("example", "copy", "toppling", "/proc/1/x", cwd=tmp_path)
    assert_refused(r, "/proc/1", "not writable")


def test_a_bench_height_above_the_slope_is_refused(tmp_path):
    """Found by fuzzing: benches 100 m apart on a 10 m slope cut none, silently."""
    from rockdem.geometry import Profile

    with pytest.raises(rd.InputError, match="bench_height: 100 is not less than"):
        Profile.simple(10, 60, bench_width=2, bench_height=100)
    Profile.simple(10, 60, bench_width=2, bench_height=5)  # two lifts, one bench


def test_a_bench_height_of_a_micrometre_is_refused_at_once(tmp_path):
    """Found by fuzzing: benches 1e-6 apart on a 100 m slope (1e8 benches)
    built the profile point by point until 5.6 GB ran out (exit 1)."""
    text = SLOPE.replace(
        "profile: {height: 6, face_angle: 60}",
        "profile: {height: 100, face_angle: 60, bench_width: 2, bench_height: 1.0e-6}",
    )
    r = assert_refused(check(tmp_path, text), "bench_height", "100,000,000 benches")
    assert "at least 0.01" in r


def test_two_study_inputs_on_one_number_are_refused(tmp_path):
    """Found by fuzzing: `joints.cross.friction_angle` and the same path with
    a trailing space (or `[*]` and `[0]` of one list) both set one number;
    the later won and samples.csv reported values never used."""
    inputs = (
        "study:\n  samples: 2\n  inputs:\n"
        "    joints.cross.friction_angle: {distribution: normal, mean: 35, sd: 2}\n"
        '    "joints.cross.friction_angle ": {distribution: normal, mean: 30, sd: 2}\n'
    )
    (tmp_path / "m.yaml").write_text(SLOPE + inputs, encoding="utf-8")
    r = inproc("study", "m.yaml", "--out", "o", "--workers", "0", cwd=tmp_path)
    line = assert_refused(r, "study.inputs.joints.cross.friction_angle", "sets too")
    assert "only one of them would be used" in line
    assert not (tmp_path / "o").exists()


PLANE_20 = """units: kN, m, kPa
materials: {r: {unit_weight: 25}}
joints:
  strong: {normal_stiffness: 1.0e+6, friction_angle: 30}
  weak: {normal_stiffness: 1.0e+6, friction_angle: 10}
joint_lines:
  - {joint: weak, point: [0, OFFSET], dip: 20}
blocks:
  - {fixed: true, vertices: [[-10, 3.6397023426620234], [10, -3.6397023426620234], [10, -10],
                             [-10, -10]]}
  - {material: r, vertices: [[-2, 0.7279404685324047], [2, -0.7279404685324047],
                             [2, 1.2720595314675953], [-2, 2.7279404685324047]]}
"""


@pytest.mark.parametrize("offset", ["0.001", "0"])
def test_a_joint_line_along_no_contact_is_warned_about(tmp_path, offset):
    """Found by fuzzing: a weak joint (phi 10) meant for the base of a block
    on a 20 degree plane, drawn 1 mm off it, left the base on the strong
    default (phi 30): STABLE instead of UNSTABLE (tan 10 < tan 20), silently.
    Now a warning names the line; on the base itself there is none."""
    (tmp_path / "m.yaml").write_text(PLANE_20.replace("OFFSET", offset), encoding="utf-8")
    r = inproc("run", "m.yaml", cwd=tmp_path)
    assert r.returncode == 0
    warned = [ln for ln in r.stderr.splitlines() if ln.startswith("warning: ")]
    if offset == "0":
        assert not warned and "UNSTABLE" in r.stdout
    else:
        assert warned == [
            "warning: m.yaml:7: joint_lines[0] (joint weak) lies along no contact between "
            "blocks, but close along one: it gives its joint to none; check its points if it "
            "was meant for one"
        ]
        assert "STABLE" in r.stdout


def test_a_joint_line_over_part_of_a_contact_is_warned_about(tmp_path):
    """Found by fuzzing: a weak joint drawn over half of a 4 m contact gave
    it to none (an interface takes a line's joint only along most of its
    length), FS 2.000 for 0.728, silently."""
    text = (
        "units: kN, m, kPa\n"
        "joints:\n  strong: {normal_stiffness: 1.0e+6, friction_angle: 45}\n"
        "  weak: {normal_stiffness: 1.0e+6, friction_angle: 20}\n"
        "default_joint: strong\n"
        "joint_lines:\n  - {joint: weak, start: [0, 2], end: [2, 2]}\n"
        "blocks:\n"
        "  - {fixed: true, vertices: [[-5, -1], [9, -1], [9, 0], [-5, 0]]}\n"
        "  - {unit_weight: 25, vertices: [[0, 0], [4, 0], [4, 2], [0, 2]]}\n"
        "  - {unit_weight: 25, vertices: [[0, 2], [4, 2], [4, 4], [0, 4]]}\n"
    )
    (tmp_path / "m.yaml").write_text(text, encoding="utf-8")
    r = inproc("check", "m.yaml", cwd=tmp_path)
    assert r.returncode == 0
    assert "warning: m.yaml:7: joint_lines[0] (joint weak) lies along no contact" in r.stderr


def test_traces_far_from_every_contact_are_not_warned_about(tmp_path):
    """The bundled section's traces run on through the fixed ground, where
    they give no joint to any contact (18 of the 44 segments; a DXF round
    trip keeps them all): they follow no contact, so nothing was meant for
    one, and neither the import nor check warns (both printed a warning
    about the bundled example).  The weak line of the 20 degree plane moved
    1 m into the ground is not warned about either; 1 mm off, it is."""
    r = inproc("import", "--example", "--bolt-force", "100", "-o", "m.yaml", cwd=tmp_path)
    assert r.returncode == 0 and "warning" not in r.stderr, r.stderr
    r = inproc("check", "m.yaml", cwd=tmp_path)
    assert r.returncode == 0 and "warning" not in r.stderr, r.stderr
    (tmp_path / "p.yaml").write_text(PLANE_20.replace("OFFSET", "-1"), encoding="utf-8")
    r = inproc("check", "p.yaml", cwd=tmp_path)
    assert r.returncode == 0 and "warning" not in r.stderr, r.stderr


def test_a_correlation_of_three_inputs_is_not_asked_for_as_a_point(tmp_path):
    """Found by fuzzing: three inputs in one correlation were answered with
    "expected a point [x, y]" (any pair in the format was taken for a point)."""
    study = (
        "study:\n  samples: 2\n  inputs:\n"
        "    joints.cross.friction_angle: {distribution: normal, mean: 35, sd: 2}\n"
        "    joints.bedding.friction_angle: {distribution: normal, mean: 35, sd: 2}\n"
        "  correlations:\n    - {inputs: [joints.cross.friction_angle, "
        "joints.bedding.friction_angle, joints.base.friction_angle], coefficient: 0.5}\n"
    )
    (tmp_path / "m.yaml").write_text(SLOPE + study, encoding="utf-8")
    r = inproc("study", "m.yaml", "--out", "o", "--workers", "0", cwd=tmp_path)
    line = assert_refused(r, "study.correlations[0].inputs", "has 3 items", "at most 2")
    assert "point" not in line


@pytest.mark.parametrize(
    ("loads", "fragments"),
    [
        (
            "loads: {water_unit_weight: 9.81, water_table: [[100, 5], [-100, 5]]}",
            ("m.yaml:14: loads.water_table: needs two or more finite points with x increasing",),
        ),
        (
            "loads: {water_table: [[-100, 5], [100, 5]]}",
            ("loads.water_unit_weight: is 0 or missing: a water table needs it",),
        ),
        (  # found by fuzzing: a 0 written in the file was called "missing"
            "loads: {water_unit_weight: 0, water_table: [[-100, 5], [100, 5]]}",
            ("loads.water_unit_weight: is 0 or missing: a water table needs it",),
        ),
    ],
)
def test_a_water_table_error_names_the_loads_key(tmp_path, loads, fragments):
    """Found by fuzzing: a reversed water table, or one without the unit
    weight of water, was blamed on `slope:`; the missing unit weight read
    "0.0 is not a positive unit weight", a value the user never wrote."""
    r = check(tmp_path, SLOPE + loads + "\n")
    assert_refused(r, *fragments)


def test_a_study_on_thousands_of_local_workers_is_refused(tmp_path):
    """Found by reading the code while fuzzing: --workers was capped only by
    the number of samples, so --workers 5000 would start 5000 processes."""
    study = (
        "study:\n  samples: 9000\n  inputs:\n"
        "    joints.cross.friction_angle: {distribution: normal, mean: 35, sd: 2}\n"
    )
    (tmp_path / "m.yaml").write_text(SLOPE + study, encoding="utf-8")
    r = inproc("study", "m.yaml", "--out", "o", "--workers", "5000", cwd=tmp_path)
    assert_refused(r, "--workers 5000", "processes per CPU core")
    assert not (tmp_path / "o").exists()


def test_a_berm_off_the_model_names_no_function_of_the_library(tmp_path):
    """Found by fuzzing: "stabilisation.berm: cut_to_profile profile: does not overlap"."""
    berm = "stabilisation: {berm: [[-100, 100], [100, 100]]}\n"
    line = assert_refused(check(tmp_path, SLOPE + berm), "stabilisation.berm", "does not overlap")
    assert "cut_to_profile" not in line


def test_a_loose_equilibrium_tolerance_is_warned_about(tmp_path):
    """Found by fuzzing: `tolerance: 0.00999` (allowed) gave the paper's wedge
    FS 0.9991 instead of 0.9786 (Eq. 7), silently: out-of-balance forces of
    1% of the loads counted as equilibrium.  Now a warning says so."""
    from rockdem.examples import example_path

    text = example_path("wedge-verification").read_text(encoding="utf-8")
    loose = text.replace("analysis:\n", "analysis:\n  tolerance: 0.00999\n", 1)
    for name, model in (("default.yaml", text), ("loose.yaml", loose)):
        (tmp_path / name).write_text(model, encoding="utf-8")
    quiet = inproc("check", "default.yaml", cwd=tmp_path)
    assert quiet.returncode == 0 and "warning" not in quiet.stderr
    r = inproc("check", "loose.yaml", cwd=tmp_path)
    assert r.returncode == 0
    warned = [ln for ln in r.stderr.splitlines() if ln.startswith("warning: ")]
    assert len(warned) == 1 and "loose.yaml:55: analysis.tolerance 0.00999" in warned[0]
    # in Python, a warning of its own category (it was a bare logged line)
    from rockdem.config import load_model

    with pytest.warns(rd.ModelWarning, match=r"loose.yaml:55: analysis.tolerance 0.00999") as got:
        load_model(tmp_path / "loose.yaml")
    assert got[0].filename == __file__  # shown at the caller's line


@pytest.mark.parametrize(
    ("y", "how"), [("-1e-6", "overlaps block 0 by a sliver"), ("1e-6", "misses block 0 by 1e-06")]
)
def test_a_block_off_its_neighbour_by_a_hair_is_told_so(tmp_path, y, how):
    """Found by fuzzing: a block sunk 1e-6 into the ground was said to "touch
    no other block (it would float)"."""
    text = (
        "units: kN, m, kPa\nmaterials: {r: {unit_weight: 25}}\n"
        "joints:\n  j: {normal_stiffness: 1.0e+6, friction_angle: 30}\nblocks:\n"
        "  - {fixed: true, vertices: [[-5, -1], [9, -1], [9, 0], [-5, 0]]}\n"
        f"  - {{material: r, vertices: [[0, {y}], [4, {y}], [4, 2], [0, 2]]}}\n"
    )
    line = assert_refused(check(tmp_path, text), "blocks[1]", how, "geometric tolerance")
    assert "float" not in line


def test_a_slope_beyond_the_machines_memory_is_refused_whatever_the_limit(monkeypatch):
    """Found by fuzzing: with the block limit raised to 1e12, a 1 mm spacing
    (284 million blocks, about 7 TB) ran until the memory ran out.  Here the
    machine is made to have 1 MB."""
    from rockdem.geometry import JointSet, Profile, generate_slope, size

    monkeypatch.setattr(size, "physical_memory", lambda: 1e6)
    joint = rd.Joint(normal_stiffness=1e6, friction_angle=30)
    sets = [JointSet("bedding", 20, 1.0, joint), JointSet("cross", 100, 1.0, joint)]
    with pytest.raises(rd.InputError, match="more than this machine's"):
        generate_slope(Profile.simple(10, 60), sets, depth=5, max_blocks=10**12)


@pytest.mark.parametrize("existed", [False, True])
def test_results_written_meanwhile_by_another_command_are_kept_and_so_are_these(
    tmp_path, existed
):
    """Two commands writing into the same --out: each checks the folder before
    it computes, and the second to finish moved its files over the first's
    (the folder had appeared meanwhile), both exiting 0.  Without
    --overwrite both result sets are kept now, and the error says where."""
    from rockdem.errors import InputError
    from rockdem.output import staged_folder

    out = tmp_path / "results"
    if existed:
        out.mkdir()
    with pytest.raises(InputError, match=r"from another command.*kept in (\S+)") as info:
        with staged_folder(out, overwrite=False) as tmp:
            (tmp / "result.json").write_text("ours")
            out.mkdir(exist_ok=True)  # the other command, finishing first
            (out / "result.json").write_text("theirs")
    assert (out / "result.json").read_text() == "theirs"
    kept = info.value.args[0].split("kept in ")[-1].strip()
    assert (Path(kept) / "result.json").read_text() == "ours"
    assert Path(kept).parent == tmp_path
