"""Result files: tables of blocks, interfaces and springs, and ``result.json``.

:func:`write_results` writes ``blocks.csv``, ``interfaces.csv``,
``springs.csv`` and ``result.json`` (the same tables plus the summary, the
model echo and the rockdem version) into a folder, all or nothing: the files
are written into a temporary folder beside the target and moved into place
only when all of them are complete.  Existing result files are replaced only
with ``overwrite=True``.

Sign conventions: normal forces and stresses are compression-positive.
Current state and history are separate columns.  ``current_state`` is the
state now (of most of the interface's length; ``open_fraction`` and
``sliding_fraction`` give the shares): ``elastic`` (never failed, holding),
``closed-failed-earlier`` (failed at some time, now closed and holding),
``sliding`` (at its shear strength now) or ``open`` (at or beyond its
tensile strength now).  ``state`` is the history: the worst failure flag the
interface has ever had (``elastic`` = never failed, ``shear`` = yielded at
some time, ``tension`` = failed in tension at some time), and
``failed_fraction`` the share of its length that has ever failed;
``first_failure`` is the load step (or strength-reduction stage) at which the
interface first failed, -1 if never; ``local_fos`` is the full shear strength
over the shear stress (``inf`` where unstressed).  In ``springs.csv``,
``capacity`` is the full shear strength (F = 1) and ``strength_at_factor``
the strength at the factor the stresses were found at.  ``failure_mode`` (in
``blocks.csv``) is the block's mode at the limit (:mod:`rockdem.modes`).
``bolts.csv`` has a row per joint a bolt crosses (:mod:`rockdem.bolts`):
``extension`` and ``offset`` of the bolt across the joint, ``axial_force``
(tension positive) and ``shear_force`` per bolt, ``axial_capacity`` there
(steel or bond beyond the joint), ``utilisation`` (axial force / capacity),
``yielded`` and ``first_yield`` (the load step or strength-reduction stage
at which it first reached its capacity, -1 never); only its heading
without bolts.

When the model's ``units`` note names a system (:func:`rockdem.units.parse_units`:
"kN, m, kPa", "t, m, t/m^2", ...) every CSV heading with a unit carries it in
brackets, ``area [m^2]``, ``normal_force [kN]``, ``normal_stress [kPa]``,
``ux [m]``, ``rotation [rad]``, and ``result.json`` maps the columns to their
units under ``column_units`` (its tables keep the bare names).
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

import numpy as np

from .errors import InputError
from .loads import joint_water, pore_pressure, water_loads
from .mechanism import slip_polylines
from .modes import MODES, boundary_contacts, failure_modes
from .results import CURRENT_NAMES
from .spring_law import STATE_NAMES
from .trust import trust_statements

#: The files :func:`write_results` writes.
RESULT_FILES = ("blocks.csv", "interfaces.csv", "springs.csv", "bolts.csv", "result.json")

__all__ = [
    "RESULT_FILES",
    "analysis_summary",
    "analysis_tables",
    "bolt_summary",
    "check_output_dir",
    "column_units",
    "csv_header",
    "fos_summary",
    "jsonable",
    "mechanism_summary",
    "state_counts",
    "units_summary",
    "write_results",
]


def jsonable(value: Any) -> Any:
    """Plain JSON data from numpy scalars and arrays; inf and nan become None."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, np.bool_ | bool):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating | float):
        v = float(value)
        return v if math.isfinite(v) else None
    if isinstance(value, np.str_):
        return str(value)
    return value


# --------------------------------------------------------------- tables
def analysis_tables(analysis, modes=None) -> dict[str, list[dict[str, Any]]]:
    """Rows of the three tables of an :class:`~rockdem.Analysis`.

    ``modes`` (a :class:`~rockdem.modes.BlockModes`, default: those of
    ``analysis``) fills the blocks' ``failure_mode`` column: for a
    factor-of-safety search, pass the modes of the failed end (the mechanism
    at the limit) beside the tables of the last equilibrium.

    Returns
    -------
    dict
        ``{"blocks": [...], "interfaces": [...], "springs": [...]}``, each a
        list of rows (dicts with the same keys, in column order).
    """
    system = analysis.system
    b = system.blocks
    d, mech = analysis.displacement, analysis.mechanism
    mode = np.where(b.fixed, "fixed", (modes or failure_modes(analysis)).name)
    water = water_loads(b, system.interfaces, joint_water(b, system.model.loads))
    blocks = [
        {
            "id": int(b.ids[i]),
            "fixed": bool(b.fixed[i]),
            "area": float(b.area[i]),
            "unit_weight": float(b.unit_weight[i]),
            "weight": float(b.weight[i]),
            "water_fx": float(water[i, 0]),
            "water_fy": float(water[i, 1]),
            "centroid_x": float(b.centroid[i, 0]),
            "centroid_y": float(b.centroid[i, 1]),
            "ux": float(d[i, 0]),
            "uy": float(d[i, 1]),
            "rotation": float(d[i, 2]),
            "unstable": bool(analysis.unstable[i]),
            "mechanism_x": float(mech[i, 0]),
            "mechanism_y": float(mech[i, 1]),
            "mechanism_rotation": float(mech[i, 2]),
            "failure_mode": str(mode[i]),
        }
        for i in range(b.n_blocks)
    ]
    r = analysis.interfaces
    faces = system.interfaces
    normal_stress, shear_stress, state_name = r.normal_stress, r.shear_stress, r.state_name
    now_name = r.current_name
    slip = np.zeros(r.n_interfaces, dtype=bool)
    slip[analysis.slip_surface] = True
    interfaces = [
        {
            "interface": i,
            "block_a": int(r.block_a[i]),
            "block_b": int(r.block_b[i]),
            "kind": str(r.kind[i]),
            "start_x": float(faces.start[i, 0]),
            "start_y": float(faces.start[i, 1]),
            "end_x": float(faces.end[i, 0]),
            "end_y": float(faces.end[i, 1]),
            "length": float(r.length[i]),
            "normal_force": float(r.normal_force[i]),
            "shear_force": float(r.shear_force[i]),
            "normal_stress": float(normal_stress[i]),
            "shear_stress": float(shear_stress[i]),
            "state": str(state_name[i]),
            "failed_fraction": float(r.failed_fraction[i]),
            "current_state": str(now_name[i]),
            "open_fraction": float(r.open_fraction[i]),
            "sliding_fraction": float(r.sliding_fraction[i]),
            "local_fos": float(r.local_fos[i]),
            "first_failure": int(r.first_failure[i]),
            "slip_surface": bool(slip[i]),
        }
        for i in range(r.n_interfaces)
    ]
    s = analysis.springs
    point_xy = system.springs.point
    fos, s_state, s_now = s.local_fos, s.state_name, s.current_name
    water = pore_pressure(joint_water(system.blocks, system.model.loads), point_xy)
    springs = [
        {
            "interface": int(s.interface[k]),
            "point": k % system.springs.points_per_interface,
            "x": float(point_xy[k, 0]),
            "y": float(point_xy[k, 1]),
            "sigma": float(s.sigma[k]),
            "tau": float(s.tau[k]),
            "pore_pressure": float(water[k]),
            "capacity": float(s.capacity[k]),
            "strength_at_factor": float(s.strength[k]),
            "state": str(s_state[k]),
            "current_state": str(s_now[k]),
            "first_failure": int(s.first_failure[k]),
            "local_fos": float(fos[k]),
        }
        for k in range(len(s.sigma))
    ]
    return {
        "blocks": blocks,
        "interfaces": interfaces,
        "springs": springs,
        "bolts": bolt_rows(analysis),
    }


def bolt_rows(analysis) -> list[dict[str, Any]]:
    """One row per joint a bolt crosses: force per bolt, capacity there,
    utilisation and whether it yielded (empty without bolts)."""
    r = analysis.bolts
    if r is None:
        return []
    use = r.utilisation
    return [
        {
            "bolt": str(r.name[k]),
            "interface": int(r.interface[k]),
            "x": float(r.point[k, 0]),
            "y": float(r.point[k, 1]),
            "depth": float(r.depth[k]),
            "extension": float(r.extension[k]),
            "offset": float(r.offset[k]),
            "axial_force": float(r.axial_force[k]),
            "shear_force": float(r.shear_force[k]),
            "axial_capacity": float(r.capacity[k]),
            "utilisation": float(use[k]),
            "yielded": bool(r.yielded[k]),
            "first_yield": int(r.first_yield[k]),
        }
        for k in range(r.n)
    ]


def _failed(analysis) -> list[dict[str, Any]]:
    r = analysis.interfaces
    names, now = r.state_name, r.current_name
    return [
        {
            "interface": int(i),
            "block_a": int(r.block_a[i]),
            "block_b": int(r.block_b[i]),
            "kind": str(r.kind[i]),
            "state": str(names[i]),
            "failed_fraction": float(r.failed_fraction[i]),
            "current_state": str(now[i]),
            "first_failure": int(r.first_failure[i]),
        }
        for i in analysis.failed_interfaces
    ]


def bolt_summary(analysis) -> list[dict[str, Any]]:
    """Per bolt: the joints it crosses, its largest axial force (per bolt), the
    largest utilisation, how many of its crossings have yielded, and the
    stage of its first yield (None: never)."""
    if analysis is None or analysis.bolts is None:
        return []
    r = analysis.bolts
    out = []
    for name in dict.fromkeys(r.name):
        k = r.name == name
        first = r.first_yield[k][r.first_yield[k] >= 0]
        out.append(
            {
                "bolt": str(name),
                "crossings": int(k.sum()),
                "max_axial_force": float(np.max(r.axial_force[k])),
                "max_utilisation": float(np.max(r.utilisation[k])),
                "yielded_crossings": int(r.yielded[k].sum()),
                "first_yield": int(first.min()) if first.size else None,
            }
        )
    return out


def state_counts(analysis) -> dict[str, dict[str, int]]:
    """Interfaces by current state and by failure history, kept apart.

    ``now``: elastic, closed-failed-earlier, sliding, open (each interface by
    the state of most of its length); ``history``: elastic (never failed),
    shear (yielded at some time), tension (failed in tension at some time).
    """
    r = analysis.interfaces
    now = np.bincount(r.current, minlength=len(CURRENT_NAMES))
    ever = np.bincount(r.state, minlength=len(STATE_NAMES))
    return {
        "now": {name: int(n) for name, n in zip(CURRENT_NAMES, now, strict=True)},
        "history": {name: int(n) for name, n in zip(STATE_NAMES, ever, strict=True)},
    }


def mechanism_summary(analysis) -> dict[str, Any]:
    """What the mechanism does: ``failure_modes`` (ids of the moving blocks by
    mode), ``boundary_contacts`` (where it touches a fixed side of the model),
    ``warnings`` (one sentence each) and ``slip_polylines`` (the slip surface
    as ordered polylines with the stresses of each segment); all empty for a
    stable analysis."""
    if analysis is None or analysis.stable:
        return {"failure_modes": {}, "boundary_contacts": [], "warnings": [], "slip_polylines": []}
    modes = failure_modes(analysis)
    by_mode = {m: [int(i) for i in modes.blocks(m)] for m in MODES if m != "stable"}
    contacts = boundary_contacts(analysis)
    return {
        "failure_modes": {m: ids for m, ids in by_mode.items() if ids},
        "boundary_contacts": [
            {
                "side": c.side,
                "at": c.at,
                "span": list(c.span),
                "blocks": list(c.blocks),
                "interfaces": [int(i) for i in c.interfaces],
            }
            for c in contacts
        ],
        "warnings": [c.message for c in contacts],
        "slip_polylines": slip_polylines(analysis),
    }


def analysis_summary(analysis) -> dict[str, Any]:
    """The verdict of a staged analysis as plain data.

    Keys: ``stable``, ``verdict``, ``load_factor``, ``strength_factor``,
    ``unstable_blocks`` (ids), ``failed_interfaces`` (the history: every
    interface that has failed at some time, with the blocks, kind, state,
    current state and first failure), ``interface_states`` (counts by current
    state and by history, see :func:`state_counts`), ``failure_modes``,
    ``boundary_contacts`` and ``warnings`` (:func:`mechanism_summary`),
    ``slip_surface`` (interface numbers), ``bolt_summary`` (:func:`bolt_summary`),
    ``steps`` and ``evidence``.
    """
    return jsonable(
        {
            "stable": analysis.stable,
            "verdict": analysis.verdict,
            "load_factor": analysis.load_factor,
            "strength_factor": analysis.strength_factor,
            "unstable_blocks": [int(i) for i in analysis.unstable_blocks],
            "failed_interfaces": _failed(analysis),
            "interface_states": state_counts(analysis),
            **mechanism_summary(analysis),
            "slip_surface": [int(i) for i in analysis.slip_surface],
            "bolt_summary": bolt_summary(analysis),
            "steps": [
                {
                    "stage": s.stage,
                    "load_factor": s.load_factor,
                    "strength_factor": s.strength_factor,
                    "converged": s.converged,
                    "failed_springs": s.n_failed_springs,
                    "evidence": str(s.evidence),
                    "proof": s.evidence.proof,
                }
                for s in analysis.steps
            ],
            "evidence": str(analysis.evidence),
            "proof": analysis.evidence.proof,
        }
    )


def fos_summary(fos) -> dict[str, Any]:
    """A :class:`~rockdem.FactorOfSafety` as plain data.

    ``factor_of_safety`` is None when strength does not control the
    mechanism; an open upper end of ``bracket`` is None (infinity).
    ``mechanism_blocks`` are the blocks moving at the unstable end (the strength
    factor of that state: ``mechanism_factor``), with their
    ``failure_modes``, ``boundary_contacts`` and ``warnings``
    (:func:`mechanism_summary`); ``bolts_at_limit``: the bolts in the last
    equilibrium below the limit (:func:`bolt_summary`).
    """
    failed, base = fos.failed_analysis, fos.stable_analysis
    return jsonable(
        {
            "factor_of_safety": fos.value,
            "bracket": list(fos.bracket),
            "mode": fos.mode,
            "proof": fos.proof,
            "certified_upper_bound": fos.certified_upper_bound,
            "relaxation": None if failed is None else failed.evidence.relaxation,
            "trust": [] if base is None else trust_statements(base, fos),
            "definition": fos.definition,
            "mechanism_blocks": [] if failed is None else [int(i) for i in failed.unstable_blocks],
            "mechanism_factor": None if failed is None else failed.strength_factor,
            "bolts_at_limit": bolt_summary(base),
            **mechanism_summary(failed),
            "trials": [
                {
                    "factor": t.factor,
                    "stable": t.stable,
                    "evidence": str(t.evidence),
                    "proof": t.evidence.proof,
                }
                for t in fos.trials
            ],
        }
    )


# --------------------------------------------------------------- writing
def check_output_dir(
    folder: str | Path, *, overwrite: bool = False, extra_files: tuple[str, ...] = ()
) -> Path:
    """Fail early if results cannot be written to ``folder``.

    ``extra_files`` are the files of the exchange formats asked for
    (:mod:`rockdem.exchange.results`), checked like the others.

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
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else ("inf" if v > 0 else "-inf" if v < 0 else "nan")
    return v


_COLUMNS = {
    "blocks": list(
        "id fixed area unit_weight weight water_fx water_fy centroid_x centroid_y ux uy "
        "rotation unstable "
        "mechanism_x mechanism_y mechanism_rotation failure_mode".split()
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
        "bolt interface x y depth extension offset axial_force shear_force axial_capacity "
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
        From :func:`analysis_tables`.
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
    with staged_folder(folder) as tmp:
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
def staged_folder(folder: Path) -> Iterator[Path]:
    """A temporary folder beside ``folder`` to write into; when the block ends
    without error its files are moved into ``folder`` (the folder itself is
    renamed into place when it did not exist), else it is removed: the
    results appear all or nothing, and files already in ``folder`` that were
    not written again are left as they are."""
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
            for path in sorted(tmp.iterdir()):
                os.replace(path, folder / path.name)
    finally:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
