"""Frozen result containers: what an analysis returns, never written into the model."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .bolts import BoltResults, bolt_results
from .relaxation import MECHANISM_TEXT
from .solver import System
from .spring_law import STATE_NAMES, SpringState, strength


def format_factor(F: float) -> str:
    """A strength factor for labels: ``"1"`` for a whole number, else four
    decimals (``"1.1996"``, never ``"1.2"`` for 1.19958)."""
    F = float(F)
    if F == round(F):
        return f"{F:.0f}"
    return f"{F:.4f}"


def bracket_decimals(lo: float, hi: float) -> int:
    """Decimals that show a bracket's two ends apart (4 to 8): at 4 the
    wedge's [0.978577, 0.978638] read "0.9786, 0.9786"."""
    if not (np.isfinite(lo) and np.isfinite(hi)) or hi <= lo:
        return 4
    return int(min(8, max(4, np.ceil(-np.log10(hi - lo)) + 1)))


#: Current state of a spring point or interface (codes, worst last): never failed
#: and holding; failed earlier (yielded or broken) but now closed and holding;
#: at its shear strength now; open now (at or beyond its tensile strength).
CURRENT_NAMES = ("elastic", "closed-failed-earlier", "sliding", "open")
#: The same in words, for legends and tables.
CURRENT_LABELS = ("elastic", "failed earlier, now closed", "sliding", "open")
#: A closed point slides when its shear stress is within this share of its strength.
SLIDING_SHARE = 1e-6


def current_state(sigma, tau, strength, is_open, failed) -> np.ndarray:
    """Current state codes (see :data:`CURRENT_NAMES`) of spring points.

    ``strength`` is the shear strength at the factor of the stresses;
    ``failed`` the committed failure flags (yielded or broken).  A point is
    sliding when closed with its shear stress at its strength (within
    :data:`SLIDING_SHARE`), whatever its history.
    """
    strength = np.asarray(strength)
    sliding = ~is_open & (strength > 0) & (np.abs(tau) >= (1 - SLIDING_SHARE) * strength)
    return np.where(is_open, 3, np.where(sliding, 2, np.where(failed, 1, 0)))


@dataclass(frozen=True, eq=False)
class Evidence:
    """Why a solve was judged converged or failed."""

    reason: str
    iterations: int
    residuals: tuple[float, ...]
    certified: bool | None = None  # failure proven by the equilibrium LP (None: not checked)
    reached: float | None = None  # strength homotopy: largest factor found in equilibrium
    failed_at: float | None = None  # ... and the factor just beyond it that failed
    #: the equilibrium LP's statement (rockdem.certificate), when it was solved
    certificate: str | None = None
    #: the strength factor at which the LP was solved
    certified_at: float | None = None
    #: dynamic relaxation's statement on the failure (rockdem.relaxation)
    relaxation: str | None = None
    #: the strength factor at which dynamic relaxation left the blocks moving
    #: (a little beyond the bracket: the failure is confirmed there, not below)
    confirmed_at: float | None = None

    @property
    def proof(self) -> str | None:
        """How a failure is known: ``"lp-certificate"`` (no statically admissible
        force field exists: proven), ``"dynamic-relaxation"`` (not proven, but
        confirmed by a second, independent method: the blocks keep moving),
        ``"undecided"`` (the solver found no equilibrium and nothing settles
        whether one exists); None if converged."""
        if self.reason == "converged" or self.reason == "no load":
            return None
        if self.certified:
            return "lp-certificate"
        if self.relaxation is not None and self.relaxation.startswith(MECHANISM_TEXT):
            return "dynamic-relaxation"
        return "undecided"

    def __str__(self) -> str:
        last = self.residuals[-1] if self.residuals else float("nan")
        text = f"{self.reason} after {self.iterations} iterations (residual {last:.2e})"
        if self.certificate is not None:
            text += f"; {self.certificate}"
        if self.relaxation is not None:
            text += f"; {self.relaxation}"
        return text


@dataclass(frozen=True, eq=False)
class Step:
    """One load step or one strength-reduction trial."""

    stage: int
    load_factor: float
    strength_factor: float
    converged: bool
    evidence: Evidence
    n_failed_springs: int


@dataclass(frozen=True, eq=False, repr=False)
class SpringResults:
    """Per spring point: stresses, state, local factor of safety, first failure."""

    interface: np.ndarray
    point: np.ndarray
    sigma: np.ndarray
    tau: np.ndarray
    capacity: np.ndarray
    state: np.ndarray
    first_failure: np.ndarray
    #: shear strength at the strength factor and spring state the stresses
    #: were evaluated with (``capacity`` is at full strength, F = 1); None in
    #: results made before it was recorded
    strength: np.ndarray | None = None
    #: current state codes (:data:`CURRENT_NAMES`); ``state`` is the history
    current: np.ndarray | None = None

    @property
    def current_name(self) -> np.ndarray:
        """Current state of every point: elastic, closed-failed-earlier, sliding, open."""
        return np.asarray(CURRENT_NAMES)[self.current]

    @property
    def local_fos(self) -> np.ndarray:
        """Shear strength over shear stress (inf where unstressed)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            fos = np.where(np.abs(self.tau) > 0, self.capacity / np.abs(self.tau), np.inf)
        return fos

    @property
    def state_name(self) -> np.ndarray:
        return np.asarray(STATE_NAMES)[self.state]


@dataclass(frozen=True, eq=False, repr=False)
class InterfaceResults:
    """Per interface: forces, mean stresses, state and first failure."""

    block_a: np.ndarray  # user ids
    block_b: np.ndarray
    kind: np.ndarray  # joint name
    length: np.ndarray
    normal_force: np.ndarray
    shear_force: np.ndarray
    state: np.ndarray  # worst point state (2 tension > 1 shear > 0 elastic)
    failed_fraction: np.ndarray  # fraction of the length that has failed
    local_fos: np.ndarray
    first_failure: np.ndarray  # -1 if never failed
    #: current state code of most of the length (ties: the worse state);
    #: ``state`` and ``failed_fraction`` are the history
    current: np.ndarray | None = None
    #: fraction of the length open now, and sliding now
    open_fraction: np.ndarray | None = None
    sliding_fraction: np.ndarray | None = None

    @property
    def current_name(self) -> np.ndarray:
        """Current state: elastic, closed-failed-earlier, sliding or open."""
        return np.asarray(CURRENT_NAMES)[self.current]

    @property
    def normal_stress(self) -> np.ndarray:
        return self.normal_force / self.length

    @property
    def shear_stress(self) -> np.ndarray:
        return self.shear_force / self.length

    @property
    def state_name(self) -> np.ndarray:
        return np.asarray(STATE_NAMES)[self.state]

    @property
    def n_interfaces(self) -> int:
        return len(self.length)


@dataclass(frozen=True, eq=False, repr=False)
class Analysis:
    """Result of a staged analysis (gravity in load steps) at one strength factor.

    Attributes
    ----------
    stable : bool
        Equilibrium was found at the full load.
    load_factor : float
        Largest load factor at which equilibrium was found.
    displacement : ndarray (n_blocks, 3)
        ``(ux, uy, rotation)`` of each block at the last equilibrium.
    mechanism : ndarray (n_blocks, 3)
        Direction of motion of the failure mechanism (zeros if stable),
        scaled so that the largest block motion is 1.
    unstable : ndarray of bool (n_blocks,)
        Blocks that move in the failure mechanism.
    slip_surface : ndarray of int
        Interfaces (positions) that have failed and bound the moving blocks.
    limit_interfaces : InterfaceResults or None
        For a failure: the interfaces at the last equilibrium before it (the
        largest stable factor of a factor-of-safety search, or the last load
        carried in a staged analysis; None when no load was carried): which
        contacts were open or at their strength as failure began
        (:func:`rockdem.modes.failure_modes` reads sliding or toppling from
        them).
    unloaded_limit : (float, float, ndarray) or None
        For a failure in the first load step: ``(load factor, strength
        factor, free-dof displacements)`` of the equilibrium the search found
        at that load at the largest strength factor it reached, from the
        unloaded state (so valid at that factor whatever this analysis's):
        a staged analysis at that factor starts its first step there
        (``analyse(start=...)``) instead of from scratch.
    failure_start : (SpringState, ndarray, float) or None
        For a proven failure whose mechanism was not yet shown
        (``analyse(show_mechanism=False)``): the committed state, free-dof
        displacements and load factor it failed from, for
        :func:`rockdem.analysis.show_mechanism`.
    """

    system: System
    stable: bool
    load_factor: float
    strength_factor: float
    displacement: np.ndarray
    mechanism: np.ndarray
    unstable: np.ndarray
    springs: SpringResults
    interfaces: InterfaceResults
    slip_surface: np.ndarray
    steps: tuple[Step, ...]
    state: SpringState = field(repr=False)
    limit_interfaces: InterfaceResults | None = field(default=None, repr=False)
    unloaded_limit: tuple[float, float, np.ndarray] | None = field(default=None, repr=False)
    failure_start: tuple[SpringState, np.ndarray, float] | None = field(default=None, repr=False)

    @property
    def unstable_blocks(self) -> np.ndarray:
        """User ids of the blocks that move in the mechanism."""
        return self.system.blocks.ids[self.unstable]

    @property
    def q(self) -> np.ndarray:
        """``displacement`` as the solver's vector over the free blocks' dof."""
        asm, free = self.system.assembly, ~self.system.blocks.fixed
        q = np.zeros(asm.n_dof)
        q[asm.dof[free].ravel()] = self.displacement[free].ravel()
        return q

    @property
    def bolts(self) -> BoltResults | None:
        """Force in every bolt at every joint it crosses, at ``displacement``
        (None without bolts)."""
        system = self.system
        if system.bolts is None:
            return None
        return bolt_results(
            system.bolts, self.q, self.state.bolt_first_yield, self.state.bolt_reference
        )

    @property
    def failed_interfaces(self) -> np.ndarray:
        """Positions of interfaces with at least one failed point."""
        return np.flatnonzero(self.interfaces.state > 0)

    @property
    def evidence(self) -> Evidence:
        return self.steps[-1].evidence

    @property
    def stress_factor(self) -> float:
        """The strength factor at which ``springs`` (stresses, strength) were evaluated.

        ``strength_factor`` for an equilibrium; for a failed solve, the factor
        of its last iterate (``evidence.failed_at`` when the strength
        homotopy ran: the stresses of a failed analysis are not at the
        factor it was asked for).
        """
        if not self.stable and self.evidence.failed_at is not None:
            return float(self.evidence.failed_at)
        return float(self.strength_factor)

    @property
    def equilibrium(self) -> Step | None:
        """The last step that found equilibrium (the state ``displacement``
        belongs to), or None when no step did."""
        for step in reversed(self.steps):
            if step.converged:
                return step
        return None

    @property
    def verdict(self) -> str:
        """``"stable"``, ``"unstable"`` (failure proven by the LP or confirmed by
        dynamic relaxation) or ``"undecided"`` (no equilibrium found, but
        nothing proves or confirms failure: a stall is no verdict)."""
        if self.stable:
            return "stable"
        return "undecided" if self.evidence.proof == "undecided" else "unstable"

    def __repr__(self) -> str:
        return (
            f"<Analysis: {self.verdict}, load factor {self.load_factor:.3g}, "
            f"{len(self.failed_interfaces)} failed interfaces, "
            f"{int(self.unstable.sum())} unstable blocks>"
        )


@dataclass(frozen=True, eq=False, repr=False)
class Trial:
    """One strength-reduction trial.

    ``max_displacement`` is the largest block translation of the converged
    state (NaN when the trial found no equilibrium).
    """

    factor: float
    stable: bool
    evidence: Evidence
    max_displacement: float = float("nan")


@dataclass(frozen=True, eq=False, repr=False)
class FactorOfSafety:
    """Shear strength reduction factor of safety.

    Attributes
    ----------
    value : float or None
        Midpoint of the bracket; None when strength cannot control the
        mechanism (toppling) or no stable state exists at any factor.
    bracket : (float, float)
        Largest factor found stable, smallest found unstable.
    mode : str
        ``"strength"`` (a value was found), ``"strength-independent"`` (the
        mechanism forms even with the strengths multiplied by the largest
        factor tried: toppling, a free block, or joints with c = 0 and
        phi = 0), or ``"no-failure"`` (stable at the largest factor tried).
    stable_analysis, failed_analysis : Analysis
        The state at the lower end of the bracket and the mechanism at the
        upper end.
    lp_bound : float or None
        Where the upper end is not proven: the smallest factor, up to where
        failure is confirmed, at which the equilibrium LP proves failure
        (:func:`rockdem.certificate.upper_bound`), or None.
    """

    value: float | None
    bracket: tuple[float, float]
    mode: str
    trials: tuple[Trial, ...]
    stable_analysis: Analysis | None
    failed_analysis: Analysis | None
    definition: str
    lp_bound: float | None = None

    def __post_init__(self) -> None:
        # plain floats, whatever arithmetic made them (a bracket printed as
        # ``(3.53, np.float64(3.71))`` is noise in a user's report)
        plain = None if self.value is None else float(self.value)
        object.__setattr__(self, "value", plain)
        object.__setattr__(self, "bracket", tuple(float(b) for b in self.bracket))

    @property
    def proof(self) -> str | None:
        """How the upper end of the bracket is known to fail: ``"lp-certificate"``
        (proven: no admissible force field), ``"dynamic-relaxation"``
        (confirmed by the second solver a little beyond it) or
        ``"undecided"`` (nothing settles it: the factor of safety may be
        higher); None without a failed trial.

        A strength-independent result shows the slope's own failure (at the
        starting factor) but states that the slope fails at the top of its
        bracket, the smallest factor tried: its proof is that trial's (a
        slope toppled by its joint water, r_u 0.27, read "lp-certificate"
        from the LP at F = 1, while at the top, F = 0.0585, the LP found an
        admissible field and only dynamic relaxation confirmed the failure;
        found by the verdict audit)."""
        if self.failed_analysis is None:
            return None
        if self.mode == "strength-independent":
            top = [t for t in self.trials if not t.stable and t.factor == self.bracket[1]]
            if top:
                return top[-1].evidence.proof
        return self.failed_analysis.evidence.proof

    @property
    def certified_upper_bound(self) -> float | None:
        """Smallest factor at which the equilibrium LP proved that no
        admissible force field exists (a rigorous upper bound), or None."""
        bounds = [
            t.evidence.certified_at
            for t in self.trials
            if not t.stable and t.evidence.certified and t.evidence.certified_at is not None
        ]
        if self.lp_bound is not None:
            bounds.append(self.lp_bound)
        return min(bounds) if bounds else None

    @property
    def confirmed_upper_bound(self) -> float | None:
        """Where the failure is confirmed by dynamic relaxation (proof
        ``"dynamic-relaxation"``): a little beyond the bracket, which ends
        where Newton lost equilibrium.  The limit lies below it; between the
        bracket and it, nothing proves or confirms failure.  None otherwise."""
        if self.proof != "dynamic-relaxation":
            return None
        return self.failed_analysis.evidence.confirmed_at

    def __repr__(self) -> str:
        if self.value is None:
            return f"<FactorOfSafety: none ({self.mode}), bracket {self.bracket}>"
        lo, hi = self.bracket
        return (
            f"<FactorOfSafety: {self.value:.4f} in [{lo:.4f}, {hi:.4f}], {len(self.trials)} trials>"
        )


def tabulate(system: System, state: SpringState, resp, strength_factor: float, reduce_tensile):
    """Spring and interface tables from a response and its committed state."""
    springs = system.springs
    c, tan_phi, _ = strength(springs, state, 1.0, reduce_tensile)
    cap = np.where(resp.open, 0.0, np.maximum(c + resp.sigma * tan_phi, 0.0))
    now = current_state(
        resp.sigma, resp.tau, resp.capacity, resp.open, state.yielded | state.broken
    )
    sp_res = SpringResults(
        springs.interface,
        springs.point,
        resp.sigma,
        resp.tau,
        cap,
        state.state,
        state.first_failure,
        resp.capacity,
        now,
    )
    faces = system.interfaces
    m = springs.points_per_interface
    w = springs.weight.reshape(-1, m)
    N = (w * resp.sigma.reshape(-1, m)).sum(1)
    S = (w * resp.tau.reshape(-1, m)).sum(1)
    C = (w * cap.reshape(-1, m)).sum(1)
    st = state.state.reshape(-1, m)
    failed_len = (w * (st > 0)).sum(1)
    ff = state.first_failure.reshape(-1, m)
    first = np.where((ff >= 0).any(1), np.where(ff >= 0, ff, np.iinfo(np.int64).max).min(1), -1)
    with np.errstate(divide="ignore", invalid="ignore"):
        fos = np.where(np.abs(S) > 0, C / np.abs(S), np.inf)
    ids = system.blocks.ids
    names = np.asarray([j.name for j in system.model.joints])
    length = faces.length
    if_res = InterfaceResults(
        ids[faces.block_a],
        ids[faces.block_b],
        names[faces.joint],
        length,
        N,
        S,
        st.max(1) if st.size else np.zeros(0, dtype=int),
        failed_len / length,
        fos,
        first,
        *_current_by_length(now.reshape(-1, m), w, length),
    )
    return sp_res, if_res


def _current_by_length(now: np.ndarray, w: np.ndarray, length: np.ndarray):
    """Interface current state, open and sliding fractions, from point codes
    ``(n, m)`` and weights.

    Open, sliding or holding, by most of the length (ties to the worse);
    a holding interface is ``closed-failed-earlier`` if any point of it has
    failed earlier and is closed and holding now, else ``elastic`` (its
    history, ``state``, may still show a failure of a minor part).
    """
    if not len(length):
        z = np.zeros(0)
        return np.zeros(0, dtype=int), z, z
    share = np.stack([(w * (now == k)).sum(1) for k in range(4)], axis=1) / length[:, None]
    three = np.column_stack([share[:, 3], share[:, 2], share[:, 0] + share[:, 1]])
    top = np.argmax(three >= three.max(1, keepdims=True) * (1 - 1e-9), axis=1)
    current = np.choose(top, [3, 2, np.where((now == 1).any(1), 1, 0)])
    return current, share[:, 3], share[:, 2]
