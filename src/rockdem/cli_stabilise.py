"""``rockdem stabilise``: block removal, berm, support force and excavation stages.

Registered in :mod:`rockdem.cli` with ``app.command()(stabilise)``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any

import typer

__all__ = ["stabilise"]


#: bracket width of every factor of safety the stabilisation study rates
RATING_WIDTH = 0.01


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
            help="Factor of safety to reach, 0 < F <= 20 "
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
        from .output import units_summary
        from .stabilisation import study
        from .units import parse_units

        path, m, cfg = _load(model, example)
        if target_fos is not None and not 0 < target_fos <= 20:
            # the same range as stabilisation.target_fos in a model file
            raise InputError("--target-fos", f"{target_fos} is out of range", "give 0 < F <= 20")
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
        units = parse_units(cfg.units)
        with _progress_line(quiet or json_) as note:
            try:
                result = study(
                    m,
                    cfg,
                    target_fos=target_fos,
                    support=not no_support,
                    width=RATING_WIDTH,
                    progress=note,
                )
            except InputError as exc:
                if not exc.where.startswith("stabilisation."):
                    raise
                # a key of the model file found wrong only once the mechanism
                # is known (where a support acts): name the file with it
                raise InputError(f"{path}: {exc.where}", exc.problem, exc.fix) from None
        doc = {
            **_header(path, m, cfg),
            "unit_system": units_summary(units),
            "command": "stabilise",
            **summary(result),
        }
        if out_dir is not None:
            files = write(out_dir, result, doc, units)
            if not (quiet or json_):
                from .cli import err

                err.print(f"results written to {out_dir}/ ({len(files)} files)")
        if json_:
            from .cli import _echo_json

            _echo_json(doc)
            return
        print_summary(doc, units)
        width = cfg.analysis.strength_reduction.width
        if width != RATING_WIDTH:
            from .cli import out

            # plane-failure-water: "slope as it is 1.106" here, 1.1072 by `rockdem fos`
            out.print(
                f"FS here: the middle of a strength-reduction bracket {RATING_WIDTH:g} wide; "
                f"`rockdem fos` narrows it to {width:g} (analysis.strength_reduction.width), "
                "so the slope as it is may read slightly differently there",
                soft_wrap=False,
            )


@contextmanager
def _progress_line(quiet: bool) -> Iterator[Callable[[str], None]]:
    """A spinner on stderr with what the study is computing and the time so far
    (nothing when quiet or when stderr is not a terminal); yields the note hook."""
    from rich.markup import escape
    from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

    from .cli import err

    bar = Progress(
        SpinnerColumn(),
        TimeElapsedColumn(),
        TextColumn("{task.description}"),
        console=err,
        transient=True,
        disable=quiet or not err.is_terminal,
    )
    with bar:
        task = bar.add_task("stabilisation study", total=None)

        def note(text: str) -> None:
            bar.update(task, description=escape(text))

        yield note


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


#: every file a stabilisation writes (the tables and pictures it has)
WRITTEN = (
    "stabilisation.json",
    "measures.csv",
    "removal.csv",
    "designs.csv",
    "stages.csv",
    "stage_failures.csv",
    "trial-[0-9][0-9]*.png",
    "stage-[0-9][0-9]*.png",
)


def write(folder: Path, result, doc: dict[str, Any], units=None) -> list[Path]:
    """stabilisation.json, one CSV per table (headings with units when the model
    names them) and the pictures.  Replacing an earlier stabilisation's
    results (--overwrite), the files of it that this one does not write go
    too: its stages.csv and stage pictures stayed beside a study without
    stages, as if they were this model's (found by hostile testing)."""
    import csv
    import json
    import re

    from .output import column_units, csv_header, csv_text, staged_folder
    from .result_tables import jsonable
    from .stabilisation import save_pictures

    earlier = []
    if (folder / "stabilisation.json").is_file():
        # only the names this writes: a glob took a user's 'trial-00-marked.png' too
        ours = re.compile(r"(trial|stage)-\d{2,}\.png")
        earlier = [
            p
            for pattern in WRITTEN
            for p in folder.glob(pattern)
            if p.is_file() and ("*" not in pattern or ours.fullmatch(p.name))
        ]
    with staged_folder(folder) as tmp:  # all or nothing
        path = tmp / "stabilisation.json"
        path.write_text(json.dumps(jsonable(doc), indent=1, allow_nan=False), encoding="utf-8")
        for name, rows in result.tables().items():
            if not rows:
                continue
            columns = list(rows[0])
            unit_map = column_units(columns, units)
            with (tmp / f"{name}.csv").open("w", newline="", encoding="utf-8") as fh:
                w = csv.writer(fh, lineterminator="\n")
                w.writerow([csv_header(c, unit_map) for c in columns])
                for r in rows:
                    w.writerow(
                        [
                            " ".join(map(str, v))
                            if isinstance(v, list)
                            else csv_text(v)
                            if isinstance(v, str)
                            else v
                            for v in r.values()
                        ]
                    )
        save_pictures(result, tmp)
        names = sorted(p.name for p in tmp.iterdir())
    for path in earlier:
        if path.name not in names:
            path.unlink(missing_ok=True)
    return [folder / name for name in names]


def _f(v) -> str:
    return "-" if v is None else f"{v:.3g}"


#: the footnote of a factor of safety printed as "> X"
MORE_THAN = (
    "> X: no failure at any strength factor tried, up to X, the largest the search "
    "tries: the factor of safety is at least X."
)


def print_summary(doc: dict[str, Any], units=None) -> None:
    """The study as tables: every column headed, units on areas and forces, notes
    wrapped at word boundaries (never cut)."""
    from rich.markup import escape
    from rich.table import Table

    from .cli import out
    from .units import UNKNOWN

    units = units or UNKNOWN
    area = "area removed" + units.suffix("area")
    force = "support force" + units.suffix("force")

    def table(title: str, *columns: str) -> Table:
        t = Table(title=title, box=None, pad_edge=False, title_justify="left")
        for c in columns:
            t.add_column(c, overflow="fold")
        return t

    # notes inline on a wide console; on a narrow one under the table, where they
    # wrap between words at the full width (a narrow column would cut them)
    inline = out.width >= 120
    footnotes: list[str] = []

    def note(text: str) -> str:
        if inline or not text:
            return escape(text)
        footnotes.append(text)
        return f"note {len(footnotes)}"

    def boundary_warning(what: str, row: dict) -> None:
        """Where a trial's or design's mechanism reaches a fixed side of the model."""
        if row.get("boundary"):
            out.print(
                f"[yellow]warning[/yellow]: {escape(what)} (FS {escape(row['fos_text'])}): "
                f"{escape(row['boundary'])}",
                soft_wrap=False,
            )

    out.print(
        f"[bold]{escape(doc['model_name'])}[/bold]  ({escape(doc['model_file'])}): "
        f"target factor of safety {doc['target_fos']:g}"
    )
    texts: list[str] = []
    if doc.get("removal"):
        t = table("block removal", "trial", "removed blocks", area, "FS", "target", "design")
        for r in doc["removal"]:
            ids = r["blocks_removed"]
            shown = ", ".join(map(str, ids[:12])) + (" ..." if len(ids) > 12 else "")
            texts.append(r["fos_text"])
            t.add_row(
                f"{r['trial']}: {escape(r['label'])}",
                f"{len(ids)}: {shown}" if ids else "0",
                _f(r["area_removed"]),
                escape(r["fos_text"]),
                "yes" if r["reaches_target"] else "no",
                "accepted" if r["accepted"] else "tried",
            )
        out.print(t)
        # "design: accepted" on a row below the target read as an approval
        out.print(
            "design: accepted = the next round starts from it (the last accepted is the "
            "result); it meets the target only where 'target' says yes",
            soft_wrap=False,
        )
        for r in doc["removal"]:
            boundary_warning(f"trial {r['trial']}", r)
    t = table("measures side by side", "measure", area, force, "FS", "target", "note")
    for r in doc["measures"]:
        texts.append(r["fos_text"])
        t.add_row(
            escape(r["measure"]),
            _f(r["removed_area"]),
            _f(r["support_force"]),
            escape(r["fos_text"]),
            "yes" if r["reaches_target"] else "no",
            note(r["note"]),
        )
    shown = 0

    def print_with_notes(t: Table) -> None:
        nonlocal shown
        out.print(t)
        for k, text in enumerate(footnotes[shown:], start=shown + 1):
            out.print(f"note {k}: {escape(text)}", soft_wrap=False)
        shown = len(footnotes)

    print_with_notes(t)
    if doc.get("designs"):
        t = table(
            "designs of the file",
            "design",
            area,
            "FS",
            "target",
            "further blocks removed",
            "total " + area,
            "note",
        )
        for r in doc["designs"]:
            texts.append(r["fos_text"])
            t.add_row(
                escape(r["design"]),
                _f(r["area_removed"]),
                escape(r["fos_text"]),
                "yes" if r["reaches_target"] else "no",
                str(len(r["further_blocks"])),
                _f(r["total_area_removed"]),
                note(r["note"]),
            )
        print_with_notes(t)
        for r in doc["designs"]:
            boundary_warning(f"design {r['design']}", r)
    if doc.get("stages"):
        t = table("excavation stages", "stage", "name", "verdict", area, "joints failed")
        for r in doc["stages"]:
            t.add_row(
                str(r["stage"]),
                escape(r["name"]),
                "stable" if r["stable"] else "UNSTABLE",
                _f(r["area_removed"]),
                str(r["new_failed_joints"]),
            )
        out.print(t)
        out.print(escape(doc["excavation_message"]))
    if any(x.startswith(">") for x in texts):
        out.print(escape(MORE_THAN), soft_wrap=False)
    verdict = (
        "[bold green]REACHED[/bold green]" if doc["reached"] else "[bold red]NOT REACHED[/bold red]"
    )
    out.print(f"block removal: {verdict}: {escape(doc['message'])}", soft_wrap=False)
    if doc["needs"]:
        out.print(f"needed instead: {escape(doc['needs'])}", soft_wrap=False)
