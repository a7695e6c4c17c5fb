"""A slope section drawn in CAD (DXF), read into blocks and joint lines (the model
file of ``rockdem import`` is written by :mod:`~rockdem.exchange.model_file`).

Layers
------
The drawing's model space is read by layer (layer names compare without
regard to case, as CAD programs do); by default:

``OUTLINE``
    The section: one closed polyline (LWPOLYLINE or POLYLINE), the rock
    that the joints cut into blocks.
``FIXED``
    Fixed ground: closed polylines inside the outline or beside it (sharing
    its edge), not across it.  Whatever of the section lies in them is
    immobile; every part is one ground block.
``JOINT_<name>`` (or ``JOINT-<name>``)
    Joint traces (LINE, LWPOLYLINE, POLYLINE) that take the joint ``<name>``
    of the model.  A trace that crosses a block from side to side cuts it; a
    trace that ends inside a block does not (it still assigns its joint to
    the interfaces it lies on).
``WATER`` (optional)
    The water table: one polyline (or line), read left to right.
``BOLTS`` (optional)
    Bolts: lines from the head on the face into the rock; each becomes a
    support force of the given magnitude at the head, pulling along the line.

Other layers are not read (text, hatching, title blocks); block references
(INSERT) are not expanded.  A mapping overrides the names::

    {"outline": "SECTION", "fixed": "GROUND", "joints": {"BEDDING": "bedding"}}

Arcs and splines are refused (explode them into straight segments).

Units and coordinates
---------------------
``$INSUNITS`` of the drawing is read and the coordinates are converted to
the model's length unit (metres unless the model says otherwise); a
unitless drawing is read as it is.  Site coordinates are kept (x = 5e5,
y = 7e6 stay so): the section is cut relative to a local origin and moved
back, so a far-away section gives the same blocks as the same section near
the origin, and the outline's vertices come back bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .dxf_entities import (
    DxfError,
    _check_fixed_regions,
    _check_simple_line,
    _closed_ring,
    _describe,
    _entity_points,
    _fail,
    _layer_names,
    _open,
    _scale,
    _water_table,
)

__all__ = [
    "DEFAULT_LAYERS",
    "JOINT_PREFIXES",
    "Bolt",
    "DxfError",
    "Section",
    "SectionBlocks",
    "Trace",
    "example_dxf",
    "read_section",
]

#: Default layer of each part of the section.
DEFAULT_LAYERS = {"outline": "OUTLINE", "fixed": "FIXED", "water": "WATER", "bolts": "BOLTS"}
#: A layer named ``JOINT_<name>`` (or ``JOINT-<name>``) holds traces of the joint ``<name>``.
JOINT_PREFIXES = ("JOINT_", "JOINT-")
#: Most straight segments of joint traces (each may cut every other).
MAX_SEGMENTS = 20_000
#: Entities that annotate a drawing: never geometry, skipped on every layer.
ANNOTATION = frozenset(
    "TEXT MTEXT HATCH DIMENSION ARC_DIMENSION LEADER MLEADER MULTILEADER POINT ATTDEF "
    "ATTRIB VIEWPORT IMAGE WIPEOUT TOLERANCE".split()
)


@dataclass(frozen=True)
class Trace:
    """A joint trace as drawn: the polyline's points (model units) and its joint."""

    joint: str
    layer: str
    points: np.ndarray


@dataclass(frozen=True)
class Bolt:
    """A bolt: its head (on the face) and its far end, the force pulls along head -> tail."""

    head: np.ndarray
    tail: np.ndarray

    @property
    def length(self) -> float:
        return float(np.hypot(*(self.tail - self.head)))

    @property
    def angle(self) -> float:
        """Direction of the pull in degrees counter-clockwise from +x."""
        d = self.tail - self.head
        return math.degrees(math.atan2(d[1], d[0]))


@dataclass(frozen=True)
class Section:
    """A slope section read from a drawing (coordinates in the model's length unit).

    Attributes
    ----------
    outline : ndarray, shape (n, 2)
        The section's closed outline, as drawn (not repeating the first point).
    fixed : tuple of ndarray
        Outlines of fixed ground.
    traces : tuple of Trace
    water_table : ndarray or None
        Left to right.
    bolts : tuple of Bolt
    insunits : int
        The drawing's $INSUNITS (0: unitless).
    scale : float
        Drawing units to model units.
    layers : dict
        The layer read for each part (``outline``, ``fixed``, ``water``, ``bolts``).
    joint_layers : dict
        Layer -> joint name.
    skipped : dict
        Layer -> entities not read (layers of no part, annotations).
    """

    source: str
    outline: np.ndarray
    fixed: tuple[np.ndarray, ...]
    traces: tuple[Trace, ...]
    water_table: np.ndarray | None
    bolts: tuple[Bolt, ...]
    insunits: int
    scale: float
    layers: dict[str, str | None]
    joint_layers: dict[str, str]
    skipped: dict[str, int] = field(default_factory=dict)

    @property
    def joints(self) -> list[str]:
        """Joint names of the traces, in the order first drawn."""
        return list(dict.fromkeys(self.joint_layers.values()))

    @property
    def extent(self) -> float:
        """Diagonal of the bounding box of the outline and the fixed ground."""
        xy = np.vstack([self.outline, *self.fixed])
        return float(np.hypot(*(xy.max(axis=0) - xy.min(axis=0))))


@dataclass(frozen=True)
class SectionBlocks:
    """The section cut into blocks: free blocks (by centroid x, then y), then ground.

    ``lines`` are the joint traces as ``(joint, start, end)`` segments, as drawn.
    """

    polygons: tuple[np.ndarray, ...]
    fixed: np.ndarray
    lines: tuple[tuple[str, np.ndarray, np.ndarray], ...]

    @property
    def n_free(self) -> int:
        return int((~self.fixed).sum())


# ------------------------------------------------------------------ reading
def example_dxf() -> Path:
    """The bundled example section (``rockdem import --example``), made by
    ``examples/make_dxf.py``: a 60 degree slope, bedding dipping 35 degrees out of
    the face, a steep cross set, fixed ground, a water table and two bolts."""
    from importlib import resources

    return Path(str(resources.files("rockdem.exchange").joinpath("data", "section.dxf")))


def _resolve(
    layers: Mapping[str, Any] | None,
    names: dict[str, str],
    joints: Sequence[str] | None,
    source: str,
    drawn: set[str] | None = None,
) -> tuple[dict[str, str | None], dict[str, str]]:
    """(role -> layer name in the drawing, joint layer -> joint name).

    ``drawn``: the upper-case names of the layers that hold entities; a
    ``JOINT_`` layer found by its name and holding none is left out (found by
    fuzzing: an empty leftover layer JOINT_old made a template refused for
    "no joint 'old'", and an empty JOINT_aaa named the ground's joint)."""
    given = dict(layers or {})
    unknown = set(given) - {*DEFAULT_LAYERS, "joints"}
    if unknown:
        key = sorted(unknown)[0]
        raise _fail(
            source,
            f"layers.{key}: not a part of a section",
            f"use {', '.join(DEFAULT_LAYERS)} or joints",
            f"layers.{key}",
        )
    available = ", ".join(sorted(names.values())) or "none"
    roles: dict[str, str | None] = {}
    for role, default in DEFAULT_LAYERS.items():
        wanted = given.get(role)
        name = names.get((wanted or default).upper())
        if wanted is not None and name is None:
            raise _fail(
                source,
                f"layers.{role}: there is no layer {wanted!r} in the drawing "
                f"(its layers: {available})",
                "name one of its layers",
                f"layers.{role}",
            )
        if name is None and role in ("outline", "fixed"):
            what = "the section outline" if role == "outline" else "the fixed ground"
            raise _fail(
                source,
                f"no layer {default} for {what} (the drawing's layers: {available})",
                f"put it on a layer {default}, or name its layer with layers.{role}",
                f"layers.{role}",
            )
        roles[role] = name
    joint_layers: dict[str, str] = {}
    mapping = given.get("joints")
    if mapping is not None:
        for layer, joint in dict(mapping).items():
            name = names.get(str(layer).upper())
            if name is None:
                raise _fail(
                    source,
                    f"layers.joints: there is no layer {layer!r} in the drawing "
                    f"(its layers: {available})",
                    "name one of its layers",
                    f"layers.joints.{layer}",
                )
            if joints is not None and joint not in joints:
                raise _fail(
                    source,
                    f"layers.joints.{layer}: joint {joint!r} is not defined in `joints`",
                    f"use one of {list(joints)}",
                    f"layers.joints.{layer}",
                )
            joint_layers[name] = str(joint)
    else:
        for upper, name in sorted(names.items()):
            prefix = next((p for p in JOINT_PREFIXES if upper.startswith(p)), None)
            if prefix is None or len(name) == len(prefix):
                continue
            if drawn is not None and upper not in drawn:
                continue
            joint_layers[name] = _joint_of(name[len(prefix) :], joints, name, source)
    taken: dict[str, str] = {}
    for role, name in roles.items():
        if name is None:
            continue
        other = taken.setdefault(name.upper(), role)
        if other != role:  # `--layer outline=FIXED`: one layer in two parts
            raise _fail(
                source,
                f"layer {name} is both the {other} and the {role}",
                "give each part of the section its own layer",
                f"layers.{role}",
            )
    for layer in joint_layers:
        if layer.upper() in taken:
            raise _fail(
                source,
                f"layer {layer} is both the {taken[layer.upper()]} and a joint layer",
                "give each part of the section its own layer",
            )
    return roles, joint_layers


def _joint_of(name: str, joints: Sequence[str] | None, layer: str, source: str) -> str:
    if joints is None:
        return name
    if name in joints:
        return name
    same = [j for j in joints if j.upper() == name.upper()]
    if len(same) == 1:
        return same[0]
    raise _fail(
        source,
        f"layer {layer}: no joint {name!r} in `joints` (joints: {', '.join(joints)})",
        "add the joint to `joints`, rename the layer, or map it with geometry.layers.joints",
        "layers.joints",
    )


def read_section(
    path: str | Path,
    *,
    layers: Mapping[str, Any] | None = None,
    joints: Sequence[str] | None = None,
    length_unit: str | None = None,
) -> Section:
    """Read a slope section from a DXF drawing (see the module's layer convention).

    Parameters
    ----------
    path : str or Path
    layers : mapping, optional
        Layer names overriding :data:`DEFAULT_LAYERS` (keys ``outline``,
        ``fixed``, ``water``, ``bolts``) and ``joints``: ``{layer: joint}``
        (instead of the ``JOINT_<name>`` layers).
    joints : sequence of str, optional
        The model's joint names: every joint layer must name one (case aside).
        None: the joint names are taken from the layers (``rockdem import``).
    length_unit : str, optional
        The model's length unit (``"m"``, ``"mm"``, ...; default m): the
        drawing's $INSUNITS is converted to it.

    Raises
    ------
    DxfError
        A missing, empty or non-DXF file, an unknown layer, an open or
        self-crossing outline, a fixed region across the outline's edge, a
        self-crossing trace, arcs, a water table that turns back, too many traces.
    """
    path = Path(path)
    source = str(path)
    doc = _open(path, source)
    names = _layer_names(doc)
    drawn = {e.dxf.get("layer", "0").upper() for e in doc.modelspace()}
    roles, joint_layers = _resolve(layers, names, joints, source, drawn)
    insunits, scale = _scale(doc, length_unit, source)
    by_layer: dict[str, list] = {}
    skipped: dict[str, int] = {}
    wanted = {n.upper() for n in roles.values() if n} | {n.upper() for n in joint_layers}
    for e in doc.modelspace():
        layer = e.dxf.get("layer", "0")
        if layer.upper() in wanted and e.dxftype() not in ANNOTATION:
            by_layer.setdefault(layer.upper(), []).append(e)
        else:
            skipped[layer] = skipped.get(layer, 0) + 1

    def entities(name: str | None) -> list:
        return by_layer.get(name.upper(), []) if name else []

    # -------------------------------------------------------------- outline
    outline_layer = roles["outline"]
    found = entities(outline_layer)
    for e in found:
        if e.dxftype() not in ("LINE", "LWPOLYLINE", "POLYLINE"):
            _entity_points(e, scale, source, outline_layer)  # says what it is
    polys = [e for e in found if e.dxftype() != "LINE"]
    if not found:
        raise _fail(
            source,
            f"layer {outline_layer} holds no outline",
            "draw the section as one closed polyline on it",
            "layers.outline",
        )
    if len(found) != len(polys):
        raise _fail(
            source,
            f"layer {outline_layer}: the outline is drawn with LINEs",
            "join them into one closed polyline (PEDIT Join)",
            "layers.outline",
        )
    if len(polys) > 1:
        raise _fail(
            source,
            f"layer {outline_layer} holds {len(polys)} polylines",
            "draw the section as one closed polyline (put fixed ground on the fixed layer)",
            "layers.outline",
        )
    xy, closed = _entity_points(polys[0], scale, source, outline_layer)
    outline = _closed_ring(xy, closed, source, outline_layer, "outline", polys[0])

    # -------------------------------------------------------------- fixed
    fixed = []
    for e in entities(roles["fixed"]):
        xy, closed = _entity_points(e, scale, source, roles["fixed"])
        fixed.append(_closed_ring(xy, closed, source, roles["fixed"], "fixed region", e))
    if not fixed:
        raise _fail(
            source,
            f"layer {roles['fixed']} holds no closed polyline: nothing holds the blocks",
            "draw the fixed ground (the rock below and behind the section) as closed polylines",
            "layers.fixed",
        )
    _check_fixed_regions(outline, fixed, entities(roles["fixed"]), source, roles["fixed"])

    # -------------------------------------------------------------- joints
    traces = []
    n_segments = 0
    for layer, joint in joint_layers.items():
        for e in entities(layer):
            xy, closed = _entity_points(e, scale, source, layer)
            if closed and len(xy) > 2:
                xy = np.vstack([xy, xy[:1]])
            _check_simple_line(xy, source, layer, e)
            traces.append(Trace(joint, layer, xy))
            n_segments += len(xy) - 1
    if n_segments > MAX_SEGMENTS:
        raise _fail(
            source,
            f"has {n_segments:,} joint trace segments, more than the limit of {MAX_SEGMENTS:,}",
            "draw fewer or simpler traces (or a generated `slope`)",
        )

    # -------------------------------------------------------------- water
    water = None
    if roles["water"]:
        found = entities(roles["water"])
        if len(found) > 1:
            raise _fail(
                source,
                f"layer {roles['water']} holds {len(found)} entities",
                "draw the water table as one polyline from left to right",
                "layers.water",
            )
        if found:
            xy, _ = _entity_points(found[0], scale, source, roles["water"])
            water = _water_table(xy, source, roles["water"], found[0])

    # -------------------------------------------------------------- bolts
    bolts = []
    if roles["bolts"]:
        import shapely

        ring = shapely.LinearRing(outline)
        ground = shapely.union_all([shapely.Polygon(f) for f in fixed])
        touch = 1e-6 * float(np.ptp(outline, axis=0).max())
        for e in entities(roles["bolts"]):
            xy, _ = _entity_points(e, scale, source, roles["bolts"])
            if len(xy) != 2:
                raise _fail(
                    source,
                    f"layer {roles['bolts']}: {_describe(e)} is not one straight line",
                    "draw each bolt as a LINE from its head on the face into the rock",
                    "layers.bolts",
                )
            # the head: the end on the face, not on the fixed ground, whichever
            # way the line was drawn (found by fuzzing: one drawn from the back
            # edge to the face put its head on the ground)
            ends = shapely.points(xy)
            on_ground = shapely.distance(ends, ground) <= touch
            d0, d1 = shapely.distance(ends, ring)
            first = d0 <= d1 if on_ground[0] == on_ground[1] else not on_ground[0]
            head, tail = (xy[0], xy[1]) if first else (xy[1], xy[0])
            twin = next(
                (
                    k
                    for k, b in enumerate(bolts)
                    if np.abs(b.head - head).max() <= touch and np.abs(b.tail - tail).max() <= touch
                ),
                None,
            )
            if twin is not None:  # (found by fuzzing: a copy doubled the bolting silently)
                raise _fail(
                    source,
                    f"layer {roles['bolts']}: {_describe(e)} lies on bolt {twin + 1} (a copy?)",
                    "draw each bolt once (delete the copy; OVERKILL in AutoCAD)",
                    "layers.bolts",
                )
            bolts.append(Bolt(head, tail))
    return Section(
        source=source,
        outline=outline,
        fixed=tuple(fixed),
        traces=tuple(traces),
        water_table=water,
        bolts=tuple(bolts),
        insunits=insunits,
        scale=scale,
        layers=roles,
        joint_layers=joint_layers,
        skipped=skipped,
    )
