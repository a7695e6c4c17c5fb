"""What a study's table says: probability of failure with its confidence interval,
statistics of the factor of safety, reliability indices, sensitivity, the worst
samples."""

from __future__ import annotations

import math
import re
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


def level_text(confidence: float) -> str:
    """A confidence level in percent, with the digits that keep it below 100
    (0.999999999 printed "100% interval"; hostile round 5)."""
    text = f"{100 * confidence:g}"
    return f"{100 * confidence:.12g}" if text == "100" and confidence < 1 else text


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
    distributions: dict[str, str] | None = None,
) -> dict[str, Any]:
    """The summary of a study table (a DataFrame as :func:`rockdem.study` returns).

    Keys: ``samples`` (planned), ``done``, ``errors``, ``ok``, ``failed``,
    ``pf`` and ``pf_interval`` (FS < 1 among the samples without error; None
    for a sweep), ``fs`` (mean, sd, percentiles of the finite factors),
    ``reliability_index`` (normal: (mean - 1) / sd; lognormal; from PF:
    -Phi^-1(PF)), ``sensitivity`` (Spearman rank correlation of each input with
    the factor of safety, or with failure for ``compute: verdict``), ``worst``
    (sample numbers, lowest factor first), ``left_out`` (the samples with an
    error, why, and which way leaving them out biases ``pf``: see
    :func:`left_out`; ``distributions``, input -> distribution name, makes its
    advice specific), ``warned`` (the samples whose analysis warned, and the
    commonest warnings: :func:`warned`).
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
    ranked = ranked_factors(ok) if compute == "fos" else np.zeros(0)
    ranked = ranked[~np.isnan(ranked)]
    fs = ranked[np.isfinite(ranked)]
    if compute == "fos" and len(fs):
        # order statistics over every sample with a verdict: one that fails
        # at any strength ranks below every factor, one that never failed
        # above (found by fuzzing: 12 of 40 samples, the worst, were left
        # out of the percentiles without a word); the mean and sd can only
        # be those of the samples with a factor
        q = np.percentile(ranked, [5, 50, 95], method="inverted_cdf")
        mean = float(fs.mean())
        sd = float(fs.std(ddof=1)) if len(fs) > 1 else float("nan")
        out["fs"] = {
            "n": len(fs),
            "without_factor": {
                "strength-independent": int(np.sum(ranked == -np.inf)),
                "no-failure": int(np.sum(ranked == np.inf)),
            },
            "mean": mean,
            "sd": _finite(sd),
            "min": _finite(ranked.min()),
            "p05": _finite(q[0]),
            "median": _finite(q[1]),
            "p95": _finite(q[2]),
            "max": _finite(ranked.max()),
        }
    else:
        out["fs"] = None
    beta: dict[str, float | None] = {"normal": None, "lognormal": None, "from_pf": None}
    censored = out["fs"] is not None and any(out["fs"]["without_factor"].values())
    if out["fs"] is not None and out["fs"]["sd"] and kind == "probabilistic" and not censored:
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
    out["left_out"] = left_out(table, names, out, distributions)
    out["warned"] = warned(ok)
    return out


#: the most common warnings a summary lists
WARNINGS_LISTED = 5


def warned(ok) -> dict[str, Any]:
    """How many samples (without error) carried a warning, and the most common
    warnings with their counts (``samples``, ``top``: [{"warning", "samples"}])."""
    if "warnings" not in ok:
        return {"samples": 0, "top": []}
    texts = ok["warnings"].dropna()
    texts = texts[texts.astype(str).str.len() > 0]
    counts: dict[str, int] = {}
    for joined in texts:
        for text in str(joined).split(" | "):
            counts[text] = counts.get(text, 0) + 1
    top = sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))[:WARNINGS_LISTED]
    return {"samples": len(texts), "top": [{"warning": w, "samples": n} for w, n in top]}


#: A side of the valid range holding at least this share of the samples left out is
#: "one tail": P(failure) is then said to be likely under- or overestimated.
ONE_TAIL = 2 / 3
#: A rank correlation with a p-value above this does not tell the weak side.
WEAK_SIDE_P = 0.05


def left_out(
    table, names: list[str], summary: dict[str, Any], distributions: dict[str, str] | None = None
) -> dict[str, Any]:
    """The samples left out of the statistics (those with an ``error``), and what
    that does to the probability of failure.

    ``pf`` is estimated among the samples that could be analysed.  A sample is
    left out when its model is invalid, most often because an input's
    distribution reaches past the input's valid range (a normal friction angle
    below 0).  Such samples are not a random share: they lie in a tail of the
    distribution, and when that is the weak tail (low friction) most of them
    would be failures, so ``pf`` is biased low; in the strong tail, high.  What
    a careful engineer expects, and what is given here, is not a silently
    "corrected" number (a friction angle of -20 degrees has no factor of
    safety) but the plain facts: how many were left out and why, on which side
    of the valid range, which side is the weak one (the sign of the input's
    rank correlation with FS, or with failure, among the samples analysed, when
    its p-value is below :data:`WEAK_SIDE_P`), which way ``pf`` is then likely
    biased (when at least :data:`ONE_TAIL` of them lie on one side), ``pf`` if
    every sample left out held and if every one failed (the bounds of the
    whole sample's PF), and a distribution that stays in range (the study
    offers truncated-normal, and lognormal for a value that must be > 0).

    Keys: ``n`` (left out), ``of`` (samples done), ``reasons`` (most common
    first: ``n``, ``example`` (one error text), and for an input out of its
    valid range ``input``, ``below``, ``above``, ``range`` (the valid range as
    the model file's check states it), ``weak_side`` (``"below"``,
    ``"above"`` or None) and ``fix``), ``bias`` (``"underestimated"``,
    ``"overestimated"``, ``"unknown"``; None for a sweep or when nothing was
    left out or analysed), ``pf_if_stable``, ``pf_if_failed`` (None for a
    sweep) and ``note`` (all of it in words; None when nothing was left out).
    """
    errors = table[table["error"].notna()]
    n, done = len(errors), len(table)
    out: dict[str, Any] = {"n": n, "of": done, "reasons": [], "bias": None}
    out.update(pf_if_stable=None, pf_if_failed=None, note=None)
    if not n:
        return out
    ok = table[table["error"].isna()]
    rho = {r["input"]: r for r in summary.get("sensitivity") or []}
    patterns = {name: _path_pattern(name) for name in names}
    groups: dict[str, dict[str, Any]] = {}
    for _, row in errors.iterrows():
        text = re.sub(r"^.*?\(sample \d+\): ", "", str(row["error"]))
        name, valid = None, None
        for candidate, pattern in patterns.items():
            m = re.search(pattern + r": \S+ is out of range(?:; (.*))?$", text)
            if m:
                name, valid = candidate, m.group(1)
                break
        key = f"range:{name}" if name else re.sub(r"-?\d[\d.e+-]*", "#", text)
        group = groups.setdefault(key, {"n": 0, "example": text})
        group["n"] += 1
        if name is None:
            continue
        valid = valid.removeprefix("give a value ") if valid else group.get("range")
        group.update(input=name, range=valid)
        side = _side(float(row[name]), valid, ok[name].to_numpy(dtype=float))
        group.setdefault("below", 0)
        group.setdefault("above", 0)
        if side:
            group[side] += 1
    reasons = sorted(groups.values(), key=lambda g: -g["n"])
    weak = strong = 0
    for g in reasons:
        if "input" not in g:
            continue
        g["weak_side"] = _weak_side(rho.get(g["input"]), summary["compute"])
        if g["weak_side"]:
            other = "above" if g["weak_side"] == "below" else "below"
            weak += g[g["weak_side"]]
            strong += g[other]
        g["fix"] = _stay_in_range(g, summary["kind"], (distributions or {}).get(g["input"]))
    out["reasons"] = reasons
    parts = []
    for g in reasons:
        if "input" in g:
            where = f" ({g['range']})" if g.get("range") else ""
            sides = ", ".join(f"{g[s]} {s}" for s in ("below", "above") if g[s])
            parts.append(
                f"{g['input']} out of its valid range{where} in {g['n']}"
                + (f" ({sides})" if sides else "")
            )
        else:
            parts.append(f"{g['n']} stopped with: {_short(g['example'])}")
    note = [
        f"{n} of {done} samples were left out of the statistics (they could not be "
        "analysed): " + "; ".join(parts)
    ]
    if summary["kind"] == "probabilistic" and summary["ok"]:
        failed = summary["failed"]
        out["pf_if_stable"] = failed / done
        out["pf_if_failed"] = (failed + n) / done
        out["bias"] = "unknown"
        if weak >= ONE_TAIL * n:
            out["bias"], count, what = "underestimated", weak, "weak"
        elif strong >= ONE_TAIL * n:
            out["bias"], count, what = "overestimated", strong, "strong"
        pf = f"P(FS < 1) = {summary['pf']:.3g}"
        if out["bias"] == "unknown":
            text = f"Which way this biases {pf} is not known from the samples"
        else:
            sided = [g for g in reasons if g.get("weak_side")]
            share = f"all {n}" if count == n else f"{count} of the {n}"
            if len(sided) == 1:
                g = sided[0]
                side = g["weak_side"] if what == "weak" else _other(g["weak_side"])
                text = f"{share} left out had {g['input']} {side} its valid range"
            else:
                text = f"{share} left out lay beyond an input's valid range"
            text += f", the {what} side: {pf} is likely {out['bias']}"
        note.append(
            f"{text} (counting every sample left out as stable: "
            f"{out['pf_if_stable']:.3g}, as failed: {out['pf_if_failed']:.3g})"
        )
    fixes = [g["fix"] for g in reasons if g.get("fix")]
    fix = "; ".join(fixes) if fixes else "see the `error` column of samples.csv"
    note.append(fix)
    out["note"] = ". ".join(s[:1].upper() + s[1:] for s in note) + "."
    return out


def _path_pattern(name: str) -> str:
    """A regular expression of the key paths an input stands for (``[*]``: any index)."""
    return r"(?<![\w.\]])" + re.escape(name).replace(r"\[\*\]", r"\[\d+\]")


def _short(text: str, n: int = 160) -> str:
    return text if len(text) <= n else text[: n - 3] + "..."


def _side(value: float, valid: str | None, ok_values: np.ndarray) -> str | None:
    """``"below"`` or ``"above"`` the valid range: from the range the check states
    (``give a value >= 0 and < 90``), else from the values that were valid."""
    if math.isnan(value):
        return None
    lo = hi = None
    for op, bound in re.findall(r"([<>]=?) (-?[\d.]+(?:e[+-]?\d+)?)", valid or ""):
        if op.startswith(">"):
            lo = float(bound)
        else:
            hi = float(bound)
    if lo is None and hi is None and len(ok_values):
        lo, hi = float(np.min(ok_values)), float(np.max(ok_values))
    if lo is not None and value <= lo:
        return "below"
    if hi is not None and value >= hi:
        return "above"
    return None


def _weak_side(sens: dict | None, compute: str) -> str | None:
    """The side of an input where failure is more likely, from its rank correlation
    with FS (``compute: fos``) or with failure (``verdict``) among the samples
    analysed; None when that correlation is not significant."""
    if not sens or sens.get("spearman") is None or sens.get("p_value") is None:
        return None
    if sens["p_value"] > WEAK_SIDE_P or sens["spearman"] == 0:
        return None
    rises = sens["spearman"] > 0  # FS (or failure) rises with the input
    return "below" if rises == (compute == "fos") else "above"


def _other(side: str) -> str:
    return "above" if side == "below" else "below"


def _stay_in_range(group: dict, kind: str, distribution: str | None) -> str:
    """What to give an input whose samples left its valid range (``distribution``:
    its distribution's name, if known)."""
    name = group["input"]
    if kind == "sweep":
        return f"give {name} values inside its valid range"
    head = f"give {name} a distribution that stays in its valid range"
    if distribution in ("uniform", "triangular", "truncated-normal"):
        return f"{head}: min and max inside it"
    if distribution is None:
        return f"{head}, such as truncated-normal with min and max inside it"
    how = "truncated-normal with min and max inside it (or a smaller sd)"
    positive = re.search(r">=? 0(?![\d.e])", group.get("range") or "")
    if distribution == "normal" and group["below"] and not group["above"] and positive:
        how += ", or lognormal (never below 0)"
    return f"{head}: {how}"


def fs_line(f: dict) -> str:
    """The ``fs`` summary in one line.  A percentile that falls among the
    samples without a factor says which (fails at any strength: below every
    factor; never failed: above), and the mean and sd say whose they are."""
    without = f.get("without_factor") or {}
    low, high = without.get("strength-independent", 0), without.get("no-failure", 0)
    total = f["n"] + low + high

    def at(share: float, v) -> str:
        if v is not None:
            return f"{v:.4g}"
        rank = max(math.ceil(share * total) - 1, 0)  # (numpy's inverted_cdf)
        return "fails at any strength" if rank < low else "no failure"

    sd = "-" if f["sd"] is None else f"{f['sd']:.4g}"
    line = (
        f"mean {f['mean']:.4g}, sd {sd}, 5% {at(0.05, f['p05'])}, median "
        f"{at(0.5, f['median'])}, 95% {at(0.95, f['p95'])} (min {at(0.0, f['min'])}, "
        f"max {at(1.0, f['max'])})"
    )
    if low or high:
        parts = [f"{low} fail at any strength"] * bool(low) + [f"{high} never failed"] * bool(high)
        side = " and ".join(["below"] * bool(low) + ["above"] * bool(high))
        line += (
            f"; {' and '.join(parts)}: no factor, so the mean and sd are of the other "
            f"{f['n']} samples, and the percentiles rank them {side} every factor"
        )
    return line


def ranked_factors(ok) -> np.ndarray:
    """The factors of safety of the samples, for ranking: -inf where the
    mechanism forms at any strength (strength-independent), +inf where no
    failure was found, NaN where there is no verdict."""
    fs = ok["fs"].to_numpy(dtype=float).copy()
    mode = ok["mode"].to_numpy() if "mode" in ok else np.full(len(fs), None)
    missing = np.isnan(fs)
    fs[missing & (mode == "strength-independent")] = -np.inf
    fs[missing & (mode == "no-failure")] = np.inf
    return fs


def sensitivity(ok, names: list[str], compute: str) -> list[dict[str, Any]]:
    """Spearman rank correlation of each input with the factor of safety (or with
    failure, for ``compute: verdict``), strongest first; samples without a
    factor rank below or above every factor (:func:`ranked_factors`)."""
    target = ranked_factors(ok) if compute == "fos" else None
    if target is None:
        target = ok["failed"].fillna(False).astype(float).to_numpy()
    keep = ~np.isnan(target)
    rows = []
    for name in names:
        x = ok[name].to_numpy(dtype=float)[keep]
        y = target[keep]
        if len(x) < 3 or np.ptp(x) == 0 or len(np.unique(y)) < 2:
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
        # no value: a strength-independent mechanism is worse than any factor
        key = ranked_factors(ok)
        key[np.isnan(key)] = np.inf
        order = ok.index[np.argsort(key, kind="stable")]
    else:
        failed = ok[ok["failed"].fillna(False).astype(bool)]
        order = (
            failed["unstable_area"].astype(float).sort_values(ascending=False, kind="stable").index
        )
    return [int(ok.loc[i, "sample"]) for i in order[:k]]
