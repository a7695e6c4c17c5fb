"""One equilibrium solve: semismooth Newton with an adaptive shift.

Given the committed spring state, the load factor and the strength factor,
find block displacements ``q`` where the internal spring forces balance the
external loads.  The residual is non-smooth (springs switch between
elastic, sliding and open), so plain Newton may cycle; we use

* the consistent tangent (non-symmetric where friction couples shear to
  normal stress), assembled on the fixed sparsity pattern, LU-factorised;
* a Levenberg-Marquardt shift ``beta K0`` (``K0`` the elastic stiffness):
  ``beta`` grows x10 when the line search fails and shrinks /10 after a
  full step; beyond ``BETA_MAX`` the solve gives up;
* a trust radius: a step longer than the larger of the elastic displacement
  and the distance already travelled is solved again with ``beta`` raised to
  fit (a block whose springs all slide or open has no tangent stiffness, and
  the unshifted step throws it far; shrinking ``beta``'s x10 ladder one
  failed line search at a time cost ~4 factorisations per such step);
* a backtracking line search on the scaled residual norm.

Convergence is scale-free: moments are divided by the mean block size and
the out-of-balance force is compared with the external force.  A solve that
does not converge returns its evidence; how a solve is started and carried
to its target is :mod:`rockdem.continuation`'s, and deciding that the slope
has failed is the caller's job (:mod:`rockdem.analysis`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from .assembly import Assembly, build_assembly
from .blocks import Blocks
from .bolt_placement import check_bolt_stiffness, place_bolts
from .bolts import Crossings
from .errors import InputError
from .interfaces import Interfaces, assign_joints, check_held, find_interfaces
from .joints import check_stiffness_contrast
from .linalg import Factorizer, norm
from .loads import block_loads, check_water_table, joint_water, water_loads
from .model import Model
from .spring_law import Response, evaluate, strength
from .springs import Springs, place_springs

log = logging.getLogger(__name__)

BETA_START = 1e-6
#: a Newton step may move no dof by more than this multiple of the larger of
#: the elastic displacement and the distance already travelled in the solve
#: (scaled); a longer step is re-solved with the shift raised to fit
TRUST_RADIUS = 1.0
BETA_MAX = 0.1
LINE_SEARCH_HALVINGS = 8
#: displacements beyond this multiple of the elastic response are a mechanism
BLOWUP = 1e6
#: a Newton solve has stalled when the residual fell less than x STALL_RATIO
#: over the last STALL_WINDOW accepted steps
STALL_WINDOW = 6
STALL_RATIO = 0.5


#: a solve that stalls with the out-of-balance force below this share of the
#: loads (dynamic relaxation's tolerance, rockdem.relaxation.TOLERANCE) has
#: found an equilibrium to that tolerance: the last bit is a kink of the
#: spring law (a 2,322-block slope: 2.4e-8 after 8 iterations, then no
#: step reduced it; the search took that for its limit, 0.75% low)
KINK_TOLERANCE = 1e-7
#: the reason of such a solve
KINKED = "converged to 1e-7 (Newton stalled on a kink of the spring law)"


@dataclass(frozen=True, eq=False, repr=False)
class System:
    """A model turned into arrays: built once, reused by every solve."""

    model: Model
    blocks: Blocks
    interfaces: Interfaces
    springs: Springs
    assembly: Assembly
    K0: sp.csc_array
    f_block: np.ndarray  # (n_blocks, 3) external loads at full load factor
    f_ext: np.ndarray  # (n_dof,)
    elastic_scale: float  # scaled size of the elastic displacement under f_ext
    #: the elastic displacements under f_ext (K0's factor is not kept: on
    #: 94,533 blocks it held a second PARDISO handle for the whole analysis)
    u_elastic: np.ndarray | None = None
    #: one factorisation handle for all tangents (symbolic analysis reused)
    factorizer: Factorizer = field(default_factory=Factorizer)
    #: bolt and cable crossings of the joints (rockdem.bolts), None without bolts
    bolts: Crossings | None = None
    #: answers of the equilibrium LP already solved (rockdem.certificate.certificate_for)
    certificates: dict = field(default_factory=dict)

    @property
    def scale_free(self) -> bool:
        """Does the model's response scale with its loads?  True when no
        strength carries a force scale of its own: no cohesion and no tensile
        strength (peak or residual) and no bolts.  Then a solution at load
        ``lam`` from the unloaded state, scaled by ``lam' / lam``, is the
        solution at ``lam'``, and so is every step of the search for it
        (tolerances, trust radius, fictitious strength and relaxation are all
        relative to the loads): a failure there fails at every smaller load too."""
        s = self.springs
        strengths = (s.cohesion, s.cohesion_residual, s.tensile, s.tensile_residual)
        return self.bolts is None and not any(np.any(a) for a in strengths)

    @property
    def sheds_strength(self) -> bool:
        """Can a spring lose strength when its failure is committed?  True
        where a residual strength lies below the peak, or a tensile strength
        breaks (brittle joints: progressive failure, the path matters)."""
        s = self.springs
        return bool(
            np.any(s.cohesion_residual < s.cohesion)
            or np.any(s.tan_phi_residual < s.tan_phi)
            or np.any(s.tensile > 0)
            or np.any(s.tensile_residual > 0)
        )

    def __repr__(self) -> str:
        return (
            f"<System: {self.blocks.n_blocks:,} blocks, {self.interfaces.n_interfaces:,} "
            f"interfaces, {self.springs.n_springs:,} springs, {self.assembly.n_dof:,} dof>"
        )


def build_system(model: Model, f_block: np.ndarray | None = None) -> System:
    """Interfaces, springs, assembly and loads of a model."""
    if not isinstance(model, Model):  # (a file name, None, ...)
        raise InputError(
            "model",
            f"{type(model).__name__} is not a rockdem Model",
            "build one with rockdem.Model, or read a model file with rockdem.config.load_model",
        )
    blocks = model.blocks
    faces = find_interfaces(blocks)
    faces = assign_joints(
        faces,
        blocks,
        default=0,
        ground=model.ground,
        lines=model.joint_lines,
        line_joint=model.line_joint,
    )
    # every free block must reach a fixed one (a factorisation of the singular
    # stiffness need not fail: SuperLU factorised 59 blocks and no ground)
    check_held(blocks, faces)
    check_stiffness_contrast(model.joints, faces.joint)
    s = model.settings
    springs = place_springs(faces, model.joints, s.quadrature, s.points_per_interface)
    asm = build_assembly(blocks, faces, springs)
    n = springs.n_springs
    K0 = asm.stiffness(springs.kn, np.zeros(n), springs.ks)
    bolts = place_bolts(model.bolts, blocks, faces, asm)
    check_bolt_stiffness(model.bolts, bolts, faces, model.joints, asm.length_scale)
    if bolts is not None:
        K0.data += bolts.stiffness_data(np.column_stack([bolts.k_axial, bolts.k_shear]))
    if f_block is None:
        f_block = block_loads(blocks, model.loads)
    check_water_table(blocks, faces, model.loads)
    f_block = f_block + water_loads(blocks, faces, joint_water(blocks, model.loads))
    free = ~blocks.fixed
    f_ext = np.zeros(asm.n_dof)
    f_ext[asm.dof[free].ravel()] = f_block[free].ravel()
    if asm.n_dof and not np.any(f_ext) and bolts is None:
        raise InputError(
            "the free blocks",
            "carry no load (no unit weight, or gravity off, and no other load): there is "
            "nothing to analyse",
            "give the blocks a unit weight, or apply a load",
        )
    u_elastic = None
    elastic = 1.0
    if asm.n_dof:
        try:
            # a handle of its own, freed here: the tangents' handle analyses the
            # pattern with the first tangent's values (PARDISO's matching and
            # scaling depend on them: analysed with K0's, the paths of chaotic
            # searches changed in their last bits)
            u_elastic = Factorizer().factorize(K0).solve(f_ext)
        except RuntimeError as exc:
            check_held(blocks, faces)  # a group of blocks nothing holds: name it
            raise InputError(
                "model",
                "the elastic stiffness is singular: some block is not held against "
                f"rotation ({s.points_per_interface}-point {s.quadrature} rule)",
                "use 2 or more spring points per interface",
            ) from exc
        elastic = float(np.max(np.abs(u_elastic / asm.dof_scale))) or 1.0
    return System(
        model,
        blocks,
        faces,
        springs,
        asm,
        K0,
        f_block,
        f_ext,
        elastic,
        u_elastic,
        bolts=bolts,
    )


@dataclass(frozen=True, eq=False)
class Solve:
    """Outcome of one equilibrium solve, with its evidence."""

    converged: bool
    q: np.ndarray
    response: Response
    iterations: int
    residuals: list[float]
    reason: str
    direction: np.ndarray  # last Newton direction (the mechanism if it failed)
    #: strength homotopy: the largest factor reached in equilibrium, its
    #: displacements, and the factor just beyond it that failed
    reached: float | None = None
    reached_q: np.ndarray | None = None
    failed_at: float | None = None
    #: the second method's statement on the failure (rockdem.relaxation)
    relaxation: str | None = None


def residual(system: System, q, state, load_factor, factor, strengths=None):
    """Response and out-of-balance force at displacements q (``strengths``:
    :func:`rockdem.spring_law.strength` of this state and factor, if known)."""
    asm = system.assembly
    dn, ds = asm.relative_displacement(q)
    reduce = system.model.settings.reduce_tensile
    resp = evaluate(system.springs, state, dn, ds, factor, reduce, strengths)
    r = load_factor * system.f_ext - asm.internal_force(resp.force)
    if system.bolts is not None:
        r -= system.bolts.internal_force(q, state.bolt_reference)
    return resp, r


def tangent(system: System, resp: Response, q, shift: float = 0.0, reference=None) -> sp.csc_array:
    """Consistent tangent of the springs (and bolts, installed at
    ``reference``) at ``q``, plus ``shift x K0``."""
    J = system.assembly.stiffness(resp.d_nn, resp.d_sn, resp.d_ss, shift, system.K0)
    if system.bolts is not None:
        _, d_bolt, _ = system.bolts.forces(q, reference)
        J.data += system.bolts.stiffness_data(d_bolt)
    return J


def _lu(system, J):
    try:
        return system.factorizer.factorize(J)
    except RuntimeError:  # exactly singular
        return None


class _Tangents:
    """The factorised tangent of one Newton solve, refactorised only when it changed.

    The spring law is piecewise linear: the tangent depends only on which
    springs are elastic, sliding (and which way) or open, and on the shift.
    Near a limit Newton often creeps towards the next switch of one spring in
    several damped steps under the same tangent (measured: 30-40% of the
    iterations of a creeping solve); those steps reuse the factor.
    """

    def __init__(self, system: System, bolt_reference=None) -> None:
        self.system = system
        self.reference = bolt_reference
        self.key: tuple | None = None
        self.lu = None
        self.reused = 0

    def factor(self, resp: Response, q, beta: float):
        system = self.system
        parts = [resp.d_nn, resp.d_sn, resp.d_ss]
        if system.bolts is not None:
            parts.append(system.bolts.forces(q, self.reference)[1].ravel())
        key = (beta, np.concatenate(parts))
        if (
            self.key is not None
            and self.lu is not None
            and key[0] == self.key[0]
            and np.array_equal(key[1], self.key[1])
            and getattr(self.lu, "generation", 0) in (0, system.factorizer.generation)
        ):  # (a PARDISO factor is valid until its handle factorises another matrix)
            self.reused += 1
            return self.lu
        self.key, self.lu = key, _lu(system, tangent(system, resp, q, beta, self.reference))
        return self.lu


def newton(system, state, load_factor, factor, q, max_it, tolerance=None):
    """Semismooth Newton with an adaptive Levenberg-Marquardt shift and a
    backtracking line search on the scaled out-of-balance force.

    The step solves ``(J + beta K0) dq = r`` with ``J`` the consistent tangent.
    Where sliding and open springs leave a block nearly free ``J`` is nearly
    singular; the shift ``beta K0`` (``K0`` the elastic stiffness) bounds the
    step.  ``beta`` rises x10 when the line search fails and falls /10 after
    a full step; the solve gives up when ``beta`` exceeds ``BETA_MAX``.
    A step that would move a dof farther than ``TRUST_RADIUS`` x the larger
    of the elastic displacement and the distance travelled since the start
    is re-solved with ``beta`` scaled up by the excess (the free mode's step
    is ~ 1 / beta).  ``tolerance``: the out-of-balance share of the loads
    at which it stops (default: the model's).

    Near a kink the backtracking creeps: the tangent does not change, aims at
    the same point, and each step halves the way to the kink.  Measured and
    not kept: aiming instead with the tangent of the first point the line
    search rejected (past the kink): a 2,322-block slope's stall 0.6-1.3%
    below its limit became 0.7% for every homotopy setting, but 2,952 and
    9,638-block brick slopes took 392 and 528 factorisations (334, 536);
    15 further iterations while the out-of-balance force has fallen 100x:
    15% fewer factorisations on brick slopes, but that 2,322-block slope then
    stalled 3.7% low.
    """
    asm = system.assembly
    scale = asm.dof_scale
    tol = system.model.settings.tolerance if tolerance is None else tolerance
    f_norm = norm(load_factor * system.f_ext * scale)
    # the strengths of this state and factor, for every residual of the solve
    strengths = strength(system.springs, state, factor, system.model.settings.reduce_tensile)
    resp, r = residual(system, q, state, load_factor, factor, strengths)
    merit = norm(r * scale) / f_norm
    history = [merit]
    beta = BETA_START
    bound = BLOWUP * system.elastic_scale * max(load_factor, 1e-12)
    direction = np.zeros_like(q)
    q_start, reach = q, system.elastic_scale * load_factor
    tangents = _Tangents(system, state.bolt_reference)
    for it in range(1, max_it + 1):
        if merit <= tol:
            return Solve(True, q, resp, it - 1, history, "converged", direction)
        lu = tangents.factor(resp, q, beta)
        if lu is None:
            beta *= 10.0
            if beta > BETA_MAX:
                return Solve(False, q, resp, it, history, "singular tangent", direction)
            continue
        step = lu.solve(r)
        size = np.max(np.abs(step / scale))
        radius = TRUST_RADIUS * max(reach, np.max(np.abs((q - q_start) / scale)))
        if size > radius:  # a near-free mode of the tangent: raise the shift to fit
            beta = min(beta * size / radius, BETA_MAX)
            lu = tangents.factor(resp, q, beta)
            if lu is None:
                continue
            step = lu.solve(r)
        direction = step
        alpha, accepted = 1.0, False
        for _ in range(LINE_SEARCH_HALVINGS):
            q_try = q + alpha * step
            resp_try, r_try = residual(system, q_try, state, load_factor, factor, strengths)
            merit_try = norm(r_try * scale) / f_norm
            if merit_try <= (1.0 - 1e-4 * alpha) * merit:
                accepted = True
                break
            alpha *= 0.5
        if accepted:
            q, resp, r, merit = q_try, resp_try, r_try, merit_try
            history.append(merit)
            if alpha == 1.0:
                beta = max(beta / 10.0, BETA_START)
            if len(history) > STALL_WINDOW and merit > STALL_RATIO * history[-1 - STALL_WINDOW]:
                if merit <= max(tol, KINK_TOLERANCE):  # an equilibrium, to that tolerance
                    return Solve(True, q, resp, it, history, KINKED, direction)
                return Solve(False, q, resp, it, history, "stalled", direction)
        else:
            beta *= 10.0
            if beta > BETA_MAX:
                return Solve(False, q, resp, it, history, "no descent", direction)
        if np.max(np.abs(q / scale)) > bound:
            return Solve(False, q, resp, it, history, "displacements unbounded", direction)
    if merit <= tol:
        return Solve(True, q, resp, max_it, history, "converged", direction)
    if merit <= max(tol, KINK_TOLERANCE):
        return Solve(True, q, resp, max_it, history, KINKED, direction)
    return Solve(False, q, resp, max_it, history, "iteration limit", direction)
