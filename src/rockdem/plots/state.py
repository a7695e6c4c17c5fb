"""Failure state: interfaces by state, slip surface, unstable blocks; progressive frames."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from ..modes import MODES, boundary_contacts, failure_modes
from ..results import CURRENT_LABELS, CURRENT_NAMES, format_factor
from . import _common as c
from .bolts import draw_bolt_forces
from .model import draw_block_ids, draw_blocks, draw_loads


@dataclass(frozen=True)
class Frame:
    """The failure state after one step of an analysis.

    Attributes
    ----------
    index : int
        Position in ``analysis.steps``.
    stage, load_factor, strength_factor, converged :
        Copied from the step.
    spring_state : ndarray of int
        0 elastic, 1 shear, 2 tension for every spring after this step.
    interface_state : ndarray of int
        Worst spring state on every interface.
    final : bool
        The last step (the slip surface and unstable blocks belong to it).
    failed_at : float or None
        For a strength trial without equilibrium, the factor at which
        equilibrium was lost (the state drawn is there, not at the trial's factor).
    """

    index: int
    stage: int
    load_factor: float
    strength_factor: float
    converged: bool
    spring_state: np.ndarray
    interface_state: np.ndarray
    final: bool
    failed_at: float | None = None

    @property
    def label(self) -> str:
        """A short caption, for example ``"step 3: load x0.6, F = 1"``."""
        F = format_factor(self.strength_factor)
        head = f"step {self.index + 1}: load x{self.load_factor:.3g}, F = "
        if self.converged:
            return head + F
        if self.failed_at is not None and self.failed_at != self.strength_factor:
            # "F = 1.5000 (no equilibrium)" for a trial that lost it at 1.1074
            return head + f"{F} tried (no equilibrium; lost at {format_factor(self.failed_at)})"
        return head + f"{F} (no equilibrium)"


def frames(result) -> list[Frame]:
    """The failure state at every load step / strength trial of an analysis.

    A spring counts as failed at a step when its ``first_failure`` stage is
    the stage of that step or of an earlier one; its state then is its final
    state (a spring that first yielded in shear and later opened shows as
    tension-failed from the stage it first failed).  Nothing is re-run.

    Parameters
    ----------
    result : Analysis or FactorOfSafety
        For a factor of safety, the analysis at the upper end of the bracket
        (its steps are the load steps and then the chain of strength trials).
    """
    a = c.as_analysis(result)
    sp = a.springs
    n_if = a.system.interfaces.n_interfaces
    out = []
    seen: set[int] = set()
    for k, step in enumerate(a.steps):
        seen.add(int(step.stage))
        failed = np.isin(sp.first_failure, sorted(seen)) & (sp.first_failure >= 0)
        s_state = np.where(failed, sp.state, 0)
        i_state = np.zeros(n_if, dtype=int)
        np.maximum.at(i_state, sp.interface, s_state)
        out.append(
            Frame(
                k,
                int(step.stage),
                float(step.load_factor),
                float(step.strength_factor),
                bool(step.converged),
                s_state,
                i_state,
                k == len(a.steps) - 1,
                None if step.evidence.failed_at is None else float(step.evidence.failed_at),
            )
        )
    return out


def plot_failure(
    result,
    *,
    ax: Axes | None = None,
    step: int | None = None,
    block_ids: bool = False,
    unit: str = "m",
    title: str | None = None,
    legend: bool = True,
    scale_bar: bool = True,
    current: bool = True,
) -> Axes:
    """Draw the failure state: joints by state, the slip surface, unstable blocks.

    The last step shows the *current* state of every joint, stretch by
    stretch (each spring point's share of its interface): sliding red
    (vermillion), open blue, failed earlier but now closed and holding green
    dashed (history, not a present failure), elastic grey.  Earlier
    steps (and ``current=False``) show the failure *history* by then: yielded
    in shear red, failed in tension blue, per interface.  The slip surface
    is a wide purple band under them; the blocks that move in the failure
    mechanism are shaded by failure mode (:func:`rockdem.modes.failure_modes`:
    slides orange, topples sky blue, slides and topples yellow, falls purple),
    with the pivot corners of toppling blocks dotted and contacts with a
    fixed side of the model (:func:`rockdem.modes.boundary_contacts`) dash-dotted.
    Bolts are dark lines; where one crosses a joint a dot shows its force
    as a share of its capacity (viridis, 0 to 100%; red edge: yielded).

    Parameters
    ----------
    result : Analysis, FactorOfSafety or Model
        A model is analysed first; a factor of safety shows its failed
        analysis (its title names that analysis's factor and the factor of
        safety apart).
    ax : Axes, optional
    step : int, optional
        Show the state after ``analysis.steps[step]`` (default: the last).
        The slip surface and unstable blocks are drawn at the last step only.
    block_ids, unit, title, legend, scale_bar :
        Display options.
    current : bool
        At the last step, the current state (default) or the history.

    Returns
    -------
    Axes
        Current state: LineCollections with gids ``"interfaces-elastic"``,
        ``"interfaces-closed-failed-earlier"``, ``"interfaces-sliding"``,
        ``"interfaces-open"`` (one segment per spring point's stretch).
        History: ``"interfaces-elastic"``, ``"interfaces-shear"``,
        ``"interfaces-tension"`` (one segment per interface).  Always
        ``"slip-surface"``, ``"boundary-contact"``; PolyCollection ``"unstable"``
        (face colours by mode); Line2D ``"pivots"``.
    """
    a = c.as_analysis(result)
    fos = result if isinstance(result, c.FactorOfSafety) else None
    system = a.system
    blocks = system.blocks
    own = ax is None  # a figure of our own: its legend can sit in the layout
    ax = c.new_axes(ax)
    fr = frames(a)
    frame = fr[-1 if step is None else step]
    now = current and frame.final and a.springs.current is not None
    draw_blocks(ax, blocks)
    mode_handles = []
    if frame.final and a.unstable.any():
        mode_handles = _draw_modes(ax, a)
    seg = c.segments(system)
    if frame.final and len(a.slip_surface):
        ax.add_collection(
            LineCollection(
                seg[a.slip_surface],
                colors=c.SLIP_COLOR,
                linewidths=6.0,
                alpha=0.6,
                capstyle="round",
                zorder=2,
                gid="slip-surface",
            )
        )
    handles = (
        _draw_current(ax, a)
        if now
        else _draw_history(ax, seg, a.interfaces.state if frame.final else frame.interface_state)
    )
    if frame.final and system.bolts is not None:
        # the bolts at the last equilibrium below the limit, as `rockdem fos`
        # lists them (the failed trial's own state is its start: the gravity
        # state or a trial far below the limit, with the bolts barely loaded)
        held = fos.stable_analysis if fos is not None else None
        handles += draw_bolt_forces(ax, held if held is not None else a)
    tails = np.zeros((0, 2))
    supports = tuple(p for p in system.model.loads.points if p.support)
    if supports:  # the support forces the state carries
        mdl = system.model
        only = mdl.replace(loads=replace(mdl.loads, points=supports, lines=()))
        _, tails = draw_loads(ax, only, blocks)
        handles.append(Line2D([], [], color=c.SUPPORT_COLOR, lw=2, marker=">", label="support"))
    if block_ids:
        draw_block_ids(ax, blocks, free_only=True)
    c.setup_space_axes(ax, blocks, unit, scale_bar=scale_bar, extra=tails)
    if title is None:
        title = state_title(a, fos) if frame.final else f"Failure state: {frame.label}"
    ax.set_title(title)
    if legend:
        if frame.final and len(a.slip_surface):
            handles.append(
                Line2D([], [], color=c.SLIP_COLOR, lw=6, alpha=0.6, label="slip surface")
            )
        handles += mode_handles
        style = {
            "handles": handles,
            "fontsize": 7,
            "framealpha": 0.9,
            "title": "joints now (interfaces)" if now else "failure history (interfaces)",
            "title_fontsize": 7,
        }
        if own:  # beside the model, inside the figure's constrained layout
            ax.figure.legend(loc="outside right upper", **style)
        else:  # beside the model, in the caller's layout
            ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, **style)
    return ax


def failure_legend(ax: Axes):
    """The legend :func:`plot_failure` drew (on the axes, or on its own figure)."""
    return ax.get_legend() or (ax.figure.legends[-1] if ax.figure.legends else None)


def _draw_modes(ax: Axes, a) -> list:
    """Moving blocks shaded by failure mode, pivots of toppling blocks dotted, the
    contacts with a fixed side of the model drawn dash-dotted; legend handles."""
    blocks = a.system.blocks
    modes = failure_modes(a)
    moving = np.flatnonzero(a.unstable & ~blocks.fixed)
    names = modes.name[moving]
    face = [c.MODE_FACES.get(str(m), c.UNSTABLE_FACE) for m in names]
    ax.add_collection(
        PolyCollection(
            [blocks.outline(i) for i in moving],
            facecolors=face,
            alpha=0.6,
            edgecolors="none",
            zorder=1.5,
            gid="unstable",
        )
    )
    handles = [
        Patch(facecolor=c.MODE_FACES[m], alpha=0.6, label=f"{m} ({int((names == m).sum())})")
        for m in MODES
        if m in c.MODE_FACES and (names == m).any()
    ]
    piv = modes.pivot[moving]
    piv = np.unique(piv[np.isfinite(piv).all(1)], axis=0)
    if len(piv):
        ax.plot(*piv.T, "o", ms=4, color="black", zorder=7, gid="pivots", ls="none")
        handles.append(
            Line2D([], [], marker="o", ms=4, color="black", ls="none", label="toppling pivot")
        )
    contacts = boundary_contacts(a)
    if contacts:
        seg = c.segments(a.system)
        hit = np.concatenate([b.interfaces for b in contacts])
        ax.add_collection(
            LineCollection(
                seg[hit],
                colors=c.BOUNDARY_COLOR,
                linewidths=3.0,
                linestyles="dashdot",
                zorder=2.5,
                gid="boundary-contact",
            )
        )
        handles.append(
            Line2D(
                [],
                [],
                color=c.BOUNDARY_COLOR,
                lw=2.5,
                ls="dashdot",
                label="mechanism at the model boundary",
            )
        )
    return handles


def _draw_current(ax: Axes, a) -> list:
    """Each spring point's stretch in the colour of its current state; legend handles
    counting interfaces by the state of most of their length."""
    pieces = c.point_segments(a.system)
    code = np.asarray(a.springs.current)
    counts = np.bincount(a.interfaces.current, minlength=len(CURRENT_NAMES))
    handles = []
    for k, name in enumerate(CURRENT_NAMES):
        style = {
            "colors": c.CURRENT_COLORS[k],
            "linewidths": c.CURRENT_WIDTHS[k],
            "linestyles": c.CURRENT_STYLES[k],
        }
        ax.add_collection(
            LineCollection(pieces[code == k], zorder=3 + k, gid=f"interfaces-{name}", **style)
        )
        handles.append(
            Line2D(
                [],
                [],
                color=c.CURRENT_COLORS[k],
                lw=c.CURRENT_WIDTHS[k],
                ls=c.CURRENT_STYLES[k],
                label=f"{CURRENT_LABELS[k]} ({counts[k]})",
            )
        )
    return handles


#: Legend labels of the failure history (``Analysis.interfaces.state``).
HISTORY_LABELS = ("never failed", "yielded in shear", "failed in tension")


def _draw_history(ax: Axes, seg: np.ndarray, state: np.ndarray) -> list:
    """Interfaces by their failure history (worst flag so far); legend handles."""
    labels = HISTORY_LABELS
    handles = []
    for s, name in enumerate(("elastic", "shear", "tension")):
        sel = state == s
        lw = 1.0 if s == 0 else 2.2
        ax.add_collection(
            LineCollection(
                seg[sel],
                colors=c.STATE_COLORS[s],
                linewidths=lw,
                zorder=3 + s,
                gid=f"interfaces-{name}",
            )
        )
        handles.append(
            Line2D([], [], color=c.STATE_COLORS[s], lw=lw, label=f"{labels[s]} ({sel.sum()})")
        )
    return handles


def state_title(a, fos=None) -> str:
    """``"Failure state at F = 0.9123: unstable (factor of safety 0.825)"``: the
    factor is the one the analysis reports, the factor of safety is named
    beside it, never implied."""
    title = f"Failure state at F = {format_factor(a.strength_factor)}: {a.verdict}"
    if fos is not None and fos.value is not None:
        title += f" (factor of safety {fos.value:.4f})"
    return title


def _pick(n: int, most: int) -> list[int]:
    """At most ``most`` indices out of ``n``, evenly spread, first and last kept."""
    if n <= most:
        return list(range(n))
    return sorted({int(x) for x in np.rint(np.linspace(0, n - 1, most))})


def plot_progressive(
    result, *, max_frames: int = 12, ncols: int = 3, unit: str = "m", figwidth: float = 10.0
) -> Figure:
    """Small multiples of the failure state after each step (load step or trial).

    Returns
    -------
    Figure
        One axes per frame (at most ``max_frames``, evenly chosen, the first
        and the last always shown), titled with the frame's stage.
    """
    a = c.as_analysis(result)
    fr = frames(a)
    chosen = _pick(len(fr), max_frames)
    nrows = -(-len(chosen) // ncols)
    ncols = min(ncols, len(chosen))
    lo, hi = a.system.blocks.vertices.min(0), a.system.blocks.vertices.max(0)
    aspect = (hi[1] - lo[1]) / max(hi[0] - lo[0], 1e-12)
    height = nrows * (figwidth / ncols) * aspect + 0.6 * nrows + 0.6
    fig = Figure(figsize=(figwidth, height), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False)
    for ax, k in zip(axes.flat, chosen, strict=False):
        plot_failure(
            a,
            ax=ax,
            step=k,
            unit=unit,
            title=fr[k].label,
            legend=False,
            scale_bar=False,
            current=False,
        )
        ax.title.set_fontsize(8)
        ax.tick_params(labelsize=7)
        ax.xaxis.label.set_fontsize(7)
        ax.yaxis.label.set_fontsize(7)
    for ax in axes.flat[len(chosen) :]:
        ax.set_axis_off()
    moving = failure_modes(a).name[a.unstable & ~a.system.blocks.fixed]
    handles = [
        Line2D([], [], color=col, lw=2, label=lab)
        for col, lab in zip(c.STATE_COLORS, HISTORY_LABELS, strict=True)
    ]
    handles.append(Line2D([], [], color=c.SLIP_COLOR, lw=6, alpha=0.6, label="slip surface"))
    handles += [
        Patch(facecolor=c.MODE_FACES[m], alpha=0.6, label=f"block {m}")
        for m in MODES
        if m in c.MODE_FACES and (moving == m).any()
    ]
    fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), 6), fontsize=8)
    fig.suptitle("Progressive failure: which joints have failed by each step (history)")
    return fig


def animate_progressive(
    result,
    out_file,
    *,
    fps: float = 1.5,
    dpi: int = 90,
    unit: str = "m",
    figsize=(9.0, 4.5),
    hold: int = 3,
) -> Path:
    """Write the progressive failure as an animated GIF (matplotlib's PillowWriter).

    One frame per step of the analysis (see :func:`frames`); the last frame
    is held ``hold`` extra frames.

    Returns
    -------
    Path
        The GIF written.
    """
    from matplotlib.animation import PillowWriter

    a = c.as_analysis(result)
    out = Path(out_file)
    fig = Figure(figsize=figsize)
    ax = fig.add_axes((0.07, 0.1, 0.66, 0.8))  # room for the legend on the right
    writer = PillowWriter(fps=fps)
    fr = frames(a)
    with writer.saving(fig, str(out), dpi):
        for k, frame in enumerate(fr):
            ax.clear()
            title = frame.label if not frame.final else f"{frame.label} - {a.verdict}"
            plot_failure(a, ax=ax, step=k, unit=unit, title=title, current=False)
            repeat = 1 + (hold if frame.final else 0)
            for _ in range(repeat):
                writer.grab_frame()
    return out
