"""``rockdem le``: limit equilibrium beside the DEM.

Given a model file (or ``--example``), the factor of safety by strength
reduction and the DEM's mechanism rated by Sarma's method, side by side,
with where they differ.  Given a limit-equilibrium case file (one whose
section ``limit_equilibrium`` names a closed form: ``plane_failure``,
``toppling`` or ``wedge``), that closed form.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from rich.markup import escape
from rich.table import Table

from ..limit_equilibrium.report import signed_percent
from ..results import bracket_decimals
from ..units import parse_units
from .common import (
    DebugOpt,
    ExampleOpt,
    JsonOpt,
    ModelArg,
    QuietOpt,
    _echo_json,
    _fos_options,
    _guard,
    _header,
    _ids,
    _load,
    _model_path,
    _progress,
    out,
)


def le(
    model: ModelArg = None,
    example: ExampleOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    debug: DebugOpt = False,
) -> None:
    """Limit equilibrium: Sarma's method on the DEM's mechanism, or a closed form.

    A model file: the factor of safety by strength reduction, then the
    mechanism it finds rated by Sarma's method (the same blocks on the same
    slip surface), side by side, and where the two differ.  A case file with
    a `limit_equilibrium:` section naming `plane_failure` (Hoek & Bray),
    `toppling` (Goodman & Bray) or `wedge` (the paper's Eq. 7): that closed
    form with the inputs given (see docs/limit-equilibrium.md).
    """
    with _guard(debug):
        from ..config import read_document
        from ..limit_equilibrium.cases import is_case_document, run_case

        path = _model_path(model, example)
        if example is None:
            data, nodes = read_document(path)
            if is_case_document(data):
                doc = {
                    "file": str(path),
                    "name": data.get("name"),
                    **run_case(data, source=str(path), nodes=nodes),
                }
                doc["units"] = data.get("units")
                if json_:
                    _echo_json({"command": "le", **doc})
                    return
                _print_case(doc)
                return
        _sarma_command(model, example, json_, quiet)


def _sarma_command(model, example, json_: bool, quiet: bool) -> None:
    from ..limit_equilibrium import sarma
    from ..strength_reduction import factor_of_safety
    from . import _trial_hook

    path, m, cfg = _load(model, example)
    with _progress(quiet, "strength reduction") as bar:
        task = bar.add_task("strength reduction trials", total=None)
        fos = factor_of_safety(m, **_fos_options(cfg), progress=_trial_hook(bar, task))
    result = sarma(fos)
    units = parse_units(cfg.units)
    doc = {
        **_header(path, m, cfg),
        "command": "le",
        "dem": {"factor_of_safety": fos.value, "bracket": list(fos.bracket), "mode": fos.mode},
        "sarma": result.as_dict(),
    }
    if json_:
        _echo_json(doc)
        return
    _print_sarma(doc, result, fos, units)


def _num(x: float | None, fmt: str = ".4f") -> str:
    return "none" if x is None else format(x, fmt)


def _finite(x: float | None, fmt: str) -> str:
    """A force of the toppling table; "-" where none is defined (no finite
    force holds a block)."""
    return "-" if x is None or not math.isfinite(x) else format(x, fmt)


def _print_sarma(doc: dict[str, Any], r, fos, units) -> None:
    out.print(f"[bold]{escape(doc['model_name'])}[/bold]  ({escape(doc['model_file'])})")
    if fos.value is not None:
        lo, hi = fos.bracket
        d = bracket_decimals(lo, hi)
        out.print(
            f"DEM factor of safety (strength reduction): [bold]{fos.value:.4f}[/bold] "
            f"(bracket {lo:.{d}f} - {hi:.{d}f})"
        )
    else:
        out.print(f"DEM factor of safety: none ({fos.mode})")
    if r.fos is None:
        out.print(f"Sarma (limit equilibrium): [yellow]no factor[/yellow]: {escape(r.reason)}")
        if r.bodies:
            out.print(f"moving blocks: {_ids(sorted(i for b in r.bodies for i in b))}")
        return
    line = f"Sarma (limit equilibrium) on the DEM's mechanism: [bold]{r.fos:.4f}[/bold]"
    if r.difference is not None:
        line += f" ({signed_percent(r.difference)} against the DEM)"
    out.print(line)
    if r.critical_acceleration is not None:
        out.print(
            f"critical acceleration at full strength: Kc = {r.critical_acceleration:.4f} g "
            "(horizontal, in the direction of motion"
            + (
                "; negative: the blocks slide at full strength even without one)"
                if r.critical_acceleration < 0
                else ")"
            )
        )
    out.print(f"rigid bodies ({len(r.bodies)}):")
    for i, body in enumerate(r.bodies):
        out.print(f"  {i}: blocks {_ids(body, 20)}")
    force = units.force if getattr(units, "force", None) else ""
    shown = fos.stable_analysis or fos.failed_analysis
    loads = shown.system.model.loads if shown is not None else None
    wet = loads is not None and bool(loads.water_table or loads.pore_pressure_ratio)
    # with water the normal force is the effective one, the water's taken off
    # (literature round 7: 1200 read as the total 1408.8 on an anchored block)
    normal = "N'" if wet else "N"
    table = Table(
        "face",
        "between",
        "kind",
        "LE state",
        "joints",
        f"length {units.length or ''}".strip(),
        f"{normal} {force}".strip(),
        f"S {force}".strip(),
        "DEM now",
        box=None,
        pad_edge=False,
    )
    for i, f in enumerate(r.faces):
        between = f"{'rock' if f.body_a < 0 else f.body_a}-{f.body_b}"
        states = sorted(set(f.dem_state))
        table.add_row(
            str(i),
            between,
            f.kind,
            f.state,
            escape(", ".join(f.joints)),
            f"{f.length:.3g}",
            _num(f.normal_force, ".4g"),
            _num(f.shear_force, ".4g"),
            escape(", ".join(states)),
        )
    out.print(table)
    if wet:
        out.print("  N': the effective normal force (the water's force on the face taken off)")
    out.print("where the two differ:")
    for note in r.notes:
        out.print(f"  - {escape(note)}")


def _print_case(doc: dict[str, Any]) -> None:
    title = doc.get("name") or Path(doc["file"]).name
    out.print(f"[bold]{escape(str(title))}[/bold]  ({escape(doc['file'])})")
    r, case = doc["result"], doc["case"]
    if case == "plane_failure":
        out.print("plane failure with a tension crack (Hoek & Bray 1981)")
        fs = r["fos"]
        if not math.isfinite(fs):
            # (a bolt's force, or a weight too small to drive: no bolt is to be named then)
            bolt = doc["inputs"].get("bolt_force")
            why = ": the bolt force balances the driving force" if bolt else ""
            out.print(f"factor of safety: unbounded (nothing drives the block down the plane{why})")
        else:
            out.print(f"factor of safety: [bold]{fs:.4f}[/bold]")
        where = "the face" if r["crack_in_face"] else "the upper surface"
        out.print(f"tension crack depth z = {r['crack_depth']:.4g} (in {where})")
        out.print(
            f"W = {r['weight']:.5g}, A = {r['area']:.5g}, U = {r['uplift']:.5g}, "
            f"V = {r['crack_thrust']:.5g}"
        )
    elif case == "wedge":
        verdict = "stable" if r["stable"] else "unstable"
        out.print("two-block wedge (the seed paper's Eq. 7)")
        out.print(f"thrust the passive block needs: {r['thrust']:.4g} ({verdict})")
        out.print(f"factor of safety: [bold]{r['fos']:.4f}[/bold]")
    else:
        out.print("toppling on a stepped base (Goodman & Bray 1976)")
        p0 = r["support"]
        if not math.isfinite(p0):
            out.print(
                "toe force P0: no finite force holds the toe block"
                if p0 > 0
                else "toe force P0: none needed (the toe block can neither topple nor slide)"
            )
        else:
            need = "support needed" if p0 > 0 else "no support needed"
            out.print(f"toe force P0 = {p0:.4g} ({need})")
        fs = r["fos"]
        if fs is None:
            text = "none (friction cannot hold it)"
        elif not math.isfinite(fs):
            text = "above 100 (the toe needs no support for any factor up to 100)"
        else:
            text = f"[bold]{fs:.4f}[/bold]"
        out.print("factor of safety: " + text)
        if r.get("caution"):
            out.print(f"caution: {escape(r['caution'])}")
        for mode in ("stable", "toppling", "sliding"):
            ids = r[f"{mode}_blocks"]
            out.print(f"{mode} blocks ({len(ids)}): " + (_ids(ids) if ids else "none"))
        table = Table(
            "block",
            "y",
            "W",
            "P(n-1),t",
            "P(n-1),s",
            "P(n-1)",
            "R",
            "S",
            "mode",
            box=None,
            pad_edge=False,
        )
        for row in reversed(r["blocks"]):
            table.add_row(
                str(row["block"]),
                f"{row['height']:.4g}",
                f"{row['weight']:.4g}",
                _num(row["p_topple"], ".1f"),
                _num(row["p_slide"], ".1f"),
                _finite(row["p_lower"], ".1f"),
                _finite(row["normal"], ".1f"),
                _finite(row["shear"], ".1f"),
                row["mode"],
            )
        out.print(table)
        tension = [row["block"] for row in r["blocks"] if row["normal"] < 0]
        if tension:
            out.print(
                f"warning: the bases of blocks {_ids(tension)} would carry tension (R < 0): "
                "Goodman & Bray's forces are not admissible there (too much friction on the "
                "faces for these blocks); read the factor of safety with care"
            )
