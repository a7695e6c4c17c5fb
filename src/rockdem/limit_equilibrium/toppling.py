"""Goodman & Bray (1976) block toppling on a stepped base: the
limit-equilibrium recursion from the crest down that classifies every block
as stable, toppling or sliding and gives the force ``P0`` the toe needs
(:func:`toppling`); :func:`toppling_fos` reduces ``tan(phi)`` until
``P0 = 0``.  Angles in degrees, forces per unit thickness, any consistent
units (re-exported by :mod:`rockdem.limit_equilibrium.closed_forms`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, check_number

__all__ = ["MAX_TOPPLING_BLOCKS", "Toppling", "stepped_heights", "toppling", "toppling_fos"]


#: most blocks of a limit-equilibrium toppling slope
MAX_TOPPLING_BLOCKS = 10_000


def stepped_heights(n_blocks: int, crest_block: int, a1: float, a2: float, b: float) -> np.ndarray:
    """Heights ``y_n`` of a regular toppling slope (Goodman & Bray 1976).

    Blocks are numbered 1 (toe) to ``n_blocks``; ``crest_block`` is the one
    the crest cuts.  ``y_n = n (a1 - b)`` up to the crest, then
    ``y_n = y_(n-1) - a2 - b`` (Wyllie & Mah 2004, eqs. 9.10-9.11), with
    ``a1 = dx tan(psi_f - psi_p)``, ``a2 = dx tan(psi_p - psi_s)`` and the
    step ``b = dx tan(psi_b - psi_p)``.
    """
    # (a Goodman & Bray slope has tens of blocks; 1e8 ran for a minute)
    n = int(check_number("toppling", "n_blocks", n_blocks, lo=1, hi=MAX_TOPPLING_BLOCKS))
    nc = int(check_number("toppling", "crest_block", crest_block, lo=1, hi=n + 1))
    y = np.zeros(n)
    for k in range(1, n + 1):
        y[k - 1] = k * (a1 - b) if k <= nc else y[k - 2] - a2 - b
    return y


@dataclass(frozen=True)
class Toppling:
    """Result of :func:`toppling`; arrays are per block, toe (1) first.

    ``p_topple[i]`` and ``p_slide[i]`` are ``P_(n-1),t`` and ``P_(n-1),s`` of
    block ``n = i + 1``: the force on its lower face that just prevents it
    from toppling or from sliding; ``p_lower[i]`` the force taken
    (``P_(n-1)``), ``p_upper[i]`` the force from the block above (``P_n``).
    ``support`` is ``P0 = max(P_0,t, P_0,s)`` of the toe block, the force the
    toe needs (<= 0: none; its size is then the margin).
    """

    heights: np.ndarray
    weight: np.ndarray
    upper_lever: np.ndarray  #: M_n, height of P_n on the upper face
    lower_lever: np.ndarray  #: L_n, height of P_(n-1) on the lower face
    p_upper: np.ndarray
    p_topple: np.ndarray
    p_slide: np.ndarray
    p_lower: np.ndarray
    normal: np.ndarray  #: R_n on the base
    shear: np.ndarray  #: S_n on the base
    mode: tuple[str, ...]  #: "stable", "toppling" or "sliding"
    support: float

    def blocks(self, mode: str) -> list[int]:
        """Block numbers (1 = toe) in ``mode``."""
        return [i + 1 for i, m in enumerate(self.mode) if m == mode]


def toppling(
    heights: Sequence[float],
    *,
    width: float,
    step: float,
    base_dip: float,
    base_friction: float,
    face_friction: float | None = None,
    unit_weight: float = 1.0,
) -> Toppling:
    """Goodman & Bray (1976) toppling of rectangular blocks on a stepped base.

    Blocks of width ``dx`` and heights ``y_n`` (toe first) stand on a
    stepped base whose treads dip ``psi_p``; each block's base is ``step``
    (``b``) higher than the one below it.  Starting at the top with
    ``P_n = 0``, each block needs on its lower face

        P_(n-1),t = [P_n (M_n - dx tan phi_d) + W_n/2 (y_n sin psi_p - dx cos psi_p)] / L_n
        P_(n-1),s = P_n - W_n (tan phi_p cos psi_p - sin psi_p) / (1 - tan phi_p tan phi_d)

    to prevent toppling and sliding (Hoek & Bray 1981, ch. 10; Wyllie & Mah
    2004, eqs. 9.12-9.16).  A block is stable when both are <= 0 (it passes
    nothing on), toppling when ``P_t >= P_s``, else sliding; it passes on the
    larger.  ``M_n`` and ``L_n`` are where the neighbours touch it: the top of
    the lower of the two blocks, measured from its own base,
    ``M_n = min(y_n, y_(n+1) + b)``, ``L_n = min(y_n, y_(n-1) - b)`` (this gives
    Goodman & Bray's ``y_n``, ``y_n - a1`` below the crest and ``y_n - a2``,
    ``y_n`` above it); the toe block's ``y_0`` extends the regular pattern,
    ``2 y_1 - y_2``.  Inter-block shear is ``Q = P tan phi_d``.

    Parameters
    ----------
    heights : sequence of float
        ``y_n``, block heights from the toe (block 1) up (see
        :func:`stepped_heights`).
    width : float
        ``dx``, block width (the spacing of the toppling joints).
    step : float
        ``b``, the step of the base from one block to the next.
    base_dip : float
        ``psi_p``, dip of the block bases (the cross joints).
    base_friction, face_friction : float
        ``phi_p`` on the bases and ``phi_d`` on the block faces (default: ``phi_p``).
    unit_weight : float
        ``W_n = gamma y_n dx``.
    """
    where = "toppling"
    y = np.asarray(heights, dtype=float)
    if y.ndim != 1 or len(y) < 2 or not np.all(np.isfinite(y)) or np.any(y <= 0):
        raise InputError(
            f"{where} heights", "needs two or more positive block heights", "list them toe first"
        )
    dx = check_number(where, "width", width, lo=0.0, open_lo=True)
    b = check_number(where, "step", step, lo=0.0)
    psi = np.radians(check_number(where, "base_dip", base_dip, lo=0.0, hi=90.0))
    # the factor of safety divides tan(phi_p): zero friction has none
    phi_p = check_number(where, "base_friction", base_friction, lo=0.0, hi=90.0, open_lo=True)
    tp = np.tan(np.radians(phi_p))
    fd = base_friction if face_friction is None else face_friction
    td = np.tan(np.radians(check_number(where, "face_friction", fd, lo=0.0, hi=90.0)))
    gamma = check_number(where, "unit_weight", unit_weight, lo=0.0, open_lo=True)
    return _toppling(y, dx, b, psi, tp, td, gamma)


def _toppling(y, dx, b, psi, tp, td, gamma) -> Toppling:
    n = len(y)
    W = gamma * y * dx
    above = np.append(y[1:] + b, np.inf)
    below = np.concatenate([[2 * y[0] - y[1]], y[:-1]]) - b
    M = np.minimum(y, above)
    L = np.minimum(y, below)
    p_up, p_t, p_s, p_low = (np.zeros(n) for _ in range(4))
    mode = [""] * n
    P = 0.0  # force on the upper face of the block (never a pull)
    for i in range(n - 1, -1, -1):
        p_up[i] = P
        moment = P * (M[i] - dx * td) + 0.5 * W[i] * (y[i] * np.sin(psi) - dx * np.cos(psi))
        if L[i] > 0:
            p_t[i] = moment / L[i]
        else:  # nothing below the block's base can hold it up
            p_t[i] = np.inf if moment > 0 else -np.inf
        denom = 1 - tp * td
        # friction beyond 1 - tan phi_p tan phi_d = 0 locks the block against sliding
        p_s[i] = P - W[i] * (tp * np.cos(psi) - np.sin(psi)) / denom if denom > 0 else -np.inf
        need = max(p_t[i], p_s[i])
        if P <= 0 and need <= 0:
            mode[i] = "stable"  # neither pushed nor moving: passes nothing on
        else:
            mode[i] = "toppling" if p_t[i] >= p_s[i] else "sliding"
        p_low[i] = need if mode[i] != "stable" else 0.0
        P = max(need, 0.0)
    pushed = np.maximum(p_low, 0.0)  # the block below cannot pull
    with np.errstate(invalid="ignore"):  # no finite force holds a block: R, S undefined (nan)
        R = W * np.cos(psi) + (p_up - pushed) * td
        S = W * np.sin(psi) + (p_up - pushed)
    # the toe's need, signed (< 0: a margin; -inf: it can neither topple nor
    # slide; inf: no finite force holds it)
    support = max(p_t[0], p_s[0])
    return Toppling(y, W, M, L, p_up, p_t, p_s, p_low, R, S, tuple(mode), float(support))


def toppling_fos(
    heights: Sequence[float],
    *,
    width: float,
    step: float,
    base_dip: float,
    base_friction: float,
    face_friction: float | None = None,
    unit_weight: float = 1.0,
) -> float | None:
    """Factor of safety of a toppling slope: the factor ``F`` dividing
    ``tan(phi_p)`` and ``tan(phi_d)`` for which the toe needs no support
    (``P0 = 0``; Hoek & Bray 1981, ch. 10): the first factor, from 0.05 up,
    at which the toe needs support.  None when even F = 0.05 needs support
    (rotation that friction cannot hold); ``inf`` when no factor up to 100
    does."""
    result = toppling(
        heights,
        width=width,
        step=step,
        base_dip=base_dip,
        base_friction=base_friction,
        face_friction=face_friction,
        unit_weight=unit_weight,
    )
    y = result.heights
    psi = np.radians(base_dip)
    tp = np.tan(np.radians(base_friction))
    td = np.tan(np.radians(base_friction if face_friction is None else face_friction))

    big = 1e12 * float(result.weight.sum())

    def support(F: float) -> float:  # finite for the root search
        need = _toppling(y, width, step, psi, tp / F, td / F, unit_weight).support
        return float(np.clip(need, -big, big))

    grid = np.geomspace(0.05, 100.0, 300)
    values = np.array([support(F) for F in grid])
    if values[0] > 0:
        return None
    if values[-1] <= 0:
        return float("inf")
    k = int(np.argmax(values > 0))
    from scipy.optimize import brentq  # 0.13 s to import: not at start-up

    return float(brentq(support, grid[k - 1], grid[k], xtol=1e-12))
