"""Study benchmarks (issue 13): samples per second on a Dask local cluster.

Run:  python benchmarks/bench_study.py [--quick] [--repeat 3] [--wedge-samples 24]
      [--slope-samples 6]

Cases:
* the seed paper's two-block wedge (bundled example ``wedge-verification``),
  friction of the upper and lower planes normal (sd 2 degrees);
* a generated 461-block slope (bedding dipping 30 degrees, 1.0 m apart,
  vertical cross joints 1.5 m apart, 20 m high 60 degree face: the README's
  Python example), bedding friction normal (40, sd 2) and kh uniform (0, 0.05).

Each study runs on a local cluster of 1 and 2 worker processes (one thread
each; the cluster is started and a warm-up study run before the clock starts;
a plain loop of the same samples in
this process (the same per-sample function, no Dask).  Prints a Markdown
table of medians over ``--repeat`` runs: samples per second, the 2-worker /
1-worker speed-up, and the overhead per task (1-worker time minus plain loop
time, per sample), the Dask overhead per task (1-worker wall time minus the
compute time measured inside the workers, per sample: scheduling, transfer,
storing rows, the summary) and the round trip of an empty Dask task.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

SLOPE = """
name: bedded slope 461 blocks
units: kN, m, kPa
materials: {rock: {unit_weight: 26}}
joints:
  bedding: {normal_stiffness: 1.0e+6, friction_angle: 40}
  cross: {normal_stiffness: 1.0e+6, friction_angle: 40, residual_cohesion: null}
slope:
  material: rock
  profile: {height: 20, face_angle: 60}
  depth: 5
  joint_sets:
    bedding: {dip: 30, spacing: 1.0}
    cross: {dip: 90, spacing: 1.5}
"""


def cases(wedge_n: int, slope_n: int) -> list[tuple[str, object, dict]]:
    import yaml

    from rockdem.config import read_document
    from rockdem.examples import example_path

    wedge, _ = read_document(example_path("wedge-verification"))
    wedge_spec = {
        "inputs": {
            "joints.upper.friction_angle": {"distribution": "normal", "mean": 35, "sd": 2},
            "joints.lower.friction_angle": {"distribution": "normal", "mean": 30, "sd": 2},
        },
        "samples": wedge_n,
        "sampler": "latin-hypercube",
        "seed": 1,
    }
    slope = yaml.safe_load(SLOPE)
    slope_spec = {
        "inputs": {
            "joints.bedding.friction_angle": {"distribution": "normal", "mean": 40, "sd": 2},
            "loads.seismic_h": {"distribution": "uniform", "min": 0, "max": 0.05},
        },
        "samples": slope_n,
        "sampler": "latin-hypercube",
        "seed": 1,
    }
    return [("two-block wedge", wedge, wedge_spec), ("bedded slope", slope, slope_spec)]


def _noop(x):
    return x


def measure(doc, spec, repeat: int) -> dict:
    from dask.distributed import Client, LocalCluster

    import rockdem
    from rockdem.studies.plan import prepare
    from rockdem.studies.run import _args, evaluate

    plan = prepare(doc, spec)
    n = len(plan.values)
    out: dict = {"samples": n, "blocks": int(plan.nominal.blocks.n_blocks)}
    # the plain loop: the same function, in this process
    evaluate(*_args(plan, 0, plan.base))  # warm-up (imports, caches)
    loop = []
    for _ in range(repeat):
        t = time.perf_counter()
        rows = [evaluate(*_args(plan, i, plan.base)) for i in range(n)]
        loop.append(time.perf_counter() - t)
        assert not any(r.get("error") for r in rows), rows
    out["loop"] = statistics.median(loop)
    for workers in (1, 2):
        times, rtts, inside = [], [], []
        with (
            LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
            ) as cluster,
            Client(cluster) as client,
        ):
            # warm up every worker: import rockdem and run one sample there
            client.run(lambda: __import__("rockdem.studies.run") and None)
            rockdem.study(plan, client=client)
            for _ in range(repeat):
                t = time.perf_counter()
                table, s = rockdem.study(plan, client=client)
                times.append(time.perf_counter() - t)
                inside.append(float(table["seconds"].sum()))  # compute time in the workers
                assert s["errors"] == 0 and s["done"] == n
                t = time.perf_counter()
                client.gather(client.map(_noop, range(200), pure=False))
                rtts.append((time.perf_counter() - t) / 200)
        out[f"dask{workers}"] = statistics.median(times)
        out[f"noop{workers}"] = statistics.median(rtts)
        out[f"inside{workers}"] = statistics.median(inside)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--wedge-samples", type=int, default=24)
    ap.add_argument("--slope-samples", type=int, default=6)
    ap.add_argument("--quick", action="store_true", help="1 repeat, 8 and 2 samples")
    a = ap.parse_args()
    if a.quick:
        a.repeat, a.wedge_samples, a.slope_samples = 1, 8, 2
    print(f"cpus: {os.cpu_count()}, repeats: {a.repeat} (medians)\n")
    print(
        "| case | blocks | samples | plain loop samples/s | 1 worker samples/s "
        "| 2 workers samples/s | 2 / 1 workers | 1 worker - loop, per task "
        "| Dask overhead per task | empty task round trip |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, doc, spec in cases(a.wedge_samples, a.slope_samples):
        r = measure(doc, spec, a.repeat)
        n = r["samples"]
        over = (r["dask1"] - r["loop"]) / n
        dask = (r["dask1"] - r["inside1"]) / n  # wall time not spent computing samples
        print(
            f"| {name} | {r['blocks']} | {n} | {n / r['loop']:.2f} | {n / r['dask1']:.2f} "
            f"| {n / r['dask2']:.2f} | {r['dask1'] / r['dask2']:.2f} | {1000 * over:.0f} ms "
            f"| {1000 * dask:.0f} ms | {1000 * r['noop1']:.1f} ms |",
            flush=True,
        )


if __name__ == "__main__":
    main()
