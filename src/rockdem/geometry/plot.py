"""Drawing a generated slope with matplotlib (imported on first use)."""

from __future__ import annotations

import numpy as np
import shapely

from .slope import SlopeGeometry

__all__ = ["plot_geometry"]

BRIDGE_COLOR = "#d62728"
SET_COLORS = ("#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#17becf", "#e377c2")


def plot_geometry(geom: SlopeGeometry, ax=None, *, title: str | None = None, legend: bool = True):
    """Draw blocks (outlined), joints coloured by set, rock bridges, hatched ground.

    Parameters
    ----------
    geom : SlopeGeometry
    ax : matplotlib Axes, optional
        Drawn into a new figure if not given.
    title : str, optional
    legend : bool

    Returns
    -------
    matplotlib Axes
    """
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    if ax is None:
        _, ax = plt.subplots(figsize=(10, 6))
    b = geom.blocks
    outlines = [b.outline(i) for i in range(b.n_blocks)]
    free = [o for o, f in zip(outlines, b.fixed, strict=True) if not f]
    fixed = [o for o, f in zip(outlines, b.fixed, strict=True) if f]
    ax.add_collection(PolyCollection(free, facecolors="#f2efe6", edgecolors="0.35",
                                     linewidths=0.4, zorder=1))
    if fixed:
        ax.add_collection(PolyCollection(fixed, facecolors="#d9d9d9", edgecolors="0.2",
                                         linewidths=0.8, hatch="////", zorder=1))
    handles = []
    region = shapely.union_all(geom.blocks.polygons()[~b.fixed])
    if len(geom.joint_lines):
        lines = shapely.intersection(shapely.linestrings(geom.joint_lines), region)
        names = geom.line_names
        set_names = [j.name for j in geom.joints if j.name not in ("bridge", "ground")]
        for k, name in enumerate([*set_names, "bridge"]):
            sel = lines[names == name]
            parts = shapely.get_parts(sel)
            parts = parts[(shapely.get_type_id(parts) == 1) & ~shapely.is_empty(parts)]
            if not len(parts):
                continue
            segs = [np.asarray(p.coords) for p in parts]
            bridge = name == "bridge"
            color = BRIDGE_COLOR if bridge else SET_COLORS[k % len(SET_COLORS)]
            width = 2.4 if bridge else 1.1
            ax.add_collection(LineCollection(segs, colors=color, linewidths=width, zorder=3))
            label = "rock bridge" if bridge else f"joint set {name}"
            handles.append(Line2D([], [], color=color, lw=width, label=label))
    for part in shapely.get_parts(geom.section):  # the section as cut (after any excavation)
        ax.plot(*np.asarray(part.exterior.coords).T, color="k", lw=1.3, zorder=4)
    if fixed:
        handles.append(Patch(facecolor="#d9d9d9", edgecolor="0.2", hatch="////",
                             label="fixed ground"))
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    n_free = int((~b.fixed).sum())
    ax.set_title(title or f"{n_free} blocks")
    if legend and handles:
        ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.9)
    return ax
