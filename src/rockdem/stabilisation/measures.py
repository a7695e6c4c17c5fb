"""Alternative measures side by side: a berm, a support force, block removal.

The support force is found by search: the smallest anchor force at a given
point and angle with which the staged analysis still finds equilibrium at
the target factor (strengths divided by the target), bisected to a
relative tolerance, then rated by a full strength-reduction search.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..model import Model, PointLoad
from ..results import FactorOfSafety
from ..units import Units
from . import _edit, _progress
from .removal import Stabilisation, describe, mechanism_ids, meets, rate, stabilise, stable_at

__all__ = ["Measure", "MeasureComparison", "SupportSearch", "compare_measures", "support_force"]

#: default direction of a trial anchor: into the slope, 15 degrees below horizontal
DEFAULT_ANGLE = 195.0


@dataclass(frozen=True, eq=False)
class SupportSearch:
    """Result of :func:`support_force`.

    Attributes
    ----------
    force : float or None
        Smallest force found that reaches the target (None: not found up to
        ``largest``).
    at : (x, y)
    angle : float
        Direction of the force on the rock, degrees counter-clockwise from +x.
    bracket : (float, float)
        Largest force found short of the target, smallest found enough.
    evaluations : int
        Staged analyses made by the search.
    fos : FactorOfSafety or None
        Rating with ``force`` applied.
    model : Model or None
        The model with the support added.
    """

    force: float | None
    at: tuple[float, float]
    angle: float
    bracket: tuple[float, float]
    evaluations: int
    fos: FactorOfSafety | None
    model: Model | None


def with_support(model: Model, at, angle: float, force: float, name: str = "trial anchor"):
    """The model with one more support force (a :class:`PointLoad` with ``support=True``)."""
    load = PointLoad.anchor(float(at[0]), float(at[1]), float(force), float(angle), name=name)
    loads = model.loads
    from dataclasses import replace

    return model.replace(loads=replace(loads, points=(*loads.points, load)))


def support_force(
    model: Model,
    target_fos: float,
    *,
    at: Sequence[float] | None = None,
    angle: float = DEFAULT_ANGLE,
    largest: float | None = None,
    rtol: float = 0.02,
    width: float = 0.01,
) -> SupportSearch:
    """Smallest support force at ``at`` and ``angle`` that reaches ``target_fos``.

    Parameters
    ----------
    model : Model
    target_fos : float
    at : (x, y), optional
        Point of application on the face.  Default: the point of the free
        surface of the critical mechanism nearest its centroid.
    angle : float
        Direction of the force on the rock (default 195: pulling into the
        slope, 15 degrees below horizontal, as a down-dipping anchor does).
    largest : float, optional
        Give up above this force (default: twice the weight of the free rock).
    rtol : float
        Relative width of the final force bracket.
    width : float
        Bracket width of the factor-of-safety rating.
    """
    b = model.blocks
    total = float(b.weight[~b.fixed].sum())
    largest = 2.0 * total if largest is None else float(largest)
    automatic = at is None
    if automatic:
        mech = mechanism_ids(rate(model, width=width))
        if not mech:
            raise InputError("support", "no mechanism to support", "the slope has no failure")
        at = _edit.exposed_point(model, mech)
    at = (float(at[0]), float(at[1]))
    from ..loads import block_loads

    try:  # the anchor must push into a free block where it acts
        block_loads(model.blocks, with_support(model, at, angle, 1.0).loads)
    except InputError as exc:
        placed = " (at the point rockdem placed on the mechanism's free surface)"
        raise InputError(  # found by fuzzing: that point's origin was not said
            "stabilisation.support",
            f"the force at angle {angle:g}{placed if automatic else ''} {exc.problem}",
            "give an angle that pushes into the slope (about 195 for a face looking toward "
            "+x: 15 degrees below horizontal), or the support's `at`"
            + (", or leave the support out (`--no-support`)" if automatic else ""),
        ) from None
    count = 0

    def enough(force: float) -> bool:
        nonlocal count
        count += 1
        m = with_support(model, at, angle, force) if force > 0 else model
        _progress.note(f"staged analysis {count} with a force of {force:.4g}")
        return stable_at(m, target_fos)

    if enough(0.0):
        return SupportSearch(0.0, at, angle, (0.0, 0.0), count, rate(model, width=width), model)
    lo, hi = 0.0, min(0.01 * total, largest)  # never a force above `largest`
    while not enough(hi):
        if hi >= largest:
            return SupportSearch(None, at, angle, (hi, np.inf), count, None, None)
        lo, hi = hi, min(2 * hi, largest)
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        if enough(mid):
            hi = mid
        else:
            lo = mid
    final = with_support(model, at, angle, hi)
    return SupportSearch(hi, at, angle, (lo, hi), count, rate(final, width=width), final)


@dataclass(frozen=True, eq=False)
class Measure:
    """One measure in the comparison (a row of the table)."""

    kind: str  # "none", "berm", "support", "removal"
    label: str
    removed_area: float
    support_force: float | None
    fos: FactorOfSafety | None
    reached: bool
    note: str
    model: Model | None

    @property
    def factor(self) -> float | None:
        if self.fos is None:
            return None
        if self.fos.value is not None:
            return float(self.fos.value)
        return float(self.fos.bracket[0]) if self.fos.mode == "no-failure" else None


@dataclass(frozen=True, eq=False)
class MeasureComparison:
    """Result of :func:`compare_measures`: the slope as it is, then each measure."""

    target: float
    measures: tuple[Measure, ...]
    removal: Stabilisation | None
    support: SupportSearch | None

    def rows(self) -> list[dict]:
        """One dict per measure: measure, removed area, support force, FS, reached, note."""
        return [
            {
                "measure": m.label,
                "kind": m.kind,
                "removed_area": m.removed_area,
                "support_force": m.support_force,
                "factor_of_safety": m.factor,
                "fos_text": describe(m.fos) if m.fos is not None else "-",
                "reaches_target": m.reached,
                "note": m.note,
            }
            for m in self.measures
        ]


def compare_measures(
    model: Model,
    target_fos: float = 1.3,
    *,
    berm: Sequence[Sequence[float]] | None = None,
    support_at: Sequence[float] | None = None,
    support_angle: float = DEFAULT_ANGLE,
    support: bool = True,
    support_largest: float | None = None,
    bolting: dict | None = None,
    removal: bool = True,
    max_removal: float = 0.3,
    max_rounds: int = 6,
    width: float = 0.01,
    units: Units | None = None,
) -> MeasureComparison:
    """The slope as it is, a berm, a support force and block removal, side by side.

    Parameters
    ----------
    berm : list of (x, y), optional
        The new ground profile of the berm design (left to right).
    support_at, support_angle, support_largest :
        Where and in which direction the support force acts, and the largest
        force tried (see :func:`support_force`); ``support=False`` skips it.
    bolting : dict, optional
        The bolt and its inclination for a bolt-pattern row
        (:func:`rockdem.stabilisation.bolting.bolt_pattern` keywords).
    removal : bool
        Run :func:`stabilise` for the removal row.
    units : Units, optional
        The model's units (:func:`rockdem.units.parse_units`), named in the notes.
    """
    force_unit = f" {units.force}" if units is not None and units.known else ""
    with _progress.stage("the slope as it is"):
        base = rate(model, width=width)
    rows = [Measure("none", "slope as it is", 0.0, None, base, meets(base, target_fos), "", model)]
    if berm is not None:
        mb = _edit.cut_profile(model, berm)
        with _progress.stage("berm"):
            fb = rate(mb, width=width)
        _, area = _edit.removed_between(model, mb)
        took = "; ".join(_edit.removal_notes(model, mb))  # the loads and bolts on the cut rock
        rows.append(
            Measure("berm", "berm (new profile)", area, None, fb, meets(fb, target_fos), took, mb)
        )
    search = None
    if support and support_at is None and not mechanism_ids(base):
        support = False  # nothing fails: there is no mechanism to hold
        note = f"none sized: no failure mechanism up to F = {base.bracket[0]:.3g}"
        held = meets(base, target_fos)
        rows.append(Measure("support", "support force", 0.0, None, None, held, note, None))
    if support:
        with _progress.stage("support force"):
            search = support_force(
                model,
                target_fos,
                at=support_at,
                angle=support_angle,
                largest=support_largest,
                width=width,
            )
        at = f"({search.at[0]:.2f}, {search.at[1]:.2f})"
        if search.force is None:
            why = (
                "twice the free blocks' weight, as far as the search goes: a force there "
                "does not hold the mechanism; another point or angle may"
                if support_largest is None
                else "the largest force allowed (support.largest)"  # the user's cap, fuzzing
            )
            note = (
                f"at {at}, angle {search.angle:g}: not reached up to "
                f"{search.bracket[0]:.3g}{force_unit} ({why})"
            )
            rows.append(Measure("support", "support force", 0.0, None, None, False, note, None))
        else:
            lo, hi = search.bracket
            note = (
                f"at {at}, angle {search.angle:g}; force bracket {lo:.3g}-{hi:.3g}{force_unit}"
                if hi > 0  # (none needed: "force bracket 0-0 kN", hostile round 5)
                else f"none needed: the slope meets the target without it (at {at})"
            )
            rows.append(
                Measure(
                    "support",
                    "support force",
                    0.0,
                    search.force,
                    search.fos,
                    True,
                    note,
                    search.model,
                )
            )
    if bolting is not None:
        rows.append(_bolt_row(model, target_fos, bolting, width, force_unit))
    stab = None
    if removal:
        with _progress.stage("block removal"):
            stab = stabilise(
                model,
                target_fos,
                max_rounds=max_rounds,
                max_removal=max_removal,
                width=width,
                units=units,
            )
        f = stab.final
        note = stab.message if stab.reached else f"{stab.message}; needs {stab.needs}"
        rows.append(
            Measure(
                "removal",
                f"block removal ({len(f.removed_blocks)} blocks)",
                f.removed_area,
                None,
                f.fos,
                stab.reached,
                note,
                f.model,
            )
        )
    return MeasureComparison(target_fos, tuple(rows), stab, search)


def _bolt_row(model, target_fos, bolting: dict, width: float, force_unit: str) -> Measure:
    """The bolt-pattern row: rows on the mechanism's face at the widest spacing
    that reaches the target (:func:`rockdem.stabilisation.bolting.bolt_pattern`)."""
    from .bolting import bolt_pattern

    label = "bolt pattern"
    with _progress.stage(label):
        try:
            p = bolt_pattern(model, target_fos, width=width, **bolting)
        except InputError as exc:  # the whole error: the key and the fix were dropped
            return Measure("bolts", label, 0.0, None, None, False, str(exc), None)
    cap = f"{bolting['capacity']:.3g}{force_unit}"
    if p.spacing is None:
        # (found by hostile testing: with row_spacing given, which lays out its
        # own rows, this still read "up to 16 rows")
        rows = (
            "up to 16 rows of bolts"
            if bolting.get("row_spacing") is None
            else f"rows of bolts {bolting['row_spacing']:.3g} apart on the face"
        )
        note = (
            f"not reached with {rows} ({cap} capacity) 0.25 apart along "
            "the slope (longer or stronger bolts, or another measure)"
        )
        return Measure("bolts", label, 0.0, None, None, False, note, None)
    lengths = sorted(b.length for b in p.bolts)
    widest = " (the widest tried)" if not np.isfinite(p.bracket[0]) else ""
    note = (
        f"{len(p.bolts)} row{'s' if len(p.bolts) != 1 else ''} of bolts ({cap} capacity), "
        f"one every {p.spacing:.3g} along "
        f"the slope{widest}, {lengths[0]:.3g} to {lengths[-1]:.3g} long: "
        f"{p.bolts_per_metre:.3g} bolts per unit length of slope"
    )
    return Measure("bolts", label, 0.0, None, p.fos, meets(p.fos, target_fos), note, p.model)
