"""Editing an engine model for stabilisation trials (no file, no generator needed).

Removal by block ids works on any model; excavation by a region or a new
profile goes through :mod:`rockdem.geometry` (blocks are trimmed along the
cut and keep their ids), which accepts explicit-block models too.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

import numpy as np
import shapely
from shapely.ops import nearest_points

from ..bolt_placement import bolts_left_in_rock
from ..errors import InputError
from ..loads import check_water_table, loads_left_on_rock
from ..model import Model


def _geometry(model: Model):
    from ..geometry import SlopeGeometry

    b = model.blocks
    free = ~b.fixed
    lines = model.joint_lines if model.joint_lines is not None else np.zeros((0, 2, 2))
    line_joint = np.asarray(model.line_joint if model.line_joint is not None else [], dtype=int)
    return SlopeGeometry(
        b,
        tuple(model.joints),
        np.asarray(lines, dtype=float).reshape(-1, 2, 2),
        line_joint,
        model.ground,
        shapely.union_all(b.polygons()[free]),
        typical_area=float(np.median(b.area[free])) if free.any() else float("nan"),
    )


def _back(model: Model, geom) -> Model:
    """The edited geometry as a model with ``model``'s settings and name, and
    its loads and bolts as far as they are left on the rock (see
    :func:`rockdem.loads.loads_left_on_rock`, :func:`rockdem.bolt_placement.bolts_left_in_rock`)."""
    out = geom.model(settings=model.settings, name=model.name)
    loads, _ = loads_left_on_rock(out.blocks, model.loads)
    out = out.replace(loads=loads)
    try:  # (found by hostile testing: a stage or a removal round digging below the
        # water table passed `check`, then stopped stabilise naming no file or key)
        check_water_table(out.blocks, geom.interfaces(), loads)
    except InputError as exc:
        if exc.where != "loads water_table":  # the unit-weight check: not a dig (review 33)
            raise InputError(
                exc.where.replace(" ", ".", 1),
                f"{exc.problem}, once this rock is removed",
                exc.fix,
            ) from None
        raise InputError(
            "loads.water_table",
            f"{exc.problem} once this rock is removed (it digs below the water table)",
            "remove less, or lower the water table to the new ground (a drained excavation)",
        ) from None
    if not model.bolts:
        return out
    kept, _ = bolts_left_in_rock(model.bolts, out.blocks, geom.interfaces())
    return out.replace(bolts=kept)


def removal_notes(before: Model, after: Model) -> tuple[str, ...]:
    """What a removal took with the rock besides blocks: the bolts (their
    head or every joint they tied) and the loads on it (see :func:`_back`)."""
    left = Counter(b.name for b in after.bolts)  # the bolts left are named (bolts_left_in_rock)
    gone = []
    for i, b in enumerate(before.bolts):
        name = b.name or f"bolt {i + 1}"
        if left[name] > 0:
            left[name] -= 1
        else:
            gone.append(name)
    notes = [f"{name} removed with its rock (its head or every joint it tied)" for name in gone]
    _, on_loads = loads_left_on_rock(after.blocks, before.loads)
    return (*notes, *on_loads)


def remove_ids(model: Model, ids: Sequence[int]) -> Model:
    """The model without the free blocks of the given ids (unknown ids are errors)."""
    ids = np.atleast_1d(np.asarray(ids, dtype=np.int64))
    if ids.size == 0:
        return model
    from ..geometry import remove_blocks

    return _back(model, remove_blocks(_geometry(model), ids))


def cut_region(model: Model, region, where: str = "excavation region") -> Model:
    """The model with everything inside ``region`` (polygon vertices) removed."""
    from ..geometry import excavate

    return _back(model, excavate(_geometry(model), region, where=where))


def cut_profile(model: Model, profile) -> Model:
    """The model cut down to a new ground profile (a berm, a bench)."""
    from ..geometry import cut_to_profile

    return _back(model, cut_to_profile(_geometry(model), profile))


def apply_removal(model: Model, blocks=(), regions=(), profile=None) -> Model:
    """Blocks, then regions, then a profile, as the model file's ``remove`` does."""
    if not len(blocks) and not len(regions) and profile is None:
        raise InputError("removal", "removes nothing", "give blocks, regions or a profile")
    out = remove_ids(model, list(blocks)) if len(blocks) else model
    for k, region in enumerate(regions):
        out = cut_region(out, [tuple(p) for p in region], where=f"region {k}")
    if profile is not None:
        out = cut_profile(out, [tuple(p) for p in profile])
    return out


def free_area(model: Model) -> float:
    """Total area of the free blocks (the rock that could be removed)."""
    b = model.blocks
    return float(b.area[~b.fixed].sum())


def removed_between(before: Model, after: Model) -> tuple[tuple[int, ...], float]:
    """Ids of the free blocks gone (or trimmed) and the area removed."""
    b0, b1 = before.blocks, after.blocks
    gone = np.setdiff1d(b0.ids[~b0.fixed], b1.ids[~b1.fixed])
    common = np.intersect1d(b0.ids[~b0.fixed], b1.ids[~b1.fixed])
    a0 = b0.area[b0.index_of(common)] if common.size else np.zeros(0)
    a1 = b1.area[b1.index_of(common)] if common.size else np.zeros(0)
    trimmed = common[a1 < a0 * (1 - 1e-9)]
    ids = tuple(int(i) for i in np.union1d(gone, trimmed))
    return ids, max(free_area(before) - free_area(after), 0.0)


def exposed_point(model: Model, ids: Sequence[int]) -> tuple[float, float]:
    """A point of the free surface on the given blocks, nearest their centroid.

    Used to place a trial support on the moving mass when none is given.
    """
    b = model.blocks
    idx = b.index_of(np.atleast_1d(ids))
    polys = b.polygons()
    mass = shapely.union_all(polys[idx])
    # the mass's boundary away from every other block (the union of all the
    # blocks need not be one polygon: contacts that meet only to round-off)
    others = np.setdiff1d(np.arange(b.n_blocks), idx)
    touching = shapely.buffer(shapely.union_all(polys[others]), 2 * b.tolerance)
    exposed = shapely.difference(mass.boundary, touching)
    if exposed.is_empty or exposed.length == 0:
        raise InputError(
            "support",
            "the moving blocks have no free surface",
            "give the support position (at) explicitly",
        )
    centre = mass.centroid
    p = nearest_points(exposed, centre)[0]
    return float(p.x), float(p.y)
