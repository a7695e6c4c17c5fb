"""Benchmark of the geometry generator: time to cut slopes of 1k to 100k blocks.

Run: ``python benchmarks/bench_geometry.py [--runs 3] [--max 100000]``.
Reports the median wall time over the runs for each size and the growth
exponent between successive sizes (time ~ n^p).  Targets: 10,000 blocks in
< 2 s, 100,000 blocks in < 20 s.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import rockdem as rd
from rockdem.geometry import JointSet, Profile, generate_slope, section_polygon

J = rd.Joint(normal_stiffness=1e6, friction_angle=35)
BRIDGE = rd.Joint(normal_stiffness=1e7, friction_angle=45, cohesion=1000, tensile_strength=500)
GROUND = rd.Joint(normal_stiffness=1e6, friction_angle=40)


def case(n_target: int, kind: str):
    """A 50 m benched slope with two sets scaled to give about ``n_target`` blocks."""
    profile = Profile.simple(50, 60, bench_width=5, bench_height=10, crest_length=60,
                             toe_length=30)
    depth = 30.0
    s = math.sqrt(section_polygon(profile, depth).area / n_target)
    if kind == "persistent":
        sets = [JointSet("bedding", 30, s, J), JointSet("cross", 120, s, J, origin=(0.3, 0.1))]
    else:  # non-persistent bedding (rock bridges) + a random toppling set
        sets = [
            JointSet("bedding", 30, s, J, trace_length=4 * s, gap=s, stagger=0.5),
            JointSet("topple", 100, s, J, spacing_sd=0.2 * s, dip_sd=2.0, seed=1),
        ]
    return profile, sets, depth


def run(n_target: int, kind: str, runs: int) -> tuple[float, int]:
    profile, sets, depth = case(n_target, kind)
    times, n = [], 0
    for _ in range(runs):
        t0 = time.perf_counter()
        # (no size limit: the 100,000 target is estimated just above the
        # default guard of rockdem.geometry.size.MAX_BLOCKS)
        g = generate_slope(
            profile, sets, depth=depth, bridge_joint=BRIDGE, ground_joint=GROUND, max_blocks=None
        )
        times.append(time.perf_counter() - t0)
        n = g.blocks.n_blocks
    return statistics.median(times), n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--max", type=int, default=100_000)
    args = ap.parse_args()
    sizes = [s for s in (1_000, 3_000, 10_000, 30_000, 100_000) if s <= args.max]
    print(f"{'case':<15}{'target':>9}{'blocks':>9}{'median s':>10}{'growth p':>10}")
    for kind in ("persistent", "bridges"):
        prev = None
        for size in sizes:
            t, n = run(size, kind, args.runs)
            growth = ""
            if prev is not None:
                growth = f"{math.log(t / prev[0]) / math.log(n / prev[1]):.2f}"
            print(f"{kind:<15}{size:>9,}{n:>9,}{t:>10.3f}{growth:>10}", flush=True)
            prev = (t, n)


if __name__ == "__main__":
    main()
