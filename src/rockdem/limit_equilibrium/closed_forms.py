"""Classic closed-form limit-equilibrium solutions for rock slopes.

* :func:`plane_failure` - a block sliding on one plane behind a vertical
  tension crack, with water in the crack and on the plane, a horizontal
  seismic coefficient and a bolt (Hoek & Bray 1981, ch. 7; Wyllie & Mah
  2004, section 6.3).
* :func:`toppling` - Goodman & Bray (1976) block toppling on a stepped
  base: the limit-equilibrium recursion from the crest down that classifies
  every block as stable, toppling or sliding and gives the force ``P0`` the
  toe needs; :func:`toppling_fos` reduces ``tan(phi)`` until ``P0 = 0``
  (in :mod:`.toppling`, re-exported here).
* :func:`two_block_wedge` - the seed paper's Eq. 7 (the formulas live in
  :mod:`rockdem.verification`; this only wraps them).

Angles are in degrees, forces per unit thickness of the section, any
consistent units.  Every argument is checked; a bad one raises
:class:`~rockdem.errors.InputError` naming it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError, check_number
from ..verification import wedge_fos, wedge_thrust
from .toppling import Toppling, stepped_heights, toppling, toppling_fos

__all__ = [
    "PlaneFailure",
    "Toppling",
    "TwoBlockWedge",
    "plane_failure",
    "plane_failure_fos",
    "stepped_heights",
    "toppling",
    "toppling_fos",
    "two_block_wedge",
]


# ------------------------------------------------------------ plane failure
def plane_failure_fos(
    weight: float,
    area: float,
    plane_dip: float,
    friction_angle: float,
    *,
    cohesion: float = 0.0,
    uplift: float = 0.0,
    crack_thrust: float = 0.0,
    seismic_kh: float = 0.0,
    bolt_force: float = 0.0,
    bolt_angle: float = 0.0,
) -> float:
    """Hoek & Bray's factor of safety of a block on one plane (the formula only).

    ``FS = (c A + (W (cos psi - kh sin psi) - U - V sin psi + T sin(psi + theta)) tan phi)
    / (W (sin psi + kh cos psi) + V cos psi - T cos(psi + theta))``

    Parameters
    ----------
    weight : float
        ``W``, weight of the sliding block.
    area : float
        ``A``, length of the sliding plane (area per unit thickness).
    plane_dip : float
        ``psi_p``, dip of the sliding plane.
    friction_angle, cohesion : float
        ``phi`` and ``c`` of the sliding plane.
    uplift : float
        ``U``, water force on the sliding plane.
    crack_thrust : float
        ``V``, water force in the vertical tension crack.
    seismic_kh : float
        Horizontal seismic coefficient, out of the face (``kh W``).
    bolt_force, bolt_angle : float
        ``T`` and its plunge ``theta`` below the horizontal, into the slope.
    """
    psi, phi, th = np.radians([plane_dip, friction_angle, bolt_angle])
    normal = (
        weight * (np.cos(psi) - seismic_kh * np.sin(psi))
        - uplift
        - crack_thrust * np.sin(psi)
        + bolt_force * np.sin(psi + th)
    )
    driving = (
        weight * (np.sin(psi) + seismic_kh * np.cos(psi))
        + crack_thrust * np.cos(psi)
        - bolt_force * np.cos(psi + th)
    )
    if driving <= 0:
        return float("inf")
    return float((cohesion * area + normal * np.tan(phi)) / driving)


@dataclass(frozen=True)
class PlaneFailure:
    """Result of :func:`plane_failure` (forces per unit thickness)."""

    fos: float
    weight: float  #: W
    area: float  #: A, length of the sliding plane below the crack
    uplift: float  #: U = gamma_w z_w A / 2
    crack_thrust: float  #: V = gamma_w z_w^2 / 2
    crack_depth: float  #: z
    crack_in_face: bool  #: the crack cuts the face (not the upper surface)

    def as_dict(self) -> dict:
        return dict(self.__dict__)


#: longest sliding plane, in heights of the slope (as a model's longest length
#: is 1e9 of its smallest)
MAX_PLANE_LENGTH = 1e9


def plane_failure(
    *,
    height: float,
    face_angle: float,
    plane_dip: float,
    friction_angle: float,
    unit_weight: float,
    cohesion: float = 0.0,
    crack_depth: float | None = None,
    crack_distance: float | None = None,
    water_depth: float = 0.0,
    water_unit_weight: float = 9.81,
    seismic_kh: float = 0.0,
    bolt_force: float = 0.0,
    bolt_angle: float = 0.0,
) -> PlaneFailure:
    """Plane failure with a vertical tension crack (Hoek & Bray 1981, ch. 7).

    A slope of height ``H`` with a face dipping ``psi_f`` and a horizontal
    upper surface; the block slides on a plane dipping ``psi_p`` that
    daylights at the toe, behind a vertical tension crack of depth ``z``
    filled with water to ``z_w``.  Water pressure falls linearly along the
    plane from ``gamma_w z_w`` at the foot of the crack to zero at the toe.

    Parameters
    ----------
    height : float
        ``H``, slope height (toe to crest).
    face_angle : float
        ``psi_f``, dip of the face, steeper than the plane.
    plane_dip : float
        ``psi_p``, dip of the sliding plane, 0 < psi_p < psi_f.
    friction_angle, cohesion : float
        ``phi`` and ``c`` of the sliding plane.
    unit_weight : float
        ``gamma_r`` of the rock.
    crack_depth : float, optional
        ``z``, depth of the crack below the upper surface (0 <= z < H).
    crack_distance : float, optional
        ``b``, horizontal distance of the crack behind the crest (instead
        of ``crack_depth``); neither: no crack (the plane reaches the upper
        surface).
    water_depth : float
        ``z_w``, depth of water in the crack (0 <= z_w <= z).
    water_unit_weight : float
        ``gamma_w`` (9.81 kN/m^3 by default: give 1.0 for t/m^3).
    seismic_kh : float
        Horizontal seismic coefficient out of the face.
    bolt_force, bolt_angle : float
        A bolt force ``T`` per unit thickness and its plunge below the
        horizontal, into the slope.

    Returns
    -------
    PlaneFailure
        The factor of safety and ``W``, ``A``, ``U``, ``V``, ``z``.
    """
    where = "plane_failure"
    H = check_number(where, "height", height, lo=0.0, open_lo=True)
    psi_f = check_number(where, "face_angle", face_angle, lo=0.0, hi=90.0, open_lo=True)
    psi_p = check_number(where, "plane_dip", plane_dip, lo=0.0, hi=psi_f, open_lo=True)
    check_number(where, "friction_angle", friction_angle, lo=0.0, hi=90.0)
    gamma = check_number(where, "unit_weight", unit_weight, lo=0.0, open_lo=True)
    check_number(where, "cohesion", cohesion, lo=0.0)
    gamma_w = check_number(where, "water_unit_weight", water_unit_weight, lo=0.0)
    check_number(where, "seismic_kh", seismic_kh, lo=-1.0, hi=1.0)
    check_number(where, "bolt_force", bolt_force, lo=0.0)
    check_number(where, "bolt_angle", bolt_angle, lo=-90.0, hi=90.0)
    if np.sin(np.radians(psi_p)) * MAX_PLANE_LENGTH < 1:
        # (found by hostile testing: a dip of 5e-324 divided by zero and read
        # W = nan, "unbounded"; 1e-300 printed a factor of 300 digits)
        raise InputError(
            f"{where} plane_dip",
            f"{psi_p:g} is so flat that the plane runs more than {MAX_PLANE_LENGTH:g} "
            "heights to the upper surface",
            "give a steeper plane",
        )
    cot_p, cot_f = 1 / np.tan(np.radians(psi_p)), 1 / np.tan(np.radians(psi_f))
    if crack_depth is not None and crack_distance is not None:
        raise InputError(
            f"{where} crack_distance", "both crack_depth and crack_distance are given", "give one"
        )
    if crack_distance is not None:
        b = check_number(where, "crack_distance", crack_distance, lo=0.0)
        z = H - (b + H * cot_f) * np.tan(np.radians(psi_p))
        if z <= 0:
            raise InputError(
                f"{where} crack_distance",
                f"a crack {b:g} behind the crest lies beyond where the plane reaches the "
                "upper surface",
                f"give a distance < {H * (cot_p - cot_f):.4g}",
            )
    else:
        z = check_number(where, "crack_depth", crack_depth or 0.0, lo=0.0, hi=H)
    z_w = check_number(where, "water_depth", water_depth, lo=0.0)
    if z_w > z * (1 + 1e-12):
        raise InputError(
            f"{where} water_depth",
            f"{z_w:g} is deeper than the crack ({z:.4g})",
            "give 0 <= water_depth <= crack depth",
        )
    in_face = z / H > 1 - cot_f * np.tan(np.radians(psi_p))
    if in_face:
        weight = (
            0.5
            * gamma
            * H**2
            * ((1 - z / H) ** 2 * cot_p * (cot_p * np.tan(np.radians(psi_f)) - 1))
        )
    else:
        weight = 0.5 * gamma * H**2 * ((1 - (z / H) ** 2) * cot_p - cot_f)
    area = (H - z) / np.sin(np.radians(psi_p))
    U = 0.5 * gamma_w * z_w * area
    V = 0.5 * gamma_w * z_w**2
    _held_on_plane(where, weight, U, V, psi_p, seismic_kh, bolt_force, bolt_angle)
    fos = plane_failure_fos(
        weight,
        area,
        psi_p,
        friction_angle,
        cohesion=cohesion,
        uplift=U,
        crack_thrust=V,
        seismic_kh=seismic_kh,
        bolt_force=bolt_force,
        bolt_angle=bolt_angle,
    )
    return PlaneFailure(
        fos, float(weight), float(area), float(U), float(V), float(z), bool(in_face)
    )


def _held_on_plane(where, weight, uplift, thrust, psi_p, kh, bolt_force, bolt_angle) -> None:
    """Refuse a block that the water, the earthquake or the bolt lifts off its
    plane (effective normal force < 0): Hoek & Bray's formula then gives a
    negative factor of safety (found by hostile testing: a 29 m crack full of
    water in a 30 m slope read -0.34)."""
    psi, th = np.radians([psi_p, bolt_angle])
    dry = weight * np.cos(psi) + bolt_force * np.sin(psi + th)
    normal = dry - weight * kh * np.sin(psi) - uplift - thrust * np.sin(psi)
    if normal >= 0:
        return
    if dry - uplift - thrust * np.sin(psi) < 0:
        key, what = "water_depth", "the water"
    elif dry - weight * kh * np.sin(psi) < 0:
        key, what = "seismic_kh", "the seismic force"
    else:
        key, what = "water_depth", "the water with the seismic force"
    raise InputError(
        f"{where} {key}",
        f"{what} lifts the block off the plane (effective normal force {normal:.4g} < 0), "
        "where Hoek & Bray's factor of safety means nothing",
        f"give a smaller {key}, or rate the slope with `rockdem fos` on a model of it",
    )


# ------------------------------------------------------------ two-block wedge
@dataclass(frozen=True)
class TwoBlockWedge:
    """Result of :func:`two_block_wedge`."""

    thrust: float  #: Eq. 7: the force the passive block needs (> 0: unstable)
    fos: float  #: all three tan(phi) divided by it make the thrust zero


def two_block_wedge(
    *,
    active_weight: float,
    passive_weight: float,
    active_dip: float,
    passive_dip: float,
    active_friction: float,
    passive_friction: float,
    joint_friction: float,
) -> TwoBlockWedge:
    """The seed paper's two-block wedge (Eq. 7, docs/method.md section 5).

    An active block (``W1``) on a plane dipping ``d1`` pushes a passive block
    (``W2``) on a flatter plane (``d2``) across a vertical joint; friction
    ``p1``, ``p2``, ``p3`` on the upper, lower and vertical surfaces.  The
    formulas are :func:`rockdem.verification.wedge_thrust` and
    :func:`~rockdem.verification.wedge_fos`.
    """
    where = "wedge"
    w1 = check_number(where, "active_weight", active_weight, lo=0.0, open_lo=True)
    w2 = check_number(where, "passive_weight", passive_weight, lo=0.0)
    d1 = check_number(where, "active_dip", active_dip, lo=0.0, hi=90.0, open_lo=True)
    # Eq. 7 and its factor of safety hold for a passive plane dipping out of
    # the slope, flatter than the active one (a negative dip divides by
    # tan(d2) in the single-block factor and makes Eq. 7's denominator vanish)
    d2 = check_number(where, "passive_dip", passive_dip, lo=0.0, hi=d1, open_lo=True)
    p = [
        check_number(where, key, value, lo=0.0, hi=90.0)
        for key, value in (
            ("active_friction", active_friction),
            ("passive_friction", passive_friction),
            ("joint_friction", joint_friction),
        )
    ]
    try:
        fos = float(wedge_fos(w1, w2, d1, d2, *p))
    except ValueError:  # brentq: the thrust does not change sign on [0.2, 5]
        raise InputError(
            where,
            "no factor of safety between 0.2 and 5 makes Eq. 7's thrust zero",
            "check the dips and friction angles (a wedge so far from its limit is rated "
            "better by `rockdem fos`)",
        ) from None
    return TwoBlockWedge(float(wedge_thrust(w1, w2, d1, d2, *p)), fos)
