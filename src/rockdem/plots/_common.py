"""Shared plotting helpers: palette, figure creation, geometry of drawn blocks.

Library code never touches pyplot: figures are :class:`matplotlib.figure.Figure`
objects created here, so nothing leaks into a global figure manager.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..model import Model
from ..results import Analysis, FactorOfSafety
from ..solver import System, build_system

# --------------------------------------------------------------- palette
#: Okabe-Ito colour-blind-safe palette.
OKABE_ITO = {
    "black": "#000000",
    "orange": "#E69F00",
    "sky_blue": "#56B4E9",
    "bluish_green": "#009E73",
    "yellow": "#F0E442",
    "blue": "#0072B2",
    "vermillion": "#D55E00",
    "reddish_purple": "#CC79A7",
}
#: Shear failure is red (Okabe-Ito vermillion), tension failure blue, elastic grey.
STATE_COLORS = ("#9a9a9a", OKABE_ITO["vermillion"], OKABE_ITO["blue"])
STATE_LABELS = ("elastic", "shear-yielded", "tension-failed")
#: Current state (rockdem.results.CURRENT_NAMES): elastic grey, failed earlier and
#: now closed green dashed (history, holding now: not a present failure), sliding
#: red, open blue.
CURRENT_COLORS = ("#9a9a9a", OKABE_ITO["bluish_green"], OKABE_ITO["vermillion"], OKABE_ITO["blue"])
CURRENT_STYLES = ("solid", (0, (2.0, 1.2)), "solid", "solid")
CURRENT_WIDTHS = (1.0, 2.0, 2.2, 2.2)
#: Joint-set colours: the palette without vermillion (reserved for shear failure).
JOINT_COLORS = (
    OKABE_ITO["blue"],
    OKABE_ITO["orange"],
    OKABE_ITO["bluish_green"],
    OKABE_ITO["reddish_purple"],
    OKABE_ITO["sky_blue"],
    OKABE_ITO["black"],
    OKABE_ITO["yellow"],
)
ROCK_FACE = "#efe6d6"
GROUND_FACE = "#d9d9d9"
GROUND_EDGE = "#7a7a7a"
BLOCK_EDGE = "#4d4d4d"
UNSTABLE_FACE = OKABE_ITO["orange"]
#: Block faces by failure mode (rockdem.modes.MODES, "stable" unused).
MODE_FACES = {
    "slides": OKABE_ITO["orange"],
    "topples": OKABE_ITO["sky_blue"],
    "slides and topples": OKABE_ITO["yellow"],
    "falls": OKABE_ITO["reddish_purple"],
}
BOUNDARY_COLOR = OKABE_ITO["black"]
SLIP_COLOR = OKABE_ITO["reddish_purple"]
SUPPORT_COLOR = OKABE_ITO["bluish_green"]
LOAD_COLOR = OKABE_ITO["black"]
#: Sequential colour map for displacement magnitude (perceptually uniform, CVD-safe).
CMAP = "viridis"


def joint_color(index: int) -> str:
    """Colour of joint-table entry ``index``."""
    return JOINT_COLORS[index % len(JOINT_COLORS)]


# --------------------------------------------------------------- figures
def new_axes(ax: Axes | None = None, figsize=(8.0, 5.0)) -> Axes:
    """``ax`` itself, or the axes of a new (pyplot-free) figure."""
    if ax is not None:
        return ax
    # "compressed": constrained, and an equal-aspect map keeps its y label in the
    # figure beside a legend outside it (the wedge's failure picture lost "y (m)"
    # off its left edge with "constrained")
    fig = Figure(figsize=figsize, layout="compressed")
    return fig.add_subplot()


def nice_number(x: float) -> float:
    """The 1-2-5 number nearest below ``x`` (``x > 0``)."""
    if not x > 0 or not math.isfinite(x):
        return 1.0
    e = math.floor(math.log10(x))
    base = 10.0**e
    for m in (5.0, 2.0, 1.0):
        if m * base <= x:
            return m * base
    return base


def setup_space_axes(
    ax: Axes, blocks, unit: str, scale_bar: bool = True, extra: np.ndarray | None = None
) -> None:
    """Equal axes, labels with units, limits around the blocks (and ``extra``
    points, shape ``(m, 2)``), and a scale bar."""
    xy = blocks.vertices if extra is None or not len(extra) else np.vstack([blocks.vertices, extra])
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    pad = 0.04 * max(hi - lo)
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit})")
    if scale_bar:
        add_scale_bar(ax, float(hi[0] - lo[0]), unit)


def add_scale_bar(ax: Axes, span: float, unit: str) -> None:
    """A 1-2-5 scale bar of about a fifth of ``span`` in the lower left corner."""
    from matplotlib.font_manager import FontProperties
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    length = nice_number(span / 5.0)
    bar = AnchoredSizeBar(
        ax.transData,
        length,
        f"{length:g} {unit}",
        "lower left",
        pad=0.4,
        borderpad=0.5,
        sep=3,
        frameon=True,
        size_vertical=0,
        fontproperties=FontProperties(size=8),
    )
    bar.patch.set_alpha(0.8)
    bar.patch.set_edgecolor("none")
    bar.set_gid("scale-bar")
    ax.add_artist(bar)


# --------------------------------------------------------------- inputs
def as_system(obj) -> System:
    """The :class:`System` behind a model, system, analysis or factor of safety."""
    if isinstance(obj, System):
        return obj
    if isinstance(obj, Analysis):
        return obj.system
    if isinstance(obj, FactorOfSafety):
        a = obj.stable_analysis or obj.failed_analysis
        if a is None:
            raise ValueError("the factor of safety holds no analysis")
        return a.system
    if isinstance(obj, Model):
        return build_system(obj)
    raise TypeError(f"expected a Model, System, Analysis or FactorOfSafety, not {type(obj)!r}")


def as_analysis(obj) -> Analysis:
    """An :class:`Analysis` from an analysis, a factor of safety or a model."""
    if isinstance(obj, Analysis):
        return obj
    if isinstance(obj, FactorOfSafety):
        a = obj.failed_analysis or obj.stable_analysis
        if a is None:
            raise ValueError("the factor of safety holds no analysis")
        return a
    if isinstance(obj, (Model, System)):
        from ..analysis import analyse

        return analyse(obj)
    raise TypeError(f"expected a Model, System, Analysis or FactorOfSafety, not {type(obj)!r}")


# --------------------------------------------------------------- geometry
def outlines(blocks) -> list[np.ndarray]:
    """Vertex arrays of all blocks."""
    return [blocks.outline(i) for i in range(blocks.n_blocks)]


def moved_outlines(blocks, motion: np.ndarray, scale: float) -> list[np.ndarray]:
    """Block outlines after a rigid motion ``(ux, uy, rotation)`` magnified by ``scale``.

    The translation of the centroid is ``scale * (ux, uy)`` and the block
    turns rigidly by ``scale * rotation`` about its centroid, so magnified
    blocks keep their shape.
    """
    out = []
    for i in range(blocks.n_blocks):
        v = blocks.outline(i)
        c = blocks.centroid[i]
        ux, uy, th = np.asarray(motion[i], dtype=float) * scale
        cs, sn = math.cos(th), math.sin(th)
        r = v - c
        rot = np.column_stack([cs * r[:, 0] - sn * r[:, 1], sn * r[:, 0] + cs * r[:, 1]])
        out.append(c + rot + (ux, uy))
    return out


def motion_size(blocks, motion: np.ndarray) -> np.ndarray:
    """Largest displacement of any vertex of each block (translation plus rotation)."""
    size = np.zeros(blocks.n_blocks)
    for i in range(blocks.n_blocks):
        r = blocks.outline(i) - blocks.centroid[i]
        ux, uy, th = motion[i]
        d = np.column_stack([ux - th * r[:, 1], uy + th * r[:, 0]])
        size[i] = np.hypot(d[:, 0], d[:, 1]).max()
    return size


def oriented_mechanism(a) -> np.ndarray:
    """The failure mechanism of an analysis, signed so that the loads do positive work.

    A direction of motion is defined up to its sign; the engine's Newton
    step can point either way, and the blocks fall the way gravity (and the
    other loads) pushes them.
    """
    mech = np.asarray(a.mechanism, dtype=float)
    f = getattr(a.system, "f_block", None)
    if f is not None and np.sum(np.asarray(f) * mech) < 0:
        return -mech
    return mech


def point_segments(system: System) -> np.ndarray:
    """The stretch of interface each spring point stands for, ``(n_springs, 2, 2)``.

    Points run from the interface's start to its end; each stretch is as
    long as the point's quadrature weight, so the stretches tile the interface.
    """
    f, sp = system.interfaces, system.springs
    m = sp.points_per_interface
    w = sp.weight.reshape(-1, m)
    hi = np.cumsum(w, axis=1) / w.sum(axis=1, keepdims=True)
    lo = hi - w / w.sum(axis=1, keepdims=True)
    d = (f.end - f.start)[:, None, :]
    a = f.start[:, None, :] + lo[..., None] * d
    b = f.start[:, None, :] + hi[..., None] * d
    return np.stack([a, b], axis=2).reshape(-1, 2, 2)


def segments(system: System, which=None) -> np.ndarray:
    """Interface segments ``(n, 2, 2)`` (all, or those indexed by ``which``)."""
    f = system.interfaces
    seg = np.stack([f.start, f.end], axis=1)
    return seg if which is None else seg[np.asarray(which, dtype=int)]
