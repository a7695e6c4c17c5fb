"""Bolts and cables on the section: the bolt lines, and at every joint a bolt
crosses a marker coloured by its utilisation (axial force / capacity)."""

from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.lines import Line2D

BOLT_COLOR = "#333333"
#: utilisation 0 -> 1 (yielded crossings are drawn at 1, with a red edge)
UTILISATION_CMAP = "viridis"
YIELD_EDGE = "#d62728"


def draw_bolt_lines(ax: Axes, bolts) -> list:
    """Each bolt from its head to its end (``bolts``: the model's Bolt list)."""
    if not bolts:
        return []
    segs = np.array([[b.head, b.end] for b in bolts])
    ax.add_collection(
        LineCollection(segs, colors=BOLT_COLOR, linewidths=1.4, zorder=6, gid="bolts")
    )
    ax.plot(segs[:, 0, 0], segs[:, 0, 1], "s", color=BOLT_COLOR, ms=3.5, zorder=6)
    return [Line2D([], [], color=BOLT_COLOR, lw=1.4, marker="s", ms=3.5, label="bolt")]


def draw_bolt_forces(ax: Axes, analysis) -> list:
    """The bolt lines and their crossings coloured by utilisation; legend handles."""
    res = analysis.bolts
    handles = draw_bolt_lines(ax, analysis.system.model.bolts)
    if res is None:
        return handles
    use = np.clip(res.utilisation, 0.0, 1.0)
    cmap = colormaps[UTILISATION_CMAP]
    edges = np.where(res.yielded, YIELD_EDGE, BOLT_COLOR)
    ax.scatter(
        res.point[:, 0],
        res.point[:, 1],
        c=cmap(use),
        edgecolors=edges,
        linewidths=np.where(res.yielded, 1.6, 0.6),
        s=28,
        zorder=7,
        gid="bolt-crossings",
    )
    handles.append(
        Line2D([], [], ls="", marker="o", mfc=cmap(0.0), mec=BOLT_COLOR, label="bolt force 0%")
    )
    handles.append(
        Line2D([], [], ls="", marker="o", mfc=cmap(1.0), mec=BOLT_COLOR, label="... 100% capacity")
    )
    if res.yielded.any():
        handles.append(
            Line2D([], [], ls="", marker="o", mfc=cmap(1.0), mec=YIELD_EDGE, label="bolt yielded")
        )
    return handles
