"""The ``rockdem`` command line: check, run, factor of safety, report and plots.

One function per subcommand; each only parses its options, calls the public
API (:func:`rockdem.config.load_model`, :func:`rockdem.analyse`,
:func:`rockdem.factor_of_safety`, :func:`rockdem.report.write_report`,
:func:`rockdem.plots.plot_figure`) and writes.

The commands are grouped in modules: :mod:`~rockdem.cli.checks`,
:mod:`~rockdem.cli.analyses` (run, fos), :mod:`~rockdem.cli.figures` (report,
plot) and :mod:`~rockdem.cli.model_files` (schema, example); what they share is
in :mod:`~rockdem.cli.common` and :mod:`~rockdem.cli.files`.  ``stabilise``
lives in :mod:`rockdem.cli_stabilise`.  All are registered on :data:`app` here.

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
141
    The reader of the output went away (``rockdem ... | head -1``); files
    the command writes are complete.
"""

from __future__ import annotations

import os
import sys

from .analyses import _print_fos as _print_fos
from .analyses import _print_run as _print_run
from .analyses import _write as _write
from .analyses import fos as fos
from .analyses import run as run
from .checks import _check_summary as _check_summary
from .checks import _print_check as _print_check
from .checks import check as check
from .common import EXIT_FAILED as EXIT_FAILED
from .common import EXIT_INPUT as EXIT_INPUT
from .common import EXIT_OK as EXIT_OK
from .common import DebugOpt as DebugOpt
from .common import ExampleOpt as ExampleOpt
from .common import JointOpt as JointOpt
from .common import JsonOpt as JsonOpt
from .common import ModelArg as ModelArg
from .common import OutOpt as OutOpt
from .common import OverwriteOpt as OverwriteOpt
from .common import QuietOpt as QuietOpt
from .common import _echo_json as _echo_json
from .common import _fos_options as _fos_options
from .common import _guard as _guard
from .common import _header as _header
from .common import _ids as _ids
from .common import _load as _load
from .common import _model_path as _model_path
from .common import _plural as _plural
from .common import _progress as _progress
from .common import _root as _root
from .common import _step_hook as _step_hook
from .common import _trial_hook as _trial_hook
from .common import _version as _version
from .common import app as app
from .common import err as err
from .common import example_app as example_app
from .common import out as out
from .exchange import import_dxf as import_dxf
from .figures import PLOT_FORMATS as PLOT_FORMATS
from .figures import PLOT_WHAT as PLOT_WHAT
from .figures import REPORT_FILE as REPORT_FILE
from .figures import _joints as _joints
from .figures import _plot_options as _plot_options
from .figures import _plot_units as _plot_units
from .figures import _save_report as _save_report
from .figures import plot as plot
from .figures import report as report
from .files import _check_new_file as _check_new_file
from .files import _replace as _replace
from .files import _save_file as _save_file
from .files import _umask as _umask
from .le import le as le
from .model_files import example_copy as example_copy
from .model_files import example_list as example_list
from .model_files import schema as schema
from .study import study as _study

# ---------------------------------------------------------------- commands
# registered here, in the order `rockdem --help` lists them
app.command()(check)
app.command()(run)
app.command()(fos)
app.command()(le)
app.command()(report)
app.command()(plot)
app.command("study")(_study)
app.command()(schema)
app.command("import")(import_dxf)
example_app.command("list")(example_list)
example_app.command("copy")(example_copy)

# --------------------------------------------------------------- stabilise
try:  # written separately; registered when its module is present
    from ..cli_stabilise import stabilise as _stabilise
except ModuleNotFoundError as exc:  # only the module itself may be missing
    if exc.name != f"{__package__.rpartition('.')[0]}.cli_stabilise":
        raise
else:
    app.command("stabilise")(_stabilise)


def main() -> None:
    """Console script entry point (``rockdem``, ``python -m rockdem``).

    An empty argument is refused before anything runs.  A usage error
    (unknown option, bad value, missing argument) is one line on stderr
    naming the command's help, exit code 2, like every other error (click
    prints three lines: usage, a hint and the error).
    """
    _refuse_empty_arguments(sys.argv[1:])
    try:
        code = app(prog_name="rockdem", standalone_mode=False)
    except Exception as exc:  # click's own errors carry format_message and exit_code
        message = getattr(exc, "format_message", None)
        if message is None:
            raise
        if type(exc).__name__ == "NoArgsIsHelpError":  # `rockdem` alone: the help
            sys.stdout.write(f"{message()}\n")
            sys.exit(2)
        ctx = getattr(exc, "ctx", None)
        hint = f"; see `{ctx.command_path} --help`" if ctx is not None else ""
        sys.stderr.write(f"error: {message().rstrip('.')}{hint}\n")
        sys.exit(getattr(exc, "exit_code", 2))
    _exit(code if isinstance(code, int) else 0)


def _exit(code: int) -> None:
    """Exit with ``code``; after Ctrl-C stopped a study on its own local Dask
    cluster, without the interpreter's exit handlers (its files are closed
    by then): distributed's close the cluster again and join its threads,
    and in two full test-suite runs the process had not exited 60 s after
    the Ctrl-C, though the study's own teardown is bounded to 15 s."""
    on_dask = sys.modules.get("rockdem.studies.on_dask")
    if code == 130 and on_dask is not None and on_dask.OWN_CLUSTER_INTERRUPTED:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(130)
    sys.exit(code)


def _refuse_empty_arguments(args: list[str]) -> None:
    """An empty argument is never meant (an unset shell variable, ``--out "$DIR"``):
    as a path it would be the current folder.  One line naming it, exit 2."""
    for i, arg in enumerate(args):
        option = arg[:-1] if arg.startswith("--") and arg.endswith("=") else None
        if arg == "":
            option = args[i - 1] if i and args[i - 1].startswith("-") else f"argument {i + 1}"
        if option is not None:
            sys.stderr.write(
                f"error: {option}: empty value; give one (is a shell variable unset?)\n"
            )
            sys.exit(2)
