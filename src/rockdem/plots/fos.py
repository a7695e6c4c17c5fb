"""The factor-of-safety search: verdict and displacement against the trial factor."""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.transforms import blended_transform_factory

from ..results import bracket_decimals
from . import _common as c


def max_displacement(a) -> float:
    """Largest displacement of any block vertex of an analysis (translation + rotation)."""
    blocks = a.system.blocks
    if not blocks.n_blocks:
        return 0.0
    return float(c.motion_size(blocks, a.displacement).max())


def trial_displacements(fos, *, recompute: bool = True) -> tuple[np.ndarray, str]:
    """A displacement measure for every trial of a factor-of-safety search.

    Uses ``trial.max_displacement`` when the engine records it; otherwise
    (``recompute=True``) the largest block displacement of a fresh staged
    analysis at each stable trial factor (the search itself continues each
    trial from the last stable state, so this is an approximation).
    Unstable trials get NaN.

    Returns
    -------
    values : ndarray
        One value per trial (NaN where none).
    source : str
        ``"search"``, ``"recomputed"`` or ``"none"``.
    """
    trials = fos.trials
    recorded = [getattr(t, "max_displacement", None) for t in trials]
    if trials and all(v is not None for v in recorded):
        vals = np.array(recorded, dtype=float)
        vals[[not t.stable for t in trials]] = np.nan
        return vals, "search"
    base = fos.stable_analysis or fos.failed_analysis
    if not recompute or base is None:
        return np.full(len(trials), np.nan), "none"
    from ..analysis import analyse

    vals = np.full(len(trials), np.nan)
    for k, t in enumerate(trials):
        if t.stable:
            if fos.stable_analysis is not None and t.factor == fos.stable_analysis.strength_factor:
                a = fos.stable_analysis
            else:
                a = analyse(base.system, strength_factor=t.factor)
            if a.stable:
                vals[k] = max_displacement(a)
    return vals, "recomputed"


def plot_fos(
    fos,
    *,
    ax: Axes | None = None,
    displacements: np.ndarray | None = None,
    recompute: bool = True,
    unit: str = "m",
    title: str | None = None,
) -> Axes:
    """Trial factors of the strength-reduction search, their verdict and displacement.

    Stable trials are green circles at their largest block displacement;
    trials without equilibrium are red crosses along the top, hollow grey
    ones where Newton found none but the failure was neither proven (LP)
    nor confirmed (dynamic relaxation) there (such trials lie inside the
    bracket).  Numbers give
    the order of the trials; the bracket is shaded and the factor of safety
    drawn as a dashed line.

    Parameters
    ----------
    fos : FactorOfSafety
    ax : Axes, optional
    displacements : array, optional
        One value per trial (default: :func:`trial_displacements`).
    recompute : bool
        Allow :func:`trial_displacements` to re-run analyses.
    unit : str
    title : str, optional

    Returns
    -------
    Axes
        Line2D gids ``"trials-stable"``, ``"trials-unstable"`` and
        ``"trials-undecided"``.
    """
    ax = c.new_axes(ax, figsize=(7.0, 4.2))
    trials = fos.trials
    F = np.array([t.factor for t in trials], dtype=float)
    ok = np.array([t.stable for t in trials], dtype=bool)
    if displacements is None:
        disp, source = trial_displacements(fos, recompute=recompute)
    else:
        disp, source = np.asarray(displacements, dtype=float), "given"
    have = np.isfinite(disp) & ok
    top = blended_transform_factory(ax.transData, ax.transAxes)
    if have.any():
        y_ok = disp[ok]
        ax.set_ylabel(f"largest block displacement ({unit})")
        order = np.argsort(F[have])
        ax.plot(F[have][order], disp[have][order], "-", color="#888888", lw=0.8, zorder=1)
        ax.plot(
            F[ok],
            np.where(np.isfinite(y_ok), y_ok, 0.0),
            "o",
            color=c.SUPPORT_COLOR,
            ms=7,
            zorder=3,
            gid="trials-stable",
            ls="none",
        )
        ax.set_ylim(bottom=0.0, top=1.18 * float(np.nanmax(disp[have])) or 1.0)
        y_text = np.where(np.isfinite(disp), disp, 0.0)
    else:
        ax.plot(
            F[ok],
            np.full(ok.sum(), 0.5),
            "o",
            color=c.SUPPORT_COLOR,
            ms=7,
            zorder=3,
            gid="trials-stable",
            ls="none",
            transform=top,
        )
        ax.set_yticks([])
        ax.set_ylabel("verdict")
        y_text = None
    # a failed trial is a failure where the LP proved it or dynamic relaxation
    # confirmed it, and the bracket counts it (one inside the bracket was
    # confirmed only farther on); otherwise only Newton found no equilibrium
    proven = np.array([t.evidence.proof != "undecided" for t in trials], dtype=bool)
    shown = proven & (F >= fos.bracket[1] * (1 - 1e-12))
    ax.plot(
        F[~ok & shown],
        np.full((~ok & shown).sum(), 0.93),
        "X",
        color=c.STATE_COLORS[1],
        ms=8,
        zorder=3,
        gid="trials-unstable",
        ls="none",
        transform=top,
    )
    stalled = ~ok & ~shown
    ax.plot(
        F[stalled],
        np.full(stalled.sum(), 0.93),
        "X",
        mfc="none",
        color="#777777",
        ms=8,
        zorder=3,
        gid="trials-undecided",
        ls="none",
        transform=top,
    )
    for k in range(len(F)):
        if ok[k] and y_text is not None:
            ax.annotate(
                str(k + 1), (F[k], y_text[k]), xytext=(4, 4), textcoords="offset points", fontsize=7
            )
        else:
            ax.annotate(
                str(k + 1),
                (F[k], 0.93 if not ok[k] else 0.5),
                xycoords=top,
                xytext=(5, -10),
                textcoords="offset points",
                fontsize=7,
            )
    lo, hi = fos.bracket
    if np.isfinite(hi) and hi > 0:
        ax.axvspan(lo, hi, color=c.OKABE_ITO["sky_blue"], alpha=0.35, lw=0, zorder=0)
    if fos.value is not None:
        ax.axvline(fos.value, color=c.OKABE_ITO["blue"], ls="--", lw=1.2, zorder=2)
    ax.set_xlabel("trial factor F (strengths divided by F)")
    if title is None:
        d = bracket_decimals(lo, hi)
        if fos.value is not None and fos.proof == "undecided":  # as `rockdem fos` says it
            title = (
                f"Factor of safety at least {lo:.{d}f} (undecided above; "
                f"equilibrium lost at {hi:.{d}f})"
            )
        elif fos.value is not None:
            title = f"Factor of safety {fos.value:.4f} in [{lo:.{d}f}, {hi:.{d}f}]"
        else:
            title = f"No factor of safety ({fos.mode}), bracket [{lo:.3g}, {hi:.3g}]"
    ax.set_title(title, fontsize=10)
    handles = [
        Line2D([], [], marker="o", color=c.SUPPORT_COLOR, ls="none", label="equilibrium"),
        Line2D([], [], marker="X", color=c.STATE_COLORS[1], ls="none", label="no equilibrium"),
        Patch(color=c.OKABE_ITO["sky_blue"], alpha=0.35, label="bracket"),
    ]
    if stalled.any():
        handles.insert(
            2,
            Line2D(
                [],
                [],
                marker="X",
                mfc="none",
                color="#777777",
                ls="none",
                label="none found, failure not proven",
            ),
        )
    if fos.value is not None:
        handles.append(Line2D([], [], color=c.OKABE_ITO["blue"], ls="--", label="factor of safety"))
    ax.legend(handles=handles, loc="lower right", fontsize=7, framealpha=0.9)
    if source == "recomputed":
        ax.text(
            0.01,
            0.01,
            "displacements: fresh staged analyses at each stable F",
            transform=ax.transAxes,
            fontsize=6,
            color="#555555",
        )
    return ax
