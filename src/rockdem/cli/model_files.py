"""``rockdem schema`` and ``rockdem example``: the format and the bundled models."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from .common import DebugOpt, OverwriteOpt, _guard, out


# ------------------------------------------------------------------ schema
def schema(
    out_file: Annotated[
        Path | None, typer.Option("--out", "-o", help="Write to this file instead of stdout.")
    ] = None,
    debug: DebugOpt = False,
) -> None:
    """Print the JSON Schema of model files (for editor completion)."""
    with _guard(debug):
        from ..config import json_schema
        from ..errors import InputError

        text = json.dumps(json_schema(), indent=2) + "\n"
        if out_file is None:
            typer.echo(text, nl=False)
            return
        try:
            out_file.write_text(text, encoding="utf-8")
        except OSError as exc:
            raise InputError(
                f"--out {out_file}",
                f"cannot be written ({exc.strerror})",
                "give a file in an existing folder",
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
    overwrite: OverwriteOpt = False,
    debug: DebugOpt = False,
) -> None:
    """Copy a bundled example into a folder, to edit and run."""
    with _guard(debug):
        from ..examples import copy_example

        target = copy_example(name, folder, overwrite=overwrite)
        out.print(f"copied {name} to {escape(str(target))}")
        out.print(f"next: rockdem check {escape(str(target))}")
