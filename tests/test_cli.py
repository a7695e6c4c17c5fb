"""The command line, in-process (typer's CliRunner) and through ``python -m rockdem``."""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

import rockdem
from _cli import assert_refused
from _models import BOX
from rockdem.cli import EXIT_FAILED, EXIT_INPUT, app
from rockdem.config import json_schema
from rockdem.output import RESULT_FILES
from rockdem.verification import wedge_fos

runner = CliRunner()
BROKEN = Path(__file__).parent / "broken_models"
WEDGE_FOS = wedge_fos(200, 75, 37, 27, 35, 30, 35)


def invoke(*args: str):
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture
def box(tmp_path) -> Path:
    path = tmp_path / "box.yaml"
    path.write_text(BOX)
    return path


# ------------------------------------------------------------------- check
def test_check_prints_a_summary(box):
    r = invoke("check", box)
    assert r.exit_code == 0, r.output
    assert "blocks: 3 (2 free, 1 fixed); free weight 100 kN (area 4 m^2)" in r.stdout
    assert "weights: 1: 50, 2: 50" in r.stdout
    lines = [ln.split() for ln in r.stdout.splitlines()]
    assert ["bedding", "2", "4"] in lines  # two interfaces of total length 4
    assert "units: kN, m, kPa" in r.stdout
    assert r.stderr == ""


def test_check_json(box):
    r = invoke("check", box, "--json")
    assert r.exit_code == 0
    data = json.loads(r.stdout)
    assert data["blocks"]["free"] == 2 and data["blocks"]["free_weight"] == pytest.approx(100)
    assert data["interfaces"]["by_kind"] == {"bedding": {"count": 2, "length": 4.0}}
    assert data["loads"]["resultant"] == pytest.approx([0, -100])


def test_json_errors_are_a_json_object_on_stdout_too(box, monkeypatch):
    """With --json a refused model and a failed computation print, besides the
    one line on stderr, one JSON object on stdout with the same text and the
    exit code (an empty stdout failed a script's json.loads)."""
    box.write_text(BOX.replace("unit_weight: 25", "unit_weight: -3"))
    for command in ("check", "run", "fos"):
        r = invoke(command, box, "--json")
        assert r.exit_code == 2
        data = json.loads(r.stdout)
        assert data["exit_code"] == 2 and "unit_weight" in data["error"]
        assert r.stderr.strip() == f"error: {data['error']}"
    assert invoke("check", box).stdout == ""  # without --json: stderr only

    import rockdem.analysis

    def boom(*args, **kwargs):
        raise FloatingPointError("singular matrix")

    box.write_text(BOX)
    monkeypatch.setattr(rockdem.analysis, "analyse", boom)
    data = json.loads(invoke("run", box, "--json").stdout)
    assert data["exit_code"] == EXIT_FAILED and "singular matrix" in data["error"]


def test_check_example():
    r = invoke("check", "--example", "wedge-verification")
    assert r.exit_code == 0, r.output
    assert "weights: 1: 200, 2: 75" in r.stdout


# --------------------------------------------------------------------- run
def test_run_stable_model(box):
    r = invoke("run", box)
    assert r.exit_code == 0, r.output
    assert "STABLE" in r.stdout and "UNSTABLE" not in r.stdout
    assert "unstable blocks (0): none" in r.stdout


def test_run_unstable_example_exits_0_with_the_verdict():
    r = invoke("run", "--example", "wedge-verification")
    assert r.exit_code == 0, r.output
    assert "UNSTABLE" in r.stdout
    assert "unstable blocks (2): 1, 2" in r.stdout


def test_run_json():
    r = invoke("run", "-e", "wedge-verification", "--json")
    assert r.exit_code == 0
    data = json.loads(r.stdout)
    assert data["stable"] is False
    assert data["unstable_blocks"] == [1, 2]
    assert isinstance(data["failed_interfaces"], list)
    assert data["rockdem_version"] == rockdem.__version__
    assert data["command"] == "run"


def test_run_json_stable(box):
    data = json.loads(invoke("run", box, "--json").stdout)
    assert data["stable"] is True and data["unstable_blocks"] == []
    assert data["failed_interfaces"] == []
    assert data["load_factor"] == 1.0


def _read_csv(path: Path) -> list[dict[str, str]]:
    with path.open() as fh:
        return list(csv.DictReader(fh))


def test_run_writes_result_files(box, tmp_path):
    out = tmp_path / "results"
    r = invoke("run", box, "--out", out)
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in out.iterdir()) == sorted(RESULT_FILES)
    blocks = _read_csv(out / "blocks.csv")
    assert [b["id"] for b in blocks] == ["0", "1", "2"]
    # the headings carry the units of the file's `units: kN, m, kPa`
    assert float(blocks[1]["weight [kN]"]) == pytest.approx(50)
    faces = _read_csv(out / "interfaces.csv")
    assert len(faces) == 2
    for key in (
        "block_a",
        "block_b",
        "kind",
        "length [m]",
        "normal_force [kN]",
        "shear_force [kN]",
        "normal_stress [kPa]",
        "shear_stress [kPa]",
        "state",
        "local_fos",
        "first_failure",
    ):
        assert key in faces[0]
    base = next(f for f in faces if {f["block_a"], f["block_b"]} == {"0", "1"})
    assert float(base["normal_force [kN]"]) == pytest.approx(100, rel=1e-6)  # both blocks on it
    assert float(base["normal_stress [kPa]"]) == pytest.approx(50, rel=1e-6)
    assert base["state"] == "elastic" and base["first_failure"] == "-1"
    springs = _read_csv(out / "springs.csv")
    assert len(springs) == 2 * 3
    doc = json.loads((out / "result.json").read_text())
    assert doc["rockdem_version"] == rockdem.__version__
    assert doc["model"]["joints"]["bedding"]["friction_angle"] == 30
    assert doc["model"]["analysis"]["load_steps"] == 5  # the echo has the defaults
    assert doc["stable"] is True
    assert len(doc["interfaces"]) == 2 and len(doc["springs"]) == 6
    # result.json keeps the bare names (their units under column_units)
    assert list(doc["interfaces"][0]) == [k.split(" [")[0] for k in faces[0]]
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temp dirs left


def test_existing_results_are_not_overwritten(box, tmp_path):
    out = tmp_path / "results"
    assert invoke("run", box, "--out", out).exit_code == 0
    (out / "blocks.csv").write_text("mine\n")
    r = invoke("run", box, "--out", out)
    assert r.exit_code == EXIT_INPUT
    assert "already holds blocks.csv" in r.stderr and "--overwrite" in r.stderr
    assert (out / "blocks.csv").read_text() == "mine\n"
    r = invoke("run", box, "--out", out, "--overwrite")
    assert r.exit_code == 0
    assert (out / "blocks.csv").read_text().startswith("id,fixed")


def test_other_files_in_the_output_folder_are_kept(box, tmp_path):
    out = tmp_path / "results"
    out.mkdir()
    (out / "notes.txt").write_text("keep")
    assert invoke("run", box, "--out", out, "--quiet").exit_code == 0
    assert (out / "notes.txt").read_text() == "keep"
    assert (out / "result.json").exists()


def test_a_failure_while_writing_leaves_no_result_files(box, tmp_path, monkeypatch):
    import rockdem.output as output

    real = output._write_csv

    def flaky(path, rows, columns):
        if path.name == "springs.csv":
            raise OSError(28, "No space left on device")
        real(path, rows, columns)

    monkeypatch.setattr(output, "_write_csv", flaky)
    out = tmp_path / "results"
    r = invoke("run", box, "--out", out)
    assert r.exit_code == EXIT_FAILED
    assert not out.exists()
    assert list(tmp_path.iterdir()) == [box]  # no temporary folder left behind
    assert "Traceback" not in r.output


def test_a_failure_while_writing_keeps_old_results_whole(box, tmp_path, monkeypatch):
    import rockdem.output as output

    out = tmp_path / "results"
    assert invoke("run", box, "--out", out).exit_code == 0
    before = {p.name: p.read_text() for p in out.iterdir()}

    def broken(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(output.json, "dump", broken)
    r = invoke("run", box, "--out", out, "--overwrite")
    assert r.exit_code == EXIT_FAILED
    assert {p.name: p.read_text() for p in out.iterdir()} == before


def test_a_failed_computation_exits_1_without_traceback(box, monkeypatch):
    import rockdem.analysis

    def boom(*args, **kwargs):
        raise FloatingPointError("singular matrix")

    monkeypatch.setattr(rockdem.analysis, "analyse", boom)
    r = invoke("run", box)
    assert r.exit_code == EXIT_FAILED
    assert r.stderr.strip() == (
        "error: the analysis failed: FloatingPointError: singular matrix "
        "(run again with --debug for the traceback)"
    )
    r = invoke("run", box, "--debug")
    assert isinstance(r.exception, FloatingPointError)


def test_quiet_run_writes_nothing_to_stderr(box, tmp_path):
    r = invoke("run", box, "--out", tmp_path / "o", "--quiet")
    assert r.exit_code == 0 and r.stderr == ""
    r = invoke("run", box, "--out", tmp_path / "p")
    assert "results written to" in r.stderr


def test_progress_hooks_are_called(box, monkeypatch):
    """The progress bar is fed by the engine's hook after every load step."""
    import rockdem.cli as cli

    calls = []
    real = cli._step_hook

    def spy(bar, task):
        hook = real(bar, task)

        def wrapped(step, n):
            calls.append((step, n))
            hook(step, n)

        return wrapped

    monkeypatch.setattr(cli, "_step_hook", spy)
    assert invoke("run", box).exit_code == 0
    assert calls == [(k, 5) for k in range(1, 6)]


# --------------------------------------------------------------------- fos
def test_fos_of_the_wedge():
    r = invoke("fos", "--example", "wedge-verification", "--json")
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    lo, hi = data["bracket"]
    assert lo <= WEDGE_FOS <= hi
    assert data["factor_of_safety"] == pytest.approx(WEDGE_FOS, abs=0.002)
    assert data["mode"] == "strength"
    assert data["mechanism_blocks"] == [1, 2]


def test_fos_human_output():
    r = invoke("fos", "-e", "wedge-verification")
    assert r.exit_code == 0
    assert "factor of safety: 0.97" in r.stdout
    assert "bracket: stable at 0.97" in r.stdout
    # its ends, 6e-5 apart, are printed apart (at 4 decimals both read 0.9786)
    ends = r.stdout.split("bracket: stable at ")[1].split(" (")[0].split(", unstable at ")
    assert ends[0] != ends[1] and float(ends[0]) < float(ends[1])


def test_fos_names_the_blocks_at_the_transition_between_sliding_and_toppling():
    """The toppling example (Goodman & Bray's columns): column 7 stood at the
    limit on a base 1/6 open and 2/3 at its strength; its mode is the
    motion's, and the output says so instead of presenting it as decided."""
    r = invoke("fos", "-e", "toppling")
    assert r.exit_code == 0
    line = next(t for t in r.stdout.splitlines() if "at the transition" in t)
    assert "(1): 7 " in line and "chaotic" in line
    data = json.loads(invoke("fos", "-e", "toppling", "--json").stdout)
    assert data["failure_modes_from_motion"] == [7]
    # ... and the report's "how far to trust this"
    from rockdem.config import load_model
    from rockdem.examples import example_path
    from rockdem.trust import trust_statements

    model, _ = load_model(example_path("toppling"))
    fos = rockdem.factor_of_safety(model)
    said = [t for t in trust_statements(fos.stable_analysis, fos) if "between sliding" in t]
    assert len(said) == 1 and said[0].startswith("Block(s) 7 stood at the limit")


def test_fos_states_where_a_confirmed_failure_is_confirmed():
    """The toppling example's failure is confirmed by dynamic relaxation 2%
    beyond the bracket, not proven: the JSON gives that factor, and the text
    and the trust statements say that between the two nothing proves or
    confirms failure."""
    data = json.loads(invoke("fos", "-e", "toppling", "--json").stdout)
    hi = data["bracket"][1]
    assert data["proof"] == "dynamic-relaxation" and data["certified_upper_bound"] is None
    assert data["confirmed_upper_bound"] == pytest.approx(1.02 * hi, rel=1e-9)
    assert any("neither proven nor confirmed" in t for t in data["trust"])
    text = invoke("fos", "-e", "toppling").stdout
    assert f"failure confirmed at F = {1.02 * hi:.4f}" in text
    wedge = json.loads(invoke("fos", "-e", "wedge-verification", "--json").stdout)
    assert wedge["proof"] == "lp-certificate" and wedge["confirmed_upper_bound"] is None


def test_fos_no_failure_has_open_bracket(box):
    text = box.read_text().replace("friction_angle: 30}", "friction_angle: 30, cohesion: 1.0e+9}")
    box.write_text(text)
    data = json.loads(invoke("fos", box, "--json").stdout)
    assert data["factor_of_safety"] is None and data["mode"] == "no-failure"
    assert data["bracket"][1] is None  # infinity is null in JSON


def test_fos_writes_results(tmp_path):
    out = tmp_path / "fos"
    r = invoke("fos", "-e", "wedge-verification", "--out", out, "--quiet")
    assert r.exit_code == 0
    doc = json.loads((out / "result.json").read_text())
    assert doc["command"] == "fos" and doc["factor_of_safety"] is not None
    assert doc["analysis"]["stable"] is True  # the tables are the last equilibrium


# ------------------------------------------------------------- bad options
def test_model_and_example_are_exclusive(box):
    r = invoke("run", box, "--example", "wedge-verification")
    assert r.exit_code == EXIT_INPUT and "not both" in r.stderr
    r = invoke("run")
    assert r.exit_code == EXIT_INPUT and "give either a model file or --example" in r.stderr


def test_unknown_example():
    r = invoke("run", "--example", "nope")
    assert r.exit_code == EXIT_INPUT
    assert "example 'nope': does not exist; use one of:" in r.stderr
    assert "wedge-verification" in r.stderr


def test_missing_file(tmp_path):
    r = invoke("check", tmp_path / "none.yaml")
    assert r.exit_code == EXIT_INPUT
    assert r.stderr.strip() == f"error: {tmp_path / 'none.yaml'}: file not found; check the path"


def test_unknown_option_is_a_usage_error(box):
    r = invoke("run", box, "--fast")
    assert r.exit_code == 2


def test_out_is_a_file(box, tmp_path):
    f = tmp_path / "file"
    f.write_text("")
    r = invoke("run", box, "--out", f)
    assert r.exit_code == EXIT_INPUT and "is a file, not a folder" in r.stderr


def test_debug_shows_the_traceback_of_bad_input(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(BOX.replace("friction_angle: 30", "friction_angle: 95"))
    r = invoke("check", bad, "--debug")
    assert r.exit_code != 0 and isinstance(r.exception, rockdem.InputError)


# ---------------------------------------------------------- broken corpus
def _expected(path: Path) -> list[str]:
    lines = path.read_text().splitlines()
    return [ln.split(":", 1)[1].strip() for ln in lines if ln.startswith("# expect:")]


CORPUS = sorted(p for p in BROKEN.iterdir() if p.suffix in (".yaml", ".toml"))


def test_corpus_is_large_enough():
    assert len(CORPUS) >= 30
    assert all(_expected(p) for p in CORPUS)


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: p.name)
def test_broken_model(path: Path):
    r = invoke("check", path)
    assert r.exit_code == EXIT_INPUT, r.output
    assert r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    msg = lines[0]
    assert msg.startswith(f"error: {path}")
    for fragment in _expected(path):
        assert fragment in msg
    assert "; " in msg  # a fix is given


@pytest.mark.parametrize("command", ["run", "fos"])
def test_broken_model_run_and_fos(command):
    path = BROKEN / "friction-out-of-range.yaml"
    r = invoke(command, path, "--json")
    assert r.exit_code == EXIT_INPUT
    assert json.loads(r.stdout)["exit_code"] == EXIT_INPUT  # the error, for scripts
    assert "joints.bedding.friction_angle" in r.stderr


# ----------------------------------------------------------------- example
def test_example_list():
    r = invoke("example", "list")
    assert r.exit_code == 0
    names = [ln.split()[0] for ln in r.stdout.splitlines()]
    assert "wedge-verification" in names
    assert "two-block wedge" in r.stdout.lower()


def test_example_copy_then_check_and_no_overwrite(tmp_path):
    r = invoke("example", "copy", "wedge-verification", tmp_path / "mine")
    assert r.exit_code == 0, r.output
    copied = tmp_path / "mine" / "wedge-verification.yaml"
    assert copied.exists()
    assert invoke("check", copied).exit_code == 0
    copied.write_text("# edited\n" + copied.read_text())
    r = invoke("example", "copy", "wedge-verification", tmp_path / "mine")
    assert r.exit_code == EXIT_INPUT and "already exists" in r.stderr
    assert copied.read_text().startswith("# edited")
    r = invoke("example", "copy", "wedge-verification", tmp_path / "mine", "--overwrite")
    assert r.exit_code == 0 and not copied.read_text().startswith("# edited")


def test_schema_command(tmp_path):
    r = invoke("schema")
    assert json.loads(r.stdout) == json.loads(json.dumps(json_schema()))
    assert invoke("schema", "--out", tmp_path / "s.json").exit_code == 0
    assert json.loads((tmp_path / "s.json").read_text())["title"] == "rockdem model file"


def test_version():
    r = invoke("--version")
    assert r.exit_code == 0 and r.stdout.strip() == f"rockdem {rockdem.__version__}"


# -------------------------------------------------------------- subprocess
def _python_m(*args, cwd=None):
    env = dict(os.environ, COLUMNS="120")
    return subprocess.run(
        [sys.executable, "-m", "rockdem", *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=env,
        timeout=120,
    )


def test_subprocess_run_example_json():
    p = _python_m("run", "--example", "wedge-verification", "--json")
    assert p.returncode == 0, p.stderr
    data = json.loads(p.stdout)
    assert data["stable"] is False and data["unstable_blocks"] == [1, 2]


def test_subprocess_fos_example_json():
    p = _python_m("fos", "--example", "wedge-verification", "--json", "--quiet")
    assert p.returncode == 0, p.stderr
    data = json.loads(p.stdout)
    assert data["bracket"][0] <= WEDGE_FOS <= data["bracket"][1]
    assert p.stderr == ""


@pytest.mark.parametrize(
    "name",
    [
        "friction-with-unit.yaml",
        "yaml-syntax.yaml",
        "overlapping-blocks.yaml",
        "toml-unknown-key.toml",
    ],
)
def test_subprocess_bad_input(name):
    p = _python_m("run", BROKEN / name)
    assert p.returncode == 2
    assert p.stdout == ""
    assert "Traceback" not in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1
    for fragment in _expected(BROKEN / name):
        assert fragment in p.stderr


def test_subprocess_writes_results(tmp_path):
    p = _python_m("run", "-e", "wedge-verification", "--out", "res", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert sorted(x.name for x in (tmp_path / "res").iterdir()) == sorted(RESULT_FILES)
    p = _python_m("run", "-e", "wedge-verification", "--out", "res", cwd=tmp_path)
    assert p.returncode == 2 and "--overwrite" in p.stderr


@pytest.mark.parametrize(
    "args, fragments",
    [
        (("run", "-e", "wedge", "--fast"), ["No such option: --fast", "rockdem run --help"]),
        (("plot", "-e", "wedge", "--dpi", "abc", "x.png"), ["'--dpi'", "rockdem plot --help"]),
        (("nonsense",), ["No such command 'nonsense'", "rockdem --help"]),
        (("run", "-e", "wedge-verification", "--out", ""), ["--out: empty value"]),
        (("run", "-e", "wedge-verification", "--out="), ["--out: empty value"]),
        (("run", ""), ["argument 2", "empty value"]),
    ],
)  # fmt: skip
def test_subprocess_usage_errors_are_one_line(tmp_path, args, fragments):
    """Unknown options and commands, values of the wrong type, and empty
    arguments (an unset shell variable: ``--out ""`` wrote into the current
    folder) get one line and exit 2, like every other refusal; nothing is written."""
    assert_refused(_python_m(*args, cwd=tmp_path), *fragments)
    assert list(tmp_path.iterdir()) == []


def test_subprocess_no_arguments_prints_help():
    p = _python_m()
    assert "Usage: rockdem" in p.stdout + p.stderr


def test_version_answers_without_loading_the_engine():
    """`rockdem --version` (issue 10: start-up) prints the version without
    importing SciPy, PARDISO or matplotlib: the package loads its names lazily."""
    import subprocess
    import sys

    code = (
        "import sys; sys.argv = ['rockdem', '--version']\n"
        "from rockdem._launch import main; main()\n"
        "heavy = [m for m in ('scipy', 'pypardiso', 'matplotlib') if m in sys.modules]\n"
        "print('heavy:', heavy)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines() == ["rockdem 0.1.0", "heavy: []"]


def test_readme_model_file_runs(tmp_path):
    """The complete small model in the README (with its water table) is valid
    and stands: what a new user copies must work."""
    import re
    from pathlib import Path

    readme = (Path(__file__).parents[1] / "README.md").read_text()
    text = re.search(r"```yaml\n(# Two blocks on fixed ground.*?)```", readme, re.S).group(1)
    (tmp_path / "stack.yaml").write_text(text)
    r = invoke("run", str(tmp_path / "stack.yaml"))
    assert r.exit_code == 0, r.output
    assert "verdict: STABLE" in r.stdout


def test_a_warning_printed_during_a_run_is_in_its_json_and_result_files(tmp_path):
    """Found by fuzzing: joints 1e-6 stiff give a verdict that "does not hold"
    (displacements of 1e7 block sizes); the warning went to stderr while the
    JSON and result.json read "stable" with no warnings."""
    path = tmp_path / "soft.yaml"
    path.write_text(BOX.replace("normal_stiffness: 1.0e+6", "normal_stiffness: 1.0e-6"))
    r = invoke("run", path, "--json", "--quiet")
    assert r.exit_code == 0, r.output
    warnings = json.loads(r.stdout)["warnings"]
    assert any("the verdict does not hold" in w for w in warnings), warnings
    r = invoke("run", path, "--out", tmp_path / "out", "--quiet")
    assert r.exit_code == 0, r.output
    saved = json.loads((tmp_path / "out" / "result.json").read_text())["warnings"]
    assert saved == warnings
    assert r.output.count("the verdict does not hold") == 1  # printed once, on stderr
    # a model without a warning has none (nothing carried over from the last command)
    r = invoke("run", _box(tmp_path), "--json", "--quiet")
    assert json.loads(r.stdout)["warnings"] == []


def _box(tmp_path) -> Path:
    path = tmp_path / "box.yaml"
    path.write_text(BOX)
    return path


def test_a_reader_that_goes_away_ends_the_command_quietly_with_141():
    """Found by fuzzing: `rockdem fos ... --out X | head -1` exited 1, the code
    of a failed computation, though the results were written (rich exits 1
    on a broken pipe).  141 is the shell's code for it; nothing on stderr."""
    code = "from rockdem.cli.common import out\nfor _ in range(20000): out.print('x' * 40)\n"
    with subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE
    ) as p:
        assert p.stdout.readline() == b"x" * 40 + b"\n"
        p.stdout.close()
        assert p.wait(timeout=60) == 141
        assert p.stderr.read() == b""
