"""``rockdem report`` and ``rockdem plot``: the HTML report and single figures."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path
from typing import Annotated, Any

import typer

from .common import (
    ISSUED,
    DebugOpt,
    ExampleOpt,
    JointOpt,
    ModelArg,
    QuietOpt,
    _fos_options,
    _guard,
    _load,
    _progress,
)
from .files import _check_new_file, _replace, _save_file

# ------------------------------------------------------------ report, plot
REPORT_FILE = "report.html"
#: The figures of ``rockdem plot --what`` (the keys of :data:`rockdem.plots.WHAT`; kept
#: here so that the command line starts without importing matplotlib).
PLOT_WHAT = (
    "model",
    "failure",
    "deformed",
    "mechanism",
    "stress",
    "progressive",
    "animation",
    "fos",
)
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
    from ..errors import InputError

    names = [j.name for j in model.joints]
    used = {names[k] for k in set(system.interfaces.joint.tolist())}
    n_lines = 0 if model.joint_lines is None else len(model.joint_lines)
    chosen: list[str | int] = []
    for value in values or []:
        if value in names:
            if value not in used:
                raise InputError(
                    f"--joint {value}",
                    "no interface of the model has this joint",
                    f"use one of {', '.join(n for n in names if n in used)}",
                )
            chosen.append(value)
        elif value.isdigit() and int(value) < n_lines:
            chosen.append(int(value))
        else:
            lines = f", or a joint line 0-{n_lines - 1}" if n_lines else ""
            raise InputError(
                f"--joint {value}",
                "is not a joint of the model",
                f"use one of {', '.join(names)}{lines}",
            )
    return chosen


def _save_report(folder: Path, overwrite: bool, model, **options) -> Path:
    """``write_report`` into a temporary folder inside ``folder``, then move the file."""
    from ..report import write_report

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


def report(
    model: ModelArg = None,
    example: ExampleOpt = None,
    out_dir: Annotated[
        Path,
        typer.Option(
            "--out",
            "-o",
            help=f"Folder to write {REPORT_FILE} into (created if needed).",
            metavar="DIR",
            show_default=False,
        ),
    ] = ...,
    svg: Annotated[
        bool, typer.Option("--svg", help="Embed the figures as SVG (vector) instead of PNG.")
    ] = False,
    no_animation: Annotated[
        bool, typer.Option("--no-animation", help="Leave out the animated GIF (smaller, faster).")
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
        from ..analysis import analyse
        from ..output import check_output_dir
        from ..solver import build_system
        from ..strength_reduction import factor_of_safety

        # the progress hooks are looked up on the package at call time, so that
        # rockdem.cli._step_hook and rockdem.cli._trial_hook stay patchable
        from . import _step_hook, _trial_hook

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
                out_dir,
                overwrite,
                m,
                analysis=analysis,
                fos=fos,
                units=cfg.units or None,
                joints=joints,
                image_format="svg" if svg else "png",
                animation=not no_animation,
                notes=list(ISSUED),
                **_plot_units(cfg.units),
            )
        typer.echo(str(target))


#: the finest resolution drawn (a page-wide figure at 1,200 dpi is ~10,000 pixels wide)
MAX_DPI = 1200


def _plot_options(
    what: str,
    out_file: Path,
    joint: list[str] | None,
    magnification: float | None,
    ids: bool,
    dpi: int,
) -> None:
    """Check the ``plot`` options that need no model (one clear error each)."""
    from ..errors import InputError

    if what not in PLOT_WHAT:
        raise InputError(
            f"--what {what}", "is not a figure rockdem draws", f"use one of {', '.join(PLOT_WHAT)}"
        )
    if out_file.is_dir():
        raise InputError(
            f"--out {out_file}",
            "is a folder",
            f"give a file name such as {out_file / (what + '.png')}",
        )
    ext = out_file.suffix.lower()
    if ext not in PLOT_FORMATS:
        raise InputError(
            f"--out {out_file}",
            f"unsupported file type {ext!r}" if ext else "has no extension",
            "end the name in .png, .svg or .pdf (.gif for --what animation)",
        )
    if what == "animation" and ext != ".gif":
        raise InputError(
            f"--out {out_file}", "the animation is written as a GIF", "end the name in .gif"
        )
    if what != "animation" and ext == ".gif":
        raise InputError(
            f"--out {out_file}",
            "only --what animation is written as a GIF",
            "end the name in .png, .svg or .pdf",
        )
    if joint and what != "stress":
        raise InputError("--joint", "applies to --what stress only", "leave it out")
    if joint and len(joint) > 1:
        raise InputError(
            "--joint",
            "give one joint per stress plot",
            "run once per joint (`rockdem report` takes several)",
        )
    if magnification is not None and what not in ("deformed", "mechanism"):
        raise InputError(
            "--magnification", "applies to --what deformed or mechanism only", "leave it out"
        )
    if magnification is not None and not 0 < magnification < 1e12:
        raise InputError(
            f"--magnification {magnification:g}",
            "is out of range (0 < factor < 1e12)",
            "give a factor such as 100",
        )
    if ids and what not in ("model", "failure"):
        raise InputError("--ids", "applies to --what model or failure only", "leave it out")
    if not 1 <= dpi <= MAX_DPI:
        raise InputError(
            f"--dpi {dpi}", f"is out of range 1 to {MAX_DPI}", "give for example 150 (300 to print)"
        )


def plot(
    model: ModelArg = None,
    example: ExampleOpt = None,
    what: Annotated[
        str,
        typer.Option(
            "--what",
            "-w",
            help="The figure: " + ", ".join(PLOT_WHAT) + ".",
            metavar="FIGURE",
            show_default=False,
        ),
    ] = ...,
    out_file: Annotated[
        Path,
        typer.Option(
            "--out",
            "-o",
            help="File to write: .png, .svg or .pdf (.gif for "
            "animation); the format follows the extension.",
            metavar="FILE",
            show_default=False,
        ),
    ] = ...,
    joint: JointOpt = None,
    magnification: Annotated[
        float | None,
        typer.Option(
            "--magnification",
            "-m",
            help="Scale of the displacements (deformed, mechanism); default: automatic.",
            metavar="X",
            show_default=False,
        ),
    ] = None,
    ids: Annotated[
        bool, typer.Option("--ids", help="Label the blocks with their ids (model, failure).")
    ] = False,
    dpi: Annotated[
        int,
        typer.Option(
            "--dpi", help="Resolution of PNG and GIF output (GIF at most 100).", metavar="N"
        ),
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
    the failed end of the strength-reduction search (the mechanism; the title
    names its factor F and the factor of safety), found with the model file's
    strength-reduction settings.  fos: the strength-reduction trials.  Prints
    the path of the file.
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
        from ..analysis import analyse
        from ..plots import plot_figure
        from ..solver import build_system
        from ..strength_reduction import factor_of_safety

        # the progress hooks are looked up on the package at call time, so that
        # rockdem.cli._step_hook and rockdem.cli._trial_hook stay patchable
        from . import _step_hook, _trial_hook

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
                obj = factor_of_safety(system, **_fos_options(cfg), progress=_trial_hook(bar, task))
            bar.add_task(f"drawing {what}", total=None)
            target = _save_file(
                out_file, overwrite, lambda tmp: plot_figure(obj, what, tmp, dpi=dpi, **options)
            )
        typer.echo(str(target))
