"""Winkler springs: quadrature points along every interface.

Each interface gets the same number of points, stored interface after
interface, so per-interface sums are a reshape.  The weights sum to the
interface length; any rule exact for quadratics reproduces the paper's
lumped stiffness ``Kn = kn L, Ks = ks L, Kw = kn L^3 / 12``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError
from .interfaces import Interfaces
from .joints import Joint

QUADRATURES = ("lobatto", "gauss")
#: spring points per interface each rule offers (fewest, most)
POINTS_RANGE = {"lobatto": (2, 5), "gauss": (1, 10)}


def quadrature(rule: str = "lobatto", n_points: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Points and weights on [-1, 1].

    ``"lobatto"`` includes the end points, so a block pivots about its true
    corner (exact toppling); ``n_points = 3`` is Simpson's rule, the default.
    ``"gauss"`` is Gauss-Legendre (2 points = the paper's lumped springs).

    Examples
    --------
    >>> xi, w = quadrature("lobatto", 3)
    >>> xi.tolist(), (w * 3).tolist()
    ([-1.0, 0.0, 1.0], [1.0, 4.0, 1.0])
    """
    if rule == "lobatto":
        table = {
            2: ([-1.0, 1.0], [1.0, 1.0]),
            3: ([-1.0, 0.0, 1.0], [1 / 3, 4 / 3, 1 / 3]),
            4: ([-1.0, -np.sqrt(0.2), np.sqrt(0.2), 1.0], [1 / 6, 5 / 6, 5 / 6, 1 / 6]),
            5: (
                [-1.0, -np.sqrt(3 / 7), 0.0, np.sqrt(3 / 7), 1.0],
                [0.1, 49 / 90, 32 / 45, 49 / 90, 0.1],
            ),
        }
        if n_points not in table:
            raise InputError("quadrature", f"lobatto with {n_points} points", "use 2 to 5 points")
        xi, w = table[n_points]
        return np.array(xi), np.array(w)
    if rule == "gauss":
        if not 1 <= n_points <= 10:
            raise InputError("quadrature", f"gauss with {n_points} points", "use 1 to 10 points")
        return np.polynomial.legendre.leggauss(n_points)
    raise InputError("quadrature", f"unknown rule {rule!r}", f"use one of {QUADRATURES}")


@dataclass(frozen=True, eq=False, repr=False)
class Springs:
    """One row per spring point (struct of arrays).

    ``weight`` is the length each point stands for; strengths and stiffnesses
    are per unit length, copied from the interface's joint.
    """

    interface: np.ndarray
    point: np.ndarray
    weight: np.ndarray
    kn: np.ndarray
    ks: np.ndarray
    cohesion: np.ndarray
    tan_phi: np.ndarray
    tensile: np.ndarray
    cohesion_residual: np.ndarray
    tan_phi_residual: np.ndarray
    tensile_residual: np.ndarray
    points_per_interface: int

    @property
    def n_springs(self) -> int:
        return len(self.interface)

    def __repr__(self) -> str:
        n_if = self.n_springs // max(self.points_per_interface, 1)
        return f"<Springs: {self.n_springs:,} points on {n_if:,} interfaces>"


def place_springs(
    faces: Interfaces, joints: tuple[Joint, ...], rule: str = "lobatto", n_points: int = 3
) -> Springs:
    """Spring points and their properties for every interface."""
    xi, w = quadrature(rule, n_points)
    m = len(xi)
    length = faces.length
    interface = np.repeat(np.arange(faces.n_interfaces), m)
    mid = faces.midpoint[interface]
    half = 0.5 * (length[interface])[:, None] * faces.tangent[interface]
    point = mid + np.tile(xi, faces.n_interfaces)[:, None] * half
    weight = np.tile(w, faces.n_interfaces) * 0.5 * length[interface]
    table = np.array(
        [
            (
                j.normal_stiffness,
                j.shear_stiffness,
                j.cohesion,
                np.tan(np.radians(j.friction_angle)),
                j.tensile_strength,
                j.residual_cohesion,
                np.tan(np.radians(j.residual_friction_angle)),
                j.residual_tensile_strength,
            )
            for j in joints
        ],
        dtype=float,
    )
    props = table[faces.joint[interface]]
    return Springs(interface, point, weight, *props.T, points_per_interface=m)
