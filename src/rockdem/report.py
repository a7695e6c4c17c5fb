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
import html
import io
import platform
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from . import plots
from .analysis import analyse, factor_of_safety
from .model import Model
from .modes import boundary_warnings, failure_modes
from .results import Analysis, FactorOfSafety, format_factor
from .trust import trust_statements
from .units import UNKNOWN, Units, parse_units

_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,Helvetica,Arial,sans-serif;
 margin:0 auto;max-width:1100px;padding:1em 2em;color:#222;line-height:1.4}
h1{margin-bottom:.2em}h2{border-bottom:2px solid #0072B2;padding-bottom:.15em;margin-top:1.6em}
.meta{color:#555;font-size:.9em}
.verdict{display:inline-block;padding:.6em 1em;border-radius:6px;font-size:1.15em;margin:.4em 0}
.stable{background:#d7f0e6;border:2px solid #009E73}
.unstable{background:#f9e0cc;border:2px solid #D55E00}
.fos{font-size:1.3em;font-weight:600}
table{border-collapse:collapse;margin:.5em 0 1em;font-size:.88em}
th,td{border:1px solid #ccc;padding:.2em .55em;text-align:right}
th{background:#eef3f8}td.l,th.l{text-align:left}
figure{margin:1em 0}figure img{max-width:100%;height:auto;border:1px solid #ddd}
figcaption{color:#444;font-size:.9em}
.note{color:#555;font-size:.88em}
.warning{background:#fff4cc;border:2px solid #E69F00;border-radius:6px;padding:.5em 1em;
 margin:.5em 0}
nav a{margin-right:1em}
"""


# ------------------------------------------------------------------ helpers
def _esc(x) -> str:
    return html.escape(str(x), quote=True)


def _num(x, fmt: str = ".4g") -> str:
    if x is None:
        return "-"
    try:
        v = float(x)
    except (TypeError, ValueError):
        return _esc(x)
    if np.isinf(v):
        return "∞" if v > 0 else "-∞"
    if np.isnan(v):
        return "-"
    return format(v, fmt)


def _table(header: Sequence[str], rows: Sequence[Sequence], left: int = 0, cls: str = "") -> str:
    """An HTML table; the first ``left`` columns are left-aligned text."""
    head = "".join(
        f'<th class="l">{_esc(h)}</th>' if i < left else f"<th>{_esc(h)}</th>"
        for i, h in enumerate(header)
    )
    body = []
    for row in rows:
        cells = "".join(
            f'<td class="l">{_esc(v)}</td>' if i < left else f"<td>{v}</td>"
            for i, v in enumerate(row)
        )
        body.append(f"<tr>{cells}</tr>")
    return (
        f'<table class="{cls}"><thead><tr>{head}</tr></thead><tbody>{"".join(body)}</tbody></table>'
    )


def _figure_uri(fig, fmt: str, dpi: int) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format=fmt, dpi=dpi)
    mime = "image/svg+xml" if fmt == "svg" else f"image/{fmt}"
    return f"data:{mime};base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def _img(uri: str, caption: str, alt: str, ident: str) -> str:
    return (
        f'<figure id="{_esc(ident)}"><img src="{uri}" alt="{_esc(alt)}">'
        f"<figcaption>{caption}</figcaption></figure>"
    )


def _state_counts(a: Analysis) -> str:
    """Current state and failure history of the interfaces, kept apart."""
    now = np.bincount(a.interfaces.current, minlength=4)
    s = a.interfaces.state
    return (
        f"now {int(now[2])} sliding, {int(now[3])} open, {int(now[1])} failed earlier and "
        f"now closed, {int(now[0])} elastic interfaces (history: {int((s > 0).sum())} have "
        f"failed at some time, {int((s == 1).sum())} in shear, {int((s == 2).sum())} in "
        "tension)"
    )


#: current state of a failed interface, in words (codes of rockdem.results.CURRENT_NAMES)
_NOW = ("closed", "closed", "sliding", "open")


def _failed_table(a: Analysis, stress_unit: str, limit: int, u: Units = UNKNOWN) -> str:
    """Every interface that has failed at some time (the history), with its state now."""
    ir = a.interfaces
    faces = a.system.interfaces
    idx = np.flatnonzero(ir.state > 0)
    if not idx.size:
        return '<p class="note">No interface has failed.</p>'
    slip = set(np.asarray(a.slip_surface).tolist())
    rows = []
    for i in idx[:limit]:
        rows.append(
            [
                str(ir.kind[i]),
                str(ir.state_name[i]),
                _NOW[int(ir.current[i])],
                int(i),
                f"{int(ir.block_a[i])} / {int(ir.block_b[i])}",
                f"({_num(faces.start[i][0], '.3g')}, {_num(faces.start[i][1], '.3g')}) - "
                f"({_num(faces.end[i][0], '.3g')}, {_num(faces.end[i][1], '.3g')})",
                _num(ir.length[i], ".3g"),
                _num(100 * ir.failed_fraction[i], ".0f"),
                _num(ir.normal_stress[i], ".3g"),
                _num(ir.shear_stress[i], ".3g"),
                int(ir.first_failure[i]),
                "yes" if int(i) in slip else "",
            ]
        )
    header = [
        "joint",
        "failed in",
        "now",
        "interface",
        "blocks",
        "from - to",
        "length" + u.suffix("length"),
        "failed %",
        f"σ mean ({stress_unit})",
        f"τ mean ({stress_unit})",
        "first failed (stage)",
        "slip surface",
    ]
    more = f'<p class="note">... and {idx.size - limit} more.</p>' if idx.size > limit else ""
    table = _table(header, rows, left=3, cls="failed-joints") + more
    if idx.size <= 15:
        return table
    return (
        f"<details><summary>{idx.size} interfaces that have failed at some time "
        f"(click to show)</summary>{table}</details>"
    )


def _unstable_table(a: Analysis, limit: int, u: Units = UNKNOWN) -> str:
    """The moving blocks with their failure mode (rockdem.modes) and mechanism motion."""
    blocks = a.system.blocks
    idx = np.flatnonzero(a.unstable)
    if not idx.size:
        return '<p class="note">No block moves (no failure mechanism).</p>'
    rows = []
    mech = plots.oriented_mechanism(a)
    modes = failure_modes(a)
    for i in idx[:limit]:
        ux, uy, rot = mech[i]
        px, py = modes.pivot[i]
        rows.append(
            [
                int(blocks.ids[i]),
                str(modes.name[i]),
                f"({_num(px, '.4g')}, {_num(py, '.4g')})" if np.isfinite(px) else "",
                _num(blocks.area[i], ".4g"),
                _num(blocks.weight[i], ".4g"),
                f"({_num(blocks.centroid[i][0], '.4g')}, {_num(blocks.centroid[i][1], '.4g')})",
                _num(ux, ".3f"),
                _num(uy, ".3f"),
                _num(rot, ".3g"),
            ]
        )
    header = [
        "block",
        "failure mode",
        "pivot",
        "area" + u.suffix("area"),
        "weight" + u.suffix("force"),
        "centroid",
        "mech. ux",
        "mech. uy",
        "mech. rot",
    ]
    more = f'<p class="note">... and {idx.size - limit} more.</p>' if idx.size > limit else ""
    counts = ", ".join(f"{n} {m}" for m, n in modes.counts().items() if n and m != "stable")
    lead = f'<p class="modes">Failure modes: {_esc(counts)}.</p>'
    return lead + _table(header, rows, left=2, cls="unstable-blocks") + more


def _bolts_table(a: Analysis, u: Units = UNKNOWN) -> str:
    """Every joint a bolt crosses: force per bolt, capacity there, utilisation."""
    r = a.bolts
    if r is None:
        return ""
    use = r.utilisation
    rows = [
        [
            str(r.name[k]),
            _num(r.depth[k], ".3g"),
            f"({_num(r.point[k, 0], '.4g')}, {_num(r.point[k, 1], '.4g')})",
            _num(r.axial_force[k], ".4g"),
            _num(r.shear_force[k], ".4g"),
            _num(r.capacity[k], ".4g"),
            f"{100 * use[k]:.0f}%",
            "yes" if r.yielded[k] else "",
        ]
        for k in np.argsort(-use, kind="stable")
    ]
    header = [
        "bolt",
        "depth" + u.suffix("length"),
        "at joint",
        "axial force" + u.suffix("force"),
        "shear force" + u.suffix("force"),
        "capacity" + u.suffix("force"),
        "utilisation",
        "yielded",
    ]
    note = (
        '<p class="note">Force per bolt where it crosses each joint (tension positive), '
        "most used first; capacity is the steel's or the grout bond's beyond the joint.</p>"
    )
    return note + _table(header, rows, left=3, cls="bolts")


def _warnings(*analyses: Analysis | None) -> str:
    """A warning box per side of the model the mechanism reaches (rockdem.modes)."""
    shown: dict[str, str] = {}  # message -> the factor of the first state that gave it
    for a in analyses:
        for text in boundary_warnings(a) if a is not None else ():
            shown.setdefault(text, format_factor(a.strength_factor))
    return "".join(
        f'<div class="warning">Warning (mechanism at F = {F}): {_esc(t)}.</div>'
        for t, F in shown.items()
    )


def _inputs(model: Model, system, units: str | None) -> str:
    blocks = system.blocks
    n_free = int((~blocks.fixed).sum())
    summary = [
        ["name", _esc(model.name)],
        ["units", _esc(units or "consistent user units (not stated)")],
        ["blocks", f"{blocks.n_blocks} ({n_free} free, {blocks.n_blocks - n_free} fixed)"],
        ["interfaces", str(system.interfaces.n_interfaces)],
        ["spring points", str(system.springs.n_springs)],
        [
            "weight of free blocks" + parse_units(units).suffix("force"),
            _num(blocks.weight[~blocks.fixed].sum(), ".5g"),
        ],
    ]
    s = model.settings
    summary += [
        ["quadrature", f"{_esc(s.quadrature)}, {s.points_per_interface} points per interface"],
        ["load steps", str(s.load_steps)],
        ["tolerance", _num(s.tolerance, ".1e")],
    ]
    out = [_table(["quantity", "value"], summary, left=1, cls="summary")]
    used = np.bincount(system.interfaces.joint, minlength=len(model.joints))
    rows = [
        [
            j.name,
            "yes" if model.ground == k else "",
            _num(j.normal_stiffness, ".4g"),
            _num(j.shear_stiffness, ".4g"),
            _num(j.friction_angle, ".4g"),
            _num(j.cohesion, ".4g"),
            _num(j.tensile_strength, ".4g"),
            _num(j.residual_friction_angle, ".4g"),
            _num(j.residual_cohesion, ".4g"),
            int(used[k]),
        ]
        for k, j in enumerate(model.joints)
    ]
    out.append("<h3>Joints</h3>")
    out.append(
        _table(
            [
                "joint",
                "ground",
                "kn",
                "ks",
                "φ (°)",
                "c",
                "tensile",
                "φ res. (°)",
                "c res.",
                "interfaces",
            ],
            rows,
            left=2,
            cls="joints",
        )
    )
    ld = model.loads
    rows = [
        ["self-weight", "on" if ld.gravity else "off"],
        ["seismic kh / kv", f"{_num(ld.seismic_h)} / {_num(ld.seismic_v)}"],
    ]
    for k, p in enumerate(ld.points):
        kind = "support" if p.support else "point load"
        rows.append(
            [f"{kind} {p.name or k}", f"({_num(p.fx)}, {_num(p.fy)}) at ({_num(p.x)}, {_num(p.y)})"]
        )
    for k, line in enumerate(ld.lines):
        rows.append(
            [
                f"line load {line.name or k}",
                f"({_num(line.qx)}, {_num(line.qy)})"
                + (
                    ""
                    if line.q_end is None
                    else f" to ({_num(line.q_end[0])}, {_num(line.q_end[1])}) (linear)"
                )
                + " per length from "
                f"({_num(line.start[0])}, {_num(line.start[1])}) to "
                f"({_num(line.end[0])}, {_num(line.end[1])})",
            ]
        )
    out.append("<h3>Loads</h3>")
    out.append(_table(["load", "value"], rows, left=2, cls="loads"))
    return "\n".join(out)


def _verdict(a: Analysis, fos: FactorOfSafety | None) -> str:
    cls = "stable" if a.stable else "unstable"
    F = f"F = {format_factor(a.strength_factor)}"
    text = (
        f"STABLE under the full loads ({F})"
        if a.stable
        else f"UNSTABLE: no equilibrium beyond load factor {a.load_factor:.3g} ({F})"
    )
    parts = [f'<div class="verdict {cls}" id="verdict">{_esc(text)}</div>']
    if fos is not None:
        lo, hi = fos.bracket
        if fos.value is not None:
            parts.append(
                f'<p class="fos" id="fos">Factor of safety F = {fos.value:.3f} '
                f"(bracket {lo:.4f} - {_num(hi, '.4f')})</p>"
            )
        else:
            parts.append(
                f'<p class="fos" id="fos">Factor of safety: none ({_esc(fos.mode)}), '
                f"bracket {_num(lo, '.4g')} - {_num(hi, '.4g')}</p>"
            )
        parts.append(f'<p class="note">{_esc(fos.definition)}; {len(fos.trials)} trials.</p>')
    parts.append(f'<p class="note">Evidence of the last step: {_esc(a.evidence)}.</p>')
    return "\n".join(parts)


def _steps_table(a: Analysis) -> str:
    rows = [
        [
            int(s.stage),
            _num(s.load_factor, ".3g"),
            _num(s.strength_factor, ".5g"),
            "yes" if s.converged else "no",
            int(s.n_failed_springs),
            _esc(s.evidence),
        ]
        for s in a.steps
    ]
    return _table(
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
        f"{fos.value:.3f}: equilibrium was lost at {hi:.4f} within this trial)"
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

    Returns
    -------
    Path
        The HTML file written.
    """
    from . import __version__

    if isinstance(model, (str, Path)):
        from .config import load_model

        model, cfg = load_model(model)
        units = units or getattr(cfg, "units", None) or None
    if not isinstance(model, Model):
        raise TypeError(f"write_report needs a Model or a model file, not {type(model)!r}")
    if image_format not in ("png", "svg"):
        raise ValueError("image_format must be 'png' or 'svg'")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    u = parse_units(units)
    a = analysis if analysis is not None else analyse(model)
    if fos is None and compute_fos:
        fos = factor_of_safety(a.system, **(fos_options or {}))
    system = a.system
    failed = fos.failed_analysis if fos is not None else None
    progressive = failed if failed is not None else a
    n_free = int((~system.blocks.fixed).sum())
    ids = block_ids if block_ids is not None else n_free <= 60

    def fig(f, caption, alt, ident):
        uri = _figure_uri(f, image_format, dpi)
        return _img(uri, caption, alt, ident)

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
            f"Failure state at {F1}: {_state_counts(a)}. Each stretch of joint in its "
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
                f"Failure state at {where}: {_state_counts(failed)}.",
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
        f = plots.plot_joint_stress(shown, j, unit=unit, stress_unit=stress_unit)
        label = "the slip surface / failed joints" if j is None else f"joint {j}"
        at = f"F = {format_factor(shown.stress_factor)}"
        if shown is not a:
            at += " (the last equilibrium of the strength-reduction search)"
        elif not shown.stable:
            at += " (no equilibrium: the solver's last iterate)"
        pics.append(
            fig(
                f,
                f"Normal stress (compression positive), shear stress and shear strength "
                f"along {_esc(label)} at {at}; the strength is drawn at the same factor.",
                f"stress along {label}",
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
            _img(
                uri,
                "Progressive failure, animated.",
                "progressive failure animation",
                "fig-animation",
            )
        )
    now = _dt.datetime.now().astimezone().isoformat(timespec="seconds")
    title = title or f"rockdem report: {model.name}"
    sections = [
        f"<h1>{_esc(title)}</h1>",
        f'<p class="meta">rockdem {_esc(__version__)} · {_esc(now)}</p>',
        '<nav><a href="#results">Verdict</a><a href="#tables">Failed joints</a>'
        '<a href="#trust">Trust</a>'
        + ('<a href="#limit-equilibrium">Limit equilibrium</a>' if fos is not None else "")
        + '<a href="#pictures">Pictures</a>'
        '<a href="#progressive">Progressive failure</a>'
        '<a href="#inputs">Inputs</a></nav>',
        '<h2 id="results">Verdict</h2>',
        _verdict(a, fos),
        _warnings(a, failed),
        '<h3 id="trust">How far to trust this</h3>',
        "<ul>" + "".join(f"<li>{_esc(t)}</li>" for t in trust_statements(a, fos)) + "</ul>",
        '<h2 id="tables">Failed joints and unstable blocks</h2>',
        f"<h3>Joints at {F1}: state now and failure history</h3>",
        f'<p class="states">{_esc(_state_counts(a))}.</p>',
        _failed_table(a, stress_unit, max_rows, u),
        f"<h3>Unstable blocks at {F1}</h3>",
        _unstable_table(a, max_rows, u),
    ]
    if a.bolts is not None:
        sections += [f"<h3>Bolts at {F1}</h3>", _bolts_table(a, u)]
    if failed is not None and failed is not a and not _same_state(a, failed):
        sections += [
            f"<h3>Joints at F = {format_factor(failed.strength_factor)} (failure): state now "
            "and failure history</h3>",
            f'<p class="states">{_esc(_state_counts(failed))}.</p>',
            _failed_table(failed, stress_unit, max_rows, u),
            f"<h3>Unstable blocks at F = {format_factor(failed.strength_factor)} (failure)</h3>",
            _unstable_table(failed, max_rows, u),
        ]
    if fos is not None:
        from .limit_equilibrium.report import html_section as le_section

        sections += le_section(fos)
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
        _inputs(model, system, units),
        "<hr>",
        f'<p class="meta">Written by rockdem {_esc(__version__)} on {_esc(now)} '
        f"(Python {_esc(platform.python_version())}). Stage numbers: load steps, then "
        "strength-reduction trials.</p>",
    ]
    doc = (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f'<meta name="generator" content="rockdem {_esc(__version__)}">'
        f"<title>{_esc(title)}</title><style>{_CSS}</style></head>\n<body>\n"
        + "\n".join(sections)
        + "\n</body></html>\n"
    )
    path = out / filename
    path.write_text(doc, encoding="utf-8")
    return path
