"""Deformed shape, displacement vectors and the failure mechanism."""

from __future__ import annotations

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.cm import ScalarMappable
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.colors import Normalize
from matplotlib.lines import Line2D

from ..results import format_factor
from . import _common as c
from .model import draw_blocks


def _motion(a, use: str) -> tuple[np.ndarray, str]:
    if use == "auto":
        use = "displacement" if a.stable else "mechanism"
    if use == "displacement":
        return a.displacement, "displacement"
    if use == "mechanism":
        return c.oriented_mechanism(a), "mechanism"
    raise ValueError(f"use must be 'auto', 'displacement' or 'mechanism', not {use!r}")


def deformed_state(a) -> tuple[float, float] | None:
    """``(strength factor, load factor)`` of the state ``a.displacement`` shows,
    or None when no equilibrium was found (the displacements are then zero or
    belong to another state)."""
    if a.stable:
        return float(a.strength_factor), float(a.load_factor)
    step = a.equilibrium
    if step is None or not np.any(a.displacement):
        return None
    return float(step.strength_factor), float(a.load_factor)


def auto_magnification(blocks, motion: np.ndarray, share: float = 0.05) -> float:
    """A 1-2-5 factor that makes the largest block motion about ``share`` of the extent."""
    top = float(c.motion_size(blocks, motion).max()) if blocks.n_blocks else 0.0
    if top <= 0 or not np.isfinite(top):
        return 1.0
    return c.nice_number(share * blocks.extent / top)


def plot_deformed(
    result,
    *,
    ax: Axes | None = None,
    magnification: float | None = None,
    use: str = "auto",
    vectors: bool = True,
    colormap: bool = True,
    unit: str = "m",
    title: str | None = None,
):
    """Draw the deformed blocks, magnified, over the undeformed outline.

    Each block is moved rigidly: its centroid by ``magnification x (ux, uy)``
    and turned by ``magnification x rotation`` about the centroid.  Blocks
    are coloured by the magnitude of their (unmagnified) motion, and arrows
    from the centroids show the magnified translation.

    Parameters
    ----------
    result : Analysis, FactorOfSafety or Model
    ax : Axes, optional
    magnification : float, optional
        Default: a 1-2-5 factor making the largest motion ~5 % of the model size.
    use : {"auto", "displacement", "mechanism"}
        ``"auto"``: the displacements of a stable analysis, the failure
        mechanism (direction of motion, largest = 1) of an unstable one,
        because displacements after failure mean nothing.  The mechanism is
        signed so that the loads do positive work on it.
    vectors, colormap : bool
        Draw displacement arrows; colour the blocks by motion magnitude.
    unit : str
    title : str, optional

    Returns
    -------
    Axes
        PolyCollection ``"deformed"`` (free blocks, moved), LineCollection
        ``"original"`` (undeformed outlines), Quiver ``"vectors"`` (one arrow
        per free block; for a mechanism, per unstable block).
    """
    a = c.as_analysis(result)
    blocks = a.system.blocks
    motion, kind = _motion(a, use)
    mag = auto_magnification(blocks, motion) if magnification is None else float(magnification)
    ax = c.new_axes(ax)
    free = ~blocks.fixed
    draw_blocks(ax, blocks.subset(blocks.fixed), face=None)
    moved = c.moved_outlines(blocks, motion, mag)
    size = c.motion_size(blocks, motion)
    deformed = PolyCollection(
        [moved[i] for i in np.flatnonzero(free)],
        edgecolors=c.BLOCK_EDGE,
        linewidths=0.7,
        zorder=2,
        gid="deformed",
        label=f"moved x{mag:g}",
    )
    top = float(size[free].max()) if free.any() else 0.0
    norm = Normalize(0.0, top if top > 0 else 1.0)
    moving = a.unstable if kind == "mechanism" else np.ones(blocks.n_blocks, dtype=bool)
    mappable = deformed
    if colormap and kind == "displacement":
        deformed.set_array(size[free])
        deformed.set_cmap(c.CMAP)
        deformed.set_norm(norm)
    elif colormap:
        # only the moving blocks are coloured; the rest stay rock-coloured
        cmap = matplotlib.colormaps[c.CMAP]
        faces = [cmap(norm(size[i])) if moving[i] else c.ROCK_FACE for i in np.flatnonzero(free)]
        deformed.set_facecolor(faces)
        mappable = ScalarMappable(norm=norm, cmap=cmap)
    else:
        deformed.set_facecolor(c.ROCK_FACE)
    ax.add_collection(deformed)
    closed = [np.vstack([v, v[:1]]) for v in (blocks.outline(i) for i in np.flatnonzero(free))]
    ax.add_collection(
        LineCollection(
            closed, colors="#555555", linewidths=0.6, linestyles="--", zorder=3, gid="original"
        )
    )
    arrows = free & moving
    if vectors and arrows.any():
        cen = blocks.centroid[arrows]
        u = motion[arrows, :2] * mag
        q = ax.quiver(
            cen[:, 0],
            cen[:, 1],
            u[:, 0],
            u[:, 1],
            angles="xy",
            scale_units="xy",
            scale=1.0,
            color=c.OKABE_ITO["vermillion"] if kind == "mechanism" else c.OKABE_ITO["black"],
            width=0.004,
            zorder=5,
        )
        q.set_gid("vectors")
    c.setup_space_axes(ax, blocks, unit)
    # the deformed blocks may leave the undeformed extent
    allv = np.vstack([blocks.vertices, *moved])
    lo, hi = allv.min(0), allv.max(0)
    pad = 0.04 * max(hi - lo)
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    if colormap and free.any():
        cb = ax.figure.colorbar(mappable, ax=ax, shrink=0.8)
        cb.set_label(
            f"displacement ({unit})"
            if kind == "displacement"
            else "relative motion in the mechanism (largest = 1)"
        )
    if title is None:
        if kind == "displacement":
            top = float(size.max())
            where = deformed_state(a)
            if where is None:
                at = f"F = {format_factor(a.strength_factor)}, no equilibrium found"
            elif a.stable:
                at = f"F = {format_factor(where[0])}"
            else:
                F, lam = format_factor(where[0]), where[1]
                at = f"the last equilibrium, F = {F}, load factor {lam:.3g}"
            title = (
                f"Deformed shape at {at}: displacements magnified x{mag:g} "
                f"(largest {top:.3g} {unit})"
            )
        elif a.stable:  # a search that found no failure (found by fuzzing: titled
            # "Failure mechanism at F = 86.4976" for two blocks on flat ground)
            F = format_factor(a.strength_factor)
            title = f"No failure mechanism: equilibrium holds at F = {F}"
        else:
            title = (
                f"Failure mechanism at F = {format_factor(a.strength_factor)}: how the blocks move "
                f"(direction, drawn x{mag:g})"
            )
    ax.set_title(title, fontsize=10)
    ax.legend(
        handles=[
            Line2D([], [], color="#555555", lw=0.8, ls="--", label="undeformed"),
            Line2D([], [], color=c.BLOCK_EDGE, lw=0.8, label=f"moved x{mag:g}"),
        ],
        loc="upper right",
        fontsize=7,
        framealpha=0.9,
    )
    return ax
