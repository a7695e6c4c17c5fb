"""One self-contained HTML report of an analysis: inputs, verdict, tables, pictures.

The file embeds every picture (base64 PNG or SVG, and the progressive-failure
GIF) and its style sheet, and links nothing outside itself, so it opens
offline in any browser and can be mailed as one attachment.

>>> from rockdem.report import write_report  # doctest: +SKIP
>>> write_report(model, "out")  # doctest: +SKIP
PosixPath('out/report.html')
"""

from __future__ import annotations

import base64
import datetime as _dt
import platform
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from . import plots
from .analysis import analyse
from .errors import collecting_model_warnings
from .model import Model
from .report_html import CSS, esc, figure_uri, html_table, img, num
from .report_tables import (
    bolts_table,
    failed_table,
    inputs_section,
    state_counts,
    unstable_table,
    warnings_html,
)
from .results import Analysis, FactorOfSafety, bracket_decimals, format_factor
from .strength_reduction import factor_of_safety
from .trust import trust_statements
from .units import parse_units


def _not_equilibrium_note(a: Analysis) -> list[str]:
    """Where the analysis found no equilibrium, the stresses and states of its
    tables are those of the last iterate of the failed step, at that step's
    load factor (inclined-layers: load factor 0.2, stresses a fifth of those
    under the full load, under a heading that said only "F = 1")."""
    if a.stable or not a.steps:
        return []
    lf = a.steps[-1].load_factor
    at = "under the full load" if lf >= 1 else f"at load factor {lf:.3g}, not the full load"
    return [
        f'<p class="note">No equilibrium: the stresses and joint states below are those '
        f"of the last iterate of the failed step ({at}; F = {format_factor(a.stress_factor)}"
        "), not of an equilibrium: they show where the failure starts.</p>"
    ]


def _verdict(a: Analysis, fos: FactorOfSafety | None) -> str:
    cls = a.verdict
    F = f"F = {format_factor(a.strength_factor)}"
    text = (
        f"STABLE under the full loads ({F})"
        if a.stable
        else f"{a.verdict.upper()}: no equilibrium beyond load factor {a.load_factor:.3g} ({F})"
        + ("; failure neither proven nor confirmed" if a.verdict == "undecided" else "")
    )
    parts = [f'<div class="verdict {cls}" id="verdict">{esc(text)}</div>']
    if fos is not None:
        lo, hi = fos.bracket
        if fos.value is not None and fos.proof == "undecided":
            parts.append(
                f'<p class="fos" id="fos">Factor of safety: at least {lo:.4f} (undecided '
                f"above it: equilibrium was lost at {hi:.4f}, but no failure was proven or "
                "confirmed there)</p>"
            )
        elif fos.value is not None:
            d = bracket_decimals(lo, hi)
            parts.append(
                f'<p class="fos" id="fos">Factor of safety F = {fos.value:.4f} '
                f"(bracket {lo:.{d}f} - {num(hi, f'.{d}f')})</p>"
            )
        else:
            parts.append(
                f'<p class="fos" id="fos">Factor of safety: none ({esc(fos.mode)}), '
                f"bracket {num(lo, '.4g')} - {num(hi, '.4g')}</p>"
            )
        parts.append(f'<p class="note">{esc(fos.definition)}; {len(fos.trials)} trials.</p>')
    parts.append(f'<p class="note">Evidence of the last step: {esc(a.evidence)}.</p>')
    return "\n".join(parts)


def _steps_table(a: Analysis) -> str:
    rows = [
        [
            int(s.stage),
            num(s.load_factor, ".3g"),
            num(s.strength_factor, ".5g"),
            "yes" if s.converged else "no",
            int(s.n_failed_springs),
            esc(s.evidence),
        ]
        for s in a.steps
    ]
    return html_table(
        ["stage", "load factor", "F", "equilibrium", "failed springs", "evidence"],
        rows,
        cls="steps",
    )


def _failed_where(failed: Analysis, fos: FactorOfSafety) -> str:
    """Where the failed state of a search sits, in words that match its numbers."""
    F = failed.strength_factor
    hi = fos.bracket[1]
    if np.isfinite(hi) and F <= hi * (1 + 1e-9):
        return f"F = {format_factor(F)}, just above the factor of safety"
    if fos.value is None:
        return f"F = {format_factor(F)}, the factor of the failed trial"
    return (
        f"F = {format_factor(F)}, the factor of the failed trial (the factor of safety is "
        f"{fos.value:.4f}: equilibrium was lost at {hi:.4f} within this trial)"
    )


def _same_state(a: Analysis, b: Analysis) -> bool:
    """Two failed analyses that would draw the same pictures."""
    return (
        not a.stable
        and not b.stable
        and a.strength_factor == b.strength_factor
        and np.array_equal(a.unstable, b.unstable)
        and np.allclose(a.mechanism, b.mechanism)
    )


# ------------------------------------------------------------------ the report
def _analyses(model, analysis, fos, compute_fos: bool, fos_options):
    """The staged analysis and the factor of safety of a report (run where not given)."""
    if not isinstance(model, Model):
        raise TypeError(f"write_report needs a Model or a model file, not {type(model)!r}")
    analysis = analysis if analysis is not None else analyse(model)
    if fos is None and compute_fos:
        fos = factor_of_safety(analysis.system, **(fos_options or {}))
    return analysis, fos


def write_report(
    model,
    out_dir,
    *,
    analysis: Analysis | None = None,
    fos: FactorOfSafety | None = None,
    compute_fos: bool = True,
    fos_options: dict | None = None,
    filename: str = "report.html",
    title: str | None = None,
    units: str | None = None,
    unit: str = "m",
    stress_unit: str = "kPa",
    joints: Sequence[str | int] | None = None,
    image_format: str = "png",
    dpi: int = 110,
    animation: bool = True,
    block_ids: bool | None = None,
    max_rows: int = 200,
    study=None,
    notes: Sequence[str] = (),
) -> Path:
    """Write one self-contained HTML report of a model's analysis.

    Parameters
    ----------
    model : Model, or path of a model file
        A path is read with :func:`rockdem.config.load_model`.
    out_dir : path
        Directory to write into (created).
    analysis : Analysis, optional
        The staged analysis at F = 1 (default: run it).
    fos : FactorOfSafety, optional
        The strength-reduction result (default: run it if ``compute_fos``).
    compute_fos : bool
        Run the factor-of-safety search when ``fos`` is not given.
    fos_options : dict, optional
        Keyword arguments for :func:`rockdem.factor_of_safety` (width, ...).
    filename : str
        Name of the HTML file.
    title : str, optional
    units : str, optional
        Note of the units (for example ``"kN, m, kPa"``) shown with the inputs.
    unit, stress_unit : str
        Length and stress units on the axes.
    joints : sequence of str or int, optional
        Joints to plot stresses along (names, or indices of model joint
        lines); default: one plot of the slip surface / failed joints.
    image_format : {"png", "svg"}
        How figures are embedded (base64 data URIs).
    dpi : int
        Resolution of PNG figures.
    animation : bool
        Embed the progressive-failure GIF.
    block_ids : bool, optional
        Label blocks in the model picture (default: if there are <= 60).
    max_rows : int
        Longest table of failed joints / unstable blocks.
    study : StudyResult or path, optional
        A probabilistic or parametric study (:func:`rockdem.study`, or its
        ``--out`` folder): adds a section with its summary and pictures.
    notes : sequence of str
        Warnings already issued about this model (while loading it, or in the
        analyses given), shown under the verdict; the ModelWarnings issued
        while the report loads and analyses the model are added.

    Returns
    -------
    Path
        The HTML file written.
    """
    from . import __version__

    if image_format not in ("png", "svg"):
        raise ValueError("image_format must be 'png' or 'svg'")
    with collecting_model_warnings() as issued:
        if isinstance(model, (str, Path)):
            from .config import load_model

            model, cfg = load_model(model)
            units = units or getattr(cfg, "units", None) or None
        analysis, fos = _analyses(model, analysis, fos, compute_fos, fos_options)
    notes = [*notes, *issued]
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    u = parse_units(units)
    a = analysis
    system = a.system
    failed = fos.failed_analysis if fos is not None else None
    progressive = failed if failed is not None else a
    n_free = int((~system.blocks.fixed).sum())
    ids = block_ids if block_ids is not None else n_free <= 60

    def fig(f, caption, alt, ident):
        uri = figure_uri(f, image_format, dpi)
        return img(uri, caption, alt, ident)

    pics = []
    pics.append(
        fig(
            plots.plot_model(a, block_ids=ids, unit=unit).figure,
            "The model: blocks, joints coloured by joint set (rock bridges dashed), fixed "
            "ground hatched, loads (black) and supports (green).",
            "model",
            "fig-model",
        )
    )
    F1 = f"F = {format_factor(a.strength_factor)}"
    pics.append(
        fig(
            plots.plot_failure(a, unit=unit).figure,
            f"Failure state at {F1}: {state_counts(a)}. Each stretch of joint in its "
            "current state: red sliding, blue open, green dashed failed earlier and now "
            "closed (history, holding now), grey elastic; purple band: slip surface; orange: "
            "unstable blocks.",
            "failure state",
            "fig-failure",
        )
    )
    if a.stable:
        pics.append(
            fig(
                plots.plot_deformed(a, unit=unit).figure,
                f"Deformed shape at {F1} (magnification in the title), blocks coloured by "
                "displacement, arrows: magnified translation.",
                "deformed shape",
                "fig-deformed",
            )
        )
    else:  # no equilibrium, no deformed shape: the mechanism, titled as such
        pics.append(
            fig(
                plots.plot_deformed(a, use="mechanism", unit=unit).figure,
                f"Failure mechanism at {F1}: direction of motion of the blocks (arbitrary scale).",
                "failure mechanism",
                "fig-mechanism-run",
            )
        )
    if failed is not None and failed is not a and not _same_state(a, failed):
        where = _failed_where(failed, fos)
        pics.append(
            fig(
                plots.plot_failure(fos, unit=unit).figure,
                f"Failure state at {where}: {state_counts(failed)}.",
                "failure state of the factor-of-safety search",
                "fig-failure-fos",
            )
        )
        pics.append(
            fig(
                plots.plot_deformed(failed, use="mechanism", unit=unit).figure,
                f"Failure mechanism at {where}: how the blocks move.",
                "failure mechanism",
                "fig-mechanism",
            )
        )
    # stresses of an equilibrium: at F = 1 if stable, else the last one the search found
    shown = a if a.stable or fos is None or fos.stable_analysis is None else fos.stable_analysis
    for k, j in enumerate(joints if joints is not None else [None]):
        label = "the slip surface / failed joints" if j is None else f"joint {j}"
        chosen = None
        lost = fos.failed_analysis if fos is not None else None
        if j is None and not len(shown.slip_surface) and lost is not None:
            if len(lost.slip_surface):
                # the joints the slope fails on, not whatever has yielded at F = 1
                # (plane-failure-water drew the open tension crack: all zeros)
                chosen = lost.slip_surface
                F = format_factor(lost.strength_factor)
                label = f"the slip surface of the failure (found at F = {F}), stresses"
        f = plots.plot_joint_stress(shown, j, interfaces=chosen, unit=unit, stress_unit=stress_unit)
        at = f"F = {format_factor(shown.stress_factor)}"
        if shown is not a:
            at += " (the last equilibrium of the strength-reduction search)"
        elif not shown.stable:
            at += " (no equilibrium: the solver's last iterate)"
        pics.append(
            fig(
                f,
                ("Effective normal stress" if plots.stress.wet(shown) else "Normal stress")
                + " (compression positive), shear stress and shear strength "
                f"along {esc(label)} at {at}; the strength is drawn at the same factor.",
                f"stress along {label.removesuffix(', stresses')}",
                f"fig-stress-{k}",
            )
        )
    if fos is not None and fos.trials:
        pics.append(
            fig(
                plots.plot_fos(fos, unit=unit).figure,
                "Strength-reduction search: each trial factor F, whether equilibrium was "
                "found, and the largest block displacement.",
                "factor of safety search",
                "fig-fos",
            )
        )
    prog = [
        fig(
            plots.plot_progressive(progressive, unit=unit),
            "Failure history after each load step and strength-reduction trial: the "
            "joints that have failed by then (first failures by stage), not their state now.",
            "progressive failure frames",
            "fig-progressive",
        )
    ]
    if animation:
        gif = out / (Path(filename).stem + "-progressive.gif")
        plots.animate_progressive(progressive, gif, unit=unit)
        uri = "data:image/gif;base64," + base64.b64encode(gif.read_bytes()).decode("ascii")
        gif.unlink()
        prog.append(
            img(
                uri,
                "Progressive failure, animated.",
                "progressive failure animation",
                "fig-animation",
            )
        )
    now = _dt.datetime.now().astimezone().isoformat(timespec="seconds")
    title = title or f"rockdem report: {model.name}"
    sections = [
        f"<h1>{esc(title)}</h1>",
        f'<p class="meta">rockdem {esc(__version__)} · {esc(now)}</p>',
        '<nav><a href="#results">Verdict</a><a href="#tables">Failed joints</a>'
        '<a href="#trust">Trust</a>'
        + ('<a href="#limit-equilibrium">Limit equilibrium</a>' if fos is not None else "")
        + '<a href="#pictures">Pictures</a>'
        '<a href="#progressive">Progressive failure</a>'
        '<a href="#inputs">Inputs</a></nav>',
        '<h2 id="results">Verdict</h2>',
        _verdict(a, fos),
        warnings_html(a, failed, notes=notes),
        '<h3 id="trust">How far to trust this</h3>',
        "<ul>" + "".join(f"<li>{esc(t)}</li>" for t in trust_statements(a, fos)) + "</ul>",
        '<h2 id="tables">Failed joints and unstable blocks</h2>',
        f"<h3>Joints at {F1}: state now and failure history</h3>",
        f'<p class="states">{esc(state_counts(a))}.</p>',
        *_not_equilibrium_note(a),
        failed_table(a, stress_unit, max_rows, u),
        f"<h3>Unstable blocks at {F1}</h3>",
        unstable_table(a, max_rows, u),
    ]
    if a.bolts is not None:
        sections += [f"<h3>Bolts at {F1}</h3>", bolts_table(a, u)]
    if failed is not None and failed is not a and not _same_state(a, failed):
        sections += [
            f"<h3>Joints at F = {format_factor(failed.strength_factor)} (failure): state now "
            "and failure history</h3>",
            f'<p class="states">{esc(state_counts(failed))}.</p>',
            failed_table(failed, stress_unit, max_rows, u),
            f"<h3>Unstable blocks at F = {format_factor(failed.strength_factor)} (failure)</h3>",
            unstable_table(failed, max_rows, u),
        ]
    if fos is not None:
        from .limit_equilibrium.report import html_section as le_section

        sections += le_section(fos, u)
    if study is not None:
        from .studies.report import html_section

        sections += html_section(study, fig)
    sections += [
        '<h2 id="pictures">Pictures</h2>',
        *pics,
        '<h2 id="progressive">Progressive failure</h2>',
        *prog,
        "<h3>Steps</h3>",
        _steps_table(progressive),
        '<h2 id="inputs">Model inputs</h2>',
        inputs_section(model, system, units),
        "<hr>",
        f'<p class="meta">Written by rockdem {esc(__version__)} on {esc(now)} '
        f"(Python {esc(platform.python_version())}). Stage numbers: load steps, then "
        "strength-reduction trials.</p>",
    ]
    doc = (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f'<meta name="generator" content="rockdem {esc(__version__)}">'
        f"<title>{esc(title)}</title><style>{CSS}</style></head>\n<body>\n"
        + "\n".join(sections)
        + "\n</body></html>\n"
    )
    path = out / filename
    path.write_text(doc, encoding="utf-8")
    return path
