"""``rockdem stabilise``: block removal, berm, support force and excavation stages.

Registered in :mod:`rockdem.cli` with ``app.command()(stabilise)``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

__all__ = ["stabilise"]


def stabilise(
    model: Annotated[
        Path | None,
        typer.Argument(help="Model file (.yaml, .yml, .json or .toml).", show_default=False),
    ] = None,
    example: Annotated[
        str | None,
        typer.Option(
            "--example", "-e", help="Use a bundled example instead of a file.", metavar="NAME"
        ),
    ] = None,
    target_fos: Annotated[
        float | None,
        typer.Option(
            "--target-fos",
            "-t",
            min=0.0,
            help="Factor of safety to reach "
            "(default: stabilisation.target_fos of the file, else 1.3).",
        ),
    ] = None,
    out_dir: Annotated[
        Path | None,
        typer.Option(
            "--out",
            "-o",
            help="Write stabilisation.json, one table per CSV and a "
            "picture per trial into this folder.",
            metavar="DIR",
        ),
    ] = None,
    overwrite: Annotated[
        bool, typer.Option("--overwrite", help="Replace result files that exist already.")
    ] = False,
    no_support: Annotated[
        bool, typer.Option("--no-support", help="Skip the support-force search.")
    ] = False,
    json_: Annotated[
        bool, typer.Option("--json", help="Print one JSON object to stdout (for scripts).")
    ] = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No notes on stderr.")] = False,
    debug: Annotated[
        bool, typer.Option("--debug", help="Show the full traceback of errors.")
    ] = False,
) -> None:
    """Stabilise a slope: remove unstable blocks until the target factor of safety is
    reached, and compare with a berm and a support force; analyse excavation stages.

    Every trial is reported: blocks removed, area removed, factor of safety.  When
    removal cannot reach the target (toppling) the output says so and what else is
    needed.  Exit code 0 either way.
    """
    from .cli import _guard, _header, _load

    with _guard(debug):
        from .errors import InputError
        from .stabilisation import study

        path, m, cfg = _load(model, example)
        if target_fos is not None and not target_fos > 0:
            raise InputError("--target-fos", f"{target_fos}", "give a value > 0")
        if (
            out_dir is not None
            and out_dir.exists()
            and not overwrite
            and (out_dir / "stabilisation.json").exists()
        ):
            raise InputError(
                str(out_dir / "stabilisation.json"),
                "already exists",
                "use --overwrite to replace it",
            )
        result = study(m, cfg, target_fos=target_fos, support=not no_support)
        doc = {**_header(path, m, cfg), "command": "stabilise", **summary(result)}
        if out_dir is not None:
            files = write(out_dir, result, doc)
            if not (quiet or json_):
                from .cli import err

                err.print(f"results written to {out_dir}/ ({len(files)} files)")
        if json_:
            from .cli import _echo_json

            _echo_json(doc)
            return
        print_summary(doc)


def summary(result) -> dict[str, Any]:
    """The JSON document of a study: target, verdict, message, needs, tables."""
    rem = result.removal
    return {
        "target_fos": result.target,
        "reached": bool(rem.reached) if rem is not None else None,
        "message": rem.message if rem is not None else "",
        "needs": rem.needs if rem is not None else "",
        **result.tables(),
        "excavation_message": result.excavation.message if result.excavation else "",
    }


def write(folder: Path, result, doc: dict[str, Any]) -> list[Path]:
    """stabilisation.json, one CSV per table and the pictures."""
    import csv
    import json

    from .output import jsonable
    from .stabilisation import save_pictures

    folder.mkdir(parents=True, exist_ok=True)
    files = []
    path = folder / "stabilisation.json"
    path.write_text(json.dumps(jsonable(doc), indent=1, allow_nan=False), encoding="utf-8")
    files.append(path)
    for name, rows in result.tables().items():
        if not rows:
            continue
        path = folder / f"{name}.csv"
        with path.open("w", newline="", encoding="utf-8") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            for r in rows:
                w.writerow(
                    {k: (" ".join(map(str, v)) if isinstance(v, list) else v) for k, v in r.items()}
                )
        files.append(path)
    files += save_pictures(result, folder)
    return files


def _f(v) -> str:
    return "-" if v is None else f"{v:.3g}"


def print_summary(doc: dict[str, Any]) -> None:
    from rich.markup import escape
    from rich.table import Table

    from .cli import out

    out.print(
        f"[bold]{escape(doc['model_name'])}[/bold]  ({escape(doc['model_file'])}): "
        f"target factor of safety {doc['target_fos']:g}"
    )
    if doc.get("removal"):
        table = Table(
            "trial",
            "removed blocks",
            "area removed",
            "FS",
            "target",
            "",
            title="block removal",
            box=None,
            pad_edge=False,
        )
        for r in doc["removal"]:
            ids = r["blocks_removed"]
            shown = ", ".join(map(str, ids[:12])) + (" ..." if len(ids) > 12 else "")
            table.add_row(
                f"{r['trial']}: {escape(r['label'])}",
                f"{len(ids)}: {shown}" if ids else "0",
                _f(r["area_removed"]),
                escape(r["fos_text"]),
                "yes" if r["reaches_target"] else "no",
                "accepted" if r["accepted"] else "",
            )
        out.print(table)
    table = Table(
        "measure",
        "area removed",
        "support force",
        "FS",
        "target",
        "note",
        title="measures side by side",
        box=None,
        pad_edge=False,
    )
    for r in doc["measures"]:
        table.add_row(
            escape(r["measure"]),
            _f(r["removed_area"]),
            _f(r["support_force"]),
            escape(r["fos_text"]),
            "yes" if r["reaches_target"] else "no",
            escape(r["note"][:90]),
        )
    out.print(table)
    if doc.get("designs"):
        table = Table(
            "design",
            "area removed",
            "FS",
            "target",
            "further removal",
            "total area",
            title="designs of the file",
            box=None,
            pad_edge=False,
        )
        for r in doc["designs"]:
            table.add_row(
                escape(r["design"]),
                _f(r["area_removed"]),
                escape(r["fos_text"]),
                "yes" if r["reaches_target"] else "no",
                str(len(r["further_blocks"])),
                _f(r["total_area_removed"]),
            )
        out.print(table)
    if doc.get("stages"):
        table = Table(
            "stage",
            "name",
            "verdict",
            "area removed",
            "joints failed",
            title="excavation stages",
            box=None,
            pad_edge=False,
        )
        for r in doc["stages"]:
            table.add_row(
                str(r["stage"]),
                escape(r["name"]),
                "stable" if r["stable"] else "UNSTABLE",
                _f(r["area_removed"]),
                str(r["new_failed_joints"]),
            )
        out.print(table)
        out.print(escape(doc["excavation_message"]))
    verdict = (
        "[bold green]REACHED[/bold green]" if doc["reached"] else "[bold red]NOT REACHED[/bold red]"
    )
    out.print(f"block removal: {verdict}: {escape(doc['message'])}")
    if doc["needs"]:
        out.print(f"needed instead: {escape(doc['needs'])}")
