"""Stabilisation by block removal: remove the mechanism, re-analyse, repeat.

Each round rates the current slope by strength reduction; if it falls short
of the target, the blocks of the critical mechanism (the blocks moving just
above the factor of safety) are removed, and when that reaches the target a
smaller set is looked for among them, from the top of the slope down.  The
loop stops when the target is reached, when the removal would take more
than ``max_removal`` of the rock, or after ``max_rounds`` rounds.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..analysis import analyse
from ..errors import InputError
from ..model import Model
from ..results import FactorOfSafety
from ..strength_reduction import factor_of_safety
from ..units import Units
from . import _edit, _progress

__all__ = ["RemovalTrial", "Stabilisation", "meets", "rate", "stabilise"]


#: the largest target factor a design may be asked for (the model file's
#: ``stabilisation.target_fos`` and ``--target-fos``)
MAX_TARGET = 20.0


def rate(model: Model, *, width: float = 0.01, largest: float = 1.5 * MAX_TARGET) -> FactorOfSafety:
    """Factor of safety of a design (strength reduction, bracket ``width``).

    The search goes on beyond every target allowed: with the trial factor
    growing x1.5 it stopped at 17.09 of 20, and a design that never failed
    could not meet a target of 18 (found by fuzzing)."""
    return factor_of_safety(model, width=width, largest=largest, progress=_progress.trial_hook())


def _blocks(n: int, kind: str) -> str:
    """``"2 mechanism blocks"``, ``"mechanism block"`` for one (it read "the 1
    moving blocks")."""
    return f"{n} {kind} blocks" if n != 1 else f"{kind} block"


def meets(fos: FactorOfSafety, target: float) -> bool:
    """True when the design is known stable at the target factor: the bracket's
    stable end reaches it (also where no trial failed: the search stops below
    its largest factor, ``> 17.1`` of 20, say, does not meet a target of 20)."""
    if fos.mode == "no-failure":
        return fos.bracket[0] >= target
    return fos.value is not None and fos.bracket[0] >= target


def describe(fos: FactorOfSafety) -> str:
    """The factor of safety as text: a value, ``> x`` or ``none (toppling...)``."""
    if fos.value is not None:
        return f"{fos.value:.3f}"
    if fos.mode == "no-failure":
        return f"> {fos.bracket[0]:.3g}"
    return "none (strength-independent)"


def mechanism_ids(fos: FactorOfSafety) -> tuple[int, ...]:
    """Blocks moving in the critical mechanism (at the unstable end of the bracket)."""
    a = fos.failed_analysis
    if a is None:
        return ()
    return tuple(int(i) for i in a.unstable_blocks)


@dataclass(frozen=True, eq=False)
class RemovalTrial:
    """One design tried: what was removed (counted from the original) and its rating.

    Attributes
    ----------
    number : int
        0 for the slope as it is, then 1, 2, ... in the order tried.
    round : int
        Removal round (0 for the slope as it is).
    label : str
    removed_blocks : tuple of int
        Ids of all blocks removed from the original model so far (trimmed
        blocks included).
    removed_area : float
        Area (volume per unit thickness) removed from the original model.
    fos : FactorOfSafety
    model : Model
        The model of this design.
    accepted : bool
        The design the next round starts from (or the final one).
    """

    number: int
    round: int
    label: str
    removed_blocks: tuple[int, ...]
    removed_area: float
    fos: FactorOfSafety
    model: Model
    accepted: bool

    @property
    def factor(self) -> float | None:
        """The factor of safety (None for a strength-independent mechanism;
        the largest factor tried for no failure)."""
        if self.fos.value is not None:
            return float(self.fos.value)
        return float(self.fos.bracket[0]) if self.fos.mode == "no-failure" else None

    @property
    def mechanism(self) -> tuple[int, ...]:
        return mechanism_ids(self.fos)


@dataclass(frozen=True, eq=False)
class Stabilisation:
    """Result of :func:`stabilise`.

    Attributes
    ----------
    target : float
    trials : tuple of RemovalTrial
        Every design tried, the slope as it is first.
    reached : bool
        The final accepted design meets the target.
    message : str
        One sentence: what was done and the outcome.
    needs : str
        When the target was not reached: what else would be needed.
    """

    target: float
    trials: tuple[RemovalTrial, ...]
    reached: bool
    message: str
    needs: str = ""

    @property
    def original(self) -> RemovalTrial:
        return self.trials[0]

    @property
    def final(self) -> RemovalTrial:
        """The last accepted design."""
        return [t for t in self.trials if t.accepted][-1]

    @property
    def removed_blocks(self) -> tuple[int, ...]:
        return self.final.removed_blocks

    @property
    def removed_area(self) -> float:
        return self.final.removed_area

    def __repr__(self) -> str:
        f = self.final
        word = "reached" if self.reached else "NOT reached"
        return (
            f"<Stabilisation: target {self.target:g}, {word}"
            f", {len(f.removed_blocks)} blocks removed (area {f.removed_area:.3g}), "
            f"FS {describe(f.fos)}>"
        )


def stabilise(
    model: Model,
    target_fos: float = 1.3,
    *,
    max_rounds: int = 6,
    max_removal: float = 0.3,
    smallest_set: bool = True,
    width: float = 0.01,
    progress: Callable[[RemovalTrial], None] | None = None,
    units: Units | None = None,
) -> Stabilisation:
    """Remove unstable blocks until the factor of safety reaches ``target_fos``.

    Parameters
    ----------
    model : Model
    target_fos : float
        Required factor of safety (> 0).
    max_rounds : int
        Removal rounds before giving up.
    max_removal : float
        Largest share of the free rock (by area) that may be removed; a
        removal beyond it is not made and the search stops.
    smallest_set : bool
        When removing the whole mechanism reaches the target, look for a
        smaller set: the mechanism's blocks from the top down, bisecting on
        how many (a heuristic: the factor need not grow monotonically).
    width : float
        Bracket width of every factor-of-safety search.
    progress : callable, optional
        Called with each :class:`RemovalTrial` as it is made.
    units : Units, optional
        The model's units (:func:`rockdem.units.parse_units`), named in the message.

    Returns
    -------
    Stabilisation

    Examples
    --------
    >>> from rockdem.verification import two_block_wedge
    >>> s = stabilise(two_block_wedge(35, 30), 1.1, smallest_set=False)  # doctest: +SKIP
    """
    if not target_fos > 0:
        raise InputError("target factor of safety", f"{target_fos}", "give a value > 0")
    if not 0 < max_removal <= 1:
        raise InputError("max_removal", f"{max_removal}", "give a fraction in (0, 1]")
    area_unit = f" {units.area}" if units is not None and units.known else ""
    area0 = _edit.free_area(model)
    trials: list[RemovalTrial] = []

    def add(rnd, label, m, fos, accepted) -> RemovalTrial:
        ids, area = _edit.removed_between(model, m)
        t = RemovalTrial(len(trials), rnd, label, ids, area, fos, m, accepted)
        trials.append(t)
        _progress.note(f"{label}: factor of safety {describe(fos)}")
        if progress is not None:
            progress(t)
        return t

    current = add(0, "slope as it is", model, rate(model, width=width), True)
    for rnd in range(1, max_rounds + 1):
        if meets(current.fos, target_fos):
            break
        mech = current.mechanism
        if current.fos.mode == "strength-independent":
            # no factor brackets it: remove what moves under the loads as they are
            mech = tuple(int(i) for i in analyse(current.model).unstable_blocks)
        if not mech:
            return _done(
                target_fos,
                trials,
                False,
                "no moving blocks were found to remove",
                "another measure (support or a new profile)",
            )
        try:
            cand = _edit.remove_ids(current.model, mech)
        except InputError as exc:
            if exc.where == "loads.water_table":
                return _done(
                    target_fos,
                    trials,
                    False,
                    f"removing the {len(mech)} mechanism blocks would dig below the water "
                    f"table (the water table {exc.problem.split(' once ')[0]})",
                    "drainage (a lower water table), support, or a flatter profile (berm)",
                )
            return _done(
                target_fos,
                trials,
                False,
                f"the mechanism blocks cannot be removed alone ({exc.problem})",
                "remove a region instead (a new profile)",
            )
        share = 1.0 - _edit.free_area(cand) / area0
        if share > max_removal:
            return _done(target_fos, trials, False, *_too_much(current, mech, share, max_removal))
        fos = rate(cand, width=width)
        label = f"round {rnd}: remove the {_blocks(len(mech), 'mechanism')}"
        notes = _edit.removal_notes(current.model, cand)
        label += f" ({'; '.join(notes)})" if notes else ""
        chosen = add(rnd, label, cand, fos, False)
        if meets(fos, target_fos) and smallest_set and len(mech) > 1:
            chosen = _smaller(current, mech, chosen, target_fos, width, rnd, add)
        current = _accept(trials, chosen)
    final = [t for t in trials if t.accepted][-1]
    if meets(final.fos, target_fos):
        n = len(final.removed_blocks)
        return _done(
            target_fos,
            trials,
            True,
            f"target {target_fos:g} reached by removing {n} blocks "
            f"(area {final.removed_area:.3g}{area_unit}, "
            f"{100 * final.removed_area / area0:.0f}% of the rock): "
            f"factor of safety {describe(final.fos)}",
        )
    return _done(
        target_fos,
        trials,
        False,
        f"target {target_fos:g} not reached after {max_rounds} removal rounds "
        f"(factor of safety {describe(final.fos)})",
        "support forces or a flatter profile (berm)",
    )


def _accept(trials: list[RemovalTrial], chosen: RemovalTrial) -> RemovalTrial:
    """Mark ``chosen`` as the design the next round starts from."""
    k = trials.index(chosen)
    accepted = RemovalTrial(
        chosen.number,
        chosen.round,
        chosen.label,
        chosen.removed_blocks,
        chosen.removed_area,
        chosen.fos,
        chosen.model,
        True,
    )
    trials[k] = accepted
    return accepted


def _smaller(current, mech, full, target, width, rnd, add) -> RemovalTrial:
    """Bisect on how many mechanism blocks to remove, from the top down."""
    b = current.model.blocks
    idx = b.index_of(np.asarray(mech))
    order = [mech[k] for k in np.argsort(-b.centroid[idx, 1], kind="stable")]
    lo, hi, best = 0, len(order), full
    while hi - lo > 1:
        mid = (lo + hi) // 2
        try:
            m = _edit.remove_ids(current.model, order[:mid])
        except InputError:
            lo = mid
            continue
        t = add(
            rnd,
            f"round {rnd}: remove the top {mid} of the {len(order)} mechanism blocks",
            m,
            rate(m, width=width),
            False,
        )
        if meets(t.fos, target):
            hi, best = mid, t
        else:
            lo = mid
    return best


def _too_much(current: RemovalTrial, mech, share, limit) -> tuple[str, str]:
    if current.fos.mode == "strength-independent":
        return (
            f"block removal cannot reach the target: the mechanism is toppling (it forms "
            f"whatever the joint strength) and removing its {len(mech)} blocks would take "
            f"{100 * share:.0f}% of the rock (limit {100 * limit:.0f}%): the whole "
            "toppling zone would have to go",
            "support that ties the toppling columns back to stable rock (anchors or bolts "
            "across the near-vertical joints), or a flatter profile that shortens the columns",
        )
    return (
        f"block removal stopped: removing the {_blocks(len(mech), 'moving')} would take "
        f"{100 * share:.0f}% of the rock (limit {100 * limit:.0f}%)",
        "support forces (anchors or bolts) or a flatter profile (berm)",
    )


def _done(target, trials, reached, message, needs="") -> Stabilisation:
    return Stabilisation(target, tuple(trials), reached, message, "" if reached else needs)


def stable_at(model: Model, factor: float) -> bool:
    """True when the staged analysis finds equilibrium with strengths divided by
    ``factor``: a trial of a search, so without the mechanism of a failure
    and its warnings (an after_loads bolt of a slope that stands was said
    "never installed" because a trial at the target failed).  Bolts to go in
    after the loads go into the slope at its own strength (F = 1), as in
    :func:`~rockdem.factor_of_safety`, and the strengths are reduced from
    there: analysed at the target they never went into a slope that needs
    them (a pattern rated 2.42 read "not stable at 1.5"; review 33)."""
    from ..solver import build_system
    from ..strength_reduction import _continue

    system = build_system(model)
    late = system.bolts is not None and bool(np.any(system.bolts.late))
    if not late or factor <= 1.0:
        return analyse(system, strength_factor=factor, show_mechanism=False).stable
    first = analyse(system, strength_factor=1.0, show_mechanism=False)
    if not first.stable:
        return False
    stage = max(step.stage for step in first.steps) + 1
    return _continue(system, first, factor, stage)[0].stable
