"""CAD sections in, results out: DXF drawings, VTK (ParaView), GeoJSON (GIS).

* :mod:`~rockdem.exchange.dxf_in`: a slope section drawn in CAD (outline,
  joint traces, fixed ground, water table, bolts on named layers) read into
  blocks and joint lines (:func:`read_section`, :func:`cut_section`);
  :mod:`~rockdem.exchange.model_file` writes it as a model file
  (:func:`model_text`, ``rockdem import``).
* :mod:`~rockdem.exchange.dxf_out`: the blocks, joint traces and results as a
  DXF drawing (unstable blocks and failed joints on their own layers).
* :mod:`~rockdem.exchange.vtk`: blocks as polygons, interfaces as lines, with
  their result fields, as VTK unstructured grids (``.vtu``) for ParaView.
* :mod:`~rockdem.exchange.geojson`: the section (blocks, joints, interfaces)
  as a GeoJSON feature collection.

ezdxf and meshio are imported only inside these modules' functions, so that
importing :mod:`rockdem` and the other commands stay fast.
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

_NAMES = {
    "read_section": "dxf_in",
    "cut_section": "dxf_in",
    "model_text": "model_file",
    "example_dxf": "dxf_in",
    "DEFAULT_LAYERS": "dxf_in",
    "write_dxf": "dxf_out",
    "write_vtk": "vtk",
    "write_geojson": "geojson",
    "section_features": "geojson",
}

__all__ = sorted(_NAMES)


def __getattr__(name: str) -> Any:
    if name in _NAMES:
        return getattr(import_module(f".{_NAMES[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
