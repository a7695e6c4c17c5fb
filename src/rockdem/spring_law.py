"""Elasto-plastic Winkler spring law, vectorised over all spring points.

Normal: linear, never yields in compression; tension cut-off.  Shear:
Mohr-Coulomb with return mapping.  The law is evaluated from the state
*committed* at the last converged step plus the current total relative
displacement; the state changes only through :func:`commit`.

Sign conventions (docs/method.md, section 2): ``dn > 0`` opens, ``sigma`` is
compression-positive (``sigma = -kn dn``), ``tau = ks (ds - slip)``.
The generalised forces conjugate to ``(dn, ds)`` are ``(-sigma, tau)``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .springs import Springs

ELASTIC, SHEAR, TENSION = 0, 1, 2
STATE_NAMES = ("elastic", "shear", "tension")


@dataclass(frozen=True, eq=False)
class SpringState:
    """Committed state of every spring point.

    Attributes
    ----------
    slip : ndarray
        Plastic shear displacement.
    yielded : ndarray of bool
        Has reached its shear strength once (residual strength from then on).
    broken : ndarray of bool
        Has failed in tension (no cohesion or tensile strength any more).
    first_failure : ndarray of int
        Stage (load step or strength trial) of the first failure, -1 if none.
    bolt_first_yield : ndarray of int or None
        Stage at which each bolt crossing (rockdem.bolts) first reached its
        axial capacity, -1 if never; None without bolts.
    bolt_reference : ndarray (m, 2) or None
        The displacement ``(extension, offset)`` of each bolt crossing when
        it was installed: NaN while a bolt installed after the loads is not
        in yet; None when every bolt is in from the start, at zero.
    """

    slip: np.ndarray
    yielded: np.ndarray
    broken: np.ndarray
    first_failure: np.ndarray
    bolt_first_yield: np.ndarray | None = None
    bolt_reference: np.ndarray | None = None

    @classmethod
    def initial(cls, n: int, bolt_reference: np.ndarray | None = None) -> SpringState:
        return cls(
            np.zeros(n),
            np.zeros(n, dtype=bool),
            np.zeros(n, dtype=bool),
            np.full(n, -1),
            bolt_reference=bolt_reference,
        )

    def without_slip(self) -> SpringState:
        """The same failure flags with the plastic slip set to zero."""
        return replace(self, slip=np.zeros_like(self.slip))

    def with_bolts_installed(self, displacement: np.ndarray) -> SpringState:
        """The state with the bolts not yet in installed at ``displacement``
        (of every crossing, (m, 2)): from here they resist further movement."""
        ref = self.bolt_reference
        if ref is None or not np.isnan(ref).any():
            return self
        return replace(self, bolt_reference=np.where(np.isnan(ref), displacement, ref))

    @property
    def bolts_waiting(self) -> bool:
        """Are there bolts to be installed after the loads, not in yet?"""
        return self.bolt_reference is not None and bool(np.isnan(self.bolt_reference).any())

    def with_bolt_yield(self, yielded: np.ndarray, stage: int) -> SpringState:
        """The state with the bolt crossings yielded now recorded (first stage kept)."""
        first = self.bolt_first_yield
        first = np.full(len(yielded), -1) if first is None else first
        first = np.where(yielded & (first < 0), stage, first)
        return replace(self, bolt_first_yield=first)

    @property
    def state(self) -> np.ndarray:
        """0 elastic, 1 shear-yielded, 2 tension-failed (tension wins)."""
        return np.where(self.broken, TENSION, np.where(self.yielded, SHEAR, ELASTIC))


@dataclass(frozen=True, eq=False)
class Response:
    """Spring stresses and tangent at a trial displacement."""

    sigma: np.ndarray  # normal stress, compression positive
    tau: np.ndarray  # shear stress
    capacity: np.ndarray  # current shear strength (reduced by the factor)
    open: np.ndarray  # bool: at or beyond the tensile strength
    sliding: np.ndarray  # bool: at the shear strength
    d_sn: np.ndarray  # d tau / d dn (non-symmetric friction coupling)
    d_ss: np.ndarray  # d tau / d ds
    d_nn: np.ndarray  # d(-sigma) / d dn

    @property
    def force(self) -> np.ndarray:
        """Generalised forces per unit length conjugate to (dn, ds), shape (n, 2)."""
        return np.column_stack([-self.sigma, self.tau])


def strength(springs: Springs, state: SpringState, factor: float = 1.0, reduce_tensile=True):
    """Cohesion, tan(phi) and tensile strength in force, divided by ``factor``."""
    failed = state.yielded | state.broken
    c = np.where(state.broken, 0.0, np.where(failed, springs.cohesion_residual, springs.cohesion))
    tan_phi = np.where(failed, springs.tan_phi_residual, springs.tan_phi)
    tensile = np.where(
        state.broken, 0.0, np.where(state.yielded, springs.tensile_residual, springs.tensile)
    )
    return c / factor, tan_phi / factor, tensile / factor if reduce_tensile else tensile


def evaluate(
    springs: Springs,
    state: SpringState,
    dn: np.ndarray,
    ds: np.ndarray,
    factor: float = 1.0,
    reduce_tensile: bool = True,
    strengths: tuple | None = None,
) -> Response:
    """Stresses and consistent tangent at relative displacements ``(dn, ds)``.

    Within one solve the normal spring is perfectly plastic at the tensile
    strength, so the residual stays continuous; the brittle drop to zero
    happens when the state is committed (:func:`commit` marks the point
    broken and the load is solved again: the redistribution of the excess).
    ``strengths``: :func:`strength`'s result for these arguments, where the
    caller evaluates one state many times (a Newton solve).
    """
    if strengths is None:
        strengths = strength(springs, state, factor, reduce_tensile)
    c, tan_phi, tensile = strengths
    kn, ks = springs.kn, springs.ks
    pull, sigma, raw_cap, tau_trial = trial_stresses(
        springs, state.slip, (c, tan_phi, tensile), dn, ds
    )
    is_open = pull > tensile
    cap = np.maximum(raw_cap, 0.0)
    sliding = np.abs(tau_trial) > cap
    sign = np.sign(tau_trial)
    tau = np.where(sliding, sign * cap, tau_trial)
    d_nn = np.where(is_open, 0.0, kn)
    d_ss = np.where(sliding, 0.0, ks)
    d_sn = np.where(sliding & ~is_open & (raw_cap > 0), -sign * kn * tan_phi, 0.0)
    return Response(sigma, tau, cap, is_open, sliding, d_sn, d_ss, d_nn)


def trial_stresses(springs: Springs, slip, strengths, dn, ds):
    """``(kn dn, sigma, c + sigma tan phi, ks (ds - slip))``: the law's core,
    shared by :func:`evaluate` and the force-only :func:`forces`."""
    c, tan_phi, tensile = strengths
    pull = springs.kn * dn
    sigma = -np.minimum(pull, tensile)
    return pull, sigma, c + sigma * tan_phi, springs.ks * (ds - slip)


def forces(springs: Springs, slip, strengths, dn, ds, out=None) -> np.ndarray:
    """Generalised forces ``(-sigma, tau)`` only (no tangent), shape (n, 2),
    for strengths fixed in advance: the law of an explicit step, which
    :class:`rockdem.relaxation._Unbalanced` evaluates in place on its own
    layout (tested to give these values bit for bit).  ``out``: an (n, 2)
    array to write into."""
    _, sigma, raw_cap, tau_trial = trial_stresses(springs, slip, strengths, dn, ds)
    out = np.empty((len(dn), 2)) if out is None else out
    np.negative(sigma, out=out[:, 0])
    cap = np.maximum(raw_cap, 0.0, out=raw_cap)
    np.clip(tau_trial, -cap, cap, out=out[:, 1])
    return out


def commit(
    springs: Springs, state: SpringState, response: Response, ds: np.ndarray, stage: int
) -> SpringState:
    """The state after a converged step: plastic slip, failure flags, first failure."""
    new_slip = np.where(response.sliding, ds - response.tau / springs.ks, state.slip)
    yielded = state.yielded | response.sliding
    broken = state.broken | response.open
    newly = (yielded | broken) & (state.first_failure < 0)
    first = np.where(newly, stage, state.first_failure)
    return replace(state, slip=new_slip, yielded=yielded, broken=broken, first_failure=first)


#: of the bonded spring points that opened in one solve, those opened less
#: than this share of the widest are broken only if they are still open
#: once the wider ones have lost their bond and the loads have moved
STAGGER = 0.5


def widest_openings_first(springs: Springs, state: SpringState, response: Response, dn, strengths):
    """``response`` with only the widest new tension failures marked open,
    and whether any were deferred.

    A cohesive point that opens keeps its shear strength until its failure
    is committed, so every point open at the end of a solve is judged with
    the bond of the others still on: a tension crack in a slope face, open
    and still carrying its cohesion in shear, left the base point below it
    at zero stress, and both were broken together; the base point, the most
    compressed of the plane once the crack had lost its bond, never got its
    cohesion back (Hoek & Bray's crack in the face with 3 m of water: FS
    0.66-0.76 for 0.815).  So the bonds break widest opening first, as
    events: the others are re-judged after the loads have moved.
    ``strengths``: :func:`strength` of ``state`` at the factor of the solve
    (the opening is measured beyond the tensile strength in force there).
    """
    c, _, tensile = strengths  # in force now: divided by the trial factor, or residual
    bonded = (c > 0) | (tensile > 0)
    new = response.open & ~state.broken & bonded
    if not new.any():
        return response, False
    with np.errstate(divide="ignore", invalid="ignore"):
        opening = dn - np.where(springs.kn > 0, tensile / springs.kn, 0.0)
    widest = float(np.max(opening[new]))
    later = new & (opening < STAGGER * widest)
    if widest <= 0 or not later.any():
        return response, False
    return replace(response, open=response.open & ~later), True
