"""Hostile testing, round 4: what the earlier rounds missed (Ctrl-C on a
study's local Dask cluster, ...).  Each test failed before its fix."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from rockdem.cli import app

runner = CliRunner()
SRC = str(Path(__file__).resolve().parents[1] / "src")


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


def plane_model(folder: Path, **extra) -> Path:
    """A 2 x 1 block on a horizontal fixed plane, with ``extra`` top-level keys."""
    doc = {
        "units": "kN, m, kPa",
        "materials": {"rock": {"unit_weight": 25}},
        "joints": {"plane": {"normal_stiffness": 1.0e6, "friction_angle": 33}},
        "blocks": [
            {"fixed": True, "vertices": [[-8, -1], [8, -1], [8, 0], [-8, 0]]},
            {"material": "rock", "vertices": [[0, 0], [2, 0], [2, 1], [0, 1]]},
        ],
        **extra,
    }
    path = folder / "plane.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


@pytest.mark.skipif(sys.platform == "win32", reason="process groups and SIGINT")
def test_ctrl_c_on_a_study_with_local_workers_prints_one_line(tmp_path):
    """Ctrl-C reaches the whole process group: each Dask worker printed a
    KeyboardInterrupt traceback, and every running task a cancellation
    warning, after the study's own "interrupted"."""
    pytest.importorskip("dask.distributed")
    study = {
        "samples": 5000,
        "inputs": {"joints.plane.friction_angle": {"distribution": "normal", "mean": 33, "sd": 2}},
    }
    model = plane_model(tmp_path, study=study)
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}
    cmd = [
        sys.executable,
        "-m",
        "rockdem",
        "study",
        str(model),
        "--out",
        str(out),
        "--workers",
        "2",
        "--quiet",
    ]
    with subprocess.Popen(
        cmd,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,  # its own process group, as a shell gives it
    ) as proc:
        deadline = time.monotonic() + 120
        csv = out / "samples.csv"
        try:
            while time.monotonic() < deadline and proc.poll() is None:
                if csv.exists() and len(csv.read_text().splitlines()) >= 1 + 4:
                    break
                time.sleep(0.05)
            assert proc.poll() is None, proc.stderr.read()
            os.killpg(proc.pid, signal.SIGINT)  # Ctrl-C in a terminal
            _, err = proc.communicate(timeout=60)
        finally:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait(timeout=30)
    assert proc.returncode == 130, err
    assert err.strip() == "interrupted", err
