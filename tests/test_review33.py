"""Review 33: each test failed before its fix."""

from __future__ import annotations

from pathlib import Path

import yaml
from typer.testing import CliRunner

from rockdem.cli import app

runner = CliRunner()


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


def sliding_wedge(folder: Path, **extra) -> Path:
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


def test_stabilise_overwrite_keeps_a_users_file_named_like_a_picture(tmp_path):
    """--overwrite removes the earlier stabilisation's stale files by glob
    'trial-[0-9][0-9]*.png': a user's marked-up copy 'trial-00-marked.png'
    in the folder was deleted with them."""
    model = sliding_wedge(tmp_path, stabilisation={"target_fos": 0.5})
    out = tmp_path / "o"
    r = invoke("stabilise", model, "--out", out)
    assert r.exit_code == 0, r.output
    (out / "trial-00-marked.png").write_bytes(b"mine")
    (out / "stage-01 copy.png").write_bytes(b"mine")
    r = invoke("stabilise", model, "--out", out, "--overwrite")
    assert r.exit_code == 0, r.output
    assert (out / "trial-00-marked.png").read_bytes() == b"mine"
    assert (out / "stage-01 copy.png").read_bytes() == b"mine"


def test_an_unnamed_bolt_left_by_a_stage_keeps_its_yield_history():
    """bolts_left_in_rock names an unnamed bolt that stays (``bolt 2``) with
    dataclasses.replace, a new object; the stage's carry matched bolts by
    identity, so the unnamed bolt lost its history: first yield at the
    excavation stage, not in load step 1 (as a named one keeps it)."""
    from dataclasses import replace

    import numpy as np
    import pytest

    import rockdem as rd
    from rockdem.stabilisation import Stage, excavate_in_stages
    from test_stabilisation import _two_blocks_and_a_yielding_bolt

    named = _two_blocks_and_a_yielding_bolt()
    model = named.replace(bolts=tuple(replace(b, name="") for b in named.bolts))
    with pytest.warns(rd.ModelWarning, match=r"bolt 2 removed with its rock"):
        ex = excavate_in_stages(model, [Stage("cut", blocks=(2,))])
    before, after = ex.stages[0].analysis, ex.stages[1].analysis
    assert before.bolts.first_yield.tolist() == [1, -1]
    assert [b.name for b in ex.stages[1].model.bolts] == ["bolt 1"]
    assert after.stable and np.asarray(after.bolts.first_yield).tolist() == [1]
