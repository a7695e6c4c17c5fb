"""Normal and shear stress along chosen joints, from the Winkler spring points."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure

from ..results import CURRENT_LABELS, CURRENT_NAMES, format_factor
from . import _common as c
from .model import draw_blocks


@dataclass(frozen=True)
class JointPath:
    """Chosen interfaces put end to end, and the spring points along them.

    Attributes
    ----------
    interfaces : ndarray of int
        Interface positions in path order.
    springs : ndarray of int
        Spring positions in path order.
    position : ndarray
        Distance of each spring along the path from its start.
    piece : ndarray of int
        For each spring, the position of its interface in ``interfaces``.
    """

    interfaces: np.ndarray
    springs: np.ndarray
    position: np.ndarray
    piece: np.ndarray


def select_interfaces(a, joint=None, interfaces: Sequence[int] | None = None) -> np.ndarray:
    """Interfaces of a joint name, of a joint line, or the default choice.

    Parameters
    ----------
    a : Analysis
    joint : str or int, optional
        A joint name (all interfaces of that joint) or the index of one of
        the model's ``joint_lines`` (the interfaces lying on that trace).
    interfaces : sequence of int, optional
        Explicit interface positions (wins over ``joint``).

    Returns
    -------
    ndarray of int
        Default: the slip surface, else the failed interfaces that still
        carry load (not wholly open), else the interfaces of the joint with
        the smallest local factor of safety.  (An open tension crack, all
        zeros, was drawn for a plane failure that stands at F = 1.)
    """
    system = a.system
    faces = system.interfaces
    if interfaces is not None:
        return np.asarray(interfaces, dtype=int)
    if isinstance(joint, str):
        return np.flatnonzero(a.interfaces.kind == joint)
    if joint is not None:
        lines = system.model.joint_lines
        if lines is None or not 0 <= int(joint) < len(lines):
            raise ValueError(f"joint line {joint} does not exist")
        p0, p1 = lines[int(joint)]
        t = (p1 - p0) / np.hypot(*(p1 - p0))
        n = np.array([t[1], -t[0]])
        tol = 10 * system.blocks.tolerance
        length = float(np.hypot(*(p1 - p0)))
        ok = np.ones(faces.n_interfaces, dtype=bool)
        for pt in (faces.start, faces.end):
            r = pt - p0
            s = r @ t
            ok &= (np.abs(r @ n) <= tol) & (s >= -tol) & (s <= length + tol)
        return np.flatnonzero(ok)
    if len(a.slip_surface):
        return np.asarray(a.slip_surface, dtype=int)
    failed = np.asarray(a.failed_interfaces, dtype=int)
    carrying = failed[a.interfaces.open_fraction[failed] < 1.0] if failed.size else failed
    if carrying.size:
        return carrying
    fos = np.where(np.isfinite(a.interfaces.local_fos), a.interfaces.local_fos, np.inf)
    if not len(fos):
        return np.zeros(0, dtype=int)
    return np.flatnonzero(a.interfaces.kind == a.interfaces.kind[int(np.argmin(fos))])


def joint_path(a, chosen: np.ndarray) -> JointPath:
    """Order ``chosen`` interfaces along their main direction and place the springs.

    The path runs toward +x (toward the slope face); a vertical path runs
    downward.  Positions accumulate interface lengths, so along a stepped
    slip surface they are the distance measured along the surface.
    """
    faces = a.system.interfaces
    sp = a.springs
    chosen = np.asarray(chosen, dtype=int)
    if chosen.size == 0:
        z = np.zeros(0, dtype=int)
        return JointPath(z, z, np.zeros(0), z)
    mid = faces.midpoint[chosen]
    if chosen.size > 1 and np.ptp(mid, axis=0).max() > 0:
        _, _, vt = np.linalg.svd(mid - mid.mean(0), full_matrices=False)
        d = vt[0]
    else:
        d = faces.tangent[chosen[0]]
    if d[0] < -1e-9 or (abs(d[0]) <= 1e-9 and d[1] > 0):
        d = -d
    order = chosen[np.argsort(mid @ d, kind="stable")]
    # each interface's springs, by distance from its end that comes first along d
    rank = np.full(faces.n_interfaces, -1)
    rank[order] = np.arange(len(order))
    s = np.flatnonzero(rank[sp.interface] >= 0)
    piece = rank[sp.interface[s]]
    forward = np.einsum("ij,j->i", faces.end[order] - faces.start[order], d) >= 0
    start = np.where(forward[:, None], faces.start[order], faces.end[order])
    along = np.hypot(*(sp.point[s] - start[piece]).T)
    o = np.lexsort((along, piece))
    offset = np.concatenate([[0.0], np.cumsum(faces.length[order])[:-1]])
    return JointPath(order, s[o], offset[piece[o]] + along[o], piece[o])


def _broken(x: np.ndarray, y: np.ndarray, piece: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Insert NaN between pieces so a line is drawn per interface."""
    cut = np.flatnonzero(np.diff(piece) != 0) + 1
    return np.insert(x.astype(float), cut, np.nan), np.insert(y.astype(float), cut, np.nan)


def plot_joint_stress(
    result,
    joint=None,
    *,
    interfaces: Sequence[int] | None = None,
    unit: str = "m",
    stress_unit: str = "kPa",
    title: str | None = None,
) -> Figure:
    """Normal and shear stress along chosen joints, with the shear strength.

    Parameters
    ----------
    result : Analysis, FactorOfSafety or Model
    joint : str or int, optional
        Joint name or index of a model joint line; see :func:`select_interfaces`.
    interfaces : sequence of int, optional
        Explicit interface positions, put end to end along their main direction.
    unit, stress_unit : str
        Units of length and stress for the labels.
    title : str, optional

    Returns
    -------
    Figure
        Left: the model with the chosen path (LineCollection gid ``"path"``);
        right, sharing the position axis: normal stress (compression positive,
        Line2D gid ``"sigma"``) and shear stress magnitude with the shear
        strength at the factor of the stresses (gids ``"tau"``, ``"strength"``);
        points marked by their current state (red: sliding, blue: open, green
        squares: failed earlier, now closed; gids ``"now-sliding"``,
        ``"now-open"``, ``"now-closed-failed-earlier"``).  A factor of safety
        shows its last equilibrium (the stable end of the bracket).
    """
    a = stress_analysis(result)
    chosen = select_interfaces(a, joint, interfaces)
    path = joint_path(a, chosen)
    sp = a.springs
    s = path.springs
    fig = Figure(figsize=(11.0, 4.8), layout="constrained")
    gs = fig.add_gridspec(2, 2, width_ratios=(1.0, 1.25))
    ax_map = fig.add_subplot(gs[:, 0])
    ax_s = fig.add_subplot(gs[0, 1])
    ax_t = fig.add_subplot(gs[1, 1], sharex=ax_s)
    blocks = a.system.blocks
    draw_blocks(ax_map, blocks)
    seg = c.segments(a.system)
    ax_map.add_collection(LineCollection(seg, colors=c.STATE_COLORS[0], linewidths=0.8, zorder=3))
    ax_map.add_collection(
        LineCollection(
            seg[path.interfaces], colors=c.OKABE_ITO["blue"], linewidths=3.0, zorder=4, gid="path"
        )
    )
    if len(path.interfaces):
        first = seg[path.interfaces[0]]
        start = first[np.argmin(np.hypot(*(first - sp.point[s[0]]).T))]
        ax_map.plot(*start, "o", color=c.OKABE_ITO["blue"], ms=6, zorder=5)
        ax_map.annotate("0", start, xytext=(-8, 6), textcoords="offset points", fontsize=8)
    c.setup_space_axes(ax_map, blocks, unit)
    ax_map.set_title("Chosen joint (start marked 0)", fontsize=9)
    x = path.position
    xs, ys = _broken(x, sp.sigma[s], path.piece)
    ax_s.plot(
        xs,
        ys,
        "-o",
        ms=3,
        color=c.OKABE_ITO["black"],
        gid="sigma",
        label=("effective " if wet(a) else "") + "normal stress (compression +)",
    )
    ax_s.axhline(0.0, color="#999999", lw=0.6)
    ax_s.set_ylabel(("σ'" if wet(a) else "σ") + f" ({stress_unit})")
    ax_s.legend(fontsize=7, loc="best")
    F = a.stress_factor
    xt, yt = _broken(x, np.abs(sp.tau[s]), path.piece)
    xc, yc = _broken(x, shown_strength(a)[s], path.piece)
    ax_t.plot(xt, yt, "-o", ms=3, color=c.OKABE_ITO["black"], gid="tau", label="|shear stress|")
    ax_t.plot(
        xc,
        yc,
        "--",
        color=c.OKABE_ITO["bluish_green"],
        gid="strength",
        label=f"shear strength at F = {format_factor(F)}",
    )
    now = sp.current[s] if sp.current is not None else None
    marks = ((2, "o"), (3, "o"), (1, "s")) if now is not None else ()
    for code, marker in marks:
        m = now == code
        if not m.any():
            continue
        ax_t.plot(
            x[m],
            np.abs(sp.tau[s][m]),
            marker,
            ms=6,
            mfc="none",
            mew=1.5,
            color=c.CURRENT_COLORS[code],
            gid=f"now-{CURRENT_NAMES[code]}",
            label=f"{CURRENT_LABELS[code]} now" if code > 1 else CURRENT_LABELS[code],
        )
    ax_t.axhline(0.0, color="#999999", lw=0.6)
    ax_t.set_ylabel(f"τ ({stress_unit})")
    ax_t.set_xlabel(f"distance along the joint ({unit})")
    ax_t.legend(fontsize=7, loc="best")
    if title is None:
        state = "" if a.stable else "; no equilibrium: the solver's last iterate"
        title = (
            f"Stress along {path_text(a, path)} from point 0 "
            f"({len(path.interfaces)} interfaces, F = {format_factor(F)}{state})"
        )
    fig.suptitle(title, fontsize=11)
    return fig


def wet(a) -> bool:
    """True when the joints of ``a`` carry water (a water table or r_u): the
    springs' normal stress is then the effective stress, the pore pressure apart."""
    loads = a.system.model.loads
    return bool(len(loads.water_table)) or loads.pore_pressure_ratio > 0


def stress_analysis(result):
    """The analysis whose stresses a stress plot shows.

    For a factor-of-safety search, the last equilibrium (the stable end of
    the bracket): the failed trial has no equilibrium stresses to show.
    """
    if isinstance(result, c.FactorOfSafety) and result.stable_analysis is not None:
        return result.stable_analysis
    return c.as_analysis(result)


def shown_strength(a) -> np.ndarray:
    """Shear strength of every spring at the factor its stresses were evaluated at.

    ``springs.strength`` when recorded; else the full strength divided by
    ``a.stress_factor`` (c and tan(phi) are divided by the same factor).
    """
    sp = a.springs
    if getattr(sp, "strength", None) is not None:
        return np.asarray(sp.strength)
    return np.asarray(sp.capacity) / a.stress_factor


def path_kinds(a, path: JointPath) -> list[str]:
    """Joint names along a path in the order drawn (a name repeats when the path
    returns to it after another)."""
    names = a.interfaces.kind[path.interfaces].tolist()
    return [n for k, n in enumerate(names) if k == 0 or n != names[k - 1]]


def path_text(a, path: JointPath, most: int = 5) -> str:
    """The joints of a path in the order drawn: ``"upper → vertical → lower"``;
    a longer sequence names each joint once, in order of first appearance."""
    kinds = path_kinds(a, path)
    if not kinds:
        return "no interface"
    if len(kinds) <= most:
        return " → ".join(kinds)
    first = list(dict.fromkeys(kinds))
    return " → ".join(first) + f" (alternating, {len(kinds)} stretches)"
