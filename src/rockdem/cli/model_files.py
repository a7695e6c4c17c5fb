"""``rockdem schema`` and ``rockdem example``: the format and the bundled models."""

from __future__ import annotations

import json
import shlex
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from .common import DebugOpt, _guard, out


# ------------------------------------------------------------------ schema
def schema(
    out_file: Annotated[
        Path | None, typer.Option("--out", "-o", help="Write to this file instead of stdout.")
    ] = None,
    overwrite: Annotated[
        bool, typer.Option("--overwrite", help="Replace the file if it exists.")
    ] = False,
    debug: DebugOpt = False,
) -> None:
    """Print the JSON Schema of model files (for editor completion).

    With --out the file is written whole or not at all, and an existing file
    (a model, say) is replaced only with --overwrite.
    """
    with _guard(debug):
        from ..config import json_schema
        from ..errors import InputError
        from .files import _check_new_file, _save_file

        text = json.dumps(json_schema(), indent=2) + "\n"
        if out_file is None:
            typer.echo(text, nl=False)
            return
        _check_new_file(out_file, "--out", overwrite)
        if not out_file.parent.is_dir():
            raise InputError(
                f"--out {out_file}", "is not in an existing folder", "give a file in a folder"
            )
        try:
            _save_file(out_file, overwrite, lambda tmp: tmp.write_text(text, encoding="utf-8"))
        except OSError as exc:
            raise InputError(
                f"--out {out_file}",
                f"cannot be written ({exc.strerror})",
                "give a file in a folder you may write into",
            ) from None


# ----------------------------------------------------------------- example
def example_list() -> None:
    """List the bundled examples."""
    from ..examples import example_summary, list_examples

    for name in list_examples():
        out.print(f"{name:28s} {escape(example_summary(name))}")


def example_copy(
    name: Annotated[str, typer.Argument(help="Example name (see `rockdem example list`).")],
    folder: Annotated[Path, typer.Argument(help="Folder to copy it into (created if needed).")],
    overwrite: Annotated[
        bool,
        typer.Option(
            "--overwrite",
            # (hostile round 7: it read "Replace result files", but replaces the
            # model file of that name, an edited copy of the example too)
            help="Replace the model file of that name if it exists (an edited copy too).",
        ),
    ] = False,
    debug: DebugOpt = False,
) -> None:
    """Copy a bundled example into a folder, to edit and run.

    The copy is never written through a link (a link in the folder could
    point anywhere).
    """
    with _guard(debug):
        from ..errors import InputError
        from ..examples import copy_example, example_path

        target = folder / example_path(name).name
        if target.is_symlink():
            raise InputError(
                str(target),
                "is a link; the example is not written through it",
                "remove the link, or copy into another folder",
            )
        if target.is_dir():
            raise InputError(str(target), "is a folder", "remove it, or copy into another folder")
        from .files import _check_out_folder

        _check_out_folder(folder, (), overwrite=overwrite, inputs=[], option="FOLDER")
        target = copy_example(name, folder, overwrite=overwrite)
        out.print(f"copied {name} to {escape(str(target))}")
        # quoted for the shell: a folder with a space split the command in two
        out.print(f"next: rockdem check {escape(shlex.quote(str(target)))}")
