"""Engine benchmarks: medians over repeated runs, and growth with size.

Run:  python benchmarks/bench_engine.py [--quick] [--sizes 1000 10000] [--repeat 3]

Cases (issue 2):
* the two-block wedge factor of safety (in-process);
* the 463-block bedded slope of the verification tests (FS = tan40/tan30);
* generated brick-pattern slopes (bedding dipping 20 deg, staggered vertical
  cross joints, FS = tan35/tan20 = 1.9238) of increasing size: building the
  system, the staged gravity analysis and the factor of safety, with the peak
  resident memory of a fresh process per size.

* with ``--friction 15``, the same slopes failing under gravity (FS =
  tan15/tan20 = 0.7362): the staged analysis is a failed search, and the
  factor of safety is searched below it.

* with ``--paths``, search-path cases (benchmarks/models/): models whose
  factor-of-safety search once crawled (a near-flat benched slope).

Prints a Markdown table.  Times are wall-clock medians; the growth exponent
p fits t ~ n^p between consecutive sizes.
"""

from __future__ import annotations

import argparse
import itertools
import json
import statistics
import subprocess
import sys
import time

import numpy as np


def _median_time(fn, repeat):
    times, out = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def small_cases(repeat: int) -> list[dict]:
    import rockdem as rd
    from rockdem import verification as V

    rows = []
    wedge = V.two_block_wedge(35, 30)
    t, fos = _median_time(lambda: rd.factor_of_safety(wedge), max(repeat, 11))
    exact = V.wedge_fos(200, 75, 37, 27, 35, 30, 35)
    rows.append(dict(case="two-block wedge FS", n=2, seconds=t, fos=fos.value, exact=exact))
    slope = V.bedding_slope(bedding_spacing=1.0, cross_spacing=1.5)
    t, fos = _median_time(lambda: rd.factor_of_safety(slope), repeat)
    exact = np.tan(np.radians(40)) / np.tan(np.radians(30))
    n = int((~slope.blocks.fixed).sum())
    rows.append(dict(case="bedded slope FS", n=n, seconds=t, fos=fos.value, exact=exact))
    return rows


def path_cases() -> None:
    """Searches that once crawled: the result, factorisations and time of one run."""
    from pathlib import Path

    import rockdem as rd
    from rockdem.config import load_model

    print("| search-path case | blocks | FS search s | result | factorisations |")
    print("|---|---|---|---|---|")
    for path in sorted((Path(__file__).parent / "models").glob("*.yaml")):
        model, _ = load_model(path)
        system = rd.build_system(model)
        t, fos = _median_time(lambda s=system: rd.factor_of_safety(s), 1)
        lo = fos.bracket[0]
        result = f"{fos.value:.4f}" if fos.value is not None else f"{fos.mode}, stable at {lo:.4g}"
        n = int((~model.blocks.fixed).sum())
        print(f"| {path.stem} | {n:,} | {t:.1f} | {result} | {system.factorizer.count} |")


def one_size(n: int, repeat: int, fos: bool, friction: float = 35.0) -> dict:
    """Run in a fresh process so that the peak memory belongs to this size."""
    import resource

    import rockdem as rd
    from rockdem import verification as V

    model = V.brick_slope(n, friction_angle=friction)
    t_build, system = _median_time(lambda: rd.build_system(model), repeat)
    t_an, an = _median_time(lambda: rd.analyse(system), repeat)
    row = dict(
        case="brick slope",
        n=int((~model.blocks.fixed).sum()),
        dof=system.assembly.n_dof,
        springs=system.springs.n_springs,
        build=t_build,
        analyse=t_an,
        stable=an.stable,
    )
    if fos:
        from rockdem.linalg import Factorizer, backend

        before = system.factorizer.count
        t_fos, result = _median_time(lambda: rd.factor_of_safety(system), repeat)
        n_fact = (system.factorizer.count - before) / repeat
        # the analysis's peak, before the second factorisation handle below
        # (the ratio's denominator) adds its own (94,533 blocks: 4.18 GB with it)
        row["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        # one numeric factorisation + solve of the same (elastic) matrix, pattern analysed
        fz = Factorizer()
        fz.factorize(system.K0)
        t_one, _ = _median_time(lambda: fz.factorize(system.K0).solve(system.f_ext), 5)
        row.update(
            fos_seconds=t_fos,
            fos=result.value,
            bracket=list(result.bracket),
            factorisations=n_fact,
            newton_iterations=sum(t.evidence.iterations for t in result.trials),
            one_factorisation=t_one,
            ratio=t_fos / t_one,
            proof=result.proof,
            backend=backend(system.assembly.n_dof),
        )
    row.setdefault("peak_mb", resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
    return row


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=int, nargs="*", default=[1000, 10000, 100000])
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--fos-up-to", type=int, default=10000, help="largest size with a FS run")
    p.add_argument("--quick", action="store_true", help="one run each, sizes 1000 and 3000")
    p.add_argument("--one", type=int, help=argparse.SUPPRESS)
    p.add_argument("--paths", action="store_true", help="only the search-path cases (models/)")
    p.add_argument(
        "--friction",
        type=float,
        default=35.0,
        help="friction angle of the brick slopes (15: they fail under gravity, FS 0.736)",
    )
    args = p.parse_args()
    if args.paths:
        path_cases()
        return
    if args.one:
        fos = args.one <= args.fos_up_to
        print(json.dumps(one_size(args.one, args.repeat, fos, args.friction)))
        return
    if args.quick:
        args.sizes, args.repeat = [1000, 3000], 1
    print("| case | blocks | median s | FS | exact | error |")
    print("|---|---|---|---|---|---|")
    for r in small_cases(args.repeat):
        err = 100 * (r["fos"] / r["exact"] - 1)
        print(
            f"| {r['case']} | {r['n']} | {r['seconds']:.3f} | {r['fos']:.4f} | "
            f"{r['exact']:.4f} | {err:+.2f}% |",
            flush=True,
        )
    print()
    print(
        "| brick slope blocks | dof | build s | analyse s | FS s | FS | proof | "
        "LU count | Newton iterations | one LU s | FS / one LU | backend | peak MB |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    rows = []
    for n in args.sizes:
        cmd = [
            sys.executable,
            __file__,
            "--one",
            str(n),
            "--repeat",
            str(args.repeat),
            "--fos-up-to",
            str(args.fos_up_to),
            "--friction",
            str(args.friction),
        ]
        out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
        r = json.loads(out.strip().splitlines()[-1])
        rows.append(r)
        fos_s = f"{r['fos_seconds']:.2f}" if "fos_seconds" in r else "-"
        fos_v = f"{r['fos']:.4f}" if r.get("fos") else "-"
        extra = (
            f"{r['proof']} | {r['factorisations']:.0f} | {r['newton_iterations']} | "
            f"{r['one_factorisation']:.4f} | "
            f"{r['ratio']:.0f} | {r['backend']}"
            if "ratio" in r
            else "- | - | - | - | - | -"
        )
        print(
            f"| {r['n']:,} | {r['dof']:,} | {r['build']:.2f} | {r['analyse']:.2f} | {fos_s} | "
            f"{fos_v} | {extra} | {r['peak_mb']:.0f} |",
            flush=True,
        )
    for key in ("build", "analyse", "fos_seconds"):
        pts = [(r["n"], r[key]) for r in rows if key in r]
        for (n0, t0), (n1, t1) in itertools.pairwise(pts):
            print(
                f"growth of {key} from {n0:,} to {n1:,} blocks: "
                f"t ~ n^{np.log(t1 / t0) / np.log(n1 / n0):.2f}"
            )


if __name__ == "__main__":
    main()
