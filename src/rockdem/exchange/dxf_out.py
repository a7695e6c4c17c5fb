"""DXF drawings: a section in the input layer convention, and results for the CAD drawing.

:func:`write_dxf` draws a model (and its results) on these layers:

====================  =====================================================
``BLOCKS``            every free block (closed polyline)
``FIXED``             the fixed ground blocks
``UNSTABLE``          the unstable blocks again (red), when there are results
``FAILED_JOINTS``     interfaces that have failed at some time (red), when
                      there are results
``SLIP_SURFACE``      the interfaces of the slip surface (magenta)
``JOINT_<name>``      the model's joint traces (``joint_lines``), per joint
``WATER``             the water table
``BLOCK_IDS``         the id of every block at its centroid (text)
====================  =====================================================

Coordinates are the model's (site coordinates kept), written so that they
read back to the same floats; ``$INSUNITS`` is the model's length unit when
its ``units`` note names one.  The joint traces are on the layers
:mod:`~rockdem.exchange.dxf_in` reads, so a drawing's traces survive
DXF -> model -> DXF unchanged.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from pathlib import Path

import numpy as np

__all__ = ["LAYERS", "write_dxf", "write_section_dxf"]

#: Result layers and their ACI colours.
LAYERS = {
    "BLOCKS": 7,
    "FIXED": 8,
    "UNSTABLE": 1,
    "FAILED_JOINTS": 1,
    "SLIP_SURFACE": 6,
    "WATER": 5,
    "BLOCK_IDS": 3,
}
_JOINT_COLOURS = (4, 2, 30, 150, 210, 94)


def _new_doc(insunits: int):
    import ezdxf

    doc = ezdxf.new("R2010", setup=False)
    doc.header["$INSUNITS"] = int(insunits)
    doc.header["$MEASUREMENT"] = 0 if insunits in (1, 2) else 1
    return doc


def _layer(doc, name: str, colour: int) -> str:
    if name not in doc.layers:
        doc.layers.add(name, color=colour)
    return name


def _xy(points) -> list[tuple[float, float]]:
    return [(float(x), float(y)) for x, y in np.asarray(points, dtype=float).reshape(-1, 2)]


def write_section_dxf(
    path: str | Path,
    *,
    outline: Sequence,
    fixed: Sequence[Sequence] = (),
    traces: Mapping[str, Sequence[Sequence]] | None = None,
    water: Sequence | None = None,
    bolts: Sequence[tuple] = (),
    insunits: int = 6,
    as_lines: Collection[str] = (),
) -> Path:
    """Draw a section in the layer convention :func:`~rockdem.exchange.read_section` reads.

    Parameters
    ----------
    outline : sequence of (x, y)
        The section (closed polyline on ``OUTLINE``).
    fixed : sequence of polygons
        Fixed ground (closed polylines on ``FIXED``).
    traces : {joint: [polyline, ...]}
        Joint traces on ``JOINT_<joint>`` (LWPOLYLINEs).
    as_lines : collection of str
        Joints whose two-point traces are drawn as LINEs instead.
    water : sequence of (x, y), optional
    bolts : sequence of (head, tail)
    insunits : int
        ``$INSUNITS`` (6 = metres, 4 = millimetres, 0 = unitless).
    """
    doc = _new_doc(insunits)
    msp = doc.modelspace()
    msp.add_lwpolyline(_xy(outline), close=True, dxfattribs={"layer": _layer(doc, "OUTLINE", 7)})
    for poly in fixed:
        msp.add_lwpolyline(_xy(poly), close=True, dxfattribs={"layer": _layer(doc, "FIXED", 8)})
    for k, (joint, lines) in enumerate((traces or {}).items()):
        name = _layer(doc, f"JOINT_{joint}", _JOINT_COLOURS[k % len(_JOINT_COLOURS)])
        for line in lines:
            pts = _xy(line)
            if joint in as_lines and len(pts) == 2:
                msp.add_line(pts[0], pts[1], dxfattribs={"layer": name})
            else:
                msp.add_lwpolyline(pts, dxfattribs={"layer": name})
    if water is not None:
        msp.add_lwpolyline(_xy(water), dxfattribs={"layer": _layer(doc, "WATER", 5)})
    for head, tail in bolts:
        msp.add_line(_xy([head])[0], _xy([tail])[0], dxfattribs={"layer": _layer(doc, "BOLTS", 2)})
    path = Path(path)
    doc.saveas(path)
    return path


def write_dxf(
    path: str | Path, model, analysis=None, *, modes=None, units=None, failed=None
) -> Path:
    """Draw the blocks, joint traces and (with ``analysis``) the results as DXF.

    Parameters
    ----------
    model : rockdem.Model
    analysis : rockdem.Analysis, optional
        Unstable blocks, failed joints and the slip surface get their layers.
    modes : rockdem.modes.BlockModes, optional
        The failure modes to mark (default: those of ``analysis``); unstable
        blocks are those with a mode other than stable.
    units : rockdem.units.Units, optional
        Its length unit sets ``$INSUNITS`` (unitless when not known).
    failed : rockdem.Analysis, optional
        The failed end of a factor-of-safety search whose last equilibrium
        ``analysis`` is: the unstable blocks, their modes and the slip
        surface are its (the slip surface of the last equilibrium is none).
    """
    from .dxf_entities import INSUNITS

    length = getattr(units, "length", None)
    doc = _new_doc(INSUNITS.get(length, 0) if length else 0)
    msp = doc.modelspace()
    b = model.blocks
    text_height = 0.01 * b.extent
    for i in range(b.n_blocks):
        layer = _layer(
            doc, "FIXED" if b.fixed[i] else "BLOCKS", LAYERS["FIXED" if b.fixed[i] else "BLOCKS"]
        )
        msp.add_lwpolyline(_xy(b.outline(i)), close=True, dxfattribs={"layer": layer})
        c = b.centroid[i]
        msp.add_text(
            str(int(b.ids[i])),
            height=text_height,
            dxfattribs={"layer": _layer(doc, "BLOCK_IDS", LAYERS["BLOCK_IDS"])},
        ).set_placement((float(c[0]), float(c[1])))
    if model.joint_lines is not None:
        names = [j.name for j in model.joints]
        order = list(dict.fromkeys(names[k] for k in model.line_joint))
        for seg, k in zip(model.joint_lines, model.line_joint, strict=True):
            joint = names[k]
            colour = _JOINT_COLOURS[order.index(joint) % len(_JOINT_COLOURS)]
            layer = _layer(doc, f"JOINT_{_layer_safe(joint)}", colour)
            msp.add_line(_xy(seg)[0], _xy(seg)[1], dxfattribs={"layer": layer})
    if len(model.loads.water_table):
        msp.add_lwpolyline(
            _xy(model.loads.water_table), dxfattribs={"layer": _layer(doc, "WATER", 5)}
        )
    if analysis is not None:
        _results(doc, msp, analysis, modes, failed or analysis)
    path = Path(path)
    doc.saveas(path)
    return path


def _results(doc, msp, analysis, modes, limit) -> None:
    from ..modes import failure_modes

    system = analysis.system
    b = system.blocks
    if modes is None:
        modes = failure_modes(limit)
    unstable = np.asarray(limit.unstable, bool) | ((np.asarray(modes.code) > 0) & ~b.fixed)
    layer = _layer(doc, "UNSTABLE", LAYERS["UNSTABLE"])
    for i in np.flatnonzero(unstable):
        msp.add_lwpolyline(_xy(b.outline(int(i))), close=True, dxfattribs={"layer": layer})
    r, faces = analysis.interfaces, system.interfaces
    failed = np.asarray(r.state) > 0
    layer = _layer(doc, "FAILED_JOINTS", LAYERS["FAILED_JOINTS"])
    for i in np.flatnonzero(failed):
        msp.add_line(_xy([faces.start[i]])[0], _xy([faces.end[i]])[0], dxfattribs={"layer": layer})
    if len(limit.slip_surface):
        layer = _layer(doc, "SLIP_SURFACE", LAYERS["SLIP_SURFACE"])
        for i in limit.slip_surface:
            msp.add_line(
                _xy([faces.start[i]])[0], _xy([faces.end[i]])[0], dxfattribs={"layer": layer}
            )


def _layer_safe(name: str) -> str:
    """A joint name as a DXF layer name (characters CAD refuses replaced)."""
    bad = '<>/\\":;?*|=`'
    return "".join("_" if ch in bad else ch for ch in name)
