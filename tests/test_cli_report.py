"""``rockdem report`` and ``rockdem plot``: in-process (CliRunner) and through ``python -m``."""

from __future__ import annotations

import math
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from rockdem.cli import EXIT_FAILED, EXIT_INPUT, PLOT_WHAT, _plot_units, app
from rockdem.verification import wedge_fos

runner = CliRunner()
WEDGE_FOS = wedge_fos(200, 75, 37, 27, 35, 30, 35)
INCLINE_FOS = math.tan(math.radians(30)) / math.tan(math.radians(20))  # 1.586
MAGIC = {".png": b"\x89PNG\r\n\x1a\n", ".pdf": b"%PDF", ".gif": b"GIF89a", ".svg": b"<?xml"}


def _incline_yaml(**strength_reduction: float) -> str:
    """One block on a plane dipping 20 degrees, friction 30: F = tan 30 / tan 20."""
    d = math.radians(20)
    c, s = math.cos(d), math.sin(d)

    def rot(pts):
        return [[round(c * x - s * y, 12), round(s * x + c * y, 12)] for x, y in pts]

    sr = ", ".join(f"{k}: {v}" for k, v in {"width": 0.01, **strength_reduction}.items())
    return f"""name: block on a plane
units: kN, m, kPa
materials: {{rock: {{unit_weight: 25}}}}
joints:
  plane: {{normal_stiffness: 1.0e+6, friction_angle: 30}}
  unused: {{normal_stiffness: 1.0e+6, friction_angle: 40}}
blocks:
  - {{fixed: true, vertices: {rot([(-5, -1), (5, -1), (5, 0), (-5, 0)])}}}
  - {{material: rock, vertices: {rot([(0, 0), (2, 0), (2, 1), (0, 1)])}}}
analysis:
  load_steps: 1
  strength_reduction: {{{sr}}}
"""


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture
def incline(tmp_path) -> Path:
    path = tmp_path / "incline.yaml"
    path.write_text(_incline_yaml())
    return path


def _one_line_error(r, *fragments: str) -> str:
    assert r.exit_code == EXIT_INPUT, r.output
    assert r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("error: ")
    for fragment in fragments:
        assert fragment in lines[0]
    return lines[0]


def _fos_in(text: str) -> float:
    m = re.search(r"Factor of safety F = ([0-9.]+)", text)
    assert m, "no factor of safety in the report"
    return float(m.group(1))


def _images(text: str) -> list[str]:
    return re.findall(r'<img src="([^"]*)"', text)


def _no_temporary_files(folder: Path) -> None:
    assert not [p.name for p in folder.rglob(".*")], "temporary files left behind"


# ------------------------------------------------------------------ report
def test_report_of_a_file(incline, tmp_path):
    out = tmp_path / "rep"
    r = invoke("report", incline, "--out", out, "--no-animation", "--quiet")
    assert r.exit_code == 0, r.output
    assert r.stdout.strip() == str(out / "report.html")
    assert r.stderr == ""
    assert [p.name for p in out.iterdir()] == ["report.html"]
    text = (out / "report.html").read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>")
    assert _fos_in(text) == pytest.approx(INCLINE_FOS, abs=0.002)
    assert "kN, m, kPa" in text and "block on a plane" in text
    images = _images(text)
    assert len(images) >= 5
    assert all(src.startswith("data:image/png;base64,") for src in images)
    assert "data:image/gif" not in text  # --no-animation
    assert not re.search(r'(src|href)="(https?:)?//', text)


def test_report_of_an_example_svg_and_joints(tmp_path):
    out = tmp_path / "rep"
    r = invoke(
        "report",
        "-e",
        "wedge-verification",
        "--out",
        out,
        "--svg",
        "--no-animation",
        "--joint",
        "upper",
        "--joint",
        "1",
        "-q",
    )
    assert r.exit_code == 0, r.output
    text = (out / "report.html").read_text(encoding="utf-8")
    assert _fos_in(text) == pytest.approx(WEDGE_FOS, abs=0.002)
    assert "UNSTABLE" in text and "t, m, t/m^2" in text
    assert all(src.startswith("data:image/svg+xml;base64,") for src in _images(text))
    # one stress plot per --joint: the joint by name and joint line 1 (the lower plane)
    assert 'id="fig-stress-0"' in text and 'id="fig-stress-1"' in text
    assert "along joint upper" in text and "along joint 1 " in text
    assert "σ mean (t/m^2)" in text  # stress unit from the file's units note


def test_report_uses_the_files_strength_reduction_settings(tmp_path):
    model = tmp_path / "capped.yaml"
    model.write_text(_incline_yaml(largest=1.2))  # the search stops below F = 1.586
    r = invoke("report", model, "--out", tmp_path / "rep", "--no-animation", "-q")
    assert r.exit_code == 0, r.output
    text = (tmp_path / "rep" / "report.html").read_text(encoding="utf-8")
    assert "Factor of safety: none (no-failure)" in text
    assert "Factor of safety F =" not in text


def test_report_is_not_overwritten_without_overwrite(incline, tmp_path):
    out = tmp_path / "rep"
    out.mkdir()
    (out / "report.html").write_text("mine")
    (out / "notes.txt").write_text("keep")
    r = invoke("report", incline, "--out", out, "--no-animation")
    _one_line_error(r, f"--out {out / 'report.html'}", "exists already", "--overwrite")
    assert (out / "report.html").read_text() == "mine"
    r = invoke("report", incline, "--out", out, "--no-animation", "--overwrite", "-q")
    assert r.exit_code == 0, r.output
    assert (out / "report.html").read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
    assert (out / "notes.txt").read_text() == "keep"
    _no_temporary_files(out)


def test_report_bad_input(incline, tmp_path):
    out = tmp_path / "rep"
    _one_line_error(invoke("report", "--out", out), "give either a model file or --example")
    _one_line_error(invoke("report", incline, "-e", "wedge-verification", "--out", out), "not both")
    _one_line_error(invoke("report", "-e", "nope", "--out", out), "example 'nope'")
    _one_line_error(invoke("report", tmp_path / "none.yaml", "--out", out), "file not found")
    bad = tmp_path / "bad.yaml"
    bad.write_text(_incline_yaml().replace("friction_angle: 30", "friction_angle: 95"))
    _one_line_error(invoke("report", bad, "--out", out), "joints.plane.friction_angle")
    _one_line_error(
        invoke("report", incline, "--out", out, "--joint", "nope"), "--joint nope", "plane, unused"
    )
    _one_line_error(
        invoke("report", incline, "--out", out, "--joint", "unused"),
        "--joint unused",
        "no interface",
    )
    _one_line_error(
        invoke("report", incline, "--out", out, "--joint", "0"), "--joint 0"
    )  # the model has no joint lines
    _one_line_error(invoke("report", incline, "--out", incline), "is a file, not a folder")
    r = invoke("report", incline)  # --out is required
    assert r.exit_code == EXIT_INPUT and "--out" in r.output
    assert not out.exists()


def test_a_failure_while_writing_the_report_leaves_nothing(incline, tmp_path, monkeypatch):
    import rockdem.report

    def broken(model, out_dir, *, filename, **options):
        (Path(out_dir) / filename).write_text("<!DOCTYPE html><p>half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(rockdem.report, "write_report", broken)
    out = tmp_path / "new"
    r = invoke("report", incline, "--out", out)
    assert r.exit_code == EXIT_FAILED
    assert "No space left on device" in r.stderr and "Traceback" not in r.output
    assert not out.exists()  # the folder it made is removed again
    old = tmp_path / "old"
    old.mkdir()
    (old / "report.html").write_text("previous")
    r = invoke("report", incline, "--out", old, "--overwrite")
    assert r.exit_code == EXIT_FAILED
    assert [p.name for p in old.iterdir()] == ["report.html"]
    assert (old / "report.html").read_text() == "previous"


# -------------------------------------------------------------------- plot
def test_plot_what_matches_the_library():
    from rockdem.plots import WHAT

    assert PLOT_WHAT == tuple(WHAT)


@pytest.mark.parametrize(
    ("what", "ext", "extra"),
    [
        ("model", ".png", ["--ids", "--dpi", "60"]),
        ("model", ".svg", []),
        ("failure", ".pdf", ["--ids"]),
        ("deformed", ".png", ["--magnification", "200", "--dpi", "50"]),
        ("stress", ".svg", ["--joint", "plane"]),
        ("fos", ".png", ["--dpi", "50"]),
        ("animation", ".gif", ["--dpi", "40"]),
    ],
)
def test_plot_writes_the_format_of_the_extension(incline, tmp_path, what, ext, extra):
    target = tmp_path / "pics" / f"{what}{ext}"  # the folder is created
    r = invoke("plot", incline, "--what", what, "--out", target, *extra, "--quiet")
    assert r.exit_code == 0, r.output
    assert r.stdout.strip() == str(target)
    assert target.read_bytes().startswith(MAGIC[ext])
    assert target.stat().st_size > 1000
    assert [p.name for p in target.parent.iterdir()] == [target.name]


def test_plot_passes_options_and_units(tmp_path, monkeypatch):
    import rockdem.plots
    from rockdem.results import Analysis, FactorOfSafety

    calls = []

    def spy(obj, what, out_file, *, dpi, **options):
        calls.append((obj, what, dpi, options))
        Path(out_file).write_bytes(MAGIC[Path(out_file).suffix])
        return Path(out_file)

    monkeypatch.setattr(rockdem.plots, "plot_figure", spy)
    ex = ("-e", "wedge-verification")
    r = invoke("plot", *ex, "-w", "stress", "-j", "lower", "-o", tmp_path / "a.png")
    assert r.exit_code == 0, r.output
    assert (
        invoke(
            "plot", *ex, "-w", "Deformed", "-m", "50", "--dpi", "72", "-o", tmp_path / "b.pdf"
        ).exit_code
        == 0
    )
    assert invoke("plot", *ex, "-w", "mechanism", "-o", tmp_path / "c.svg").exit_code == 0
    (a, what_a, dpi_a, opt_a), (_, what_b, dpi_b, opt_b), (c, what_c, _, opt_c) = calls
    assert what_a == "stress" and isinstance(a, Analysis) and dpi_a == 150
    assert opt_a == {"unit": "m", "stress_unit": "t/m^2", "joint": "lower"}
    assert what_b == "deformed" and dpi_b == 72
    assert opt_b == {"unit": "m", "magnification": 50.0}
    # the mechanism comes from the strength-reduction search with the file's settings
    assert what_c == "mechanism" and isinstance(c, FactorOfSafety)
    assert c.value == pytest.approx(WEDGE_FOS, abs=0.002)
    assert c.bracket[1] - c.bracket[0] <= 0.002 + 1e-12  # width: 0.002 from the file
    assert opt_c == {"unit": "m"}


@pytest.mark.parametrize(
    ("args", "fragments"),
    [
        (["--what", "photo", "--out", "x.png"], ["--what photo", "use one of model, failure"]),
        (["--what", "model", "--out", "x.jpg"], ["unsupported file type '.jpg'", ".svg"]),
        (["--what", "model", "--out", "x"], ["has no extension"]),
        (["--what", "model", "--out", "x.gif"], ["only --what animation"]),
        (["--what", "animation", "--out", "x.png"], ["written as a GIF", ".gif"]),
        (["--what", "model", "--joint", "plane", "--out", "x.png"], ["--joint", "stress"]),
        (["--what", "stress", "-j", "plane", "-j", "plane", "--out", "x.png"], ["one joint"]),
        (["--what", "stress", "--joint", "nope", "--out", "x.png"], ["--joint nope"]),
        (["--what", "model", "--magnification", "5", "--out", "x.png"], ["--magnification"]),
        (
            ["--what", "deformed", "--magnification", "-5", "--out", "x.png"],
            ["out of range (0 < factor < 1e12)"],
        ),
        (["--what", "stress", "--ids", "--out", "x.png"], ["--ids", "model or failure"]),
        (["--what", "model", "--dpi", "0", "--out", "x.png"], ["--dpi 0"]),
    ],
)
def test_plot_bad_options(incline, tmp_path, args, fragments):
    args = [str(tmp_path / a) if a.startswith("x") else a for a in args]
    _one_line_error(invoke("plot", incline, *args), *fragments)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["incline.yaml"]  # nothing written


def test_plot_is_not_overwritten_without_overwrite(incline, tmp_path):
    target = tmp_path / "model.png"
    target.write_bytes(b"mine")
    r = invoke("plot", incline, "--what", "model", "--out", target)
    _one_line_error(r, f"--out {target}", "exists already", "--overwrite")
    assert target.read_bytes() == b"mine"
    folder = tmp_path / "pics.png"
    folder.mkdir()
    _one_line_error(
        invoke("plot", incline, "--what", "model", "--out", folder),
        "is a folder",
        "pics.png/model.png",
    )
    r = invoke("plot", incline, "--what", "model", "--out", target, "--overwrite", "--dpi", "40")
    assert r.exit_code == 0, r.output
    assert target.read_bytes().startswith(MAGIC[".png"])


def test_plot_bad_model_and_missing_options(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(_incline_yaml().replace("friction_angle: 30", "friction_angle: 95"))
    _one_line_error(
        invoke("plot", bad, "-w", "model", "-o", tmp_path / "m.png"), "joints.plane.friction_angle"
    )
    _one_line_error(
        invoke("plot", "-w", "model", "-o", tmp_path / "m.png"),
        "give either a model file or --example",
    )
    r = invoke("plot", "-e", "wedge-verification", "-o", tmp_path / "m.png")
    assert r.exit_code == EXIT_INPUT and "--what" in r.output
    assert not (tmp_path / "m.png").exists()


def test_a_failure_while_plotting_leaves_no_file(incline, tmp_path, monkeypatch):
    import rockdem.plots

    def broken(obj, what, out_file, **options):
        Path(out_file).write_bytes(b"\x89PNG half")
        raise MemoryError("figure too large")

    monkeypatch.setattr(rockdem.plots, "plot_figure", broken)
    target = tmp_path / "out" / "model.png"
    r = invoke("plot", incline, "--what", "model", "--out", target)
    assert r.exit_code == EXIT_FAILED
    assert "MemoryError: figure too large" in r.stderr
    assert list(target.parent.iterdir()) == []


def test_plot_units():
    assert _plot_units("kN, m, kPa") == {"unit": "m", "stress_unit": "kPa"}
    assert _plot_units("t, m, t/m^2 (angles in degrees)") == {"unit": "m", "stress_unit": "t/m^2"}
    assert _plot_units("lbf, ft") == {"unit": "ft"}
    assert _plot_units("") == {}
    assert _plot_units("SI units, angles in degrees") == {}


def test_help_lists_both_commands():
    r = invoke("--help")
    assert "report" in r.stdout and "plot" in r.stdout
    r = invoke("plot", "--help")
    assert all(w in r.stdout for w in PLOT_WHAT)
    assert "Parameters" not in r.stdout  # the numpydoc part stays out of --help


# -------------------------------------------------------------- subprocess
def test_subprocess_report_of_the_example(tmp_path):
    env = dict(os.environ, COLUMNS="120", MPLBACKEND="Agg")
    cmd = [
        sys.executable,
        "-m",
        "rockdem",
        "report",
        "--example",
        "wedge-verification",
        "--out",
        "rep",
    ]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=tmp_path, env=env, timeout=120)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip() == str(Path("rep") / "report.html")
    html = tmp_path / "rep" / "report.html"
    text = html.read_text(encoding="utf-8")
    assert _fos_in(text) == pytest.approx(WEDGE_FOS, abs=0.002)
    images = _images(text)
    assert len(images) >= 8 and all(src.startswith("data:image/") for src in images)
    assert any(src.startswith("data:image/gif;base64,") for src in images)
    assert [p.name for p in html.parent.iterdir()] == ["report.html"]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=tmp_path, env=env, timeout=120)
    assert p.returncode == 2 and p.stdout == ""
    assert "exists already" in p.stderr and "Traceback" not in p.stderr


# --------------------------------------------------------------- stabilise
def test_stabilise_is_registered_when_its_module_exists():
    pytest.importorskip("rockdem.cli_stabilise")
    r = invoke("stabilise", "--help")
    assert r.exit_code == 0 and "Usage: rockdem stabilise" in r.stdout


def test_the_command_line_works_without_the_stabilise_module():
    code = (
        "import sys; sys.modules['rockdem.cli_stabilise'] = None\n"
        "from typer.testing import CliRunner\n"
        "from rockdem.cli import app\n"
        "r = CliRunner().invoke(app, ['--help'])\n"
        "assert r.exit_code == 0 and 'report' in r.stdout and 'stabilise' not in r.stdout\n"
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0, p.stderr
