"""The ``rockdem`` command line: check, run, factor of safety, report and plots.

One function per subcommand; each only parses its options, calls the public
API (:func:`rockdem.config.load_model`, :func:`rockdem.analyse`,
:func:`rockdem.factor_of_safety`, :func:`rockdem.report.write_report`,
:func:`rockdem.plots.plot_figure`) and writes.

Exit codes
----------
0
    Done; this includes a slope found *unstable* (an unstable verdict is a
    valid result: read it from the output, or from ``"stable"`` with ``--json``).
1
    The computation itself failed (an unexpected error inside the analysis).
2
    Bad input: a broken model file, an unknown key, a value out of range, a
    geometry that makes no blocks, bad options, or result files that exist
    already (without ``--overwrite``), an unknown figure or file type.  One
    line on stderr names the file, the key path and the fix; ``--debug``
    shows the traceback instead.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from . import __version__

EXIT_OK, EXIT_FAILED, EXIT_INPUT = 0, 1, 2

app = typer.Typer(
    name="rockdem",
    help="Stability of jointed rock slopes by the discrete element method.\n\n"
    "Check a model file, run the staged gravity analysis, find the factor of safety "
    "by strength reduction, write an HTML report or draw one figure.  "
    "Start from a bundled example: `rockdem example list`.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)
example_app = typer.Typer(
    help="The bundled example models.", no_args_is_help=True, rich_markup_mode=None
)
app.add_typer(example_app, name="example")

out = Console(highlight=False, soft_wrap=True)
err = Console(stderr=True, highlight=False, soft_wrap=True)


# ---------------------------------------------------------------- options
ModelArg = Annotated[
    Path | None,
    typer.Argument(help="Model file (.yaml, .yml, .json or .toml).", show_default=False),
]
ExampleOpt = Annotated[
    str | None,
    typer.Option("--example", "-e", help="Use a bundled example instead of a file.",
                 metavar="NAME"),
]
JsonOpt = Annotated[
    bool, typer.Option("--json", help="Print one JSON object to stdout (for scripts).")
]
OutOpt = Annotated[
    Path | None,
    typer.Option("--out", "-o", help="Write blocks.csv, interfaces.csv, springs.csv and "
                 "result.json into this folder.", metavar="DIR"),
]
OverwriteOpt = Annotated[
    bool, typer.Option("--overwrite", help="Replace result files that exist already.")
]
QuietOpt = Annotated[
    bool, typer.Option("--quiet", "-q", help="No progress bars or notes on stderr.")
]
DebugOpt = Annotated[
    bool, typer.Option("--debug", help="Show the full traceback of errors.")
]
JointOpt = Annotated[
    list[str] | None,
    typer.Option("--joint", "-j", help="Plot the stresses along this joint: a joint name, or "
                 "the number (0, 1, ...) of a `joint_lines` trace.", metavar="NAME",
                 show_default=False),
]


def _version(value: bool) -> None:
    if value:
        typer.echo(f"rockdem {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool | None,
        typer.Option("--version", callback=_version, is_eager=True,
                     help="Print the version and exit."),
    ] = None,
) -> None:
    """Stability of jointed rock slopes by the discrete element method."""


# ------------------------------------------------------------------ errors
@contextmanager
def _guard(debug: bool) -> Iterator[None]:
    """Map errors to one line on stderr and an exit code (or a traceback with --debug)."""
    from pydantic import ValidationError

    from .errors import InputError

    try:
        yield
    except typer.Exit:
        raise
    except (InputError, ValidationError) as exc:
        if debug:
            raise
        text = str(exc) if isinstance(exc, InputError) else str(exc).splitlines()[0]
        err.print(f"error: {escape(text)}")
        raise typer.Exit(EXIT_INPUT) from None
    except KeyboardInterrupt:
        err.print("interrupted")
        raise typer.Exit(130) from None
    except Exception as exc:
        if debug:
            raise
        err.print(
            f"error: the analysis failed: {type(exc).__name__}: {escape(str(exc))} "
            "(run again with --debug for the traceback)"
        )
        raise typer.Exit(EXIT_FAILED) from None


def _model_path(model: Path | None, example: str | None) -> Path:
    from .errors import InputError
    from .examples import example_path

    if (model is None) == (example is None):
        raise InputError(
            "MODEL",
            "give either a model file or --example NAME" + (", not both" if model else ""),
            "see `rockdem example list`",
        )
    return example_path(example) if example is not None else model


def _load(model: Path | None, example: str | None):
    from .config import load_model

    path = _model_path(model, example)
    m, cfg = load_model(path)
    return path, m, cfg


@contextmanager
def _progress(quiet: bool, label: str) -> Iterator[Progress]:
    """A progress bar on stderr (nothing with --quiet or when stderr is not a terminal)."""
    progress = Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=err,
        transient=True,
        disable=quiet or not err.is_terminal,
    )
    with progress:
        yield progress


def _echo_json(data: dict[str, Any]) -> None:
    from .output import jsonable

    typer.echo(json.dumps(jsonable(data), indent=1, allow_nan=False))


def _header(path: Path, model, cfg) -> dict[str, Any]:
    return {
        "rockdem_version": __version__,
        "model_file": str(path),
        "model_name": model.name,
        "units": cfg.units,
    }


def _write(folder: Path, analysis, document: dict[str, Any], overwrite: bool, quiet: bool):
    from .output import analysis_tables, write_results

    files = write_results(folder, analysis_tables(analysis), document, overwrite=overwrite)
    if not quiet:
        err.print(f"results written to {escape(str(folder))}/ "
                  f"({', '.join(f.name for f in files)})")


# ------------------------------------------------------------------- check
@app.command()
def check(
    model: ModelArg = None,
    example: ExampleOpt = None,
    json_: JsonOpt = False,
    debug: DebugOpt = False,
) -> None:
    """Validate a model file and print a summary (blocks, interfaces, weights); no analysis."""
    with _guard(debug):
        from .solver import build_system

        path, m, cfg = _load(model, example)
        system = build_system(m)
        summary = _check_summary(path, m, cfg, system)
        if json_:
            _echo_json(summary)
            return
        _print_check(summary)


def _check_summary(path: Path, m, cfg, system) -> dict[str, Any]:
    import numpy as np

    b = system.blocks
    faces = system.interfaces
    names = [j.name for j in m.joints]
    kinds: dict[str, dict[str, float]] = {}
    for k, length in zip(faces.joint, faces.length, strict=True):
        row = kinds.setdefault(names[k], {"count": 0, "length": 0.0})
        row["count"] += 1
        row["length"] += float(length)
    free = ~b.fixed
    loads = m.loads
    return {
        **_header(path, m, cfg),
        "valid": True,
        "blocks": {
            "total": b.n_blocks,
            "free": int(free.sum()),
            "fixed": int(b.fixed.sum()),
            "free_weight": float(b.weight[free].sum()),
            "free_area": float(b.area[free].sum()),
            "weights": {int(i): float(w) for i, w in zip(b.ids[free], b.weight[free],
                                                         strict=True)},
        },
        "interfaces": {"total": faces.n_interfaces, "by_kind": kinds},
        "springs": system.springs.n_springs,
        "degrees_of_freedom": system.assembly.n_dof,
        "loads": {
            "gravity": loads.gravity,
            "seismic_h": loads.seismic_h,
            "seismic_v": loads.seismic_v,
            "point_loads": sum(not p.support for p in loads.points),
            "supports": sum(p.support for p in loads.points),
            "line_loads": len(loads.lines),
            "resultant": [float(v) for v in np.sum(system.f_block[free, :2], axis=0)],
        },
        "analysis": cfg.analysis.model_dump(mode="json"),
    }


def _print_check(s: dict[str, Any]) -> None:
    b = s["blocks"]
    out.print(f"[bold]{escape(s['model_name'])}[/bold]  ({escape(s['model_file'])}): valid")
    out.print(f"units: {escape(s['units']) or '(not stated: add a `units:` note)'}")
    out.print(
        f"blocks: {b['total']} ({b['free']} free, {b['fixed']} fixed); "
        f"free weight {b['free_weight']:.6g} (area {b['free_area']:.6g})"
    )
    weights = sorted(b["weights"].items())
    if weights and len(weights) <= 20:
        out.print("weights: " + ", ".join(f"{i}: {w:.6g}" for i, w in weights))
    elif weights:
        ws = [w for _, w in weights]
        out.print(f"weights: min {min(ws):.6g}, max {max(ws):.6g}, mean {sum(ws) / len(ws):.6g}")
    table = Table("interface kind", "count", "total length", box=None, pad_edge=False)
    for kind, row in s["interfaces"]["by_kind"].items():
        table.add_row(escape(kind), str(row["count"]), f"{row['length']:.6g}")
    out.print(f"interfaces: {s['interfaces']['total']} ({s['springs']} spring points)")
    out.print(table)
    ld = s["loads"]
    out.print(
        f"loads: gravity {'on' if ld['gravity'] else 'off'}, kh {ld['seismic_h']:g}, "
        f"kv {ld['seismic_v']:g}, {ld['point_loads']} point, {ld['line_loads']} line, "
        f"{ld['supports']} supports; resultant on free blocks ({ld['resultant'][0]:.6g}, "
        f"{ld['resultant'][1]:.6g})"
    )
    a = s["analysis"]
    out.print(
        f"analysis: {a['quadrature']} x {a['points_per_interface']}, "
        f"{_plural(a['load_steps'], 'load step')}, tolerance {a['tolerance']:g}"
    )


# --------------------------------------------------------------------- run
@app.command()
def run(
    model: ModelArg = None,
    example: ExampleOpt = None,
    out_dir: OutOpt = None,
    overwrite: OverwriteOpt = False,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    debug: DebugOpt = False,
) -> None:
    """Staged gravity analysis: the verdict, the failed joints and the unstable blocks.

    An unstable slope is a result, not an error: the exit code is 0.
    """
    with _guard(debug):
        from .analysis import analyse
        from .output import analysis_summary, check_output_dir

        path, m, cfg = _load(model, example)
        if out_dir is not None:
            check_output_dir(out_dir, overwrite=overwrite)
        with _progress(quiet, "load steps") as bar:
            task = bar.add_task("load steps", total=m.settings.load_steps)
            result = analyse(m, progress=_step_hook(bar, task))
        summary = analysis_summary(result)
        doc = {**_header(path, m, cfg), "command": "run", **summary}
        if out_dir is not None:
            echo = {"model": cfg.model_dump(mode="json")}
            _write(out_dir, result, {**doc, **echo}, overwrite, quiet or json_)
        if json_:
            _echo_json(doc)
            return
        _print_run(doc, result)


def _step_hook(bar: Progress, task) -> Callable[[int, int], None]:
    def hook(step: int, n: int) -> None:
        bar.update(task, completed=step, total=n)

    return hook


def _trial_hook(bar: Progress, task) -> Callable[[Any], None]:
    def hook(trial) -> None:
        verdict = "stable" if trial.stable else "unstable"
        bar.update(task, advance=1, description=f"trial F = {trial.factor:.4f}: {verdict}")

    return hook


def _fos_options(cfg) -> dict[str, float]:
    """The strength-reduction settings of the model file (``analysis.strength_reduction``)."""
    sr = cfg.analysis.strength_reduction
    return {"width": sr.width, "start": sr.start, "grow": sr.grow, "smallest": sr.smallest,
            "largest": sr.largest}


def _print_run(doc: dict[str, Any], result) -> None:
    out.print(f"[bold]{escape(doc['model_name'])}[/bold]  ({escape(doc['model_file'])})")
    n = len(result.steps)
    if doc["stable"]:
        out.print(
            f"verdict: [bold green]STABLE[/bold green] under the full load "
            f"({_plural(n, 'load step')})"
        )
    else:
        out.print(
            f"verdict: [bold red]UNSTABLE[/bold red]: no equilibrium at load step {n} "
            f"(last equilibrium at load factor {doc['load_factor']:.3g}); "
            f"{escape(doc['evidence'])}"
        )
    blocks = doc["unstable_blocks"]
    out.print(f"unstable blocks ({len(blocks)}): " + (_ids(blocks) if blocks else "none"))
    failed = doc["failed_interfaces"]
    out.print(f"failed joints ({len(failed)})" + (":" if failed else ": none"))
    if failed:
        table = Table("interface", "blocks", "kind", "state", "failed", "first step",
                      box=None, pad_edge=False)
        for row in failed[:30]:
            table.add_row(
                str(row["interface"]),
                f"{row['block_a']}-{row['block_b']}",
                escape(row["kind"]),
                row["state"],
                f"{100 * row['failed_fraction']:.0f}%",
                str(row["first_failure"]),
            )
        out.print(table)
        if len(failed) > 30:
            out.print(f"... and {len(failed) - 30} more (see interfaces.csv with --out)")
    if not doc["stable"] and doc["slip_surface"]:
        r = result.interfaces
        parts = [
            f"{i} ({escape(str(r.kind[i]))}, blocks {r.block_a[i]}-{r.block_b[i]})"
            for i in doc["slip_surface"][:20]
        ]
        more = len(doc["slip_surface"]) - len(parts)
        out.print("slip surface: " + ", ".join(parts) + (f", ... ({more} more)" if more else ""))


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" + ("" if n == 1 else "s")


def _ids(values: list[int], limit: int = 40) -> str:
    text = ", ".join(str(v) for v in values[:limit])
    return text + (f", ... ({len(values) - limit} more)" if len(values) > limit else "")


# --------------------------------------------------------------------- fos
@app.command()
def fos(
    model: ModelArg = None,
    example: ExampleOpt = None,
    out_dir: OutOpt = None,
    overwrite: OverwriteOpt = False,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    debug: DebugOpt = False,
) -> None:
    """Factor of safety by shear strength reduction: the value and its bracket.

    With --out the tables describe the last equilibrium (the stable end of the
    bracket); result.json also lists the blocks moving at the unstable end.
    """
    with _guard(debug):
        from .analysis import factor_of_safety
        from .output import check_output_dir, fos_summary

        path, m, cfg = _load(model, example)
        if out_dir is not None:
            check_output_dir(out_dir, overwrite=overwrite)
        with _progress(quiet, "strength reduction") as bar:
            task = bar.add_task("strength reduction trials", total=None)
            result = factor_of_safety(m, **_fos_options(cfg), progress=_trial_hook(bar, task))
        doc = {**_header(path, m, cfg), "command": "fos", **fos_summary(result)}
        if out_dir is not None:
            state = result.stable_analysis or result.failed_analysis
            from .output import analysis_summary

            extra = {"analysis": analysis_summary(state), "model": cfg.model_dump(mode="json")}
            _write(out_dir, state, {**doc, **extra}, overwrite, quiet or json_)
        if json_:
            _echo_json(doc)
            return
        _print_fos(doc)


def _print_fos(doc: dict[str, Any]) -> None:
    out.print(f"[bold]{escape(doc['model_name'])}[/bold]  ({escape(doc['model_file'])})")
    lo, hi = doc["bracket"]
    n = len(doc["trials"])
    if doc["factor_of_safety"] is not None:
        out.print(f"factor of safety: [bold]{doc['factor_of_safety']:.4f}[/bold]")
        out.print(f"bracket: stable at {lo:.4f}, unstable at {hi:.4f} ({n} trials)")
    elif doc["mode"] == "no-failure":
        out.print(f"factor of safety: > {lo:.4g} (no failure up to the largest factor tried, "
                  f"{n} trials)")
    else:
        out.print(
            "factor of safety: none: the mechanism forms even with the strengths scaled by "
            f"{hi:.4g} (toppling or a free block; strength does not control it)"
        )
    blocks = doc["mechanism_blocks"]
    if blocks:
        out.print(f"mechanism blocks ({len(blocks)}): {_ids(blocks)}")
    out.print(f"definition: {escape(doc['definition'])}")


# ------------------------------------------------------------ report, plot
REPORT_FILE = "report.html"
#: The figures of ``rockdem plot --what`` (the keys of :data:`rockdem.plots.WHAT`; kept
#: here so that the command line starts without importing matplotlib).
PLOT_WHAT = ("model", "failure", "deformed", "mechanism", "stress", "progressive",
             "animation", "fos")
PLOT_FORMATS = (".png", ".svg", ".pdf", ".gif")


def _plot_units(note: str) -> dict[str, str]:
    """Length and stress units for the axes from a ``units`` note such as ``"kN, m, kPa"``.

    The note is read as ``force, length[, stress]`` (a trailing remark in
    parentheses is ignored); anything else leaves the defaults (m, kPa).
    """
    text = note.split("(", 1)[0]
    parts = [p.strip() for p in text.split(",")]
    if len(parts) < 2 or not all(parts) or any(" " in p for p in parts):
        return {}
    units = {"unit": parts[1]}
    if len(parts) >= 3:
        units["stress_unit"] = parts[2]
    return units


def _joints(values: list[str] | None, model, system) -> list[str | int]:
    """``--joint`` values as joint names or joint-line numbers, checked against the model."""
    from .errors import InputError

    names = [j.name for j in model.joints]
    used = {names[k] for k in set(system.interfaces.joint.tolist())}
    n_lines = 0 if model.joint_lines is None else len(model.joint_lines)
    chosen: list[str | int] = []
    for value in values or []:
        if value in names:
            if value not in used:
                raise InputError(f"--joint {value}", "no interface of the model has this joint",
                                 f"use one of {', '.join(n for n in names if n in used)}")
            chosen.append(value)
        elif value.isdigit() and int(value) < n_lines:
            chosen.append(int(value))
        else:
            lines = f", or a joint line 0-{n_lines - 1}" if n_lines else ""
            raise InputError(f"--joint {value}", "is not a joint of the model",
                             f"use one of {', '.join(names)}{lines}")
    return chosen


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _check_new_file(target: Path, option: str, overwrite: bool) -> None:
    from .errors import InputError

    if target.is_dir():
        raise InputError(f"{option} {target}", "is a folder", "give a file name")
    if target.exists() and not overwrite:
        raise InputError(f"{option} {target}", "exists already",
                         "use --overwrite to replace it, or another name")


def _replace(tmp: Path, target: Path, option: str, overwrite: bool) -> None:
    """Move a complete file into place (atomic on one file system)."""
    _check_new_file(target, option, overwrite)  # it may have appeared meanwhile
    os.chmod(tmp, 0o666 & ~_umask())
    os.replace(tmp, target)


def _save_report(folder: Path, overwrite: bool, model, **options) -> Path:
    """``write_report`` into a temporary folder inside ``folder``, then move the file."""
    from .report import write_report

    target = folder / REPORT_FILE
    created = not folder.exists()
    folder.mkdir(parents=True, exist_ok=True)
    try:
        tmp = Path(tempfile.mkdtemp(prefix=".report.", suffix=".tmp", dir=folder))
        try:
            written = write_report(model, tmp, filename=REPORT_FILE, **options)
            _replace(written, target, "--out", overwrite)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    except BaseException:
        if created:
            try:
                folder.rmdir()  # only if we made it and it is still empty
            except OSError:
                pass
        raise
    return target


@app.command()
def report(
    model: ModelArg = None,
    example: ExampleOpt = None,
    out_dir: Annotated[
        Path,
        typer.Option("--out", "-o", help=f"Folder to write {REPORT_FILE} into (created if "
                     "needed).", metavar="DIR", show_default=False),
    ] = ...,
    svg: Annotated[
        bool, typer.Option("--svg", help="Embed the figures as SVG (vector) instead of PNG.")
    ] = False,
    no_animation: Annotated[
        bool, typer.Option("--no-animation", help="Leave out the animated GIF (smaller, "
                           "faster).")
    ] = False,
    joint: JointOpt = None,
    overwrite: Annotated[
        bool, typer.Option("--overwrite", help=f"Replace an existing {REPORT_FILE}.")
    ] = False,
    quiet: QuietOpt = False,
    debug: DebugOpt = False,
) -> None:
    """Write one self-contained HTML report: verdict, factor of safety, tables, pictures.

    Runs the staged analysis and the strength-reduction search (with the
    model file's `analysis.strength_reduction` settings) and writes
    report.html into DIR, all or nothing.  The figures and the animation are
    embedded, so the file opens offline and can be mailed as it is.  Axis
    units follow the file's `units` note read as "force, length, stress"
    (for example "kN, m, kPa").  Prints the path of the report.
    \f
    Parameters
    ----------
    model, example
        The model file, or the name of a bundled example (exactly one).
    out_dir
        Folder for ``report.html`` (created with its parents if needed).
    svg
        Embed the figures as SVG instead of PNG.
    no_animation
        Leave out the progressive-failure GIF.
    joint
        Joints to plot the stresses along (names or joint-line numbers);
        default: the slip surface, else the failed joints.
    overwrite
        Replace an existing ``report.html``.
    quiet, debug
        No progress bars; a traceback instead of the one-line error.

    Raises
    ------
    typer.Exit
        Code 2 for bad input (model, options, an existing report without
        ``--overwrite``), 1 if the computation or the writing fails; nothing
        is left behind in DIR then.
    """
    with _guard(debug):
        from .analysis import analyse, factor_of_safety
        from .output import check_output_dir
        from .solver import build_system

        _, m, cfg = _load(model, example)
        check_output_dir(out_dir, overwrite=True)  # a folder, not a file
        _check_new_file(out_dir / REPORT_FILE, "--out", overwrite)
        system = build_system(m)
        joints = _joints(joint, m, system) or None
        with _progress(quiet, "report") as bar:
            task = bar.add_task("load steps", total=m.settings.load_steps)
            analysis = analyse(system, progress=_step_hook(bar, task))
            task = bar.add_task("strength reduction trials", total=None)
            fos = factor_of_safety(system, **_fos_options(cfg), progress=_trial_hook(bar, task))
            bar.add_task("drawing the report", total=None)
            target = _save_report(
                out_dir, overwrite, m, analysis=analysis, fos=fos, units=cfg.units or None,
                joints=joints, image_format="svg" if svg else "png",
                animation=not no_animation, **_plot_units(cfg.units),
            )
        typer.echo(str(target))


def _plot_options(what: str, out_file: Path, joint: list[str] | None,
                  magnification: float | None, ids: bool, dpi: int) -> None:
    """Check the ``plot`` options that need no model (one clear error each)."""
    from .errors import InputError

    if what not in PLOT_WHAT:
        raise InputError(f"--what {what}", "is not a figure rockdem draws",
                         f"use one of {', '.join(PLOT_WHAT)}")
    if out_file.is_dir():
        raise InputError(f"--out {out_file}", "is a folder",
                         f"give a file name such as {out_file / (what + '.png')}")
    ext = out_file.suffix.lower()
    if ext not in PLOT_FORMATS:
        raise InputError(f"--out {out_file}",
                         f"unsupported file type {ext!r}" if ext else "has no extension",
                         "end the name in .png, .svg or .pdf (.gif for --what animation)")
    if what == "animation" and ext != ".gif":
        raise InputError(f"--out {out_file}", "the animation is written as a GIF",
                         "end the name in .gif")
    if what != "animation" and ext == ".gif":
        raise InputError(f"--out {out_file}", "only --what animation is written as a GIF",
                         "end the name in .png, .svg or .pdf")
    if joint and what != "stress":
        raise InputError("--joint", "applies to --what stress only", "leave it out")
    if joint and len(joint) > 1:
        raise InputError("--joint", "give one joint per stress plot",
                         "run once per joint (`rockdem report` takes several)")
    if magnification is not None and what not in ("deformed", "mechanism"):
        raise InputError("--magnification", "applies to --what deformed or mechanism only",
                         "leave it out")
    if magnification is not None and not magnification > 0:
        raise InputError(f"--magnification {magnification:g}", "must be positive",
                         "give a factor such as 100")
    if ids and what not in ("model", "failure"):
        raise InputError("--ids", "applies to --what model or failure only", "leave it out")
    if dpi < 1:
        raise InputError(f"--dpi {dpi}", "must be positive", "give for example 150")


@app.command()
def plot(
    model: ModelArg = None,
    example: ExampleOpt = None,
    what: Annotated[
        str,
        typer.Option("--what", "-w", help="The figure: " + ", ".join(PLOT_WHAT) + ".",
                     metavar="FIGURE", show_default=False),
    ] = ...,
    out_file: Annotated[
        Path,
        typer.Option("--out", "-o", help="File to write: .png, .svg or .pdf (.gif for "
                     "animation); the format follows the extension.", metavar="FILE",
                     show_default=False),
    ] = ...,
    joint: JointOpt = None,
    magnification: Annotated[
        float | None,
        typer.Option("--magnification", "-m", help="Scale of the displacements (deformed, "
                     "mechanism); default: automatic.", metavar="X", show_default=False),
    ] = None,
    ids: Annotated[
        bool, typer.Option("--ids", help="Label the blocks with their ids (model, failure).")
    ] = False,
    dpi: Annotated[
        int, typer.Option("--dpi", help="Resolution of PNG and GIF output (GIF at most 100).",
                          metavar="N")
    ] = 150,
    overwrite: Annotated[
        bool, typer.Option("--overwrite", help="Replace the file if it exists.")
    ] = False,
    quiet: QuietOpt = False,
    debug: DebugOpt = False,
) -> None:
    """Draw one figure of a model or its analysis into a file.

    model: the blocks, joints and loads (no analysis).  deformed, stress: the
    staged analysis at F = 1.  failure, mechanism, progressive, animation:
    the state just above the factor of safety (the mechanism), found with the
    model file's strength-reduction settings.  fos: the strength-reduction
    trials.  Prints the path of the file.
    \f
    Parameters
    ----------
    model, example
        The model file, or the name of a bundled example (exactly one).
    what
        One of :data:`PLOT_WHAT` (see :data:`rockdem.plots.WHAT`).
    out_file
        ``.png``, ``.svg`` or ``.pdf``; ``.gif`` for ``animation`` only.
        Written to a temporary file beside it and moved into place.
    joint
        One joint (name or joint-line number) for ``stress``.
    magnification
        Displacement scale for ``deformed`` and ``mechanism``.
    ids
        Block ids on ``model`` and ``failure``.
    dpi
        Resolution of raster output.
    overwrite
        Replace an existing file.
    quiet, debug
        No progress bars; a traceback instead of the one-line error.

    Raises
    ------
    typer.Exit
        Code 2 for bad input (an unknown figure, an unsupported extension, an
        option that does not apply to the figure, an existing file without
        ``--overwrite``, a bad model), 1 if the computation fails.
    """
    with _guard(debug):
        what = what.lower()
        _plot_options(what, out_file, joint, magnification, ids, dpi)
        _check_new_file(out_file, "--out", overwrite)
        from .analysis import analyse, factor_of_safety
        from .plots import plot_figure
        from .solver import build_system

        _, m, cfg = _load(model, example)
        system = build_system(m)
        options: dict[str, Any] = dict(_plot_units(cfg.units))
        if what != "stress":
            options.pop("stress_unit", None)
        chosen = _joints(joint, m, system)
        if chosen:
            options["joint"] = chosen[0]
        if magnification is not None:
            options["magnification"] = magnification
        if ids:
            options["block_ids"] = True
        with _progress(quiet, "plot") as bar:
            if what == "model":
                obj = system
            elif what in ("deformed", "stress"):
                task = bar.add_task("load steps", total=m.settings.load_steps)
                obj = analyse(system, progress=_step_hook(bar, task))
            else:
                task = bar.add_task("strength reduction trials", total=None)
                obj = factor_of_safety(system, **_fos_options(cfg),
                                       progress=_trial_hook(bar, task))
            bar.add_task(f"drawing {what}", total=None)
            target = _save_file(out_file, overwrite,
                                lambda tmp: plot_figure(obj, what, tmp, dpi=dpi, **options))
        typer.echo(str(target))


def _save_file(target: Path, overwrite: bool, write: Callable[[Path], Any]) -> Path:
    """Write through ``write(tmp)`` to a temporary file beside ``target``, then move it."""
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(prefix=f".{target.stem}.", suffix=target.suffix,
                                dir=target.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        write(tmp)
        _replace(tmp, target, "--out", overwrite)
    finally:
        tmp.unlink(missing_ok=True)
    return target


# ------------------------------------------------------------------ schema
@app.command()
def schema(
    out_file: Annotated[
        Path | None, typer.Option("--out", "-o", help="Write to this file instead of stdout.")
    ] = None,
    debug: DebugOpt = False,
) -> None:
    """Print the JSON Schema of model files (for editor completion)."""
    with _guard(debug):
        from .config import json_schema
        from .errors import InputError

        text = json.dumps(json_schema(), indent=2) + "\n"
        if out_file is None:
            typer.echo(text, nl=False)
            return
        try:
            out_file.write_text(text, encoding="utf-8")
        except OSError as exc:
            raise InputError(f"--out {out_file}", f"cannot be written ({exc.strerror})",
                             "give a file in an existing folder") from None


# ----------------------------------------------------------------- example
@example_app.command("list")
def example_list() -> None:
    """List the bundled examples."""
    from .examples import example_summary, list_examples

    for name in list_examples():
        out.print(f"{name:28s} {escape(example_summary(name))}")


@example_app.command("copy")
def example_copy(
    name: Annotated[str, typer.Argument(help="Example name (see `rockdem example list`).")],
    folder: Annotated[Path, typer.Argument(help="Folder to copy it into (created if needed).")],
    overwrite: OverwriteOpt = False,
    debug: DebugOpt = False,
) -> None:
    """Copy a bundled example into a folder, to edit and run."""
    with _guard(debug):
        from .examples import copy_example

        target = copy_example(name, folder, overwrite=overwrite)
        out.print(f"copied {name} to {escape(str(target))}")
        out.print(f"next: rockdem check {escape(str(target))}")


# --------------------------------------------------------------- stabilise
try:  # written separately; registered when its module is present
    from .cli_stabilise import stabilise as _stabilise
except ModuleNotFoundError as exc:  # only the module itself may be missing
    if exc.name != f"{__package__}.cli_stabilise":
        raise
else:
    app.command("stabilise")(_stabilise)


def main() -> None:
    """Console script entry point (``rockdem``, ``python -m rockdem``)."""
    app(prog_name="rockdem")


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
