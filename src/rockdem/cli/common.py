"""What every command shares: the app, the consoles, the options, the one-line
errors and exit codes, loading the model, progress bars and JSON output."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from .. import __version__
from ..exchange.results import FORMATS
from ..geometry.size import MAX_BLOCKS
from ..output import RESULT_FILES

EXIT_OK, EXIT_FAILED, EXIT_INPUT = 0, 1, 2

#: Options of the root command that every subcommand reads (set on each invocation).
_ROOT: dict[str, Any] = {"max_blocks": MAX_BLOCKS}

#: The files each command writes into its ``--out`` folder (glob patterns allowed).
_WRITES: dict[str, tuple[str, ...]] = {
    # the result files and those of --format (VTK, GeoJSON, DXF)
    "run": (*RESULT_FILES, *(f for files in FORMATS.values() for f in files)),
    "fos": (*RESULT_FILES, *(f for files in FORMATS.values() for f in files)),
    "report": ("report.html",),
    "stabilise": (
        "stabilisation.json",
        "measures.csv",
        "removal.csv",
        "designs.csv",
        "stages.csv",
        "stage_failures.csv",
        "trial-*.png",
        "stage-*.png",
    ),
}

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

#: exit code when the reader of stdout went away (``rockdem ... | head -1``):
#: the shell's for SIGPIPE, not 1, which says the computation failed
EXIT_PIPE = 141


class _Console(Console):
    def on_broken_pipe(self) -> None:
        """Stop quietly with EXIT_PIPE (rich exits 1; found by fuzzing)."""
        import os
        import sys

        self.quiet = True
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # (the interpreter flushes stdout at exit)
        raise SystemExit(EXIT_PIPE)


out = _Console(highlight=False, soft_wrap=True)
#: the narrowest the tables are laid out for: on a narrower terminal (or
#: COLUMNS), they are written as wide and the terminal wraps them, where rich
#: cut their cells to "…" (the text lines are never cut: soft_wrap)
MIN_WIDTH = 80
err = Console(stderr=True, highlight=False, soft_wrap=True)


# ---------------------------------------------------------------- options
ModelArg = Annotated[
    Path | None,
    typer.Argument(help="Model file (.yaml, .yml, .json or .toml).", show_default=False),
]
ExampleOpt = Annotated[
    str | None,
    typer.Option(
        "--example", "-e", help="Use a bundled example instead of a file.", metavar="NAME"
    ),
]
JsonOpt = Annotated[
    bool, typer.Option("--json", help="Print one JSON object to stdout (for scripts).")
]
OutOpt = Annotated[
    Path | None,
    typer.Option(
        "--out",
        "-o",
        help="Write blocks.csv, interfaces.csv, springs.csv and result.json into this folder.",
        metavar="DIR",
    ),
]
OverwriteOpt = Annotated[
    bool, typer.Option("--overwrite", help="Replace result files that exist already.")
]
QuietOpt = Annotated[
    bool, typer.Option("--quiet", "-q", help="No progress bars or notes on stderr.")
]
DebugOpt = Annotated[bool, typer.Option("--debug", help="Show the full traceback of errors.")]
JointOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--joint",
        "-j",
        help="Plot the stresses along this joint: a joint name, or "
        "the number (0, 1, ...) of a `joint_lines` trace.",
        metavar="NAME",
        show_default=False,
    ),
]


def _version(value: bool) -> None:
    if value:
        typer.echo(f"rockdem {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool | None,
        typer.Option(
            "--version", callback=_version, is_eager=True, help="Print the version and exit."
        ),
    ] = None,
    max_blocks: Annotated[
        int,
        typer.Option(
            "--max-blocks",
            min=1,
            envvar="ROCKDEM_MAX_BLOCKS",
            help="Refuse models of more blocks than this (a generated slope by its "
            "estimated size, before it is built). A factor of safety on 94,533 blocks "
            "peaked at 3.6 GB.",
            metavar="N",
        ),
    ] = MAX_BLOCKS,
) -> None:
    """Stability of jointed rock slopes by the discrete element method."""
    global _JSON_PRINTED
    _ROOT["max_blocks"] = max_blocks
    _JSON_PRINTED = False
    _show_warnings()
    _quiet_matplotlib_home()
    _tolerant_output()
    if out.width < MIN_WIDTH:  # (hostile round 7: COLUMNS=20 cut table cells to "2…")
        out.width = MIN_WIDTH


def _tolerant_output() -> None:
    """Write what a terminal's encoding cannot show as escapes (``\\xf6``).
    Found by hostile testing: under LANG=C (ASCII) or a Latin-1 terminal, a
    model named "Böschung – Süd" stopped `rockdem check` with "the analysis
    failed: UnicodeEncodeError", exit 1."""
    import codecs

    for stream in (sys.stdout, sys.stderr):
        reconfigure = getattr(stream, "reconfigure", None)
        encoding = getattr(stream, "encoding", None) or "utf-8"
        try:
            utf = codecs.lookup(encoding).name.startswith("utf")
        except LookupError:
            utf = False
        if reconfigure is not None and not utf:
            reconfigure(errors="backslashreplace")


def _matplotlib_home_note(record) -> bool:
    """False for matplotlib's two lines about a configuration folder it could
    not create (a read-only HOME): it uses a temporary folder instead, which
    is all the fix there is."""
    text = str(record.msg)
    return not text.startswith(
        ("mkdir -p failed for path", "Matplotlib created a temporary cache directory")
    )


def _quiet_matplotlib_home() -> None:
    """Drop matplotlib's warning about a read-only HOME (hostile round 7: two
    lines on stderr before every picture, a command's output being one line)."""
    import logging

    log = logging.getLogger("matplotlib")
    if _matplotlib_home_note not in log.filters:
        log.addFilter(_matplotlib_home_note)


def _check_solver_choice() -> None:
    """``ROCKDEM_SOLVER`` checked before any work, its error naming the
    variable (raised mid-analysis, the error read as the model file's).
    Checked as a model is named, not for every command (hostile round 7:
    checked in the root, a misspelt solver refused `rockdem run --help` and
    `rockdem example list`)."""
    import os

    if not os.environ.get("ROCKDEM_SOLVER", "").strip():
        return
    from ..linalg import _requested_solver

    _requested_solver()  # in the command's _guard: one line, and the JSON with --json


#: the ModelWarnings this command has printed (one line each), for its JSON
#: and result files: a warning that says a verdict does not hold must reach
#: them too, not only the terminal (found by fuzzing: joints 1e-6 stiff
#: "do not hold" the verdict on stderr while the JSON read "stable", no
#: warnings)
ISSUED: list[str] = []
#: the command printed its JSON object (an error after it adds no second one)
_JSON_PRINTED = False


def with_issued_warnings(doc: dict[str, Any]) -> dict[str, Any]:
    """``doc`` with the warnings printed so far first in its ``warnings``."""
    own = [w for w in doc.get("warnings") or [] if w not in ISSUED]
    return {**doc, "warnings": [*ISSUED, *own]}


def _show_warnings() -> None:
    """Print rockdem's :class:`~rockdem.errors.ModelWarning` as one ``warning:
    ...`` line each on the current stderr, once per command (a stabilise
    printed a bolt's warning again at every support force it tried; found by
    hostile testing), other warnings as Python shows them."""
    import warnings

    from ..errors import ModelWarning

    warnings.simplefilter("always", ModelWarning)
    ISSUED.clear()  # a new command
    if getattr(warnings.showwarning, "rockdem", False):
        return
    previous = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, ModelWarning):
            text = " ".join(str(message).split())  # one line, whatever the message
            if text not in ISSUED:
                err.print(f"warning: {escape(text)}")
                ISSUED.append(text)
        else:
            previous(message, category, filename, lineno, file, line)

    show.rockdem = True
    warnings.showwarning = show


# ------------------------------------------------------------------ errors
@contextmanager
def _guard(debug: bool) -> Iterator[None]:
    """Map errors to one line on stderr and an exit code (or a traceback with --debug)."""
    from pydantic import ValidationError

    from ..errors import InputError

    try:
        yield
    except typer.Exit:
        raise
    except (InputError, ValidationError) as exc:
        if debug:
            raise
        text = str(exc) if isinstance(exc, InputError) else str(exc).splitlines()[0]
        _error(_one_line(text), EXIT_INPUT)
        raise typer.Exit(EXIT_INPUT) from None
    except KeyboardInterrupt:
        err.print("interrupted")
        raise typer.Exit(130) from None
    except Exception as exc:
        if debug:
            raise
        _error(_one_line(_failure_text(exc)), EXIT_FAILED)
        raise typer.Exit(EXIT_FAILED) from None


def _error(text: str, code: int) -> None:
    """The one line on stderr; with ``--json`` also the JSON object scripts
    read from stdout, unless the command printed its own already (an empty
    stdout failed ``json.loads`` before the exit code was looked at)."""
    err.print(f"error: {escape(text)}")
    ctx = _current_context()
    if ctx is not None and ctx.params.get("json_") and not _JSON_PRINTED:
        typer.echo(json.dumps({"rockdem_version": __version__, "error": text, "exit_code": code}))


def _one_line(text: str) -> str:
    """``text`` on one line: line breaks and other control characters (in a
    file name, say) written as escapes, as Python writes them in a string."""
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def _failure_text(exc: Exception) -> str:
    """One line for an error that is not the input's fault (exit 1)."""
    if isinstance(exc, OSError):  # the file system refused while writing: full, read-only
        place = f"{exc.filename}: " if exc.filename else ""
        return (
            f"{place}a file could not be written or read ({exc.strerror or exc}); "
            "free some space, or give a folder you may write into"
        )
    if isinstance(exc, MemoryError):
        return f"out of memory (MemoryError: {exc}); make the model smaller (fewer blocks)"
    return (
        f"the analysis failed: {type(exc).__name__}: {exc} "
        "(run again with --debug for the traceback)"
    )


def _model_path(model: Path | None, example: str | None) -> Path:
    from ..errors import InputError
    from ..examples import example_path

    _check_solver_choice()
    if (model is None) == (example is None):
        raise InputError(
            "MODEL",
            "give either a model file or --example NAME" + (", not both" if model else ""),
            "see `rockdem example list`",
        )
    return example_path(example) if example is not None else model


def _load(model: Path | None, example: str | None):
    """Check the destination of the command (before any work), then read the model."""
    from ..config import load_model

    path = _model_path(model, example)
    _check_destination(path)
    m, cfg = load_model(path, max_blocks=_ROOT["max_blocks"])
    drawing = getattr(getattr(cfg, "geometry", None), "dxf", None)
    if drawing:  # the section's drawing is an input too: never written over
        _check_destination(path, (path.parent / drawing).resolve())
    return path, m, cfg


def _current_context() -> Any:
    """The context of the running command (None outside one).

    Typer vendors click from 0.2x on (``typer._click``); older typers use click.
    """
    import importlib

    for name in ("typer._click.globals", "click.globals"):
        try:
            module = importlib.import_module(name)
        except ImportError:
            continue
        ctx = module.get_current_context(silent=True)
        if ctx is not None:
            return ctx
    return None


def _check_destination(model: Path, *more: Path) -> None:
    """Refuse an ``--out`` the results could not be written to, or that would write
    over the model file (or ``more`` inputs: its DXF drawing), before the model is
    read or anything computed.

    Reads the ``--out`` and ``--overwrite`` options of the running command, so
    every command that writes is covered by the one call in :func:`_load`.
    """
    from .files import _check_out_file, _check_out_folder

    ctx = _current_context()
    if ctx is None:
        return
    params, command = ctx.params, ctx.info_name or ""
    overwrite = bool(params.get("overwrite", False))
    if params.get("out_dir") is not None:
        _check_out_folder(
            Path(params["out_dir"]),
            _WRITES.get(command, ()),
            overwrite=overwrite,
            inputs=[model, *more],
            temp_beside=command in ("run", "fos", "stabilise"),
            refuse_existing=command == "stabilise",
        )
    if params.get("out_file") is not None:
        _check_out_file(Path(params["out_file"]), inputs=[model, *more])


@contextmanager
def _progress(quiet: bool, label: str) -> Iterator[Progress]:
    """A progress bar on stderr (nothing with --quiet or when stderr is not a
    terminal), with the time elapsed and the time left at the rate so far (a
    study of 1e6 samples said nothing of the days it would take)."""
    progress = Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TextColumn("left"),
        TimeRemainingColumn(),
        console=err,
        transient=True,
        disable=quiet or not err.is_terminal,
    )
    with progress:
        yield progress


def _echo_json(data: dict[str, Any]) -> None:
    from ..result_tables import jsonable

    global _JSON_PRINTED
    typer.echo(json.dumps(jsonable(data), indent=1, allow_nan=False))
    _JSON_PRINTED = True


def _header(path: Path, model, cfg) -> dict[str, Any]:
    return {
        "rockdem_version": __version__,
        "model_file": str(path),
        "model_name": model.name,
        "units": cfg.units,
    }


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
    return cfg.analysis.strength_reduction.options()


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" + ("" if n == 1 else "s")


def _ids(values: list[int], limit: int = 40) -> str:
    text = ", ".join(str(v) for v in values[:limit])
    return text + (f", ... ({len(values) - limit} more)" if len(values) > limit else "")
