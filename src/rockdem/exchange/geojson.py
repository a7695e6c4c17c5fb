"""The section as GeoJSON (RFC 7946 structure) for GIS.

One ``FeatureCollection`` whose features carry a ``layer`` property:

* ``block``: a Polygon per block (counter-clockwise, closed) with ``id``,
  ``fixed``, ``area`` and, with results, ``unstable``, ``failure_mode``,
  ``ux``, ``uy``, ``rotation``;
* ``joint``: a LineString per joint trace of the model (``joint_lines``)
  with its ``joint`` name;
* ``interface`` (with results): a LineString per interface with
  ``interface``, ``block_a``, ``block_b``, ``joint``, ``state``,
  ``current_state``, ``normal_stress``, ``shear_stress``, ``failed``;
* ``water_table``: the phreatic line, if any.

The coordinates are the section's own (x along the section, y up, in the
model's length unit; site coordinates kept), not longitude and latitude:
load the file in a projected or engineering coordinate system.  The
collection's ``rockdem`` member says so and names the model and its units.
Infinite values are written as null.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["GEOJSON_FILE", "section_features", "write_geojson"]

#: The file :func:`write_geojson` writes into a results folder.
GEOJSON_FILE = "section.geojson"


def _ring(xy: np.ndarray) -> list[list[float]]:
    xy = np.asarray(xy, dtype=float)
    x, y = xy[:, 0], xy[:, 1]
    if np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y) < 0:  # clockwise
        xy = xy[::-1]
    return [[float(a), float(b)] for a, b in xy] + [[float(xy[0, 0]), float(xy[0, 1])]]


def _line(a, b) -> dict[str, Any]:
    return {
        "type": "LineString",
        "coordinates": [[float(a[0]), float(a[1])], [float(b[0]), float(b[1])]],
    }


def section_features(model, analysis=None, tables=None, *, units: str = "") -> dict[str, Any]:
    """The GeoJSON FeatureCollection (as data) of ``model`` and, optionally, the results.

    Parameters
    ----------
    model : rockdem.Model
    analysis : rockdem.Analysis, optional
        The state the ``tables`` describe (its blocks and interfaces).
    tables : dict, optional
        :func:`rockdem.result_tables.analysis_tables` of ``analysis``.
    units : str
        The model's ``units`` note (recorded in the collection).
    """
    from .. import __version__
    from ..result_tables import jsonable

    blocks = analysis.system.blocks if analysis is not None else model.blocks
    features: list[dict[str, Any]] = []
    rows = tables["blocks"] if tables is not None else None
    for i in range(blocks.n_blocks):
        props: dict[str, Any] = {
            "layer": "block",
            "id": int(blocks.ids[i]),
            "fixed": bool(blocks.fixed[i]),
            "area": float(blocks.area[i]),
        }
        if rows is not None:
            row = rows[i]
            moving = row["failure_mode"] not in ("stable", "fixed")
            props.update(
                unstable=bool(row["unstable"] or moving),
                failure_mode=row["failure_mode"],
                ux=row["ux"],
                uy=row["uy"],
                rotation=row["rotation"],
            )
        features.append(
            {
                "type": "Feature",
                "geometry": {"type": "Polygon", "coordinates": [_ring(blocks.outline(i))]},
                "properties": props,
            }
        )
    if model.joint_lines is not None:
        names = [j.name for j in model.joints]
        for k, (seg, j) in enumerate(zip(model.joint_lines, model.line_joint, strict=True)):
            features.append(
                {
                    "type": "Feature",
                    "geometry": _line(seg[0], seg[1]),
                    "properties": {"layer": "joint", "joint": names[j], "trace": k},
                }
            )
    if tables is not None and analysis is not None:
        faces = analysis.system.interfaces
        for row in tables["interfaces"]:
            i = row["interface"]
            features.append(
                {
                    "type": "Feature",
                    "geometry": _line(faces.start[i], faces.end[i]),
                    "properties": {
                        "layer": "interface",
                        "interface": i,
                        "block_a": row["block_a"],
                        "block_b": row["block_b"],
                        "joint": row["kind"],
                        "state": row["state"],
                        "current_state": row["current_state"],
                        "normal_stress": row["normal_stress"],
                        "shear_stress": row["shear_stress"],
                        "failed": row["state"] != "elastic",
                        "slip_surface": row["slip_surface"],
                    },
                }
            )
    table = model.loads.water_table
    if len(table):
        features.append(
            {
                "type": "Feature",
                "geometry": {
                    "type": "LineString",
                    "coordinates": [[float(x), float(y)] for x, y in table],
                },
                "properties": {"layer": "water_table"},
            }
        )
    return jsonable(
        {
            "type": "FeatureCollection",
            "rockdem": {
                "version": __version__,
                "model": model.name,
                "units": units,
                "coordinates": "section coordinates: x along the section, y up, in the "
                "model's length unit (not longitude and latitude)",
            },
            "features": features,
        }
    )


def write_geojson(path: str | Path, model, analysis=None, tables=None, *, units="") -> Path:
    """Write :func:`section_features` to ``path``."""
    path = Path(path)
    data = section_features(model, analysis, tables, units=units)
    with path.open("w", encoding="utf-8") as fh:
        json.dump(data, fh, allow_nan=False)
        fh.write("\n")
    return path
