"""What a study's table says: probability of failure with its confidence interval,
statistics of the factor of safety, reliability indices, sensitivity, the worst
samples."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy import stats


def pf_interval(failed: int, n: int, confidence: float) -> tuple[float, float]:
    """Clopper-Pearson (exact binomial) interval of a probability estimated as
    ``failed / n``: it covers the true value with at least ``confidence``.  For
    Latin hypercube samples the binomial interval is conservative (wider than
    the estimator's real spread)."""
    if n == 0:
        return (0.0, 1.0)
    alpha = 1.0 - confidence
    lo = 0.0 if failed == 0 else float(stats.beta.ppf(alpha / 2, failed, n - failed + 1))
    hi = 1.0 if failed == n else float(stats.beta.ppf(1 - alpha / 2, failed + 1, n - failed))
    return (lo, hi)


def _finite(x) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def summarise(
    table,
    names: list[str],
    *,
    kind: str,
    compute: str,
    confidence: float = 0.95,
    worst: int = 5,
    planned: int | None = None,
) -> dict[str, Any]:
    """The summary of a study table (a DataFrame as :func:`rockdem.study` returns).

    Keys: ``samples`` (planned), ``done``, ``errors``, ``ok``, ``failed``,
    ``pf`` and ``pf_interval`` (FS < 1 among the samples without error; None
    for a sweep), ``fs`` (mean, sd, percentiles of the finite factors),
    ``reliability_index`` (normal: (mean - 1) / sd; lognormal; from PF:
    -Phi^-1(PF)), ``sensitivity`` (Spearman rank correlation of each input with
    the factor of safety, or with failure for ``compute: verdict``), ``worst``
    (sample numbers, lowest factor first).
    """
    ok = table[table["error"].isna()]
    failed = int(ok["failed"].fillna(False).astype(bool).sum())
    n_ok = len(ok)
    out: dict[str, Any] = {
        "kind": kind,
        "compute": compute,
        "samples": int(planned if planned is not None else len(table)),
        "done": len(table),
        "errors": int(len(table) - n_ok),
        "ok": n_ok,
        "failed": failed,
        "confidence": confidence,
    }
    if kind == "probabilistic" and n_ok:
        pf = failed / n_ok
        out["pf"] = pf
        out["pf_interval"] = list(pf_interval(failed, n_ok, confidence))
    else:
        out["pf"] = None
        out["pf_interval"] = None
    fs = ok["fs"].to_numpy(dtype=float)
    fs = fs[np.isfinite(fs)]
    if compute == "fos" and len(fs):
        q = np.percentile(fs, [5, 50, 95])
        mean = float(fs.mean())
        sd = float(fs.std(ddof=1)) if len(fs) > 1 else float("nan")
        out["fs"] = {
            "n": len(fs),
            "mean": mean,
            "sd": _finite(sd),
            "min": float(fs.min()),
            "p05": float(q[0]),
            "median": float(q[1]),
            "p95": float(q[2]),
            "max": float(fs.max()),
        }
    else:
        out["fs"] = None
    beta: dict[str, float | None] = {"normal": None, "lognormal": None, "from_pf": None}
    if out["fs"] is not None and out["fs"]["sd"] and kind == "probabilistic":
        m, s = out["fs"]["mean"], out["fs"]["sd"]
        beta["normal"] = (m - 1.0) / s
        if m > 0:
            v = math.log1p((s / m) ** 2)
            beta["lognormal"] = math.log(m / math.sqrt(1.0 + (s / m) ** 2)) / math.sqrt(v)
    if out["pf"] is not None:
        beta["from_pf"] = _finite(-stats.norm.ppf(out["pf"]))
    out["reliability_index"] = beta if kind == "probabilistic" else None
    out["sensitivity"] = sensitivity(ok, names, compute)
    out["worst"] = worst_samples(ok, compute, worst)
    return out


def sensitivity(ok, names: list[str], compute: str) -> list[dict[str, Any]]:
    """Spearman rank correlation of each input with the factor of safety (or with
    failure, for ``compute: verdict``), strongest first."""
    target = ok["fs"].to_numpy(dtype=float) if compute == "fos" else None
    if target is None:
        target = ok["failed"].fillna(False).astype(float).to_numpy()
    keep = np.isfinite(target)
    rows = []
    for name in names:
        x = ok[name].to_numpy(dtype=float)[keep]
        y = target[keep]
        if len(x) < 3 or np.ptp(x) == 0 or np.ptp(y) == 0:
            rho, p = float("nan"), float("nan")
        else:
            res = stats.spearmanr(x, y)
            rho, p = float(res.statistic), float(res.pvalue)
        rows.append({"input": name, "spearman": _finite(rho), "p_value": _finite(p)})
    rows.sort(key=lambda r: -abs(r["spearman"]) if r["spearman"] is not None else 1.0)
    return rows


def worst_samples(ok, compute: str, k: int) -> list[int]:
    """The ``k`` worst samples: lowest factor of safety first (``compute: verdict``:
    the failed ones with the largest unstable area first)."""
    if k <= 0 or not len(ok):
        return []
    if compute == "fos":
        fs = ok["fs"].astype(float)
        # no value: a strength-independent mechanism is worse than any factor
        key = fs.where(fs.notna(), np.where(ok["mode"] == "strength-independent", -1.0, np.inf))
        order = key.sort_values(kind="stable").index
    else:
        failed = ok[ok["failed"].fillna(False).astype(bool)]
        order = (
            failed["unstable_area"].astype(float).sort_values(ascending=False, kind="stable").index
        )
    return [int(ok.loc[i, "sample"]) for i in order[:k]]
