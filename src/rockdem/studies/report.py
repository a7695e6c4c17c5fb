"""The study's section of the HTML report (:func:`rockdem.report.write_report` with
``study=``): the summary, the pictures, the sensitivity and the worst samples."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from ..report_html import esc, html_table, num
from .plots import figures
from .stats import fs_line


def html_section(study, fig: Callable[..., str]) -> list[str]:
    """HTML pieces of the section; ``fig(figure, caption, alt, ident)`` embeds a figure."""
    from .run import StudyResult, read_study

    if not isinstance(study, StudyResult):
        study = read_study(Path(study))
    table, s = study.table, study.summary
    names = list(s["inputs"])
    title = "Probabilistic study" if s["kind"] == "probabilistic" else "Parametric study"
    out = [f'<h2 id="study">{title}</h2>']
    if s["kind"] == "probabilistic":
        how = f"{s['samples']} samples ({esc(s['sampler'])}, seed {s['seed']})"
    else:
        how = f"a grid of {s['samples']} runs"
    out.append(
        f"<p>{how} of {len(names)} input{'s' if len(names) != 1 else ''}: "
        + ", ".join(f"<code>{esc(n)}</code>" for n in names)
        + f"; {s['done']} done, {s['errors']} with an error (left out of the statistics).</p>"
    )
    rows = []
    if s.get("pf") is not None:
        lo, hi = s["pf_interval"]
        level = f"{100 * s['confidence']:g}%"
        rows.append(
            (
                "probability of failure, P(FS < 1)",
                f"{num(s['pf'], '.4g')} ({s['failed']} of {s['ok']}; {level} interval "
                f"{num(lo, '.3g')} to {num(hi, '.3g')}, Clopper-Pearson)",
            )
        )
    if s.get("fs"):
        f = s["fs"]
        rows.append(
            (
                "factor of safety",
                fs_line(f),
            )
        )
    beta = s.get("reliability_index") or {}
    if any(v is not None for v in beta.values()):
        rows.append(
            (
                "reliability index",
                f"{num(beta.get('normal'), '.3g')} (normal FS), "
                f"{num(beta.get('lognormal'), '.3g')} (lognormal FS), "
                f"{num(beta.get('from_pf'), '.3g')} (from PF)",
            )
        )
    if rows:
        out.append(html_table(["", "value"], [(k, esc(v)) for k, v in rows], left=1))
    left = s.get("left_out") or {}
    if left.get("note"):
        out.append(f'<p class="note"><strong>Samples left out.</strong> {esc(left["note"])}</p>')
    warned = s.get("warned") or {}
    if warned.get("samples"):
        out.append(
            f'<p class="note"><strong>Warnings.</strong> {warned["samples"]} of {s["ok"]} '
            "samples carry a warning (the warnings column of samples.csv); the commonest:</p>"
        )
        out.append(
            html_table(
                ["warning", "samples"],
                [(w["warning"], w["samples"]) for w in warned["top"]],
                left=1,
            )
        )
    for stem, (figure, caption) in figures(table, s, names).items():
        out.append(fig(figure, esc(caption), stem, f"fig-study-{stem}"))
    sens = [r for r in s.get("sensitivity", []) if r["spearman"] is not None]
    if sens and s["kind"] == "probabilistic":
        out.append("<h3>Sensitivity (Spearman rank correlation)</h3>")
        out.append(
            html_table(
                ["input", "rho", "p-value"],
                [(r["input"], num(r["spearman"], ".3f"), num(r["p_value"], ".2g")) for r in sens],
                left=1,
            )
        )
    worst = s.get("worst") or []
    if worst:
        by = table.set_index("sample")
        out.append("<h3>Worst samples</h3>")
        rows = [
            (
                i,
                *(num(by.loc[i, n]) for n in names),
                num(by.loc[i, "fs"]),
                esc(by.loc[i, "mode"]),
            )
            for i in worst
        ]
        out.append(html_table(["sample", *names, "FS", "mode"], rows, left=0))
        if s.get("worst_files"):
            out.append(
                '<p class="note">Their model files are in the study folder (<code>worst/</code>): '
                "run them with <code>rockdem fos</code>.</p>"
            )
    return out
