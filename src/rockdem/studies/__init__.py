"""Probabilistic and parametric studies: many runs of one model file on Dask.

Inputs are named by their key path in the model file (``joints.bedding.friction_angle``,
``slope.joint_sets.bedding.dip``, ``loads.seismic_h``, ``loads.water_table[*][1]``);
each sample edits the parsed file and builds the model through the normal
loader, so every key of the format can be varied and a sampled value out of
range is that sample's error, not the study's.

>>> import rockdem  # doctest: +SKIP
>>> table, summary = rockdem.study("slope.yaml", out="study/")  # doctest: +SKIP
>>> summary["pf"], summary["pf_interval"]  # doctest: +SKIP

Only :mod:`~rockdem.studies.spec` (pydantic) is imported with this package;
NumPy/SciPy sampling, pandas, pyarrow and Dask load when a study runs.
"""

from __future__ import annotations

from importlib import import_module

_PUBLIC = {
    "study": ".run",
    "StudyResult": ".run",
    "StudySpec": ".spec",
    "summarise": ".stats",
    "read_study": ".run",
}


def __getattr__(name: str):
    if name in _PUBLIC:
        value = getattr(import_module(_PUBLIC[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))


__all__ = ["StudyResult", "StudySpec", "read_study", "study", "summarise"]
