"""The rows of the result tables (blocks, interfaces, springs, bolts) and the
summaries of an analysis and a factor-of-safety search, as plain data
(:mod:`rockdem.output` writes them to CSV and ``result.json``).

Sign conventions: normal forces and stresses are compression-positive.
Current state and history are separate columns.  ``current_state`` is the
state now (of most of the interface's length; ``open_fraction`` and
``sliding_fraction`` give the shares): ``elastic`` (never failed, holding),
``closed-failed-earlier`` (failed at some time, now closed and holding),
``sliding`` (at its shear strength now) or ``open`` (at or beyond its
tensile strength now).  ``state`` is the history: the worst failure flag the
interface has ever had (``elastic`` = never failed, ``shear`` = yielded at
some time, ``tension`` = failed in tension at some time), and
``failed_fraction`` the share of its length that has ever failed;
``first_failure`` is the load step (or strength-reduction stage) at which the
interface first failed, -1 if never; ``local_fos`` is the full shear strength
over the shear stress (``inf`` where unstressed).  In ``springs.csv``,
``capacity`` is the full shear strength (F = 1) and ``strength_at_factor``
the strength at the factor the stresses were found at.  ``failure_mode`` (in
``blocks.csv``) is the block's mode at the limit (:mod:`rockdem.modes`);
``failure_mode_read_from`` says whether the last equilibrium decided it
(``limit``) or the run beyond the limit did (``motion``).
``bolts.csv`` has a row per joint a bolt crosses (:mod:`rockdem.bolts`):
``extension`` and ``offset`` of the bolt across the joint, ``axial_force``
(tension positive) and ``shear_force`` per bolt, ``axial_capacity`` there
(steel or bond beyond the joint), ``utilisation`` (axial force / capacity),
``yielded`` and ``first_yield`` (the load step or strength-reduction stage
at which it first reached its capacity, -1 never); only its heading
without bolts.
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np

from .loads import joint_water, pore_pressure, water_loads
from .mechanism import slip_polylines
from .modes import MODES, boundary_contacts, failure_modes
from .results import CURRENT_NAMES
from .spring_law import STATE_NAMES
from .trust import (
    cohesion_lost_in_shear,
    cohesion_lost_in_tension,
    toppling_caution,
    trust_statements,
)

__all__ = [
    "analysis_summary",
    "analysis_tables",
    "bolt_summary",
    "fos_summary",
    "jsonable",
    "mechanism_summary",
    "state_counts",
]


def jsonable(value: Any) -> Any:
    """Plain JSON data from numpy scalars and arrays (and paths); inf and nan become None."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, np.bool_ | bool):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating | float):
        v = float(value)
        return v if math.isfinite(v) else None
    if isinstance(value, np.str_):
        return str(value)
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    return value


def analysis_tables(analysis, failed=None) -> dict[str, list[dict[str, Any]]]:
    """Rows of the three tables of an :class:`~rockdem.Analysis`.

    ``failed``: for a factor-of-safety search, its failed end; the stresses
    and joint states are those of ``analysis`` (the last equilibrium), the
    failure columns (``unstable``, ``mechanism_*``, ``failure_mode``, the
    interfaces' ``slip_surface``) those of the mechanism at the limit.  (They
    once mixed the two: every ``unstable`` and ``slip_surface`` false beside
    ``failure_mode`` "slides"; found in the review of the outputs.)

    Returns
    -------
    dict
        ``{"blocks": [...], "interfaces": [...], "springs": [...]}``, each a
        list of rows (dicts with the same keys, in column order).
    """
    system = analysis.system
    b = system.blocks
    limit = failed if failed is not None else analysis
    d, mech = analysis.displacement, limit.mechanism
    modes = failure_modes(limit)
    mode = np.where(b.fixed, "fixed", modes.name)
    moving = modes.code > 0
    read = np.where(moving & modes.decided, "limit", np.where(moving, "motion", ""))
    water = water_loads(b, system.interfaces, joint_water(b, system.model.loads))
    blocks = [
        {
            "id": int(b.ids[i]),
            "fixed": bool(b.fixed[i]),
            "area": float(b.area[i]),
            "unit_weight": float(b.unit_weight[i]),
            "weight": float(b.weight[i]),
            "water_fx": float(water[i, 0]),
            "water_fy": float(water[i, 1]),
            "centroid_x": float(b.centroid[i, 0]),
            "centroid_y": float(b.centroid[i, 1]),
            "ux": float(d[i, 0]),
            "uy": float(d[i, 1]),
            "rotation": float(d[i, 2]),
            "unstable": bool(limit.unstable[i]),
            "mechanism_x": float(mech[i, 0]),
            "mechanism_y": float(mech[i, 1]),
            "mechanism_rotation": float(mech[i, 2]),
            "failure_mode": str(mode[i]),
            "failure_mode_read_from": str(read[i]),
        }
        for i in range(b.n_blocks)
    ]
    r = analysis.interfaces
    faces = system.interfaces
    normal_stress, shear_stress, state_name = r.normal_stress, r.shear_stress, r.state_name
    now_name = r.current_name
    slip = np.zeros(r.n_interfaces, dtype=bool)
    slip[limit.slip_surface] = True
    interfaces = [
        {
            "interface": i,
            "block_a": int(r.block_a[i]),
            "block_b": int(r.block_b[i]),
            "kind": str(r.kind[i]),
            "start_x": float(faces.start[i, 0]),
            "start_y": float(faces.start[i, 1]),
            "end_x": float(faces.end[i, 0]),
            "end_y": float(faces.end[i, 1]),
            "length": float(r.length[i]),
            "normal_force": float(r.normal_force[i]),
            "shear_force": float(r.shear_force[i]),
            "normal_stress": float(normal_stress[i]),
            "shear_stress": float(shear_stress[i]),
            "state": str(state_name[i]),
            "failed_fraction": float(r.failed_fraction[i]),
            "current_state": str(now_name[i]),
            "open_fraction": float(r.open_fraction[i]),
            "sliding_fraction": float(r.sliding_fraction[i]),
            "local_fos": float(r.local_fos[i]),
            "first_failure": int(r.first_failure[i]),
            "slip_surface": bool(slip[i]),
        }
        for i in range(r.n_interfaces)
    ]
    s = analysis.springs
    point_xy = system.springs.point
    fos, s_state, s_now = s.local_fos, s.state_name, s.current_name
    water = pore_pressure(joint_water(system.blocks, system.model.loads), point_xy)
    springs = [
        {
            "interface": int(s.interface[k]),
            "point": k % system.springs.points_per_interface,
            "x": float(point_xy[k, 0]),
            "y": float(point_xy[k, 1]),
            "sigma": float(s.sigma[k]),
            "tau": float(s.tau[k]),
            "pore_pressure": float(water[k]),
            "capacity": float(s.capacity[k]),
            "strength_at_factor": float(s.strength[k]),
            "state": str(s_state[k]),
            "current_state": str(s_now[k]),
            "first_failure": int(s.first_failure[k]),
            "local_fos": float(fos[k]),
        }
        for k in range(len(s.sigma))
    ]
    return {
        "blocks": blocks,
        "interfaces": interfaces,
        "springs": springs,
        "bolts": bolt_rows(analysis),
    }


def bolt_rows(analysis) -> list[dict[str, Any]]:
    """One row per joint a bolt crosses: whether it is in the slope, force
    per bolt, capacity there, utilisation and whether it yielded (empty
    without bolts)."""
    r = analysis.bolts
    if r is None:
        return []
    use = r.utilisation
    # an after_loads bolt that never went in read force 0 with nothing to say
    # why (hostile round 5); a table built without it is of bolts all in
    installed = getattr(r, "installed", None)
    return [
        {
            "bolt": str(r.name[k]),
            "installed": bool(installed is None or installed[k]),
            "interface": int(r.interface[k]),
            "x": float(r.point[k, 0]),
            "y": float(r.point[k, 1]),
            "depth": float(r.depth[k]),
            "extension": float(r.extension[k]),
            "offset": float(r.offset[k]),
            "axial_force": float(r.axial_force[k]),
            "shear_force": float(r.shear_force[k]),
            "axial_capacity": float(r.capacity[k]),
            "utilisation": float(use[k]),
            "yielded": bool(r.yielded[k]),
            "first_yield": int(r.first_yield[k]),
        }
        for k in range(r.n)
    ]


def _failed(analysis) -> list[dict[str, Any]]:
    r = analysis.interfaces
    names, now = r.state_name, r.current_name
    return [
        {
            "interface": int(i),
            "block_a": int(r.block_a[i]),
            "block_b": int(r.block_b[i]),
            "kind": str(r.kind[i]),
            "state": str(names[i]),
            "failed_fraction": float(r.failed_fraction[i]),
            "current_state": str(now[i]),
            "first_failure": int(r.first_failure[i]),
        }
        for i in analysis.failed_interfaces
    ]


def bolt_summary(analysis) -> list[dict[str, Any]]:
    """Per bolt: the joints it crosses, its axial force of largest magnitude
    (per bolt, signed: tension positive; a bolt's largest tension would hide
    a compression at capacity at another crossing), the largest utilisation,
    how many of its crossings have yielded, the stage of its first yield
    (None: never) and whether it is installed (an after_loads bolt of a slope
    that never stood under its loads is not: it read "no axial force")."""
    if analysis is None or analysis.bolts is None:
        return []
    r = analysis.bolts
    installed = getattr(r, "installed", None)
    out = []
    for name in dict.fromkeys(r.name):
        k = r.name == name
        first = r.first_yield[k][r.first_yield[k] >= 0]
        axial = r.axial_force[k]
        out.append(
            {
                "bolt": str(name),
                "crossings": int(k.sum()),
                "max_axial_force": float(axial[np.argmax(np.abs(axial))]),
                "max_utilisation": float(np.max(r.utilisation[k])),
                "yielded_crossings": int(r.yielded[k].sum()),
                "first_yield": int(first.min()) if first.size else None,
                "installed": bool(installed is None or installed[k].all()),
            }
        )
    return out


def state_counts(analysis) -> dict[str, dict[str, int]]:
    """Interfaces by current state and by failure history, kept apart.

    ``now``: elastic, closed-failed-earlier, sliding, open (each interface by
    the state of most of its length); ``history``: elastic (never failed),
    shear (yielded at some time), tension (failed in tension at some time).
    """
    r = analysis.interfaces
    now = np.bincount(r.current, minlength=len(CURRENT_NAMES))
    ever = np.bincount(r.state, minlength=len(STATE_NAMES))
    return {
        "now": {name: int(n) for name, n in zip(CURRENT_NAMES, now, strict=True)},
        "history": {name: int(n) for name, n in zip(STATE_NAMES, ever, strict=True)},
    }


def mechanism_summary(analysis) -> dict[str, Any]:
    """What the mechanism does: ``failure_modes`` (ids of the moving blocks by
    mode), ``failure_modes_from_motion`` (those whose mode the last
    equilibrium did not decide, read from the run beyond the limit, chaotic
    in its detail: see :class:`~rockdem.modes.BlockModes`), ``carried_blocks``
    (of those, the ones whose base held on moving blocks: they ride on them),
    ``boundary_contacts`` (where it touches a fixed side of the model),
    ``warnings`` (one sentence each) and ``slip_polylines`` (the slip surface
    as ordered polylines with the stresses of each segment); all empty for a
    stable analysis."""
    if analysis is None or analysis.stable:
        return {
            "failure_modes": {},
            "failure_modes_from_motion": [],
            "carried_blocks": [],
            "boundary_contacts": [],
            "warnings": [],
            "slip_polylines": [],
        }
    modes = failure_modes(analysis)
    by_mode = {m: [int(i) for i in modes.blocks(m)] for m in MODES if m != "stable"}
    contacts = boundary_contacts(analysis)
    return {
        "failure_modes": {m: ids for m, ids in by_mode.items() if ids},
        "failure_modes_from_motion": [int(i) for i in modes.ids[(modes.code > 0) & ~modes.decided]],
        "carried_blocks": [int(i) for i in modes.ids[modes.carried]],
        "boundary_contacts": [
            {
                "side": c.side,
                "at": c.at,
                "span": list(c.span),
                "blocks": list(c.blocks),
                "interfaces": [int(i) for i in c.interfaces],
            }
            for c in contacts
        ],
        "warnings": [c.message for c in contacts],
        "slip_polylines": slip_polylines(analysis),
    }


def bond_lost(analysis) -> list[str]:
    """The sentences saying that ``analysis`` depends on the number of spring
    points because points lost their bond (in tension or, brittle, in shear):
    on the terminal too, not only in the trust list (two wedges with a
    cohesive joint between them read 1.605 / 1.595 / 1.581 with 2 / 3 / 5
    points, unsaid; found by the literature cross-check, round 5)."""
    return [*cohesion_lost_in_tension(analysis), *cohesion_lost_in_shear(analysis)]


def analysis_summary(analysis) -> dict[str, Any]:
    """The verdict of a staged analysis as plain data.

    Keys: ``stable``, ``verdict``, ``load_factor``, ``strength_factor``,
    ``unstable_blocks`` (ids), ``failed_interfaces`` (the history: every
    interface that has failed at some time, with the blocks, kind, state,
    current state and first failure), ``interface_states`` (counts by current
    state and by history, see :func:`state_counts`), ``failure_modes``,
    ``boundary_contacts`` and ``warnings`` (:func:`mechanism_summary`),
    ``slip_surface`` (interface numbers), ``bolt_summary`` (:func:`bolt_summary`),
    ``steps`` and ``evidence``.
    """
    mechanism = mechanism_summary(analysis)
    mechanism["warnings"] = [*bond_lost(analysis), *mechanism["warnings"]]
    return jsonable(
        {
            "stable": analysis.stable,
            "verdict": analysis.verdict,
            "load_factor": analysis.load_factor,
            "strength_factor": analysis.strength_factor,
            "unstable_blocks": [int(i) for i in analysis.unstable_blocks],
            "failed_interfaces": _failed(analysis),
            "interface_states": state_counts(analysis),
            **mechanism,
            "slip_surface": [int(i) for i in analysis.slip_surface],
            "bolt_summary": bolt_summary(analysis),
            "steps": [
                {
                    "stage": s.stage,
                    "load_factor": s.load_factor,
                    "strength_factor": s.strength_factor,
                    "converged": s.converged,
                    "failed_springs": s.n_failed_springs,
                    "evidence": str(s.evidence),
                    "proof": s.evidence.proof,
                }
                for s in analysis.steps
            ],
            "evidence": str(analysis.evidence),
            "proof": analysis.evidence.proof,
        }
    )


def fos_summary(fos) -> dict[str, Any]:
    """A :class:`~rockdem.FactorOfSafety` as plain data.

    ``factor_of_safety`` is None when strength does not control the
    mechanism; an open upper end of ``bracket`` is None (infinity).
    ``mechanism_blocks`` are the blocks moving at the unstable end (the strength
    factor of that state: ``mechanism_factor``), with their
    ``failure_modes``, ``boundary_contacts`` and ``warnings``
    (:func:`mechanism_summary`); ``bolts_at_limit``: the bolts in the last
    equilibrium below the limit (:func:`bolt_summary`).
    """
    failed, base = fos.failed_analysis, fos.stable_analysis
    shown = base if base is not None else failed  # no stable trial: the mechanism's
    mechanism = mechanism_summary(failed)
    lost = bond_lost(base) if base is not None and fos.value is not None else []
    mechanism["warnings"] = [*toppling_caution(fos), *lost, *mechanism["warnings"]]
    return jsonable(
        {
            "factor_of_safety": fos.value,
            "bracket": list(fos.bracket),
            "mode": fos.mode,
            "proof": fos.proof,
            "certified_upper_bound": fos.certified_upper_bound,
            "confirmed_upper_bound": fos.confirmed_upper_bound,
            "relaxation": None if failed is None else failed.evidence.relaxation,
            "trust": [] if shown is None else trust_statements(shown, fos),
            "definition": fos.definition,
            "mechanism_blocks": [] if failed is None else [int(i) for i in failed.unstable_blocks],
            "mechanism_factor": None if failed is None else failed.strength_factor,
            "bolts_at_limit": bolt_summary(base),
            **mechanism,
            "trials": [
                {
                    "factor": t.factor,
                    "stable": t.stable,
                    "evidence": str(t.evidence),
                    "proof": t.evidence.proof,
                }
                for t in fos.trials
            ],
        }
    )
