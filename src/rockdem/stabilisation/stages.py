"""Excavation in stages, carrying the spring state from stage to stage.

Stage 0 is the slope under its own weight (loads in steps).  Each further
stage removes blocks, a region or everything above a new profile; the
blocks that stay keep their displacement (translated to their new centroid
if a cut trimmed them), and every interface that survives unchanged (same
blocks, same end points) keeps its committed spring state: plastic slip,
yield, tension failure and the stage of first failure.  The new equilibrium
is then solved under the full load of the remaining blocks, so the joints
that fail at each stage are reported stage by stage.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from ..analysis import analyse, analyse_from
from ..errors import ModelWarning
from ..model import Model
from ..results import CURRENT_NAMES, Analysis
from ..solver import System, build_system
from ..spring_law import SpringState
from . import _edit

__all__ = ["Excavation", "Stage", "StageResult", "carry_state", "excavate_in_stages"]


@dataclass(frozen=True)
class Stage:
    """One excavation stage: blocks, regions (polygons) and/or a new profile."""

    name: str
    blocks: tuple[int, ...] = ()
    regions: tuple = ()
    profile: tuple | None = None


@dataclass(frozen=True, eq=False)
class StageResult:
    """The state after one stage.

    Attributes
    ----------
    number : int
        0 for the slope before excavation.
    analysis : Analysis
        Its equilibrium (or failure mechanism); ``first_failure`` of its
        springs counts load steps first, then stages (see ``stage_step``).
    stage_step : int
        The step number this stage was solved as.
    new_failures : ndarray of int
        Interfaces (positions in ``analysis``) that failed during this stage:
        with a spring point whose first failure is this stage; for an
        unstable stage (no state committed), those of the moving blocks
        sliding or open as equilibrium was lost (the joints giving way,
        failed before or not).
    removed_area : float
        Area removed by this stage.
    """

    number: int
    name: str
    model: Model
    analysis: Analysis
    stage_step: int
    new_failures: np.ndarray = field(repr=False)
    removed_area: float = 0.0

    @property
    def stable(self) -> bool:
        return self.analysis.stable


@dataclass(frozen=True, eq=False)
class Excavation:
    """Result of :func:`excavate_in_stages`: one :class:`StageResult` per stage analysed."""

    stages: tuple[StageResult, ...]
    message: str

    @property
    def stable(self) -> bool:
        return all(s.stable for s in self.stages)

    def failures_by_stage(self) -> list[dict]:
        """One row per failed interface: stage, blocks, kind, state."""
        rows = []
        for s in self.stages:
            r = s.analysis.interfaces
            for i in s.new_failures:
                state = r.state_name[i] if s.stable else r.current_name[i]
                rows.append({"stage": s.number, "stage_name": s.name, "interface": int(i),
                             "block_a": int(r.block_a[i]), "block_b": int(r.block_b[i]),
                             "kind": str(r.kind[i]), "state": str(state)})
        return rows


def _failed_in_stage(a, step: int) -> np.ndarray:
    """Interfaces of ``a`` that failed in the stage solved as ``step``.  (By
    interface keys, the failures carried onto interfaces the stage cut anew
    counted as new, and an unstable stage, whose state is not committed,
    listed only those: "joints failed" named none of the joints that gave way,
    often 0, since they had failed under gravity already.)"""
    faces = a.interfaces
    if a.stable:
        fresh = a.state.first_failure == step
        return np.unique(a.system.springs.interface[fresh]).astype(np.int64)
    giving = faces.current >= CURRENT_NAMES.index("sliding")
    moving = a.unstable  # on the mechanism's blocks (not a contact far from it)
    if moving.any():
        system = a.system
        giving &= moving[system.interfaces.block_a] | moving[system.interfaces.block_b]
    return np.flatnonzero(giving).astype(np.int64)


def _warn_removed(before: Model, after: Model, where: str) -> None:
    """A warning naming the bolts and loads that went with the rock a stage
    removed (or the line loads cut to the rock that is left)."""
    notes = _edit.removal_notes(before, after)
    if notes:
        warnings.warn(f"{where}: {'; '.join(notes)}", ModelWarning, stacklevel=3)


def _keys(system: System) -> dict:
    faces = system.interfaces
    ids = system.blocks.ids
    tol = system.blocks.tolerance
    digits = max(int(-np.floor(np.log10(tol))) + 1, 3)
    out = {}
    for k in range(faces.n_interfaces):
        key = (int(ids[faces.block_a[k]]), int(ids[faces.block_b[k]]),
               *np.round(faces.start[k], digits), *np.round(faces.end[k], digits))
        out[tuple(float(v) for v in key)] = k
    return out


def carry_state(old: System, state: SpringState, new: System) -> SpringState:
    """The committed spring state of ``old`` mapped onto the springs of ``new``.

    Interfaces are matched by their two block ids and end points; one found
    with the opposite orientation takes its points in reverse order and its
    slip with the opposite sign.  Everything else starts fresh.
    """
    m = new.springs.points_per_interface
    if old.springs.points_per_interface != m:
        raise ValueError("both systems need the same spring points per interface")
    fresh = SpringState.initial(new.springs.n_springs)
    slip, yielded = fresh.slip.copy(), fresh.yielded.copy()
    broken, first = fresh.broken.copy(), fresh.first_failure.copy()
    old_keys = _keys(old)
    matched = {}  # new interface -> old interface
    for key, k in _keys(new).items():
        a, b, x0, y0, x1, y1 = key
        sign, j = 1.0, old_keys.get(key)
        if j is None:
            j, sign = old_keys.get((b, a, x1, y1, x0, y0)), -1.0
        if j is None:
            continue
        matched[k] = j
        src = np.arange(j * m, (j + 1) * m)
        if sign < 0:
            src = src[::-1]
        dst = np.arange(k * m, (k + 1) * m)
        slip[dst] = sign * state.slip[src]
        yielded[dst] = state.yielded[src]
        broken[dst] = state.broken[src]
        first[dst] = state.first_failure[src]
    yielded_at, reference = _carry_bolts(old, state, new, matched)
    return SpringState(slip, yielded, broken, first, yielded_at, reference)


def _carry_bolts(old: System, state: SpringState, new: System, matched: dict):
    """The stage at which each bolt crossing of ``new`` first yielded, and the
    displacement it was installed at, from the same bolt's crossing of the
    same interface in ``old`` (-1 and the crossing's own start for a
    crossing the excavation made new).  (Not carried, a bolt that yielded
    under gravity was reported yielding first at the excavation stage.)"""
    if new.bolts is None:
        return None, None
    first = np.full(new.bolts.n, -1)
    reference = new.bolts.initial_reference()
    if old.bolts is None or state.bolt_first_yield is None:
        return first, reference
    # the same Bolt objects (a removal drops some: positions shift); an unnamed
    # bolt that stays is a copy named by its place (bolts_left_in_rock): it
    # lost its history, yielding anew at the stage (review 33)
    position = {id(b): k for k, b in enumerate(new.model.bolts)}
    renumber = [position.get(id(b), -1) for b in old.model.bolts]
    for k, b in enumerate(old.model.bolts):
        if renumber[k] < 0 and not b.name:
            copy = replace(b, name=f"bolt {k + 1}")
            renumber[k] = next((m for m, c in enumerate(new.model.bolts) if c == copy), -1)
    where = {
        (renumber[b], int(i)): c
        for c, (b, i) in enumerate(zip(old.bolts.bolt, old.bolts.interface, strict=True))
    }
    # a crossing of an interface the stage trimmed (its end points moved) is
    # still the same bolt across the same two blocks (found in review: a bolt
    # put in after the loads was installed again at the stage, and its force
    # had to be mobilised anew)
    by_pair: dict = {}
    for (b, i), c in where.items():
        key = (b, _pair(old, i))
        by_pair[key] = None if key in by_pair else c  # (ambiguous: not matched)
    for c, (b, i) in enumerate(zip(new.bolts.bolt, new.bolts.interface, strict=True)):
        j = matched.get(int(i))
        k = where.get((int(b), j)) if j is not None else by_pair.get((int(b), _pair(new, i)))
        if k is None:
            continue
        first[c] = int(state.bolt_first_yield[k])
        if state.bolt_reference is not None and reference is not None:
            reference[c] = state.bolt_reference[k]
    return first, reference


def _pair(system: System, interface: int) -> frozenset:
    """The ids of the two blocks of an interface."""
    faces, ids = system.interfaces, system.blocks.ids
    return frozenset((int(ids[faces.block_a[interface]]), int(ids[faces.block_b[interface]])))


def _carry_q(old: System, disp: np.ndarray, new: System) -> np.ndarray:
    """Displacements of surviving blocks (by id), moved to their new centroids."""
    asm = new.assembly
    q = np.zeros(asm.n_dof)
    ob, nb = old.blocks, new.blocks
    pos = {int(i): k for k, i in enumerate(ob.ids)}
    for k in np.flatnonzero(~nb.fixed):
        j = pos.get(int(nb.ids[k]))
        if j is None:
            continue
        ux, uy, th = disp[j]
        dx, dy = nb.centroid[k] - ob.centroid[j]
        q[asm.dof[k]] = (ux - th * dy, uy + th * dx, th)
    return q


def excavate_in_stages(model: Model, stages: Sequence[Stage], *,
                       carry: bool = True) -> Excavation:
    """Analyse the slope, then each excavation stage in turn.

    Parameters
    ----------
    model : Model
        The slope before excavation.
    stages : sequence of Stage
    carry : bool
        Carry the spring state and displacements forward (False: every
        stage analysed fresh, for comparison).

    Returns
    -------
    Excavation
        Stops after the first unstable stage (later stages are not analysed).
    """
    system = build_system(model)
    first = analyse(system)
    results = [StageResult(0, "before excavation", model, first, len(first.steps),
                           first.failed_interfaces, 0.0)]
    if not first.stable:
        return Excavation(tuple(results), "unstable before excavation")
    prev_sys, prev = system, first
    step = len(first.steps)
    for k, st in enumerate(stages, start=1):
        m = _edit.apply_removal(prev.system.model, st.blocks, st.regions, st.profile)
        _, area = _edit.removed_between(prev.system.model, m)
        _warn_removed(prev.system.model, m, f"stage {k} ({st.name})")
        sys_k = build_system(m)
        step += 1
        if carry:
            state0 = carry_state(prev_sys, prev.state, sys_k)
            q0 = _carry_q(prev_sys, prev.displacement, sys_k)
            if state0.bolts_waiting:  # crossings of bolts put in after the loads, cut anew
                state0 = state0.with_bolts_installed(sys_k.bolts.displacement(q0))
            a = analyse_from(sys_k, state0, q0, stage=step)
            new_failures = _failed_in_stage(a, step)
        else:
            a = analyse(sys_k)
            new_failures = a.failed_interfaces
        results.append(StageResult(k, st.name, m, a, step, new_failures, area))
        if not a.stable:
            return Excavation(tuple(results),
                              f"stage {k} ({st.name}) is unstable; later stages not analysed")
        prev_sys, prev = sys_k, a
    return Excavation(tuple(results), f"all {len(stages)} stages stable")

