"""Reading a DXF drawing: the file, its layers and units, and the points of
its entities, each refusal a one-line :class:`DxfError` naming the entity
(its type and handle) and the fix.  What the layers mean and how a section
is built from them: :mod:`rockdem.exchange.dxf_in`."""

from __future__ import annotations

import io
import logging
import math
import re
import struct
from pathlib import Path

import numpy as np

from ..errors import InputError

#: Largest DXF file read, in bytes.
MAX_DXF_BYTES = 64 * 2**20
#: Length units of model files (:mod:`rockdem.units`) and their DXF $INSUNITS codes.
INSUNITS = {"in": 1, "ft": 2, "mm": 4, "cm": 5, "m": 6, "km": 7}


class DxfError(InputError):
    """A drawing that cannot be read as a section: names the file, the layer and the fix.

    ``key`` is the option at fault (``"layers.fixed"``, ``"bolt_force"``; empty
    when it is the drawing itself), so that a model file can name its key.
    """

    def __init__(self, source: str, problem: str, fix: str, key: str = "") -> None:
        self.key = key
        super().__init__(source, problem, fix)


def _fail(source: str, problem: str, fix: str, key: str = "") -> DxfError:
    return DxfError(source, problem, fix, key)


def _open(path: Path, source: str):
    """The ezdxf document of ``path``; one-line errors for everything else."""
    from ..config.parse import read_bounded

    try:
        raw = read_bounded(path, source, MAX_DXF_BYTES)
    except InputError as exc:  # worded for model files: say it of a drawing
        problem = exc.problem.replace("a model file", "a DXF file")
        if "regular file" in problem:
            fix = "save the drawing to a file and give its path"
        elif "folder" in problem:
            fix = "give a DXF file"
        elif "larger" in problem:
            fix = "give the section alone (purge the drawing, or copy the section to a new one)"
        else:
            fix = exc.fix
        raise _fail(source, problem, fix) from None
    if not raw.strip():
        raise _fail(source, "the file is empty", "export the section from CAD as a DXF file")
    head = raw.lstrip()[:22]
    binary = raw.startswith(b"AutoCAD Binary DXF")
    if not binary and not re.match(rb"^(0|999)\s*[\r\n]", head):
        what = "a DWG drawing" if raw.startswith(b"AC10") else "not a DXF file"
        raise _fail(
            source,
            f"is {what} (it does not start with a DXF group code)",
            "save or export the drawing as DXF (ASCII or binary)",
        )
    if not binary and raw.rstrip().rsplit(None, 1)[-1] != b"EOF":
        raise _fail(
            source,
            "is incomplete: it does not end with the EOF of a DXF file (cut short?)",
            "export or copy the drawing again",
        )
    import ezdxf
    from ezdxf import recover

    # ezdxf logs every repair it makes while reading ("recovered invalid
    # floating point value ..."); the auditor reports the same, and its first
    # error is the one line said below
    ezdxf_log = logging.getLogger("ezdxf")
    was_disabled, ezdxf_log.disabled = ezdxf_log.disabled, True
    try:
        if binary:  # (recover reads text only; found by fuzzing: binary DXF was refused)
            doc = ezdxf.readfile(str(path))
            auditor = doc.audit()
        else:
            doc, auditor = recover.read(io.BytesIO(raw))
    except (
        ezdxf.DXFError,
        ValueError,
        IndexError,
        KeyError,
        TypeError,
        UnicodeError,
        struct.error,
    ) as exc:
        text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise _fail(
            source,
            f"is not a readable DXF file ({text})",
            "save or export the drawing as DXF from CAD again",
        ) from None
    finally:
        ezdxf_log.disabled = was_disabled
    if auditor.has_errors:
        first = auditor.errors[0].message if auditor.errors else ""
        raise _fail(
            source,
            f"has {len(auditor.errors)} structural errors ({first})",
            "open it in CAD, run AUDIT and save it again",
        )
    return doc


def _layer_names(doc) -> dict[str, str]:
    """Upper-case name -> name of every layer defined or used in model space."""
    names: dict[str, str] = {}
    for layer in doc.layers:
        names.setdefault(layer.dxf.name.upper(), layer.dxf.name)
    for e in doc.modelspace():
        name = e.dxf.get("layer", "0")
        names.setdefault(name.upper(), name)
    return names


def _scale(doc, length_unit: str | None, source: str) -> tuple[int, float]:
    from ezdxf.units import conversion_factor

    insunits = int(doc.header.get("$INSUNITS", 0) or 0)
    target = INSUNITS.get(length_unit or "m", 6)
    if insunits == 0 or insunits == target:
        return insunits, 1.0
    try:
        factor = float(conversion_factor(insunits, target))
    except (KeyError, ValueError, IndexError, ZeroDivisionError, TypeError):
        # (TypeError: ezdxf's "Unsupported conversion" for US survey feet, 21,
        # microinches, 8, and the like; found by fuzzing: exit 1)
        raise _fail(
            source,
            f"$INSUNITS = {insunits} is not a unit of length rockdem can convert",
            "set the drawing units (UNITS) to m, cm, mm, km, ft or in",
        ) from None
    if not (math.isfinite(factor) and factor > 0):
        raise _fail(source, f"$INSUNITS = {insunits} gives no scale", "set the drawing units")
    return insunits, factor


def _describe(e) -> str:
    """``LWPOLYLINE #1F``: the entity's type and handle (to find it in CAD)."""
    handle = e.dxf.get("handle", None)
    return f"{e.dxftype()}" + (f" #{handle}" if handle else "")


def _entity_points(e, scale: float, source: str, layer: str) -> tuple[np.ndarray, bool]:
    """Points (k, 2) in model units and whether the entity is closed."""
    kind = e.dxftype()
    where = f"layer {layer}: {_describe(e)}"
    if kind == "LINE":
        pts = [e.dxf.start, e.dxf.end]
        closed = False
    elif kind == "LWPOLYLINE":
        if any(b for *_, b in e.get_points("xyb")):
            raise _fail(
                source,
                f"{where} has arcs (bulges)",
                "rockdem reads straight segments only: explode the arcs into short segments",
            )
        pts, closed = list(e.vertices_in_wcs()), bool(e.closed)
    elif kind == "POLYLINE":
        if not (e.is_2d_polyline or e.is_3d_polyline):
            raise _fail(source, f"{where} is a mesh, not a line", "draw a polyline")
        if any(v.dxf.get("bulge", 0) for v in e.vertices):
            raise _fail(
                source,
                f"{where} has arcs (bulges)",
                "rockdem reads straight segments only: explode the arcs into short segments",
            )
        pts, closed = list(e.points_in_wcs()), bool(e.is_closed)
    else:
        raise _fail(
            source,
            f"{where} is not a line or polyline",
            "draw the section with LINE and POLYLINE only (explode blocks, arcs and splines)",
        )
    xy = np.array([(p[0], p[1]) for p in pts], dtype=float).reshape(-1, 2) * scale
    if not np.isfinite(xy).all():
        raise _fail(
            source, f"{where} has a coordinate that is not a finite number", "fix the drawing"
        )
    if np.abs(xy).max(initial=0.0) > 1e9:
        raise _fail(
            source,
            f"{where} lies beyond 1e9 from the origin (in model units)",
            "move the drawing to a local origin, or check $INSUNITS",
        )
    if len(xy) > 1:  # repeated points (a CAD habit) carry no geometry
        keep = np.ones(len(xy), dtype=bool)
        keep[1:] = (xy[1:] != xy[:-1]).any(axis=1)
        xy = xy[keep]
    return xy, closed


def _closed_ring(xy: np.ndarray, closed: bool, source: str, layer: str, what: str, e) -> np.ndarray:
    """A simple closed ring (first point not repeated), or a one-line error."""
    import shapely

    where = f"layer {layer}: {_describe(e)}"
    size = float(np.hypot(*(xy.max(axis=0) - xy.min(axis=0)))) if len(xy) else 0.0
    if len(xy) > 2 and np.hypot(*(xy[-1] - xy[0])) <= 1e-9 * size:
        xy, closed = xy[:-1], True
    if not closed:
        gap = float(np.hypot(*(xy[-1] - xy[0]))) if len(xy) else 0.0
        raise _fail(
            source,
            f"the {what} ({where}) is open: its ends ({_pt(xy[0])} and {_pt(xy[-1])}) "
            f"are {gap:.4g} apart",
            "close the polyline (PEDIT Close, or tick 'closed')",
        )
    if len(xy) < 3 or size == 0.0:
        raise _fail(
            source,
            f"the {what} ({where}) has fewer than 3 distinct points",
            "draw it around an area",
        )
    poly = shapely.Polygon(xy)
    if not poly.is_valid:
        reason = shapely.is_valid_reason(poly)
        m = re.search(r"\[([-+0-9.eE]+) ([-+0-9.eE]+)\]", reason)
        at = f" at ({float(m.group(1)):.6g}, {float(m.group(2)):.6g})" if m else ""
        raise _fail(
            source,
            f"the {what} ({where}) crosses itself{at}",
            "redraw it so that it goes once around the area without crossing",
        )
    if poly.area <= (1e-8 * size) ** 2:
        raise _fail(source, f"the {what} ({where}) has no area", "draw it around an area")
    return xy


def _check_fixed_regions(
    outline: np.ndarray, fixed: list[np.ndarray], found: list, source: str, layer: str
) -> None:
    """Refuse a fixed region that lies partly inside the outline and partly outside it.

    A fixed region inside the outline marks part of the section as ground; one
    beside it (sharing its edge) adds ground to it.  One across the outline's
    edge is neither (found by fuzzing: a rectangle over the toe, half outside,
    grew the ground into a 5 m wall beyond the drawn slope).  Within the
    geometry tolerance (``GEOMETRY_RTOL`` of the size, as the cut uses) a region
    along the outline's edge is inside or beside it.
    """
    import shapely

    from ..blocks import GEOMETRY_RTOL

    origin = outline.min(axis=0)  # about a local origin, as the cut is made
    xy = np.vstack([outline, *fixed])
    extent = float(np.hypot(*(xy.max(axis=0) - xy.min(axis=0))))
    tol = GEOMETRY_RTOL * extent
    rock = shapely.Polygon(outline - origin)
    grown = shapely.buffer(rock, tol, join_style="mitre")
    core = shapely.buffer(rock, -tol, join_style="mitre")
    for ring, e in zip(fixed, found, strict=True):
        region = shapely.Polygon(ring - origin)
        if shapely.covered_by(region, grown) or shapely.intersection(region, core).area <= 0:
            continue
        out = shapely.difference(region, rock)
        step = max(extent / 1000, shapely.length(out) / 1e5)  # the farthest point, to step/2
        pts = shapely.points(shapely.get_coordinates(shapely.segmentize(out, step)))
        far = shapely.distance(pts, rock)
        k = int(np.argmax(far))
        at = shapely.get_coordinates(pts[k])[0] + origin
        raise _fail(
            source,
            f"the fixed region (layer {layer}: {_describe(e)}) crosses the outline: "
            f"it reaches {far[k]:.3g} outside it, to {_pt(at)}",
            "draw the FIXED region inside the outline (or beside it, sharing its edge, "
            "to add ground there)",
            "layers.fixed",
        )


def _check_simple_line(xy: np.ndarray, source: str, layer: str, e) -> None:
    import shapely

    where = f"layer {layer}: {_describe(e)}"
    if len(xy) < 2:
        raise _fail(source, f"{where} has zero length", "delete it or draw the trace")
    line = shapely.LineString(xy)
    if not line.is_simple:
        parts = shapely.get_parts(shapely.node(line))
        ends = shapely.get_coordinates(shapely.boundary(parts))
        uniq, count = np.unique(ends, axis=0, return_counts=True)
        inner = uniq[count > 2] if (count > 2).any() else uniq[count > 1]
        at = f" at {_pt(inner[0])}" if len(inner) else ""
        raise _fail(
            source,
            f"{where} crosses itself{at}",
            "draw each joint trace as a line that does not cross or double back on itself",
        )


def _pt(p) -> str:
    return f"({p[0]:.6g}, {p[1]:.6g})"


def _water_table(xy: np.ndarray, source: str, layer: str, e) -> np.ndarray:
    if len(xy) < 2:
        raise _fail(source, f"layer {layer}: the water table is a point", "draw it as a line")
    if xy[-1, 0] < xy[0, 0]:
        xy = xy[::-1]
    dx = np.diff(xy[:, 0])
    if (dx <= 0).any():
        k = int(np.flatnonzero(dx <= 0)[0]) + 1
        raise _fail(
            source,
            f"layer {layer}: the water table ({_describe(e)}) turns back at {_pt(xy[k])}",
            "draw it from left to right, one level per x",
            "layers.water",
        )
    return xy
