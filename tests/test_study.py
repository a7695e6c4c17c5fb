"""Probabilistic and parametric studies (rockdem.study, `rockdem study`).

The closed form: a block on a plane dipping psi with a normally distributed
friction angle phi fails iff tan(phi) < tan(psi), so P(FS < 1) =
Phi((psi - mean) / sd).  Monte Carlo must find it within its confidence
interval; Latin hypercube, with one input, within 1/n (one sample per stratum:
only the stratum holding the limit can be misjudged), with 5x fewer samples.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy import stats
from typer.testing import CliRunner

import rockdem
from _cli import assert_refused
from rockdem.cli import app
from rockdem.config import load_model
from rockdem.studies import sampling
from rockdem.studies.plan import prepare
from rockdem.studies.spec import StudySpec
from rockdem.studies.stats import pf_interval
from rockdem.verification import sliding_fos

pytest.importorskip("pandas")
pytest.importorskip("pyarrow")

runner = CliRunner()
PSI = 30.0  # dip of the plane
PHI = "joints.plane.friction_angle"
VOLATILE = ["seconds", "worker"]


def plane_document(dip: float = PSI) -> dict:
    """A 2 x 1 block on a fixed plane dipping ``dip`` toward +x (as the parsed file)."""
    d = np.radians(-dip)
    R = np.array([[np.cos(d), -np.sin(d)], [np.sin(d), np.cos(d)]])
    ground = np.array([(-8, -1), (8, -1), (8, 0), (-8, 0)]) @ R.T
    block = np.array([(0, 0), (2, 0), (2, 1), (0, 1)]) @ R.T
    return {
        "name": "block on a plane",
        "units": "kN, m, kPa",
        "materials": {"rock": {"unit_weight": 25}},
        "joints": {"plane": {"normal_stiffness": 1.0e6, "friction_angle": 33}},
        "blocks": [
            {"fixed": True, "vertices": ground.tolist()},
            {"material": "rock", "vertices": block.tolist()},
        ],
    }


def normal_phi(**kw) -> dict:
    return {"inputs": {PHI: {"distribution": "normal", "mean": 33, "sd": 2.5}}, **kw}


def write_model(folder: Path, study: dict | None, name: str = "plane.yaml") -> Path:
    doc = plane_document()
    if study is not None:
        doc["study"] = study
    path = folder / name
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def same_table(a, b) -> None:
    """Equal tables, apart from where and how long each sample ran."""
    import pandas.testing as pdt

    pdt.assert_frame_equal(a.drop(columns=VOLATILE), b.drop(columns=VOLATILE))


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


# ------------------------------------------------------------- closed form
@pytest.fixture(scope="module")
def monte_carlo():
    spec = normal_phi(samples=200, seed=7, compute="verdict", confidence=0.99)
    return rockdem.study(plane_document(), spec, workers=0)


def test_monte_carlo_pf_matches_the_closed_form_within_its_interval(monte_carlo):
    table, s = monte_carlo
    exact = stats.norm.cdf((PSI - 33) / 2.5)  # P(tan phi < tan psi) = P(phi < psi)
    lo, hi = s["pf_interval"]
    assert s["done"] == s["ok"] == 200 and s["errors"] == 0
    assert lo <= exact <= hi, (exact, s["pf"], lo, hi)
    assert s["pf"] == pytest.approx(s["failed"] / 200)
    # every sample's verdict is the closed form's, but within 0.05 degrees of the limit
    phi = table[PHI].to_numpy()
    wrong = table["failed"].to_numpy(dtype=bool) != (phi < PSI)
    assert not np.any(wrong & (np.abs(phi - PSI) > 0.05)), phi[wrong]
    # the samples follow the distribution (Kolmogorov-Smirnov, 1% level)
    assert stats.kstest(phi, stats.norm(33, 2.5).cdf).pvalue > 0.01


def test_latin_hypercube_gives_the_same_with_five_times_fewer_samples(monte_carlo):
    n = 40
    table, s = rockdem.study(
        plane_document(),
        normal_phi(samples=n, sampler="latin-hypercube", compute="verdict"),
        workers=0,
    )
    exact = stats.norm.cdf((PSI - 33) / 2.5)
    # one input: one sample per stratum of width 1/n, only the stratum of the limit can
    # be misjudged, so the estimate is within 1/n of the exact value
    assert abs(s["pf"] - exact) <= 1.0 / n
    # ... which is tighter than the Monte Carlo interval of 200 samples
    lo, hi = monte_carlo.summary["pf_interval"]
    assert 1.0 / n < (hi - lo) / 2
    # stratified: exactly one sample in each 1/n of the probability
    u = stats.norm(33, 2.5).cdf(table[PHI].to_numpy())
    assert sorted(np.floor(u * n).astype(int)) == list(range(n))


@pytest.fixture(scope="module")
def fos_study(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fos-study")
    model = write_model(folder, normal_phi(samples=8, sampler="latin-hypercube", seed=3, worst=2))
    return model, rockdem.study(model, out=folder / "out", workers=0)


def test_each_factor_of_safety_is_the_closed_form(fos_study):
    _, (table, s) = fos_study
    phi = table[PHI].to_numpy()
    exact = np.tan(np.radians(phi)) / np.tan(np.radians(PSI))
    assert np.allclose(table["fs"].to_numpy(dtype=float), exact, rtol=0.005)
    assert (table["fs_low"] <= table["fs"]).all() and (table["fs"] <= table["fs_high"]).all()
    assert list(table["failed"]) == list(exact < 1)
    assert np.allclose(table["unstable_area"].to_numpy(dtype=float), 2.0)  # the 2 x 1 block
    assert (table["unstable_blocks"] == 1).all()
    fs = table["fs"].to_numpy(dtype=float)
    assert s["fs"]["mean"] == pytest.approx(fs.mean())
    assert s["reliability_index"]["normal"] == pytest.approx((fs.mean() - 1) / fs.std(ddof=1))
    assert s["sensitivity"][0]["spearman"] == pytest.approx(1.0)  # FS rises with phi
    assert s["worst"] == [int(i) for i in table.sort_values("fs")["sample"][:2]]


def test_the_files_are_written_and_the_worst_samples_replay(fos_study):
    import pandas as pd

    _, (table, s) = fos_study
    folder = Path(s["folder"])
    for name in (
        "samples.csv",
        "samples.parquet",
        "summary.json",
        "study.json",
        "fs-distribution.png",
        "sensitivity.png",
    ):
        assert (folder / name).stat().st_size > 0, name
    same_table(pd.read_parquet(folder / "samples.parquet"), table)
    assert json.loads((folder / "summary.json").read_text())["pf"] == s["pf"]
    assert len(s["worst_files"]) == 2
    for i, rel in zip(s["worst"], s["worst_files"], strict=True):
        model, cfg = load_model(folder / rel)
        row = table.set_index("sample").loc[i]
        assert cfg.joints["plane"].friction_angle == row[PHI]
        assert rockdem.factor_of_safety(model).value == pytest.approx(row["fs"], rel=1e-9)


def test_the_report_gets_a_study_section(fos_study, tmp_path):
    from rockdem.report import write_report

    model, result = fos_study
    plan = prepare(model)
    path = write_report(plan.nominal, tmp_path, study=result, animation=False)
    html = path.read_text()
    assert 'id="study"' in html and "Probabilistic study" in html
    assert 'id="fig-study-fs-distribution"' in html and PHI in html
    assert f"{result.summary['pf']:.4g}" in html


# ------------------------------------------------------------ parametric sweep
def test_a_sweep_over_two_inputs_is_the_closed_form_on_its_grid(tmp_path):
    spec = {
        "sweep": {
            PHI: {"values": [28, 34]},
            "loads.seismic_h": {"start": 0, "stop": 0.1, "steps": 2},
        }
    }
    table, s = rockdem.study(plane_document(), spec, workers=0, out=tmp_path / "sweep")
    assert s["kind"] == "sweep" and s["pf"] is None and s["samples"] == 4
    assert list(zip(table[PHI], table["loads.seismic_h"], strict=True)) == [
        (28, 0),
        (28, 0.1),
        (34, 0),
        (34, 0.1),
    ]
    exact = [
        sliding_fos(PSI, p, k=k) for p, k in zip(table[PHI], table["loads.seismic_h"], strict=True)
    ]
    assert np.allclose(table["fs"].to_numpy(dtype=float), exact, rtol=0.005)
    assert (tmp_path / "sweep" / "sweep.png").stat().st_size > 0


def test_a_sweep_over_the_spring_points_runs_each_rule(tmp_path):
    """The toppling warning sends users to this sweep to see how their limit
    depends on the spring points; a sliding block's does not (the closed form
    at every rule)."""
    spec = {"sweep": {"analysis.points_per_interface": {"values": [2, 3, 5]}}}
    table, _ = rockdem.study(plane_document(), spec, workers=0, out=tmp_path / "points")
    assert table["analysis.points_per_interface"].tolist() == [2, 3, 5]
    exact = sliding_fos(PSI, 33.0)
    assert np.allclose(table["fs"].to_numpy(dtype=float), exact, rtol=0.005)


def test_samples_without_a_factor_are_ranked_not_dropped(tmp_path):
    """Found by fuzzing: a block tipped by kh 0.9 with vertical accelerations
    from -0.99 to 0.5: 12 of 40 samples fail at any strength (no factor);
    P(FS < 1) counted them, but the mean, the percentiles and the rank
    correlation were of the other 28 without a word, the 5% among them."""
    doc = plane_document(0.0)
    doc["loads"] = {"seismic_h": 0.9}
    spec = {
        "samples": 40,
        "seed": 3,
        "inputs": {"loads.seismic_v": {"distribution": "uniform", "min": -0.99, "max": 0.5}},
    }
    table, s = rockdem.study(doc, spec, workers=0, out=tmp_path / "kh")
    none = int((table["mode"] == "strength-independent").sum())
    assert none > 2  # 40 x 5%: the 5% lies among them
    f = s["fs"]
    assert f["without_factor"] == {"strength-independent": none, "no-failure": 0}
    assert f["n"] == 40 - none and f["p05"] is None and f["min"] is None
    assert s["reliability_index"]["normal"] is None  # no mean and sd of all samples
    from rockdem.studies.stats import fs_line

    line = fs_line(f)
    assert "5% fails at any strength" in line and f"{none} fail at any strength" in line
    # they have the largest upward accelerations and rank lowest: kv and FS
    # rise together
    rho = s["sensitivity"][0]["spearman"]
    assert rho > 0.9


# ------------------------------------------------------------------ sampling
def test_distributions_correlation_and_seeds():
    spec = StudySpec.model_validate(
        {
            "inputs": {
                "a": {"distribution": "lognormal", "mean": 10, "sd": 3},
                "b": {"distribution": "normal", "mean": 35, "sd": 2},
                "c": {"distribution": "triangular", "min": 1, "mode": 2, "max": 5},
                "d": {
                    "distribution": "truncated-normal",
                    "mean": 0,
                    "sd": 1,
                    "min": -0.5,
                    "max": 2,
                },
                "e": {"distribution": "uniform", "min": 3, "max": 4},
            },
            "correlations": [{"inputs": ["a", "b"], "rho": -0.6}],
            "samples": 4000,
            "seed": 11,
        }
    )
    x = sampling.draw(spec)
    assert np.array_equal(x, sampling.draw(spec))  # reproducible
    other = sampling.draw(spec.model_copy(update={"seed": 12}))
    assert not np.allclose(x, other)
    assert x[:, 0].mean() == pytest.approx(10, rel=0.03) and x[:, 0].std() == pytest.approx(
        3, rel=0.06
    )
    assert (x[:, 0] > 0).all()
    assert (
        x[:, 2].min() >= 1
        and x[:, 2].max() <= 5
        and x[:, 2].mean() == pytest.approx(8 / 3, rel=0.03)
    )
    assert x[:, 3].min() >= -0.5 and x[:, 3].max() <= 2
    assert x[:, 4].min() >= 3 and x[:, 4].max() <= 4
    # Gaussian copula: the normal scores carry the correlation, the ranks nearly so
    za = stats.norm.ppf(sampling.distribution(spec.inputs["a"]).cdf(x[:, 0]))
    zb = stats.norm.ppf(sampling.distribution(spec.inputs["b"]).cdf(x[:, 1]))
    assert np.corrcoef(za, zb)[0, 1] == pytest.approx(-0.6, abs=0.03)
    assert abs(stats.spearmanr(x[:, 0], x[:, 2]).statistic) < 0.05  # independent


def test_the_pf_interval_covers_as_often_as_it_says():
    rng = np.random.default_rng(0)
    for p, n in ((0.02, 100), (0.3, 50)):
        k = rng.binomial(n, p, size=2000)
        covered = [pf_interval(int(j), n, 0.95) for j in k]
        rate = np.mean([lo <= p <= hi for lo, hi in covered])
        assert rate >= 0.94, (p, n, rate)


# ------------------------------------------------------------------- Dask
def test_dask_local_cluster_of_two_processes_gives_the_serial_table(tmp_path):
    from dask.distributed import Client, LocalCluster

    spec = normal_phi(samples=6, sampler="latin-hypercube", seed=5)
    serial, _ = rockdem.study(plane_document(), spec, workers=0)
    with (
        LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        Client(cluster) as client,
    ):
        table, s = rockdem.study(plane_document(), spec, client=client, out=tmp_path / "d")
    assert s["workers"] == 2 and s["done"] == 6 and s["errors"] == 0
    assert table["worker"].nunique() == 2  # both processes ran samples
    assert not set(table["worker"]) & set(serial["worker"])  # none ran here
    same_table(table, serial)


# ------------------------------------------------------- interruption, resume
def test_an_interrupted_study_continues_where_it_stopped(tmp_path):
    spec = normal_phi(samples=10, seed=2)
    one_run, _ = rockdem.study(plane_document(), spec, workers=0, out=tmp_path / "one")

    def stop_after(k):
        def hook(p):
            if p.done == k:
                raise KeyboardInterrupt

        return hook

    out = tmp_path / "resumed"
    with pytest.raises(KeyboardInterrupt):
        rockdem.study(plane_document(), spec, workers=0, out=out, progress=stop_after(4))
    rows = (out / "samples.csv").read_text().splitlines()
    assert len(rows) == 1 + 4  # the header and the four rows done
    seen = []
    table, s = rockdem.study(
        plane_document(), spec, workers=0, out=out, progress=lambda p: seen.append(p.row["sample"])
    )
    assert s["resumed"] == 4 and s["ran"] == 6 and len(seen) == 6
    same_table(table, one_run)
    assert (out / "samples.csv").read_text().split("\n")[0] == (
        tmp_path / "one" / "samples.csv"
    ).read_text().split("\n")[0]


def test_a_killed_command_loses_nothing_and_the_rerun_finishes(tmp_path):
    import pandas as pd

    model = write_model(tmp_path, normal_phi(samples=8, seed=4))
    out = tmp_path / "killed"
    cmd = [
        sys.executable,
        "-m",
        "rockdem",
        "study",
        str(model),
        "--out",
        str(out),
        "--workers",
        "0",
        "--quiet",
    ]
    csv_path = out / "samples.csv"
    deadline = time.monotonic() + 120
    with subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE) as proc:
        try:
            while time.monotonic() < deadline and proc.poll() is None:
                if csv_path.exists() and len(csv_path.read_text().splitlines()) >= 1 + 3:
                    break
                time.sleep(0.02)
            assert proc.poll() is None, proc.stderr.read()
        finally:
            if proc.poll() is None:
                os.kill(proc.pid, signal.SIGKILL)
            proc.wait(timeout=30)
    killed_at = len(csv_path.read_text().splitlines()) - 1
    assert 3 <= killed_at < 8
    r = invoke("study", model, "--out", out, "--workers", "0")
    assert r.exit_code == 0, r.output
    assert f"{killed_at} from an earlier run" in r.stdout
    r = invoke("study", model, "--out", tmp_path / "whole", "--workers", "0")
    assert r.exit_code == 0, r.output
    same_table(
        pd.read_parquet(out / "samples.parquet"),
        pd.read_parquet(tmp_path / "whole" / "samples.parquet"),
    )
    strip = [c for c in pd.read_csv(out / "samples.csv").columns if c not in VOLATILE]
    assert pd.read_csv(out / "samples.csv")[strip].equals(
        pd.read_csv(tmp_path / "whole" / "samples.csv")[strip]
    )


def test_a_resumed_study_runs_again_the_rows_it_could_not_have_written(tmp_path):
    """Found by fuzzing: a hand-edited samples.csv was trusted on resuming.
    A negative factor of safety entered the statistics, an index outside the
    study or a row of -inf stopped it with an exception (exit 1), and a byte
    that is not UTF-8 with UnicodeDecodeError.  Such rows are run again;
    a file that is not text is refused."""
    spec = normal_phi(samples=4, compute="fos")
    out = tmp_path / "o"
    table, _ = rockdem.study(plane_document(), spec, workers=0, out=out)
    good = (out / "samples.csv").read_text(encoding="utf-8").splitlines()
    header, rows = good[0], good[1:]
    fs = header.split(",").index("fs")
    bad = rows[0].split(",")
    bad[fs] = "-5"
    edited = [header, ",".join(bad), "-5" + rows[1][1:], "99999999999999999999" + rows[2][1:]]
    (out / "samples.csv").write_text("\n".join(edited) + "\n", encoding="utf-8")
    again, _ = rockdem.study(plane_document(), spec, workers=0, out=out)
    same_table(again, table)
    with open(out / "samples.csv", "ab") as fh:
        fh.write(b"\xff\xfe\n")
    with pytest.raises(rockdem.InputError, match=r"samples\.csv is not UTF-8 text"):
        rockdem.study(plane_document(), spec, workers=0, out=out)


def test_a_folder_of_another_study_is_refused(tmp_path):
    rockdem.study(
        plane_document(), normal_phi(samples=2, compute="verdict"), workers=0, out=tmp_path / "o"
    )
    with pytest.raises(rockdem.InputError, match="results of another study"):
        rockdem.study(
            plane_document(),
            normal_phi(samples=3, compute="verdict"),
            workers=0,
            out=tmp_path / "o",
        )


@pytest.mark.parametrize("overwrite", [False, True])
def test_a_study_never_writes_over_its_own_model_file(tmp_path, overwrite):
    """A worst sample's file studied into the folder it came from (or a model
    named like a result file there) is refused, even with --overwrite."""
    spec = normal_phi(samples=3, compute="verdict")
    for name in ("worst/sample-000000.yaml", "summary.json"):
        folder = tmp_path / name.replace("/", "-")
        (folder / "worst").mkdir(parents=True)
        model = write_model(folder, spec, name)
        before = model.read_bytes()
        flag = ["--overwrite"] if overwrite else []
        r = invoke("study", model, "--out", folder, "--workers", 0, "--quiet", *flag)
        assert_refused(r, "would write over its input", "another folder")
        assert model.read_bytes() == before


def test_a_fresh_folder_with_the_users_files_is_refused(tmp_path):
    """Not a study's folder (no study.json) but holding a file the study would
    write (a picture, a worst sample): refused without --overwrite."""
    model = write_model(tmp_path, normal_phi(samples=3, compute="verdict"))
    for mine in ("sensitivity.png", "fs-distribution.png", "worst/sample-000002.yaml"):
        folder = tmp_path / f"out-{mine.replace('/', '-')}"
        (folder / "worst").mkdir(parents=True)
        (folder / mine).write_text("mine\n")
        r = invoke("study", model, "--out", folder, "--workers", 0, "--quiet")
        assert_refused(r, f"holds {mine}", "--overwrite")
        assert (folder / mine).read_text() == "mine\n"


@pytest.mark.parametrize("overwrite", [False, True])
def test_a_worst_sample_edited_in_place_is_never_deleted(tmp_path, overwrite):
    """Fuzzing: every run rewrites worst/, so a worst sample edited where it
    was written was deleted by the next run (or by --overwrite).  The study
    records what it wrote (summary.json) and refuses a folder whose worst/
    file changed since, even with --overwrite; an unchanged folder runs on."""
    model = write_model(tmp_path, normal_phi(samples=3, sampler="latin-hypercube", worst=1))
    folder = tmp_path / "out"
    r = invoke("study", model, "--out", folder, "--workers", 0, "--quiet")
    assert r.exit_code == 0, r.stderr
    (sample,) = (folder / "worst").glob("sample-*.yaml")
    r = invoke("study", model, "--out", folder, "--workers", 0, "--quiet")  # unchanged: resumes
    assert r.exit_code == 0, r.stderr
    edited = sample.read_text() + "# my notes\n"
    sample.write_text(edited)
    flag = ["--overwrite"] if overwrite else []
    r = invoke("study", model, "--out", folder, "--workers", 0, "--quiet", *flag)
    assert_refused(r, f"worst/{sample.name} was changed", "move the file out of worst/")
    assert sample.read_text() == edited


# ---------------------------------------------------------------- bad input
BAD = [
    (
        {
            "inputs": {
                "joints.plane.friction_angel": {"distribution": "normal", "mean": 33, "sd": 2}
            }
        },
        ["study.inputs.joints.plane.friction_angel", "did you mean `friction_angle`"],
    ),
    (
        {
            "inputs": {
                "joints.bedding.friction_angle": {"distribution": "normal", "mean": 3, "sd": 2}
            }
        },
        ["study.inputs.joints.bedding.friction_angle", "`joints` has no key `bedding`"],
    ),
    (
        {"inputs": {"blocks[5].unit_weight": {"distribution": "normal", "mean": 3, "sd": 1}}},
        ["study.inputs.blocks[5].unit_weight", "has 2 items"],
    ),
    (
        {"inputs": {"joints.plane": {"distribution": "normal", "mean": 3, "sd": 1}}},
        ["study.inputs.joints.plane", "is a mapping, not a number"],
    ),
    (
        {"inputs": {"loads.water_table[*][1]": {"distribution": "normal", "mean": 3, "sd": 1}}},
        ["study.inputs.loads.water_table[*][1]", "`loads.water_table` is not in the file"],
    ),
    (  # found by fuzzing: "slope.profile: required key is missing" (a blocks model)
        {"inputs": {"slope.seed": {"distribution": "uniform", "min": 0, "max": 100}}},
        ["study.inputs.slope.seed", "the file has no `slope` section", "does nothing"],
    ),
    (
        {"inputs": {PHI: {"distribution": "normal", "mean": 33, "sd": 0}}},
        ["study.inputs.joints.plane.friction_angle", "sd = 0 must be > 0"],
    ),
    (
        {"inputs": {PHI: {"distribution": "uniform", "min": 40, "max": 30}}},
        ["study.inputs.joints.plane.friction_angle", "min = 40 must be < max = 30"],
    ),
    (
        {"inputs": {PHI: {"distribution": "triangular", "min": 30, "max": 40}}},
        ["triangular needs", "`mode` is missing"],
    ),
    (
        {"inputs": {PHI: {"distribution": "normal", "mean": 33, "sd": 2, "max": 40}}},
        ["normal takes `mean`, `sd`, not `max`"],
    ),
    (
        {"inputs": {PHI: {"distribution": "gaussian", "mean": 33, "sd": 2}}},
        ["study.inputs.joints.plane.friction_angle.distribution", "'normal'"],
    ),
    (
        {"inputs": {PHI: {"distribution": "lognormal", "mean": -1, "sd": 2}}},
        ["lognormal: mean = -1 must be > 0"],
    ),
    (  # scipy's overflow warnings before the error line; "inf is not finite" (fuzzing)
        {"inputs": {PHI: {"distribution": "normal", "mean": 1e308, "sd": 1e308}}},
        ["study.inputs.joints.plane.friction_angle", "a parameter of 1e+308 is beyond 1e+15"],
    ),
    (
        {"inputs": {PHI: {"distribution": "uniform", "min": -1.7e308, "max": 1.7e308}}},
        ["study.inputs.joints.plane.friction_angle", "a parameter of 1.7e+308 is beyond"],
    ),
    (  # overflowed in the sampler: "the analysis failed: OverflowError" (fuzzing)
        {"inputs": {PHI: {"distribution": "lognormal", "mean": 1, "sd": 1e200}}},
        ["study.inputs.joints.plane.friction_angle", "sd / mean = 1e+200 is over 100"],
    ),
    (  # underflowed to a zero spread: "cohesion: nan is not a finite number" (fuzzing)
        {"inputs": {PHI: {"distribution": "lognormal", "mean": 10, "sd": 1e-300}}},
        ["study.inputs.joints.plane.friction_angle", "sd / mean = 1e-301 is below 1e-09"],
    ),
    (
        {"inputs": {PHI: {"distribution": "normal", "mean": 95, "sd": 1}}},
        ["study inputs at their medians", "joints.plane.friction_angle: 95", "out of range"],
    ),
    (
        {
            "inputs": {PHI: {"distribution": "normal", "mean": 33, "sd": 2}},
            "correlations": [{"inputs": [PHI, "joints.plane.cohesion"], "rho": 0.5}],
        },
        ["correlations: 'joints.plane.cohesion' is not one of `inputs`"],
    ),
    (
        {"inputs": {PHI: {"distribution": "normal", "mean": 33, "sd": 2}}, "sampels": 10},
        ["study.sampels", "unknown key", "did you mean `samples`"],
    ),
    (
        {
            "sweep": {PHI: {"values": [30, 31]}},
            "inputs": {PHI: {"distribution": "normal", "mean": 33, "sd": 2}},
        },
        ["either `inputs`", "not both"],
    ),
    (  # said "has None items" (found by fuzzing)
        {
            "sweep": {
                PHI: {"values": [30, 31]},
                "joints.plane.cohesion": {"values": [0, 1]},
                "loads.seismic_h": {"values": [0, 0.1]},
            }
        },
        ["study.sweep", "has 3 items; give at most 2"],
    ),
]


@pytest.mark.parametrize(("spec", "fragments"), BAD, ids=[str(i) for i in range(len(BAD))])
def test_bad_input_is_one_line_and_exit_2(tmp_path, spec, fragments):
    model = write_model(tmp_path, spec)
    r = invoke("study", model, "--out", tmp_path / "out", "--workers", "0")
    assert_refused(r, "plane.yaml", *fragments)
    assert not (tmp_path / "out").exists()  # refused before anything is written


def test_contradictory_correlations_are_refused(tmp_path):
    inputs = {
        k: {"distribution": "normal", "mean": 30, "sd": 1}
        for k in ("joints.plane.friction_angle", "joints.plane.cohesion", "loads.seismic_h")
    }
    inputs["loads.seismic_h"] = {"distribution": "uniform", "min": 0, "max": 0.1}
    inputs["joints.plane.cohesion"] = {"distribution": "uniform", "min": 0, "max": 5}
    a, b, c = inputs
    spec = {
        "inputs": inputs,
        "correlations": [
            {"inputs": [a, b], "rho": 0.9},
            {"inputs": [b, c], "rho": 0.9},
            {"inputs": [a, c], "rho": -0.9},
        ],
    }
    r = invoke("study", write_model(tmp_path, spec), "--out", tmp_path / "o", "--workers", "0")
    assert_refused(r, "study.correlations", "not positive definite")


def test_no_study_section_and_workers_with_scheduler(tmp_path):
    model = write_model(tmp_path, None)
    assert_refused(invoke("study", model, "--out", tmp_path / "o"), "has no `study:` section")
    spec = tmp_path / "s.yaml"
    spec.write_text(yaml.safe_dump({"study": normal_phi(samples=2, compute="verdict")}))
    assert_refused(
        invoke(
            "study",
            model,
            "--out",
            tmp_path / "o",
            "--workers",
            "1",
            "--scheduler",
            "tcp://127.0.0.1:1",
        ),
        "--workers",
        "not both",
    )
    r = invoke("study", model, "--spec", spec, "--out", tmp_path / "o", "--workers", "0", "--json")
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["done"] == 2


def test_without_dask_the_command_says_how_to_install_it(tmp_path, monkeypatch):
    model = write_model(tmp_path, normal_phi(samples=2, compute="verdict"))
    monkeypatch.setitem(sys.modules, "dask.distributed", None)  # import fails
    assert_refused(invoke("study", model, "--out", tmp_path / "o"), "pip install 'rockdem[study]'")


def test_a_sample_out_of_range_is_a_row_with_its_error():
    spec = normal_phi(samples=30, seed=1, compute="verdict")
    spec["inputs"][PHI] = {"distribution": "uniform", "min": 70, "max": 95}
    table, s = rockdem.study(plane_document(), spec, workers=0)
    bad = table[PHI] >= 90
    assert bad.any() and (~bad).any()
    assert table["error"][bad].str.contains("friction_angle: .* is out of range").all()
    assert table["error"][~bad].isna().all()
    assert s["errors"] == int(bad.sum()) and s["ok"] == int((~bad).sum())


def test_the_command_line_does_not_load_dask_or_pandas():
    code = (
        "import sys, rockdem.cli; from rockdem.config import load_model; "
        "from rockdem.examples import example_path; load_model(example_path('wedge-verification'));"
        "print(sorted(m for m in ('dask', 'distributed', 'pandas', 'pyarrow') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_bolt_utilisation_per_sample():
    """A bolted block pushed sideways (kh 0.5), friction swept: the largest bolt
    utilisation of each sample's last equilibrium is in the table, and it falls
    as the joint gets stronger (the bolt carries less)."""
    doc = yaml.safe_load(
        """
units: kN, m, kPa
joints:
  rock: {normal_stiffness: 1.0e+6, friction_angle: 30}
blocks:
  - {vertices: [[-5, -1], [5, -1], [5, 0], [-5, 0]], fixed: true}
  - {vertices: [[0, 0], [1, 0], [1, 1], [0, 1]], unit_weight: 25}
loads: {seismic_h: 0.5}
bolts:
  - {head: [0.8, 1.0], angle: 240, length: 2.5, capacity: 50, axial_stiffness: 1.0e+4}
"""
    )
    spec = {"sweep": {"joints.rock.friction_angle": {"values": [20, 25, 30]}}, "compute": "verdict"}
    table, _ = rockdem.study(doc, spec, workers=0)
    use = table.sort_values("joints.rock.friction_angle")["bolt_utilisation"].to_numpy(float)
    assert np.all((use > 0) & (use <= 1)), use
    assert np.all(np.diff(use) < 0), use


# -------------------------------------------------- samples left out (F6)
def wide_phi(**kw) -> dict:
    """Friction angle normal(30, 20): seed 5 draws 30 samples of which 6 are below
    0 (the weak tail) and 1 above 90, so 7 cannot be analysed."""
    spec = {"inputs": {PHI: {"distribution": "normal", "mean": 30, "sd": 20}}}
    return {**spec, "samples": 30, "seed": 5, "compute": "verdict", **kw}


def test_samples_left_out_in_the_weak_tail_are_said_to_bias_the_pf(tmp_path):
    """Fuzzing (F6): samples out of range were dropped from P(FS < 1) with only a
    note on stderr, while most of them lay in the weak tail (phi < 0): the
    estimate was biased low without a word.  The summary (text, summary.json,
    --json, the report) says how many were left out, on which side, which way
    that biases P(failure), P(failure) if they all held or all failed, and a
    distribution that stays in range."""
    model = write_model(tmp_path, wide_phi())
    out = tmp_path / "out"
    r = invoke("study", model, "--out", out, "--workers", 0, "--json")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    assert s == {**s, "errors": 7, "ok": 23}
    left = s["left_out"]
    assert left["n"] == 7 and left["bias"] == "underestimated"
    (why,) = left["reasons"]
    assert why["input"] == PHI and (why["n"], why["below"], why["above"]) == (7, 6, 1)
    assert left["pf_if_stable"] == pytest.approx(s["failed"] / 30)
    assert left["pf_if_failed"] == pytest.approx((s["failed"] + 7) / 30)
    assert left["pf_if_stable"] <= s["pf"] <= left["pf_if_failed"]
    assert json.loads((out / "summary.json").read_text())["left_out"] == left
    for text in (left["note"], invoke("study", model, "--out", out, "--workers", 0).stdout):
        text = " ".join(text.split())  # (rich wraps long lines)
        assert "7 of 30 samples were left out" in text, text
        assert f"6 of the 7 left out had {PHI} below its valid range" in text, text
        assert "is likely underestimated" in text, text
        assert "truncated-normal" in text, text
    from rockdem.studies.report import html_section

    html = "".join(html_section(out, lambda *a: ""))
    assert "likely underestimated" in html and "truncated-normal" in html


def test_when_no_sample_can_be_analysed_the_study_is_refused(tmp_path):
    """Fuzzing (F6): with sd 1e300 every sample was out of range, nothing was
    computed and the command exited 0.  It is refused in one line (why and the
    fix), and the folder is left as it was."""
    # (sd 1e6: each sample lies in [0, 90) with probability 4e-5)
    spec = {"inputs": {PHI: {"distribution": "normal", "mean": 33, "sd": 1e6}}, "samples": 4}
    model = write_model(tmp_path, spec)
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine\n")
    r = invoke("study", model, "--out", out, "--workers", 0)
    assert_refused(
        r, "no sample could be analysed", f"{PHI} was out of its valid range", "truncated-normal"
    )
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]
    r = invoke("study", model, "--out", tmp_path / "new", "--workers", 0)
    assert_refused(r, "no sample could be analysed")
    assert not (tmp_path / "new").exists()
    with pytest.raises(rockdem.InputError, match="no sample could be analysed"):
        rockdem.study(plane_document(), spec, workers=0)


# ------------------------------------------- an unreachable scheduler (F13)
def test_an_unreachable_scheduler_leaves_the_folder_as_it_was(tmp_path, monkeypatch):
    """Fuzzing (F13): `--scheduler tcp://127.0.0.1:1` failed after the folder
    had study.json, samples.csv and samples.parquet, so the next study there
    was refused as "another study".  The scheduler is reached before anything
    is written."""
    import socket

    from rockdem.studies import on_dask

    monkeypatch.setattr(on_dask, "CONNECT_TIMEOUT", 1, raising=False)
    with socket.socket() as s:  # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    model = write_model(tmp_path, normal_phi(samples=2, compute="verdict"))
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine\n")
    address = f"tcp://127.0.0.1:{port}"
    r = invoke("study", model, "--out", out, "--scheduler", address)
    assert_refused(r, f"--scheduler {address}", "no dask scheduler answered", "tcp://host:8786")
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]
    r = invoke("study", model, "--out", tmp_path / "new", "--scheduler", address)
    assert_refused(r, f"--scheduler {address}")
    assert not (tmp_path / "new").exists()
    other = write_model(tmp_path, normal_phi(samples=3, compute="verdict"), "other.yaml")
    r = invoke("study", other, "--out", out, "--workers", 0, "--quiet")
    assert r.exit_code == 0, r.output


def test_a_scheduler_address_where_something_else_answers_is_one_clear_line(tmp_path):
    """Fuzzing (F13): a port where something other than a dask scheduler answers
    gave "cannot connect (MemoryError: Unable to allocate 3.07 EiB ...)"."""
    import socket
    import threading

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    port = server.getsockname()[1]

    def answer():
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            with conn:
                conn.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n" * 4)
                time.sleep(0.2)

    threading.Thread(target=answer, daemon=True).start()
    model = write_model(tmp_path, normal_phi(samples=2, compute="verdict"))
    address = f"tcp://127.0.0.1:{port}"
    try:
        r = invoke("study", model, "--out", tmp_path / "out", "--scheduler", address)
    finally:
        server.close()
    line = assert_refused(r, f"--scheduler {address}", "is not a dask scheduler", "tcp://host:8786")
    assert "MemoryError" not in line and "EiB" not in line
    assert not (tmp_path / "out").exists()


def test_a_correlation_of_one_input_asks_for_both(tmp_path):
    """`inputs: [a]` under a correlation said "inputs[1]: required key is
    missing; add `1:`", as if 1 were a key to write."""
    spec = {**normal_phi(samples=2), "correlations": [{"inputs": [PHI], "rho": 0.5}]}
    r = invoke("check", write_model(tmp_path, spec))
    assert_refused(r, "study.correlations[0].inputs:", "expected 2 items, got 1", "write both")
    assert "add `1:`" not in r.output


def test_an_empty_study_file_is_blamed_not_the_model(tmp_path):
    """A `--spec` file holding `study: null` (or `study:` alone) was reported
    as "the model file has no `study:` section", naming the model."""
    model = write_model(tmp_path, None)
    spec = tmp_path / "s.yaml"
    spec.write_text("study:\n")
    r = invoke("study", model, "--spec", spec, "--out", tmp_path / "o")
    assert_refused(r, "s.yaml", "study: the section is empty")
    assert "plane.yaml" not in r.output
    assert not (tmp_path / "o").exists()


def test_an_empty_spec_file_asks_for_a_study_not_a_model(tmp_path):
    """An empty --spec file said "write a model (see `rockdem example list`)",
    the model file's advice (found by hostile testing)."""
    model = write_model(tmp_path, None)
    spec = tmp_path / "spec.yaml"
    spec.write_text("")
    r = invoke("study", model, "--spec", spec, "--out", tmp_path / "out", "--workers", "0")
    said = assert_refused(r, "spec.yaml", "the file is empty", "write a `study:` section")
    assert "example list" not in said


def test_each_sample_keeps_what_its_analysis_warned_of(tmp_path):
    """A sample's warnings were lost (every sample could, say, carry water
    nowhere or reach the model's cut without a word in samples.csv or the
    summary): they are the row's ``warnings``, counted in the summary and
    printed once with their count, not once per sample."""
    doc = plane_document()
    doc["loads"] = {"water_table": [[-20, -100], [20, -100]], "water_unit_weight": 9.81}
    doc["study"] = normal_phi(samples=5, seed=2, compute="verdict")
    path = tmp_path / "dry.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    r = invoke("study", path, "--out", tmp_path / "out", "--workers", "0")
    assert r.exit_code == 0, r.output
    import pandas as pd

    table = pd.read_csv(tmp_path / "out" / "samples.csv")
    assert table["warnings"].str.startswith("loads.water_table lies at or below").all()
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["warned"]["samples"] == 5
    [top] = summary["warned"]["top"]
    assert top["samples"] == 5 and "(sample" not in top["warning"]
    assert "warned: 5 of 5 samples carry a warning" in r.stdout
    # stderr: the nominal model's warning once, not one per sample
    assert r.stderr.count("water_table lies at or below") == 1


def test_a_sample_without_warnings_has_none():
    table, s = rockdem.study(plane_document(), normal_phi(samples=3, compute="verdict"), workers=0)
    assert table["warnings"].isna().all() and s["warned"] == {"samples": 0, "top": []}
