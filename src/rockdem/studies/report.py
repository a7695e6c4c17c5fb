"""The study's section of the HTML report (:func:`rockdem.report.write_report` with
``study=``): the summary, the pictures, the sensitivity and the worst samples."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from ..report import _esc, _num, _table
from .plots import figures


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
        how = f"{s['samples']} samples ({_esc(s['sampler'])}, seed {s['seed']})"
    else:
        how = f"a grid of {s['samples']} runs"
    out.append(
        f"<p>{how} of {len(names)} input{'s' if len(names) != 1 else ''}: "
        + ", ".join(f"<code>{_esc(n)}</code>" for n in names)
        + f"; {s['done']} done, {s['errors']} with an error (left out of the statistics).</p>"
    )
    rows = []
    if s.get("pf") is not None:
        lo, hi = s["pf_interval"]
        level = f"{100 * s['confidence']:g}%"
        rows.append(
            (
                "probability of failure, P(FS < 1)",
                f"{_num(s['pf'], '.4g')} ({s['failed']} of {s['ok']}; {level} interval "
                f"{_num(lo, '.3g')} to {_num(hi, '.3g')}, Clopper-Pearson)",
            )
        )
    if s.get("fs"):
        f = s["fs"]
        rows.append(
            (
                "factor of safety",
                f"mean {_num(f['mean'])}, sd {_num(f['sd'])}, 5% {_num(f['p05'])}, "
                f"median {_num(f['median'])}, 95% {_num(f['p95'])} ({f['n']} values)",
            )
        )
    beta = s.get("reliability_index") or {}
    if any(v is not None for v in beta.values()):
        rows.append(
            (
                "reliability index",
                f"{_num(beta.get('normal'), '.3g')} (normal FS), "
                f"{_num(beta.get('lognormal'), '.3g')} (lognormal FS), "
                f"{_num(beta.get('from_pf'), '.3g')} (from PF)",
            )
        )
    if rows:
        out.append(_table(["", "value"], [(k, _esc(v)) for k, v in rows], left=1))
    for stem, (figure, caption) in figures(table, s, names).items():
        out.append(fig(figure, _esc(caption), stem, f"fig-study-{stem}"))
    sens = [r for r in s.get("sensitivity", []) if r["spearman"] is not None]
    if sens and s["kind"] == "probabilistic":
        out.append("<h3>Sensitivity (Spearman rank correlation)</h3>")
        out.append(
            _table(
                ["input", "rho", "p-value"],
                [(r["input"], _num(r["spearman"], ".3f"), _num(r["p_value"], ".2g")) for r in sens],
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
                *(_num(by.loc[i, n]) for n in names),
                _num(by.loc[i, "fs"]),
                _esc(by.loc[i, "mode"]),
            )
            for i in worst
        ]
        out.append(_table(["sample", *names, "FS", "mode"], rows, left=0))
        if s.get("worst_files"):
            out.append(
                '<p class="note">Their model files are in the study folder (<code>worst/</code>): '
                "run them with <code>rockdem fos</code>.</p>"
            )
    return out
