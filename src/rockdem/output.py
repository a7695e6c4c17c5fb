"""Result files: tables of blocks, interfaces and springs, and ``result.json``.

:func:`write_results` writes ``blocks.csv``, ``interfaces.csv``,
``springs.csv`` and ``result.json`` (the same tables plus the summary, the
model echo and the rockdem version) into a folder, all or nothing: the files
are written into a temporary folder beside the target and moved into place
only when all of them are complete.  Existing result files are replaced only
with ``overwrite=True``.

When the model's ``units`` note names a system (:func:`rockdem.units.parse_units`:
"kN, m, kPa", "t, m, t/m^2", ...) every CSV heading with a unit carries it in
brackets, ``area [m^2]``, ``normal_force [kN]``, ``normal_stress [kPa]``,
``ux [m]``, ``rotation [rad]``, and ``result.json`` maps the columns to their
units under ``column_units`` (its tables keep the bare names).

The columns and their sign conventions: :mod:`rockdem.result_tables`.
"""

from __future__ import annotations

import csv
import json
import math
import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from .errors import InputError
from .result_tables import jsonable

#: The files :func:`write_results` writes.
RESULT_FILES = ("blocks.csv", "interfaces.csv", "springs.csv", "bolts.csv", "result.json")

__all__ = [
    "RESULT_FILES",
    "check_output_dir",
    "column_units",
    "csv_header",
    "units_summary",
    "write_results",
]


# --------------------------------------------------------------- writing
def check_output_dir(
    folder: str | Path,
    *,
    overwrite: bool = False,
    extra_files: tuple[str, ...] = (),
    other_files: tuple[str, ...] = (),
) -> Path:
    """Fail early if results cannot be written to ``folder``.

    ``extra_files`` are the files of the exchange formats asked for
    (:mod:`rockdem.exchange.results`), checked like the others;
    ``other_files`` those of the formats not asked for: when results are
    overwritten, such files of an earlier run would stay beside the new
    results, another model's VTK beside this one's tables (found by
    fuzzing), so they are refused rather than deleted.

    Raises
    ------
    InputError
        ``folder`` is a file, or holds result files and ``overwrite`` is False.
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"--out {folder}", "is a file, not a folder", "give a folder")
    for name in extra_files:
        if (folder / name).is_dir():
            raise InputError(
                f"--out {folder}", f"{name} is a folder", "remove it or write to another folder"
            )
    stale = [name for name in other_files if (folder / name).exists()]
    if overwrite and stale and any((folder / name).exists() for name in RESULT_FILES):
        raise InputError(
            f"--out {folder}",
            f"holds {', '.join(stale)} of an earlier run, which this run would not replace: "
            "the folder would mix two results",
            "remove them, write to another folder, or ask for that format too (--format)",
        )
    if not overwrite:
        for name in (*RESULT_FILES, *extra_files):
            if (folder / name).exists():
                raise InputError(
                    f"--out {folder}",
                    f"already holds {name}",
                    "use --overwrite to replace the results, or another folder",
                )
    return folder


#: The quantity of every column with a unit (rockdem.units.Units attribute names).
COLUMN_QUANTITY = {
    **dict.fromkeys("area area_removed removed_area total_area_removed free_area".split(), "area"),
    **dict.fromkeys(
        "weight water_fx water_fy normal_force shear_force support_force free_weight force "
        "axial_force axial_capacity".split(),
        "force",
    ),
    **dict.fromkeys(
        "normal_stress shear_stress sigma tau pore_pressure capacity strength_at_factor".split(),
        "stress",
    ),
    **dict.fromkeys(
        "centroid_x centroid_y start_x start_y end_x end_y x y length depth".split(), "length"
    ),
    **dict.fromkeys("ux uy extension offset".split(), "displacement"),
    "unit_weight": "unit_weight",
}


def column_units(columns, units=None) -> dict[str, str]:
    """The unit of each column that has one (``{"area": "m^2", ...}``); empty when
    ``units`` (a :class:`~rockdem.units.Units`) names no system."""
    if units is None or not units.known:
        return {}
    out = {c: units.unit(COLUMN_QUANTITY[c]) for c in columns if c in COLUMN_QUANTITY}
    if "rotation" in columns:
        out["rotation"] = "rad"
    return out


def units_summary(units) -> dict[str, str | None]:
    """The unit of each quantity as plain data (all None when not known)."""
    names = ("force", "length", "stress", "area", "displacement", "unit_weight")
    return {q: (units.unit(q) if units is not None else None) for q in names}


def csv_header(column: str, unit_map: dict[str, str]) -> str:
    """A CSV heading: ``"normal_stress [kPa]"`` when the unit is known, else the name."""
    unit = unit_map.get(column)
    return f"{column} [{unit}]" if unit else column


def _write_csv(path: Path, rows: list[dict[str, Any]], columns: list[str], units=None) -> None:
    unit_map = column_units(columns, units)
    header = [csv_header(c, unit_map) for c in columns]
    with path.open("w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh, lineterminator="\n")
        writer.writerow(header)
        for row in rows:
            writer.writerow([_csv_value(row[c]) for c in columns])


def _csv_value(v: Any) -> Any:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):  # (-0.0, an open point's stress, is written 0.0)
        return (
            repr(v + 0.0) if math.isfinite(v) else ("inf" if v > 0 else "-inf" if v < 0 else "nan")
        )
    if isinstance(v, str):
        return csv_text(v)
    return v


#: first characters that make a spreadsheet read a cell as a formula
_FORMULA_START = ("=", "+", "-", "@", "\t", "\r")


def csv_text(text: str) -> str:
    """A name for a CSV cell, with a leading ``'`` where a spreadsheet would
    run it as a formula (a joint named ``=HYPERLINK(...)`` was written as it
    stands; found by hostile testing).  Numbers written as text are kept."""
    if not text.startswith(_FORMULA_START):
        return text
    try:
        float(text)
    except ValueError:
        return "'" + text
    return text


_COLUMNS = {
    "blocks": list(
        "id fixed area unit_weight weight water_fx water_fy centroid_x centroid_y ux uy "
        "rotation unstable "
        "mechanism_x mechanism_y mechanism_rotation failure_mode failure_mode_read_from".split()
    ),
    "interfaces": list(
        "interface block_a block_b kind start_x start_y end_x end_y length normal_force "
        "shear_force normal_stress shear_stress state failed_fraction current_state "
        "open_fraction sliding_fraction local_fos first_failure slip_surface".split()
    ),
    "springs": list(
        "interface point x y sigma tau pore_pressure capacity strength_at_factor state "
        "current_state first_failure local_fos".split()
    ),
    "bolts": list(
        "bolt installed interface x y depth extension offset axial_force shear_force "
        "axial_capacity "
        "utilisation yielded first_yield".split()
    ),
}


def write_results(
    folder: str | Path,
    tables: dict[str, list[dict[str, Any]]],
    document: dict[str, Any],
    *,
    overwrite: bool = False,
    units=None,
    extra_files: tuple[str, ...] = (),
    write_extra=None,
) -> list[Path]:
    """Write the result files into ``folder``, all or nothing.

    Parameters
    ----------
    folder : str or Path
        Created if needed (with its parents).
    tables : dict
        From :func:`rockdem.result_tables.analysis_tables`.
    document : dict
        Everything else for ``result.json`` (version, command, model echo,
        summary); the tables are added under their names.
    overwrite : bool
        Replace result files already in ``folder``.
    units : Units, optional
        The model's units (:func:`rockdem.units.parse_units`): CSV headings
        carry them (``"normal_stress [kPa]"``) and ``result.json`` gets a
        ``column_units`` map; without a known system the headings are bare.
    extra_files, write_extra : optional
        More files (VTK, GeoJSON, DXF: :mod:`rockdem.exchange.results`), and
        the function that writes them into the temporary folder; they are
        moved into place with the others.

    Returns
    -------
    list of Path
        The files written.
    """
    folder = check_output_dir(folder, overwrite=overwrite, extra_files=extra_files)
    with staged_folder(folder, overwrite) as tmp:
        for name in ("blocks", "interfaces", "springs", "bolts"):
            _write_csv(tmp / f"{name}.csv", tables.get(name, []), _COLUMNS[name], units)
        doc = dict(document)
        if units is not None and units.known:
            doc["column_units"] = {
                name: column_units(_COLUMNS[name], units)
                for name in ("blocks", "interfaces", "springs", "bolts")
            }
        doc.update(tables)
        with (tmp / "result.json").open("w", encoding="utf-8") as fh:
            json.dump(jsonable(doc), fh, indent=1, allow_nan=False)
            fh.write("\n")
        if write_extra is not None:
            write_extra(tmp)
    return [folder / name for name in (*RESULT_FILES, *extra_files)]


@contextmanager
def staged_folder(folder: Path, overwrite: bool = True) -> Iterator[Path]:
    """A temporary folder beside ``folder`` to write into; when the block ends
    without error its files are moved into ``folder`` (the folder itself is
    renamed into place when it did not exist), else it is removed: the
    results appear all or nothing, and files already in ``folder`` that were
    not written again are left as they are.

    ``overwrite=False``: where files of the same names appeared in ``folder``
    while the results were computed (another command writing there), they are
    kept, and so are these results, in a folder beside it named in the error.
    """
    parent = folder.parent
    parent.mkdir(parents=True, exist_ok=True)
    tmp: Path | None = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", suffix=".tmp", dir=parent))
    umask = os.umask(0o022)
    os.umask(umask)
    os.chmod(tmp, 0o777 & ~umask)  # mkdtemp makes it private; the results are not
    try:
        yield tmp
        if not folder.exists():
            try:
                os.rename(tmp, folder)
                tmp = None
            except OSError:  # created meanwhile: fall back to moving file by file
                folder.mkdir(exist_ok=True)
        if tmp is not None:
            taken = [p.name for p in sorted(tmp.iterdir()) if (folder / p.name).exists()]
            if taken and not overwrite:
                kept = Path(tempfile.mkdtemp(prefix=f"{folder.name}-", dir=parent))
                os.rmdir(kept)
                os.rename(tmp, kept)
                tmp = None
                raise InputError(
                    f"--out {folder}",
                    f"received {taken[0]} from another command while this one ran",
                    f"this run's results are kept in {kept}",
                )
            for path in sorted(tmp.iterdir()):
                os.replace(path, folder / path.name)
    finally:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
