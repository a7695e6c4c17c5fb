"""``rockdem run`` and ``rockdem fos``: the staged analysis and the factor of safety,
printed, as JSON, or as result files."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape
from rich.table import Table

from ..results import bracket_decimals, format_factor
from ..units import parse_units
from .common import (
    DebugOpt,
    ExampleOpt,
    JsonOpt,
    ModelArg,
    OutOpt,
    OverwriteOpt,
    QuietOpt,
    _echo_json,
    _fos_options,
    _guard,
    _header,
    _ids,
    _load,
    _plural,
    _progress,
    err,
    out,
    with_issued_warnings,
)

FormatOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--format",
        help="Also write these formats into --out: vtk (blocks.vtu, interfaces.vtu for "
        "ParaView), geojson (section.geojson for GIS), dxf (result.dxf for CAD), or all; "
        "comma-separated or repeated.  CSV and JSON are always written.",
        metavar="FORMATS",
        show_default=False,
    ),
]


def _formats(values: list[str] | None, out_dir: Path | None) -> tuple[str, ...]:
    """The exchange formats asked for (rockdem.exchange.results); they need --out."""
    if not values:
        return ()
    from ..errors import InputError
    from ..exchange.results import parse_formats

    formats = parse_formats(values)
    if formats and out_dir is None:
        raise InputError("--format", "needs --out DIR", "give the folder to write the files into")
    return formats


def _format_files(formats: tuple[str, ...]) -> tuple[str, ...]:
    from ..exchange.results import format_files

    return format_files(formats) if formats else ()


def _other_format_files(formats: tuple[str, ...]) -> tuple[str, ...]:
    """The files of the exchange formats not asked for."""
    from ..exchange.results import FORMATS

    asked = set(_format_files(formats))
    return tuple(name for names in FORMATS.values() for name in names if name not in asked)


def run(
    model: ModelArg = None,
    example: ExampleOpt = None,
    out_dir: OutOpt = None,
    overwrite: OverwriteOpt = False,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    debug: DebugOpt = False,
    format_: FormatOpt = None,
) -> None:
    """Staged gravity analysis: the verdict, the failed joints and the unstable blocks.

    An unstable slope is a result, not an error: the exit code is 0.
    """
    with _guard(debug):
        from ..analysis import analyse
        from ..output import check_output_dir
        from ..result_tables import analysis_summary

        # the progress hooks are looked up on the package at call time, so that
        # rockdem.cli._step_hook and rockdem.cli._trial_hook stay patchable
        from . import _step_hook

        formats = _formats(format_, out_dir)
        path, m, cfg = _load(model, example)
        if out_dir is not None:
            check_output_dir(
                out_dir,
                overwrite=overwrite,
                extra_files=_format_files(formats),
                other_files=_other_format_files(formats),
            )
        with _progress(quiet, "load steps") as bar:
            task = bar.add_task("load steps", total=m.settings.load_steps)
            result = analyse(m, progress=_step_hook(bar, task))
        summary = analysis_summary(result)
        units = parse_units(cfg.units)
        doc = {**_header(path, m, cfg), **_units(units), "command": "run", **summary}
        if out_dir is not None:
            note = _iterate_note(result)
            if note:  # inclined-layers: the CSVs' stresses at load factor 0.2, unsaid
                doc["stresses_note"] = note
            echo = {"model": cfg.model_dump(mode="json")}
            _write(
                out_dir,
                result,
                with_issued_warnings({**doc, **echo}),
                overwrite,
                quiet or json_,
                units=units,
                formats=formats,
                units_note=cfg.units,
            )
            if note and not (quiet or json_):
                err.print(f"note: {note}")
        if json_:
            _echo_json(with_issued_warnings(doc))
            return
        _print_run(doc, result)


def _iterate_note(result) -> str:
    """Where a staged analysis found no equilibrium, what the stresses written
    are: the last iterate of the failed step, at that step's load factor."""
    if result.stable or not result.steps:
        return ""
    lf = result.steps[-1].load_factor
    load = "the full load" if lf >= 1 else f"load factor {lf:.3g}, not the full load"
    return (
        "no equilibrium: the stresses and joint states in these files are the last "
        f"iterate of the failed step ({load}), not an equilibrium"
    )


def _write(
    folder: Path,
    analysis,
    document: dict[str, Any],
    overwrite: bool,
    quiet: bool,
    failed=None,
    units=None,
    formats: tuple[str, ...] = (),
    units_note: str = "",
):
    from ..output import write_results
    from ..result_tables import analysis_tables

    tables = analysis_tables(analysis, failed)
    extra: dict[str, Any] = {}
    if formats:  # VTK, GeoJSON, DXF beside the tables (rockdem.exchange)
        from ..exchange.results import result_writer

        extra = {
            "extra_files": _format_files(formats),
            "write_extra": result_writer(
                formats, analysis, tables, failed=failed, units=units, units_note=units_note
            ),
        }
    files = write_results(folder, tables, document, overwrite=overwrite, units=units, **extra)
    if not quiet:
        err.print(f"results written to {escape(str(folder))}/ ({', '.join(f.name for f in files)})")


def _units(units) -> dict[str, Any]:
    """``unit_system``: the unit of each quantity read from the ``units`` note."""
    from ..output import units_summary

    return {"unit_system": units_summary(units)}


_PROOF = {
    "lp-certificate": "proven: no statically admissible force field carries the loads "
    "(equilibrium LP)",
    "dynamic-relaxation": "confirmed by a second method: dynamic relaxation from the last "
    "equilibrium leaves the blocks moving (a confirmation, not a proof)",
    "undecided": "[yellow]undecided[/yellow]: the solver found no equilibrium, but an "
    "admissible force field exists; failure is not proven (the factor may be higher)",
    None: "none needed (equilibrium found)",
}


def _print_run(doc: dict[str, Any], result) -> None:
    out.print(f"[bold]{escape(doc['model_name'])}[/bold]  ({escape(doc['model_file'])})")
    n = len(result.steps)
    if doc["stable"]:
        out.print(
            f"verdict: [bold green]STABLE[/bold green] under the full load "
            f"({_plural(n, 'load step')})"
        )
        from ..trust import relaxed_steps

        for line in relaxed_steps(result):
            out.print(f"note: {escape(line)}")
    else:
        word = (
            "[bold yellow]UNDECIDED[/bold yellow]"
            if doc["verdict"] == "undecided"
            else "[bold red]UNSTABLE[/bold red]"
        )
        out.print(
            f"verdict: {word}: no equilibrium at load step {n} "
            f"(last equilibrium at load factor {doc['load_factor']:.3g}); "
            f"{escape(doc['evidence'])}"
        )
        out.print(f"proof: {_PROOF[doc['proof']]}")
    blocks = doc["unstable_blocks"]
    out.print(f"unstable blocks ({len(blocks)}): " + (_ids(blocks) if blocks else "none"))
    _print_mechanism(doc)
    _print_states(doc["interface_states"])
    failed = doc["failed_interfaces"]
    out.print(
        f"failure history: {_plural(len(failed), 'interface')} failed at some time"
        + (" (history; 'now' is the current state):" if failed else ": none")
    )
    if failed:
        table = Table(
            "interface",
            "blocks",
            "kind",
            "failed in",
            "failed",
            "now",
            "first step",
            box=None,
            pad_edge=False,
        )
        for row in failed[:30]:
            table.add_row(
                str(row["interface"]),
                f"{row['block_a']}-{row['block_b']}",
                escape(row["kind"]),
                row["state"],
                f"{100 * row['failed_fraction']:.0f}%",
                _NOW[row["current_state"]],
                str(row["first_failure"]),
            )
        out.print(table)
        if len(failed) > 30:
            out.print(f"... and {len(failed) - 30} more (see interfaces.csv with --out)")
    _print_bolts(doc, "bolt_summary", "bolts")
    if not doc["stable"] and doc["slip_surface"]:
        r = result.interfaces
        parts = [
            f"{i} ({escape(str(r.kind[i]))}, blocks {r.block_a[i]}-{r.block_b[i]})"
            for i in doc["slip_surface"][:20]
        ]
        more = len(doc["slip_surface"]) - len(parts)
        out.print("slip surface: " + ", ".join(parts) + (f", ... ({more} more)" if more else ""))


def _print_bolts(doc: dict[str, Any], key: str, title: str) -> None:
    """One line per bolt: its largest force, utilisation and yielded crossings."""
    bolts = doc[key]
    if not bolts:
        return
    unit = (doc.get("unit_system") or {}).get("force")
    unit = f" {unit}" if unit else ""
    out.print(f"{title} (force per bolt):")
    for b in bolts:
        yielded = b["yielded_crossings"]
        state = f", yielded at {_plural(yielded, 'joint')}" if yielded else ""
        if b.get("first_yield") is not None:
            state += f" (first at stage {b['first_yield']})"
        force = b["max_axial_force"]
        sense = "tension" if force > 0 else "compression"
        axial = f"largest axial force {abs(force):.4g}{unit} {sense}" if force else "no axial force"
        if not b.get("installed", True):
            out.print(f"  {escape(b['bolt'])}: not installed (installed: after_loads)")
            continue
        out.print(
            f"  {escape(b['bolt'])}: crosses {_plural(b['crossings'], 'joint')}, {axial} "
            f"({100 * b['max_utilisation']:.0f}% of capacity{state})"
        )


#: current states in words (rockdem.results.CURRENT_NAMES -> CURRENT_LABELS)
_NOW = {
    "elastic": "closed",
    "closed-failed-earlier": "closed",
    "sliding": "[red]sliding[/red]",
    "open": "[blue]open[/blue]",
}


def _print_mechanism(doc: dict[str, Any]) -> None:
    """Failure mode per block and the model-boundary warnings of a summary."""
    modes = doc.get("failure_modes") or {}
    if len(modes) == 1:
        out.print(f"  failure mode: all {next(iter(modes))}")
    elif modes:
        out.print("  failure modes:")
        for mode, ids in modes.items():
            out.print(f"    {mode} ({len(ids)}): {_ids(ids, 20)}")
    carried = doc.get("carried_blocks") or []
    guessed = [i for i in doc.get("failure_modes_from_motion") or [] if i not in carried]
    moving = sum(len(ids) for ids in modes.values())
    if guessed and len(guessed) < moving:  # some at the transition: say which
        out.print(
            f"  at the transition between sliding and toppling ({len(guessed)}): "
            f"{_ids(guessed, 20)} (their base was partly open and partly at its strength at "
            "the limit; their mode is the motion's beyond it, which is chaotic in its detail)"
        )
    if carried and len(carried) < moving:
        out.print(
            f"  carried by the blocks under them ({len(carried)}): {_ids(carried, 20)} (their "
            "base held at the limit: they move with those blocks)"
        )
    for text in doc.get("warnings") or []:
        out.print(f"[bold yellow]warning[/bold yellow]: {escape(text)}")


def _print_states(states: dict[str, dict[str, int]]) -> None:
    """The current state of the joints, apart from their failure history."""
    now = states["now"]
    total = sum(now.values())
    out.print(
        f"joints now ({_plural(total, 'interface')}, each by most of its length): "
        f"{now['sliding']} sliding, {now['open']} open, "
        f"{now['closed-failed-earlier']} failed earlier and now closed, "
        f"{now['elastic']} elastic"
    )


def fos(
    model: ModelArg = None,
    example: ExampleOpt = None,
    out_dir: OutOpt = None,
    overwrite: OverwriteOpt = False,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    debug: DebugOpt = False,
    format_: FormatOpt = None,
) -> None:
    """Factor of safety by shear strength reduction: the value and its bracket.

    With --out the tables describe the last equilibrium (the stable end of the
    bracket), except the blocks' failure_mode: the mode at the limit (the
    failed end); result.json also lists the blocks moving at the unstable end.
    """
    with _guard(debug):
        from ..output import check_output_dir
        from ..result_tables import fos_summary
        from ..strength_reduction import factor_of_safety

        # the progress hooks are looked up on the package at call time, so that
        # rockdem.cli._step_hook and rockdem.cli._trial_hook stay patchable
        from . import _trial_hook

        formats = _formats(format_, out_dir)
        path, m, cfg = _load(model, example)
        if out_dir is not None:
            check_output_dir(
                out_dir,
                overwrite=overwrite,
                extra_files=_format_files(formats),
                other_files=_other_format_files(formats),
            )
        with _progress(quiet, "strength reduction") as bar:
            task = bar.add_task("strength reduction trials", total=None)
            result = factor_of_safety(m, **_fos_options(cfg), progress=_trial_hook(bar, task))
        units = parse_units(cfg.units)
        doc = {**_header(path, m, cfg), **_units(units), "command": "fos", **fos_summary(result)}
        if out_dir is not None:
            state = result.stable_analysis or result.failed_analysis
            from ..result_tables import analysis_summary

            extra = {"analysis": analysis_summary(state), "model": cfg.model_dump(mode="json")}
            # the tables describe the last equilibrium; the failure columns the limit's
            _write(
                out_dir,
                state,
                with_issued_warnings({**doc, **extra}),
                overwrite,
                quiet or json_,
                result.failed_analysis,
                units,
                formats=formats,
                units_note=cfg.units,
            )
        if json_:
            _echo_json(with_issued_warnings(doc))
            return
        _print_fos(doc)


def _print_fos(doc: dict[str, Any]) -> None:
    out.print(f"[bold]{escape(doc['model_name'])}[/bold]  ({escape(doc['model_file'])})")
    lo, hi = doc["bracket"]
    n = len(doc["trials"])
    if doc["factor_of_safety"] is not None:
        if doc["proof"] == "undecided":  # nothing shows a failure above the stable end
            out.print(
                f"factor of safety: [bold]at least {lo:.4f}[/bold] ([yellow]undecided[/yellow] "
                f"above it: equilibrium was lost at {hi:.4f}, but no failure was proven or "
                "confirmed there)"
            )
        elif doc["factor_of_safety"] == lo < hi:  # a bracket the search could not narrow
            out.print(
                f"factor of safety: [bold]{lo:.4f}[/bold] (the largest factor found stable; the "
                "bracket stays wide: failure is confirmed only at its top)"
            )
        else:
            out.print(f"factor of safety: [bold]{doc['factor_of_safety']:.4f}[/bold]")
        d = bracket_decimals(lo, hi)
        out.print(f"bracket: stable at {lo:.{d}f}, unstable at {hi:.{d}f} ({n} trials)")
        out.print(f"unstable end: {_PROOF[doc['proof']]}")
        if doc["proof"] in ("dynamic-relaxation", "undecided") and doc.get("relaxation"):
            out.print(f"  ({escape(doc['relaxation'])})")
        if doc.get("certified_upper_bound") is not None:
            out.print(f"rigorous upper bound (equilibrium LP): {doc['certified_upper_bound']:.4f}")
        top = doc.get("confirmed_upper_bound")
        if top is not None and top > hi:
            cap = min(top, doc.get("certified_upper_bound") or top)
            known = f"failure confirmed at F = {top:.4f}"
            if cap < top:
                known = f"failure proven from F = {cap:.4f} (LP) and confirmed at {top:.4f}"
            out.print(
                f"{known}; between {hi:.4f} and {cap:.4f} it is neither proven nor confirmed "
                f"(the limit lies below {cap:.4f})"
            )
    elif doc["mode"] == "no-failure":
        out.print(
            f"factor of safety: > {lo:.4g} (no failure up to the largest factor tried, {n} trials)"
        )
    else:
        out.print(
            "factor of safety: none: the mechanism forms even with the strengths divided by "
            f"{hi:.4g} ({1 / hi:.3g} times their values: toppling, a free block, or joints "
            "with no strength to scale (c = 0 and phi = 0); strength does not control it)"
        )
    blocks = doc["mechanism_blocks"]
    if blocks:
        at = format_factor(doc["mechanism_factor"])
        out.print(f"mechanism blocks ({len(blocks)}, failed state at F = {at}): {_ids(blocks)}")
    _print_mechanism(doc)
    _print_bolts(doc, "bolts_at_limit", "bolts at the last equilibrium below the limit")
    if doc["bolts_at_limit"]:
        # (literature round 7: a dowel sized by Wyllie & Mah's passive equation
        # for 1.5 read 2.02 here, and nothing said which factor this is)
        out.print(
            "  the bolts' forces are not divided by F (only the joints' strengths are): with a "
            "bolt at its capacity this is the factor of a tensioned anchor, its force taken off "
            "the driving force (Hoek & Bray; Wyllie & Mah, sec. 6.5), higher than the factor "
            "of a passive dowel whose force is added to the resisting force (above 1 the two "
            "differ; at 1 they agree)"
        )
    out.print(f"definition: {escape(doc['definition'])}")
