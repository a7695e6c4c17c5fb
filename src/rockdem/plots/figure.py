"""One figure to one file: the backend of ``rockdem plot MODEL --what ... --out FILE``."""

from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

from ..model import Model
from ..results import FactorOfSafety
from . import _common as c
from .fos import plot_fos
from .model import plot_model
from .motion import plot_deformed
from .state import animate_progressive, plot_failure, plot_progressive
from .stress import plot_joint_stress

#: What :func:`plot_figure` can draw, with a one-line description.
WHAT = {
    "model": "blocks, joints by set, rock bridges, ground, loads and supports",
    "failure": "interfaces by state, slip surface, unstable blocks",
    "deformed": "deformed shape (magnified) coloured by displacement, with vectors",
    "mechanism": "how the blocks move in the failure mechanism",
    "stress": "normal and shear stress along a joint",
    "progressive": "failure state after every load step / strength trial",
    "animation": "progressive failure as an animated GIF",
    "fos": "strength-reduction trials: verdict and displacement against F",
}


def _fos(obj):
    if isinstance(obj, FactorOfSafety):
        return obj
    if isinstance(obj, Model):
        from ..strength_reduction import factor_of_safety

        return factor_of_safety(obj)
    raise TypeError("the 'fos' figure needs a Model or a FactorOfSafety")


def make_figure(model_or_result, what: str, **options) -> Figure:
    """Draw one figure (see :data:`WHAT`) and return it (not for ``"animation"``)."""
    what = what.lower()
    if what not in WHAT or what == "animation":
        raise ValueError(f"unknown figure {what!r}; use one of {sorted(WHAT)}")
    obj = model_or_result
    if what == "model":
        return plot_model(obj, **options).figure
    if what == "fos":
        return plot_fos(_fos(obj), **options).figure
    if isinstance(obj, Model) and what in ("failure", "mechanism", "progressive"):
        # a stable slope fails at its factor of safety: show that mechanism
        obj = _fos(obj)
    a = c.as_analysis(obj)
    if what == "failure":  # the search itself: the title names the factor of safety too
        return plot_failure(obj if isinstance(obj, FactorOfSafety) else a, **options).figure
    if what == "deformed":
        return plot_deformed(a, **options).figure
    if what == "mechanism":
        return plot_deformed(a, use="mechanism", **options).figure
    if what == "stress":
        return plot_joint_stress(a, **options)
    return plot_progressive(a, **options)


def plot_figure(model_or_result, what: str, out_file, *, dpi: int = 150, **options) -> Path:
    """Draw one figure and save it; the format follows the file's extension.

    Parameters
    ----------
    model_or_result : Model, Analysis or FactorOfSafety
        A model is analysed as needed: ``"failure"``, ``"mechanism"`` and
        ``"progressive"`` run the factor-of-safety search (so a stable slope
        shows the mechanism of its failed end, at the factor that analysis
        reports); ``"deformed"``
        and ``"stress"`` run one staged analysis.
    what : str
        One of :data:`WHAT`.
    out_file : path
        ``.png``, ``.svg``, ``.pdf`` (vector) ...; ``.gif`` for ``"animation"``.
    dpi : int
        Resolution of raster output.
    **options
        Passed to the drawing function (for example ``block_ids=True``,
        ``joint="bedding"``, ``magnification=500``, ``unit="ft"``).

    Returns
    -------
    Path
        The file written.

    Examples
    --------
    >>> plot_figure(model, "failure", "failure.svg")  # doctest: +SKIP
    """
    out = Path(out_file)
    out.parent.mkdir(parents=True, exist_ok=True)
    if what.lower() == "animation":
        obj = model_or_result
        if isinstance(obj, Model):
            obj = _fos(obj)
        return animate_progressive(c.as_analysis(obj), out, dpi=min(dpi, 100), **options)
    fig = make_figure(model_or_result, what, **options)
    fig.savefig(out, dpi=dpi)
    return out


__all__ = ["WHAT", "make_figure", "plot_figure"]
