"""Results as VTK unstructured grids (``.vtu``, written with meshio) for ParaView.

``blocks.vtu``
    One polygon cell per block (cell ``i`` is block ``i`` of ``blocks.csv``),
    each with its own copy of its vertices (rigid blocks move apart).
    Cell data: ``block_id``, ``fixed`` (0/1), ``unstable`` (0/1: moving in the
    mechanism; for ``fos`` at the limit), ``failure_mode`` (code, see
    :data:`MODE_CODES`), ``displacement`` (ux, uy, 0), ``rotation``,
    ``mechanism`` (x, y, rotation of the failure motion), ``area``,
    ``weight``.  Point data: ``displacement`` (ux, uy, 0) of each vertex from
    the block's rigid motion, so that ParaView's *Warp By Vector* draws the
    displaced blocks.
``interfaces.vtu``
    One line cell per interface (cell ``i`` is interface ``i`` of
    ``interfaces.csv``), from its start to its end.  Cell data: ``interface``,
    ``block_a``, ``block_b``, ``joint`` (index into the model's joints),
    ``normal_stress``, ``shear_stress`` (mean, compression > 0),
    ``normal_force``, ``shear_force``, ``state`` (history code, see
    :data:`STATE_CODES`), ``current_state`` (code, see :data:`CURRENT_CODES`),
    ``failed_fraction``, ``open_fraction``, ``sliding_fraction``,
    ``local_fos`` (NaN where unstressed), ``first_failure`` (-1: never),
    ``slip_surface`` (0/1).

Coordinates are the model's, site coordinates included (Float64).
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np

from ..modes import MODES
from ..results import CURRENT_NAMES
from ..spring_law import STATE_NAMES

__all__ = ["CURRENT_CODES", "MODE_CODES", "STATE_CODES", "VTK_FILES", "write_vtk"]

#: The files :func:`write_vtk` writes.
VTK_FILES = ("blocks.vtu", "interfaces.vtu")
#: ``failure_mode`` codes: -1 fixed, then the modes in :data:`rockdem.modes.MODES` order.
MODE_CODES = {"fixed": -1, **{name: k for k, name in enumerate(MODES)}}
#: ``state`` (history) codes.
STATE_CODES = {name: k for k, name in enumerate(STATE_NAMES)}
#: ``current_state`` codes.
CURRENT_CODES = {name: k for k, name in enumerate(CURRENT_NAMES)}


def _column(rows: Sequence[dict[str, Any]], key: str, dtype=float) -> np.ndarray:
    return np.array([row[key] for row in rows], dtype=dtype)


def _runs(sizes: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of the runs of equal polygon size, in order."""
    cuts = np.flatnonzero(np.diff(sizes)) + 1
    bounds = np.concatenate([[0], cuts, [len(sizes)]])
    return [(int(a), int(b)) for a, b in pairwise(bounds)]


def write_vtk(folder: str | Path, analysis, tables: dict[str, list[dict[str, Any]]]) -> list[Path]:
    """Write ``blocks.vtu`` and ``interfaces.vtu`` into ``folder``.

    Parameters
    ----------
    analysis : rockdem.Analysis
        The state the tables describe (its geometry is used).
    tables : dict
        :func:`rockdem.result_tables.analysis_tables` of it (the fields are the
        tables' columns, so the files agree with the CSV files).
    """
    import meshio

    folder = Path(folder)
    system = analysis.system
    b = system.blocks
    rows = tables["blocks"]
    # ------------------------------------------------------------ blocks
    sizes = np.diff(b.offsets)
    points = np.zeros((len(b.vertices), 3))
    points[:, :2] = b.vertices
    owner = np.repeat(np.arange(b.n_blocks), sizes)
    ux, uy, rot = (_column(rows, k) for k in ("ux", "uy", "rotation"))
    rel = b.vertices - b.centroid[owner]
    vertex_u = np.zeros_like(points)
    vertex_u[:, 0] = ux[owner] - rot[owner] * rel[:, 1]
    vertex_u[:, 1] = uy[owner] + rot[owner] * rel[:, 0]
    mode = np.array([MODE_CODES[row["failure_mode"]] for row in rows], dtype=np.int32)
    fixed = _column(rows, "fixed", bool)
    unstable = _column(rows, "unstable", bool) | ((mode > 0) & ~fixed)
    fields = {
        "block_id": _column(rows, "id", np.int64),
        "fixed": fixed.astype(np.int32),
        "unstable": unstable.astype(np.int32),
        "failure_mode": mode,
        "displacement": np.column_stack([ux, uy, np.zeros_like(ux)]),
        "rotation": rot,
        "mechanism": np.column_stack(
            [_column(rows, k) for k in ("mechanism_x", "mechanism_y", "mechanism_rotation")]
        ),
        "area": _column(rows, "area"),
        "weight": _column(rows, "weight"),
    }
    cells, cell_data = [], {name: [] for name in fields}
    for start, stop in _runs(sizes):
        n = int(sizes[start])
        first = b.offsets[start:stop]
        cells.append(("polygon", (first[:, None] + np.arange(n)[None, :]).astype(np.int64)))
        for name, values in fields.items():
            cell_data[name].append(values[start:stop])
    blocks_file = folder / VTK_FILES[0]
    meshio.Mesh(points, cells, point_data={"displacement": vertex_u}, cell_data=cell_data).write(
        blocks_file, file_format="vtu"
    )
    # ------------------------------------------------------------ interfaces
    faces = system.interfaces
    rows = tables["interfaces"]
    m = len(rows)
    lp = np.zeros((2 * m, 3))
    lp[0::2, :2] = faces.start[:m]
    lp[1::2, :2] = faces.end[:m]
    names = [j.name for j in system.model.joints]
    fos = _column(rows, "local_fos")
    line_fields = {
        "interface": _column(rows, "interface", np.int64),
        "block_a": _column(rows, "block_a", np.int64),
        "block_b": _column(rows, "block_b", np.int64),
        "joint": np.array(
            [names.index(r["kind"]) if r["kind"] in names else -1 for r in rows], dtype=np.int32
        ),
        "normal_stress": _column(rows, "normal_stress"),
        "shear_stress": _column(rows, "shear_stress"),
        "normal_force": _column(rows, "normal_force"),
        "shear_force": _column(rows, "shear_force"),
        "state": np.array([STATE_CODES[r["state"]] for r in rows], dtype=np.int32),
        "current_state": np.array(
            [CURRENT_CODES[r["current_state"]] for r in rows], dtype=np.int32
        ),
        "failed_fraction": _column(rows, "failed_fraction"),
        "open_fraction": _column(rows, "open_fraction"),
        "sliding_fraction": _column(rows, "sliding_fraction"),
        "local_fos": np.where(np.isfinite(fos), fos, np.nan),
        "first_failure": _column(rows, "first_failure", np.int32),
        "slip_surface": _column(rows, "slip_surface", bool).astype(np.int32),
    }
    lines = np.arange(2 * m, dtype=np.int64).reshape(-1, 2)
    interfaces_file = folder / VTK_FILES[1]
    meshio.Mesh(lp, [("line", lines)], cell_data={k: [v] for k, v in line_fields.items()}).write(
        interfaces_file, file_format="vtu"
    )
    return [blocks_file, interfaces_file]
