"""Pictures of a study: the distribution of the factor of safety (histogram and
CDF), the sensitivity of each input, and a sweep drawn as FS against the input.

Matplotlib figures without pyplot (as :mod:`rockdem.plots`); Okabe-Ito colours.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from .stats import level_text

BLUE, VERMILLION, ORANGE, GREEN = "#0072B2", "#D55E00", "#E69F00", "#009E73"


def _ok(table):
    return table[table["error"].isna()]


def fs_distribution(table, summary: dict) -> Figure:
    """Histogram and empirical CDF of the factor of safety, FS = 1 marked, the
    probability of failure and its interval in the title."""
    fs = _ok(table)["fs"].to_numpy(dtype=float)
    fs = np.sort(fs[np.isfinite(fs)])
    fig = Figure(figsize=(10.0, 4.0), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    if len(fs):
        n_bins = min(50, max(5, int(np.sqrt(len(fs)))))
        w = (fs[-1] - fs[0]) / n_bins or 0.01
        # FS = 1 on a bin edge: the red bins are exactly the failed samples
        bins = 1.0 + w * np.arange(np.floor((fs[0] - 1.0) / w), np.floor((fs[-1] - 1.0) / w) + 2)
        _, edges, patches = ax1.hist(fs, bins=bins, color=BLUE, edgecolor="white")
        for left, patch in zip(edges[:-1], patches, strict=True):
            if left < 1.0:
                patch.set_facecolor(VERMILLION)
        ax2.step(fs, np.arange(1, len(fs) + 1) / len(fs), where="post", color=BLUE)
    for ax in (ax1, ax2):
        ax.axvline(1.0, color="black", lw=1, ls="--")
        ax.set_xlabel("factor of safety")
        ax.grid(alpha=0.3)
    ax1.set_ylabel("samples")
    ax2.set_ylabel("P(FS <= x)")
    ax2.set_ylim(0, 1)
    pf, ci = summary.get("pf"), summary.get("pf_interval")
    title = f"{len(fs)} samples"
    if pf is not None and ci is not None:
        level = level_text(summary.get("confidence", 0.95))
        title += f"; P(FS < 1) = {pf:.3g} ({level}% interval {ci[0]:.3g} to {ci[1]:.3g})"
    fig.suptitle(title)
    return fig


def sensitivity(summary: dict) -> Figure:
    """Spearman rank correlation of each input with the factor of safety (or failure)."""
    rows = [r for r in summary["sensitivity"] if r["spearman"] is not None][::-1]
    fig = Figure(figsize=(8.0, 0.5 * max(len(rows), 2) + 1.2), layout="constrained")
    ax = fig.subplots()
    names = [r["input"] for r in rows]
    rho = [r["spearman"] for r in rows]
    ax.barh(names, rho, color=[BLUE if v >= 0 else VERMILLION for v in rho])
    ax.axvline(0.0, color="black", lw=0.8)
    ax.set_xlim(-1, 1)
    target = "factor of safety" if summary.get("compute") == "fos" else "failure (FS < 1)"
    ax.set_xlabel(f"Spearman rank correlation with {target}")
    ax.grid(axis="x", alpha=0.3)
    return fig


def sweep(table, names: list[str]) -> Figure:
    """FS against the first swept input, one line per value of the second."""
    ok = _ok(table)
    fig = Figure(figsize=(7.5, 4.5), layout="constrained")
    ax = fig.subplots()
    x = names[0]
    groups = [(None, ok)] if len(names) == 1 else list(ok.groupby(names[1], sort=True))
    colours = [BLUE, ORANGE, GREEN, VERMILLION, "#CC79A7", "#56B4E9", "#000000"]
    for k, (value, rows) in enumerate(groups):
        rows = rows.sort_values(x)
        label = None if value is None else f"{names[1]} = {value:g}"
        ax.plot(rows[x], rows["fs"].astype(float), "o-", color=colours[k % 7], label=label)
    ax.axhline(1.0, color="black", lw=1, ls="--")
    ax.set_xlabel(x)
    ax.set_ylabel("factor of safety")
    ax.grid(alpha=0.3)
    if len(names) > 1:
        ax.legend(fontsize="small")
    return fig


def figures(table, summary: dict, names: list[str]) -> dict[str, tuple[Figure, str]]:
    """The study's figures by file stem, each with a caption."""
    out: dict[str, tuple[Figure, str]] = {}
    if summary["kind"] == "sweep":
        if summary["compute"] == "fos":
            out["sweep"] = (sweep(table, names), "Factor of safety against the swept input.")
        return out
    if summary["compute"] == "fos" and summary.get("fs"):
        out["fs-distribution"] = (
            fs_distribution(table, summary),
            "Distribution of the factor of safety: histogram (FS < 1 in red) and "
            "cumulative distribution; dashed: FS = 1.",
        )
    if any(r["spearman"] is not None for r in summary["sensitivity"]):
        out["sensitivity"] = (
            sensitivity(summary),
            "Sensitivity: Spearman rank correlation of each input with the result.",
        )
    return out


def write_pictures(folder: Path, table, summary: dict, names: list[str]) -> list[str]:
    """Save the figures as PNG files in ``folder``; their names."""
    written = []
    for stem, (fig, _) in figures(table, summary, names).items():
        path = Path(folder) / f"{stem}.png"
        fig.savefig(path, dpi=110)
        written.append(path.name)
    return written
