"""The exchange formats ``rockdem run`` and ``rockdem fos`` write beside the CSV and
JSON results (``--format vtk,geojson,dxf``)."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from ..errors import InputError

__all__ = ["DXF_FILE", "FORMATS", "format_files", "parse_formats", "result_writer"]

#: The results drawing written into a results folder.
DXF_FILE = "result.dxf"
#: Formats beside CSV and JSON, and the files each writes into the results folder.
FORMATS = {
    "vtk": ("blocks.vtu", "interfaces.vtu"),
    "geojson": ("section.geojson",),
    "dxf": (DXF_FILE,),
}
#: Always written: accepted in --format and ignored.
ALWAYS = ("csv", "json")


def parse_formats(values: Iterable[str] | None, option: str = "--format") -> tuple[str, ...]:
    """The formats named in ``--format`` values (comma-separated or repeated; ``all``)."""
    out: list[str] = []
    for value in values or ():
        for name in str(value).split(","):
            name = name.strip().lower()
            if not name or name in ALWAYS:
                continue
            if name == "all":
                out.extend(FORMATS)
            elif name in FORMATS:
                out.append(name)
            else:
                raise InputError(
                    f"{option} {value}",
                    f"{name!r} is not a result format",
                    f"use {', '.join(FORMATS)} or all (CSV and JSON are always written)",
                )
    return tuple(dict.fromkeys(out))


def format_files(formats: Iterable[str]) -> tuple[str, ...]:
    """The files the formats write."""
    return tuple(name for f in formats for name in FORMATS[f])


def result_writer(
    formats: Iterable[str], analysis, tables, *, failed=None, units=None, units_note: str = ""
) -> Callable[[Path], Any]:
    """A function writing the formats' files into a folder (the results' temporary one)."""
    formats = tuple(formats)

    def write(folder: Path) -> None:
        if "vtk" in formats:
            from .vtk import write_vtk

            write_vtk(folder, analysis, tables)
        if "geojson" in formats:
            from .geojson import GEOJSON_FILE, write_geojson

            write_geojson(
                folder / GEOJSON_FILE, analysis.system.model, analysis, tables, units=units_note
            )
        if "dxf" in formats:
            from .dxf_out import write_dxf

            model = analysis.system.model
            write_dxf(folder / DXF_FILE, model, analysis, failed=failed, units=units)

    return write
