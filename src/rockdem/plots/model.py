"""The model picture: blocks, joints by set, rock bridges, ground, loads and supports."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.lines import Line2D
from matplotlib.patches import FancyArrowPatch, Patch

from . import _common as c
from .bolts import draw_bolt_lines


def draw_blocks(ax: Axes, blocks, verts=None, *, face=None, zorder: float = 1.0) -> tuple:
    """Free blocks as one PolyCollection, fixed ground hatched as another.

    Returns ``(free, ground)`` collections (gids ``"blocks"`` and ``"ground"``).
    """
    verts = c.outlines(blocks) if verts is None else verts
    fixed = blocks.fixed
    free_verts = [v for v, f in zip(verts, fixed, strict=True) if not f]
    ground_verts = [v for v, f in zip(verts, fixed, strict=True) if f]
    free = PolyCollection(
        free_verts,
        facecolors=c.ROCK_FACE if face is None else face,
        edgecolors=c.BLOCK_EDGE,
        linewidths=0.6,
        zorder=zorder,
        gid="blocks",
    )
    ground = PolyCollection(
        ground_verts,
        facecolors=c.GROUND_FACE,
        edgecolors=c.GROUND_EDGE,
        linewidths=0.6,
        hatch="///",
        zorder=zorder,
        gid="ground",
    )
    ax.add_collection(ground)
    ax.add_collection(free)
    return free, ground


def _is_bridge(joint, bridges) -> bool:
    if bridges is not None:
        return joint.name in bridges
    return "bridge" in joint.name.lower()


def draw_loads(
    ax: Axes, model, blocks, *, labels: bool = True
) -> tuple[list[FancyArrowPatch], np.ndarray]:
    """Point loads (black) and supports (green) as arrows ending at their point,
    line loads as rows of arrows; arrow lengths are fixed, magnitudes are labelled.

    Returns the arrows (gids ``"load"``, ``"support"``, ``"line-load"``) and
    their tail points ``(m, 2)`` (for the axis limits)."""
    arrows = []
    tails_all = [np.zeros((0, 2))]
    length = 0.07 * blocks.extent
    for p in model.loads.points:
        f = np.array([p.fx, p.fy], dtype=float)
        mag = float(np.hypot(*f))
        if mag == 0:
            continue
        head = np.array([p.x, p.y])
        tail = head - length * f / mag
        color = c.SUPPORT_COLOR if p.support else c.LOAD_COLOR
        arrow = FancyArrowPatch(
            tail,
            head,
            arrowstyle="-|>",
            mutation_scale=12,
            lw=1.8,
            color=color,
            zorder=6,
            gid="support" if p.support else "load",
        )
        ax.add_patch(arrow)
        arrows.append(arrow)
        tails_all.append(tail[None, :])
        if labels:
            text = (p.name + " " if p.name else "") + f"{mag:.3g}"
            u = -f / mag  # from the head toward the tail, and on beyond it
            ax.annotate(
                text,
                tail,
                xytext=(6 * u[0], 6 * u[1]),
                textcoords="offset points",
                fontsize=7,
                color=color,
                ha="left" if u[0] > 0.3 else ("right" if u[0] < -0.3 else "center"),
                va="bottom" if u[1] > 0.3 else ("top" if u[1] < -0.3 else "center"),
                zorder=6,
            )
    for line in model.loads.lines:
        t = np.linspace(0.0, 1.0, 5)
        q = line.traction(t)  # arrows scaled by the local traction (a trapezoid)
        mag = np.hypot(q[:, 0], q[:, 1])
        if not mag.max() > 0:
            continue
        p0, p1 = np.asarray(line.start, float), np.asarray(line.end, float)
        u = q / mag.max()
        heads = p0 + t[:, None] * (p1 - p0)
        tails = heads - 0.6 * length * u
        ax.plot(tails[:, 0], tails[:, 1], color=c.LOAD_COLOR, lw=1.0, zorder=6, gid="line-load")
        tails_all.append(tails)
        for h, t in zip(heads, tails, strict=True):
            arrow = FancyArrowPatch(
                t,
                h,
                arrowstyle="-|>",
                mutation_scale=9,
                lw=1.2,
                color=c.LOAD_COLOR,
                zorder=6,
                gid="line-load",
            )
            ax.add_patch(arrow)
            arrows.append(arrow)
        if labels:
            mid = tails.mean(axis=0)
            size = f"{mag[0]:.3g}" if np.ptp(mag) == 0 else f"{mag[0]:.3g} to {mag[-1]:.3g}"
            text = (line.name + " " if line.name else "") + f"{size}/length"
            ax.annotate(
                text,
                mid,
                xytext=(0, 3),
                textcoords="offset points",
                fontsize=7,
                ha="center",
                va="bottom",
                zorder=6,
            )
    return arrows, np.vstack(tails_all)


#: the water table's colour (Okabe-Ito sky blue)
WATER_COLOR = "#56B4E9"


def draw_water_table(ax: Axes, table, blocks) -> None:
    """The phreatic line across the model (level beyond its ends), dashed."""
    xy = np.asarray(table, dtype=float)
    lo, hi = blocks.vertices[:, 0].min(), blocks.vertices[:, 0].max()
    xs = np.concatenate([[lo], xy[(xy[:, 0] > lo) & (xy[:, 0] < hi), 0], [hi]])
    ax.plot(
        xs,
        np.interp(xs, xy[:, 0], xy[:, 1]),
        color=WATER_COLOR,
        lw=1.5,
        ls="--",
        zorder=4,
        gid="water-table",
    )


def draw_pressure_diagrams(ax: Axes, system, samples: int = 9) -> None:
    """The joint water pressure along every interface below the table, drawn
    as a diagram on the joint (filled, offset along its normal; the largest
    pressure is 4% of the model's size)."""
    from ..loads import joint_water, pore_pressure

    faces, loads = system.interfaces, joint_water(system.blocks, system.model.loads)
    t = np.linspace(0.0, 1.0, samples)
    pts = faces.start[:, None, :] + t[None, :, None] * (faces.end - faces.start)[:, None, :]
    u = pore_pressure(loads, pts.reshape(-1, 2)).reshape(-1, samples)
    wet = np.flatnonzero(u.max(axis=1) > 0)
    if not wet.size:
        return
    size = 0.04 * system.blocks.extent / float(u.max())
    offset = pts[wet] + size * u[wet][:, :, None] * faces.normal[wet][:, None, :]
    polys = [np.vstack([p, o[::-1]]) for p, o in zip(pts[wet], offset, strict=True)]
    ax.add_collection(
        PolyCollection(
            polys,
            facecolors=WATER_COLOR,
            edgecolors=WATER_COLOR,
            alpha=0.35,
            linewidths=0.5,
            zorder=4,
            gid="water-pressure",
        )
    )


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")


def draw_block_ids(ax: Axes, blocks, centroids=None, *, free_only: bool = False) -> None:
    """Block ids written at the centroids (gid ``"block-id"``)."""
    centroids = blocks.centroid if centroids is None else centroids
    for i in range(blocks.n_blocks):
        if free_only and blocks.fixed[i]:
            continue
        ax.text(
            *centroids[i],
            str(int(blocks.ids[i])),
            ha="center",
            va="center",
            fontsize=7,
            zorder=7,
            gid="block-id",
        )


def plot_model(
    model,
    *,
    ax: Axes | None = None,
    block_ids: bool = False,
    loads: bool = True,
    bridges: Sequence[str] | None = None,
    unit: str = "m",
    title: str | None = None,
    legend: bool = True,
) -> Axes:
    """Draw the model: blocks, joints coloured by joint set, rock bridges dashed,
    the fixed ground hatched, loads (black) and supports (green) as arrows.

    Parameters
    ----------
    model : Model, System, Analysis or FactorOfSafety
    ax : Axes, optional
        Draw into these axes (default: a new figure).
    block_ids : bool
        Write each block's id at its centroid.
    loads : bool
        Draw point loads, supports and line loads.
    bridges : sequence of str, optional
        Names of the joints that are rock bridges (default: joints whose name
        contains ``"bridge"``).
    unit : str
        Length unit for the axis labels and the scale bar.
    title : str, optional
    legend : bool

    Returns
    -------
    Axes
        Interfaces are in LineCollections with gids ``"joints"`` and
        ``"bridges"`` (one segment per interface, coloured by joint).
    """
    system = c.as_system(model)
    ax = c.new_axes(ax)
    blocks = system.blocks
    mdl = system.model
    draw_blocks(ax, blocks)
    seg = c.segments(system)
    joint = system.interfaces.joint
    is_bridge = np.array([_is_bridge(j, bridges) for j in mdl.joints], dtype=bool)
    bridge = is_bridge[joint] if len(joint) else np.zeros(0, dtype=bool)
    colors = [c.joint_color(int(j)) for j in joint]
    normal = LineCollection(
        seg[~bridge],
        colors=[col for col, b in zip(colors, bridge, strict=True) if not b],
        linewidths=1.8,
        zorder=3,
        gid="joints",
    )
    dashed = LineCollection(
        seg[bridge],
        colors=[col for col, b in zip(colors, bridge, strict=True) if b],
        linewidths=2.2,
        linestyles=(0, (1.5, 1.5)),
        zorder=3,
        gid="bridges",
    )
    ax.add_collection(normal)
    ax.add_collection(dashed)
    tails = np.zeros((0, 2))
    if loads:
        _, tails = draw_loads(ax, mdl, blocks)
        # room for the arrows and for the labels above their tails
        lift = np.array([0.0, 0.04 * blocks.extent])
        tails = np.vstack([tails, tails + lift])
    if loads and mdl.loads.water_table:
        draw_water_table(ax, mdl.loads.water_table, blocks)
    if loads and (mdl.loads.water_table or mdl.loads.pore_pressure_ratio):
        draw_pressure_diagrams(ax, system)
    bolt_handles = draw_bolt_lines(ax, mdl.bolts)
    if block_ids:
        draw_block_ids(ax, blocks, free_only=True)
    c.setup_space_axes(ax, blocks, unit, extra=tails)
    if title is None:
        title = (
            f"{mdl.name}: {_count(int((~blocks.fixed).sum()), 'block')}, "
            f"{_count(system.interfaces.n_interfaces, 'interface')}"
        )
    ax.set_title(title)
    if legend:
        handles = [
            Patch(
                facecolor=c.GROUND_FACE, edgecolor=c.GROUND_EDGE, hatch="///", label="fixed ground"
            )
        ]
        used = np.unique(joint)
        for j in used:
            ls = (0, (1.5, 1.5)) if is_bridge[j] else "-"
            kind = "rock bridge" if is_bridge[j] else "joint"
            handles.append(
                Line2D(
                    [],
                    [],
                    color=c.joint_color(int(j)),
                    lw=2,
                    ls=ls,
                    label=f"{kind}: {mdl.joints[j].name}",
                )
            )
        if loads and any(p.support for p in mdl.loads.points):
            handles.append(Line2D([], [], color=c.SUPPORT_COLOR, lw=2, marker=">", label="support"))
        if loads and mdl.loads.water_table:
            handles.append(Line2D([], [], color=WATER_COLOR, lw=1.5, ls="--", label="water table"))
        if loads and (mdl.loads.water_table or mdl.loads.pore_pressure_ratio):
            handles.append(Patch(facecolor=WATER_COLOR, alpha=0.35, label="joint water pressure"))
        handles += bolt_handles
        if loads and (any(not p.support for p in mdl.loads.points) or mdl.loads.lines):
            handles.append(Line2D([], [], color=c.LOAD_COLOR, lw=2, marker=">", label="load"))
        ax.legend(handles=handles, loc="upper right", fontsize=7, framealpha=0.9)
    return ax
