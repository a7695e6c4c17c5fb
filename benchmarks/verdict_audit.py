"""Seeded random audit of the factor of safety's verdict (audit 34).

Generated slopes of the kinds an engineer meets (planar sliding on
daylighting bedding, toppling on steep joints dipping into the slope, two
perpendicular sets, a set near the face), with and without cohesion, water
(r_u or a water table) and kh.  For each: the factor of safety, its
invariance (load steps 1 / 5 / 20, coordinates + (1e5, 1e4), kN -> t, block
order reversed), the closed form where one applies, the evidence of the
verdict and the plausibility of the mechanism.

    python benchmarks/verdict_audit.py --seeds 0-19 --out audit.jsonl
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

import rockdem as rd
from rockdem.modes import failure_modes

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[1] / "tests"))
from _audit_slopes import G_T, build, closed_form, draw, transformed


# ----------------------------------------------------------------- checks
def planar_bound(p: dict) -> float | None:
    """Upper bound from planar sliding on set 1 where it daylights (c = 0;
    water only lowers it; kh through the resultant's dip)."""
    dip = p["dips"][0]
    if p["cohesion"] or not (0 < dip < p["face"]) or p["kind"] == "toppling":
        return None
    if p["dips"][1] != 90.0 and p["kind"] != "perpendicular":
        return None
    eff = np.radians(dip) + np.arctan(p["kh"])
    return float(np.tan(np.radians(p["phi"])) / np.tan(eff))


class Timeout(Exception):
    pass


def _alarm(signum, frame):
    raise Timeout()


LIMIT = 90  # seconds per factor of safety


def run(model: rd.Model) -> dict:
    import signal

    t0 = time.perf_counter()
    system = rd.build_system(model)
    before = system.factorizer.count
    signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(LIMIT)
    try:
        fos = rd.factor_of_safety(system)
    except Timeout:
        return dict(
            value=None,
            bracket=None,
            mode="timeout",
            proof=None,
            time=time.perf_counter() - t0,
            lu=system.factorizer.count - before,
            newton=None,
            n_trials=None,
            cert=None,
            confirmed=None,
            _fos=None,
        )
    finally:
        signal.alarm(0)
    dt = time.perf_counter() - t0
    out = dict(
        value=fos.value,
        bracket=list(fos.bracket),
        mode=fos.mode,
        proof=fos.proof,
        time=dt,
        lu=system.factorizer.count - before,
        newton=int(sum(t.evidence.iterations for t in fos.trials)),
        n_trials=len(fos.trials),
        cert=fos.certified_upper_bound,
        confirmed=fos.confirmed_upper_bound,
    )
    out["_fos"] = fos
    return out


def evidence_problems(fos) -> list[str]:
    bad = []
    lo, hi = fos.bracket
    if fos.mode == "strength":
        if fos.proof is None:
            bad.append("failure without a proof kind")
        if fos.failed_analysis is None:
            bad.append("no failed analysis")
    if fos.proof == "undecided":
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            bad.append(f"undecided without a finite bracket {fos.bracket}")
        ev = fos.failed_analysis.evidence
        if not ev.reason:
            bad.append("undecided without a reason")
    for t in fos.trials:
        if not t.stable and t.evidence.proof is None:
            bad.append(f"failed trial {t.factor:.4g} without proof kind ({t.evidence.reason})")
    cert = fos.certified_upper_bound
    if cert is not None and cert < lo * (1 - 1e-6):
        bad.append(f"LP bound {cert:.5g} below a stable factor {lo:.5g}")
    conf = fos.confirmed_upper_bound
    if conf is not None and conf < lo * (1 - 1e-6):
        bad.append(f"confirmed bound {conf:.5g} below a stable factor {lo:.5g}")
    if fos.value is not None and not (lo - 1e-9 <= fos.value <= hi + 1e-9):
        bad.append(f"value {fos.value} outside bracket {fos.bracket}")
    if fos.proof == "lp-certificate" and cert is None:
        bad.append("lp-certificate without a certified bound")
    return bad


def mechanism_problems(fos, p) -> tuple[list[str], dict]:
    bad: list[str] = []
    info: dict = {}
    a = fos.failed_analysis
    if a is None or a.stable:
        return bad, info
    system = a.system
    faces = system.interfaces
    un = np.asarray(a.unstable, bool)
    fixed = system.blocks.fixed
    info["n_unstable"] = int(un.sum())
    if not un.any():
        bad.append("failure with no unstable block")
        return bad, info
    if (un & fixed).any():
        bad.append("a fixed block is unstable")
    slip = np.asarray(a.slip_surface)
    info["n_slip"] = len(slip)
    if not len(slip):
        bad.append("unstable blocks but no slip surface")
    else:
        side = un[faces.block_a[slip]] | un[faces.block_b[slip]]
        if not side.all():
            bad.append(f"{int((~side).sum())} slip interfaces touch no unstable block")
    modes = failure_modes(a)
    counts = {m: n for m, n in modes.counts().items() if n and m != "stable"}
    info["modes"] = counts
    moving_ids = set(system.blocks.ids[un].tolist())
    for m in counts:
        if not set(modes.blocks(m).tolist()) <= moving_ids:
            bad.append(f"mode {m!r} names blocks that are not unstable")
    # the moving mass reaches the free surface (a block on the profile)
    bnd = np.zeros(system.blocks.n_blocks, bool)
    from rockdem.loads import rock_surface

    surf = rock_surface(system.blocks)
    if surf:
        import shapely

        line = shapely.LineString(surf)
        polys = system.blocks.polygons()
        tol = system.blocks.tolerance * 10
        bnd = np.array([not fixed[i] and polys[i].distance(line) <= tol for i in range(len(polys))])
        if not (un & bnd).any():
            bad.append("no unstable block reaches the ground surface")
    # sliding on set 1 (planar kinds): unstable blocks above the deepest slip plane on set 1
    if p["kind"] in ("planar", "face-parallel") and "slides" in counts:
        names = np.asarray([j.name for j in system.model.joints])[faces.joint[slip]]
        on1 = slip[names == "set1"]
        if len(on1):
            d = np.radians(p["dips"][0])
            nrm = np.array([np.sin(d), np.cos(d)])  # upward normal of set 1
            mid = 0.5 * (faces.start[on1] + faces.end[on1])
            deepest = (mid @ nrm).min()
            off = system.blocks.centroid[un] @ nrm
            info["below_deepest"] = int((off < deepest - 1e-6).sum())
            if (off < deepest - 1e-6).any():
                bad.append(
                    f"{int((off < deepest - 1e-6).sum())} unstable blocks below the deepest "
                    "set-1 slip plane"
                )
    if (
        p["kind"] == "toppling"
        and fos.mode == "strength"
        and not ({"topples", "slides and topples"} & set(counts))
    ):
        info["note"] = "toppling kind without a toppling block"
    return bad, info


def audit(seed: int, variants=True) -> dict:
    p = draw(seed)
    model = build(p)
    n = int((~model.blocks.fixed).sum())
    row = dict(p)
    row["blocks"] = n
    base = run(model)
    fos = base.pop("_fos")
    if fos is None:
        row["base"] = base
        return row
    row["base"] = base
    row["evidence"] = evidence_problems(fos)
    mech_bad, info = mechanism_problems(fos, p)
    row["mechanism"] = mech_bad
    row["mech_info"] = info
    cf = closed_form(p)
    row["closed_form"] = cf
    row["cf_error"] = None if cf is None or base["value"] is None else base["value"] / cf - 1
    pb = planar_bound(p)
    row["planar_bound"] = pb
    if pb is not None and base["value"] is not None and base["value"] > pb * 1.01:
        row["evidence"].append(f"FS {base['value']:.4f} above planar-sliding bound {pb:.4f}")
    if (
        base["value"] is not None
        and base["cert"] is not None
        and p["water"] is None
        and pb is not None
    ):
        pass
    var = {}
    if variants:
        for name, kw in (
            ("steps1", dict(steps=1)),
            ("steps20", dict(steps=20)),
            ("shift", dict(shift=(1e5, 1e4))),
            ("tonnes", dict(force=1 / G_T)),
            ("reversed", dict(reverse=True)),
        ):
            r = run(transformed(model, **kw))
            f = r.pop("_fos")
            if f is None:
                var[name] = r
                continue
            r["evidence"] = evidence_problems(f)
            r["unstable"] = (
                sorted(f.failed_analysis.unstable_blocks.tolist()) if f.failed_analysis else []
            )
            var[name] = r
        if p["cohesion"]:
            r = run(build(p, cohesion=0.0))
            r.pop("_fos")
            var["c0"] = r
    row["variants"] = var
    row["base_unstable"] = (
        sorted(fos.failed_analysis.unstable_blocks.tolist()) if fos.failed_analysis else []
    )
    vals = [base["value"]] + [
        v["value"] for k, v in var.items() if k != "c0" and v["mode"] != "timeout"
    ]
    if all(v is not None for v in vals) and vals:
        row["spread"] = max(vals) / min(vals) - 1
    else:
        row["spread"] = None if all(v is None for v in vals) else float("inf")
    return row


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", default="0-7")
    ap.add_argument("--out", default="verdict_audit.jsonl")
    ap.add_argument("--no-variants", action="store_true")
    a = ap.parse_args(argv)
    lo, _, hi = a.seeds.partition("-")
    seeds = range(int(lo), int(hi or lo) + 1)
    with open(a.out, "a") as fh:
        for s in seeds:
            t = time.perf_counter()
            try:
                row = audit(s, variants=not a.no_variants)
            except Exception as exc:
                row = dict(seed=s, error=f"{type(exc).__name__}: {exc}", params=draw(s))
            row["wall"] = time.perf_counter() - t
            fh.write(json.dumps(row, default=float) + "\n")
            fh.flush()
            b = row.get("base", {})
            print(
                s,
                row.get("kind", row.get("params", {}).get("kind")),
                row.get("blocks"),
                b.get("value"),
                b.get("proof"),
                row.get("spread"),
                row.get("cf_error"),
                round(b.get("time", 0), 2),
                row.get("evidence"),
                row.get("mechanism"),
                row.get("error"),
                flush=True,
            )


if __name__ == "__main__":
    sys.exit(main())
