"""Building the engine model from a validated file, and mapping the engine's input
errors back to the key path at fault."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..geometry.size import MAX_BLOCKS, memory_for
from ..interfaces import check_held
from .diagnose import (
    _from_engine,
    _warn_coincident_joint_lines,
    _warn_dry_water_table,
    _warn_loose_tolerance,
    _warn_seismic_without_gravity,
    _warn_unit_weights,
    _warn_unused_lines,
)
from .errors import Loc, ModelFileError, _keypath, _line
from .sections import ProfileSpec
from .spec import ModelFile


def _unit_weight(cfg: ModelFile, material: str | None, value: float | None) -> float | None:
    if value is not None:
        return value
    if material is not None:
        return cfg.materials[material].unit_weight
    if len(cfg.materials) == 1:
        return next(iter(cfg.materials.values())).unit_weight
    return None


def _joints(cfg: ModelFile) -> tuple:
    from ..joints import Joint

    names = list(cfg.joints)
    if cfg.default_joint is not None:
        names.remove(cfg.default_joint)
        names.insert(0, cfg.default_joint)
    return tuple(
        Joint(
            normal_stiffness=j.normal_stiffness,
            friction_angle=j.friction_angle,
            shear_stiffness=j.shear_stiffness,
            cohesion=j.cohesion,
            tensile_strength=j.tensile_strength,
            residual_cohesion=j.residual_cohesion,
            residual_friction_angle=j.residual_friction_angle,
            residual_tensile_strength=j.residual_tensile_strength,
            stiffness_ratio=j.stiffness_ratio,
            name=name,
        )
        for name, j in ((n, cfg.joints[n]) for n in names)
    )


def _loads(cfg: ModelFile, names: dict[str, Loc]):
    from ..model import LineLoad, Loads, PointLoad

    points = []
    for i, p in enumerate(cfg.loads.points):
        name = p.name or _keypath(("loads", "points", i))
        names[name] = ("loads", "points", i)
        points.append(PointLoad(p.at[0], p.at[1], p.force[0], p.force[1], name=name))
    for i, s in enumerate(cfg.supports):
        name = s.name or _keypath(("supports", i))
        names[name] = ("supports", i)
        points.append(PointLoad.anchor(s.at[0], s.at[1], s.force, s.angle, name=name))
    lines = []
    for i, ln in enumerate(cfg.loads.lines):
        name = ln.name or _keypath(("loads", "lines", i))
        names[name] = ("loads", "lines", i)
        q_end = None if ln.q_end is None else tuple(ln.q_end)
        lines.append(
            LineLoad(tuple(ln.start), tuple(ln.end), ln.q[0], ln.q[1], name=name, q_end=q_end)
        )
    return Loads(
        gravity=cfg.loads.gravity,
        seismic_h=cfg.loads.seismic_h,
        seismic_v=cfg.loads.seismic_v,
        points=tuple(points),
        lines=tuple(lines),
        water_table=tuple(tuple(p) for p in cfg.loads.water_table),
        water_unit_weight=cfg.loads.water_unit_weight or 0.0,
        pore_pressure_ratio=cfg.loads.pore_pressure_ratio,
    )


def _bolts(cfg: ModelFile, names: dict[str, Loc], own: int):
    """The bolts; ``own``: how many the file lists (a drawing's come after
    them, and their errors go to `geometry.bolt`: they went to a `bolts[0]`
    the file does not have, at line 1)."""
    from ..bolts import Bolt

    bolts = []
    for i, b in enumerate(cfg.bolts):
        name = b.name or _keypath(("bolts", i))
        names[f"bolts {name}"] = ("bolts", i) if i < own else ("geometry", "bolt")
        fields = b.model_dump(exclude={"name", "bond_strength"})
        bond = np.inf if b.bond_strength is None else b.bond_strength
        bolts.append(Bolt(**fields, bond_strength=bond, name=name))
    return tuple(bolts)


def _settings(cfg: ModelFile):
    from ..model import Settings

    a = cfg.analysis
    return Settings(
        quadrature=a.quadrature,
        points_per_interface=a.points_per_interface,
        load_steps=a.load_steps,
        tolerance=a.tolerance,
        max_iterations=a.max_iterations,
        reduce_tensile=a.reduce_tensile,
    )


def _joint_lines(cfg: ModelFile, vertices: np.ndarray, tol: float) -> np.ndarray:
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    centre, size = 0.5 * (lo + hi), float(np.hypot(*(hi - lo))) or 1.0
    segments = []
    for i, line in enumerate(cfg.joint_lines):
        if line.start is not None:
            length = math.dist(line.start, line.end)
            if length <= tol:
                raise InputError(
                    f"joint_lines {i}",
                    f"has zero length (start and end {length:.3g} apart)",
                    "give two different end points, or `point` and `dip` for a whole line",
                )
            segments.append([line.start, line.end])
        else:
            p = np.asarray(line.point, dtype=float)
            d = np.radians(line.dip)
            t = np.array([math.cos(d), -math.sin(d)])
            reach = size + float(np.hypot(*(p - centre)))
            segments.append([p - reach * t, p + reach * t])
    return np.asarray(segments, dtype=float).reshape(-1, 2, 2)


#: Most vertices of one listed block.
MAX_VERTICES = 10_000


def build_model(
    cfg: ModelFile,
    *,
    source: str = "<string>",
    nodes: Any = None,
    max_blocks: int | None = MAX_BLOCKS,
):
    """The :class:`rockdem.Model` a validated file describes.

    Parameters
    ----------
    max_blocks : int or None
        Refuse a model of more blocks than this, before building it (a
        generated slope by its estimated size); None: no limit.

    Raises
    ------
    ModelFileError
        Geometry problems found while building (overlapping or degenerate
        blocks, loads that miss every block, a slope that makes no blocks or
        too many, blocks that nothing holds), and anything the stabilisation
        designs would be refused for, mapped to the key path at fault.
    """
    names: dict[str, Loc] = {}
    ids: dict[int, int] = {}  # block id -> position in `blocks`
    own_lines = len(cfg.joint_lines or ())  # a drawing's traces come after them
    own_bolts = len(cfg.bolts or ())  # and its bolts
    try:
        if cfg.geometry is not None:  # a drawn section: its blocks, as if listed
            from .geometry import with_dxf_blocks

            cfg = with_dxf_blocks(cfg, source, nodes, max_blocks)
        loads = _loads(cfg, names)
        settings = _settings(cfg)
        _warn_loose_tolerance(settings.tolerance, source, nodes)
        joints = _joints(cfg)
        name = cfg.name or Path(source).stem
        if cfg.blocks is not None:
            _check_count(cfg, source, nodes, max_blocks)
            model = _explicit_model(cfg, joints, loads, settings, name, ids)
        else:
            model = _slope_model(cfg, joints, loads, settings, name, max_blocks)
        if cfg.bolts:
            model = model.replace(bolts=_bolts(cfg, names, own_bolts))
        _check_free(model, cfg, source, nodes)
        from ..solver import build_system

        try:
            system = build_system(model)  # interfaces, springs, loads on blocks: every check
        except InputError:
            check_held(model.blocks)  # a singular stiffness: say which blocks nothing holds
            raise
        _warn_unused_lines(system, cfg, own_lines, source, nodes)
        _warn_unit_weights(model, cfg, source, nodes)
        _warn_seismic_without_gravity(model, source, nodes)
        _warn_dry_water_table(system, source, nodes)
        _warn_coincident_joint_lines(model, source)
    except ModelFileError:
        raise
    except InputError as exc:
        raise _from_engine(exc, cfg, ids, names, source, nodes) from None
    _check_stabilisation(model, cfg, source, nodes)
    return model


def _check_count(cfg: ModelFile, source: str, nodes: Any, max_blocks: int | None) -> None:
    assert cfg.blocks is not None
    n = len(cfg.blocks)
    if max_blocks is not None and n > max_blocks:
        raise ModelFileError(
            source,
            "blocks",
            f"{n:,} blocks are more than the limit of {max_blocks:,} "
            f"(about {memory_for(n) / 1e9:.1f} GB of memory)",
            "raise the limit with `rockdem --max-blocks N ...` if the machine has the memory",
            _line(nodes, ("blocks",)),
        )

    for i, block in enumerate(cfg.blocks):
        k = len(block.vertices)
        if k > MAX_VERTICES:
            loc: Loc = ("blocks", i, "vertices")
            raise ModelFileError(
                source,
                _keypath(loc),
                f"{k:,} vertices are more than the limit of {MAX_VERTICES:,} for one block "
                "(every edge is an interface of its own: 100,000 collinear points made 3 "
                "blocks into 43,751 interfaces)",
                "merge collinear points, or draw the block with fewer vertices",
                _line(nodes, loc),
            )


def _check_free(model, cfg: ModelFile, source: str, nodes: Any) -> None:
    if not (~model.blocks.fixed).any():
        loc: Loc = ("slope",) if cfg.slope is not None else ("remove",)
        raise ModelFileError(
            source,
            _keypath(loc),
            "the geometry leaves no free block to analyse",
            "check the profile, the joint sets and the removal regions",
            _line(nodes, loc),
        )


def _check_stabilisation(model, cfg: ModelFile, source: str, nodes: Any) -> None:
    """Try every design of `stabilisation` on the model's geometry (no analysis), so
    that `check` refuses what `stabilise` would: unknown or fixed blocks, regions and
    profiles that remove nothing or leave blocks floating, a support off the rock."""
    from ..stabilisation import _edit

    spec = cfg.stabilisation

    def attempt(loc: Loc, action):
        try:
            return action()
        except ModelFileError:
            raise
        except InputError as exc:
            raise ModelFileError(
                source, _keypath(loc), f"{exc.where}: {exc.problem}", exc.fix, _line(nodes, loc)
            ) from None

    def removal(r):
        return {"blocks": list(r.blocks), "regions": list(r.regions), "profile": r.profile}

    def held(m):
        if not (~m.blocks.fixed).any():
            raise InputError(
                "the design",
                "removes every free block: nothing is left to analyse",
                "remove fewer blocks",
            )
        check_held(m.blocks)  # the analysis of the design would find it singular
        from ..loads import block_loads

        try:  # (found: a stage taking the block a point load acted on failed mid-run)
            block_loads(m.blocks, m.loads)
        except InputError as exc:
            raise InputError(
                exc.where,
                f"{exc.problem} once this rock is removed (the load acted on rock it removes)",
                "move the load onto rock that stays, or take it out of `loads`",
            ) from None
        return m

    for i, trial in enumerate(spec.trials):
        loc: Loc = ("stabilisation", "trials", i, "remove")
        attempt(loc, lambda t=trial: held(_edit.apply_removal(model, **removal(t.remove))))
    current = model
    for i, stage in enumerate(spec.stages):
        loc = ("stabilisation", "stages", i, "remove")

        def staged(s=stage, m=current, i=i):
            try:
                return held(_edit.apply_removal(m, **removal(s.remove)))
            except InputError as exc:
                if i == 0 or "does not overlap" not in exc.problem:
                    raise
                try:  # each stage removes from what the stages before it left
                    _edit.apply_removal(model, **removal(s.remove))
                except InputError:
                    raise exc from None
                # by key and name: the report's stage 0 is the slope before them all
                names = ", ".join(f"`{t.name}`" for t in spec.stages[:i])
                earlier = f"stages[0] ({names})" if i == 1 else f"stages[0:{i}] ({names})"
                raise InputError(
                    exc.where,
                    f"removes only rock that {earlier} already excavated",
                    f"remove rock still there after {earlier}, or drop the stage",
                ) from None

        current = attempt(loc, staged)
    if spec.berm is not None:
        attempt(
            ("stabilisation", "berm"),
            lambda: held(_edit.cut_profile(model, [tuple(p) for p in spec.berm])),
        )
    if spec.support is not None and spec.support.at is not None:
        from ..loads import block_loads
        from ..model import PointLoad

        at = spec.support.at
        probe = PointLoad.anchor(at[0], at[1], 1.0, spec.support.angle, name="support")
        loads = replace(model.loads, points=(probe,), lines=())
        attempt(("stabilisation", "support", "at"), lambda: block_loads(model.blocks, loads))


def _explicit_model(cfg: ModelFile, joints, loads, settings, name: str, positions: dict):
    import shapely

    from ..blocks import Blocks
    from ..geometry._topology import as_region
    from ..model import Model

    assert cfg.blocks is not None
    specs = list(enumerate(cfg.blocks))
    removed = set(cfg.remove.blocks)
    specs = [(i, b) for i, b in specs if (i if b.id is None else b.id) not in removed]
    for k, r in enumerate(cfg.remove.regions):
        # as a generated slope's excavation would: a region is a valid polygon
        # that takes a block away (found by fuzzing: self-crossing, flat and
        # missing regions were taken silently)
        region = as_region(r, f"remove.regions {k}")
        if not any(region.contains(shapely.Polygon(b.vertices).centroid) for _, b in specs):
            raise InputError(
                f"remove.regions {k}",
                "holds the centroid of no listed block, so it removes none",
                "enclose the centroid of every block to remove, or delete the region",
            )
    if cfg.remove.regions and specs:
        regions = shapely.union_all([shapely.Polygon(r) for r in cfg.remove.regions])
        keep = []
        for i, b in specs:
            if not regions.contains(shapely.Polygon(b.vertices).centroid):
                keep.append((i, b))
        specs = keep
    if not specs:
        raise InputError("remove", "removes every block", "remove fewer blocks")
    polygons = [b.vertices for _, b in specs]
    fixed = [b.fixed for _, b in specs]
    gamma = [_unit_weight(cfg, b.material, b.unit_weight) for _, b in specs]
    gamma = [0.0 if g is None else g for g in gamma]
    ids = [i if b.id is None else b.id for i, b in specs]
    positions.update(zip(ids, (i for i, _ in specs), strict=True))
    blocks = Blocks.from_polygons(polygons, fixed=fixed, unit_weight=gamma, ids=ids)
    lines = line_joint = None
    if cfg.joint_lines:
        lines = _joint_lines(cfg, blocks.vertices, blocks.tolerance)
        line_joint = [ln.joint for ln in cfg.joint_lines]
    model = Model(
        blocks,
        joints,
        joint_lines=lines,
        line_joint=line_joint,
        ground=cfg.ground_joint,
        loads=loads,
        settings=settings,
        name=name,
    )
    return model


def _profile(spec: ProfileSpec):
    from ..geometry import Profile

    if spec.points is not None:
        return Profile([tuple(p) for p in spec.points])
    kw: dict[str, Any] = {"bench_width": spec.bench_width, "toe": tuple(spec.toe)}
    for key in ("crest_length", "toe_length", "bench_height"):
        value = getattr(spec, key)
        if value is not None:
            kw[key] = value
    return Profile.simple(spec.height, spec.face_angle, **kw)


def _slope_model(cfg: ModelFile, joints, loads, settings, name: str, max_blocks: int | None):
    try:
        from .. import geometry
    except ImportError as exc:  # pragma: no cover - the geometry module is being written
        raise InputError(
            "slope", f"generated slopes need rockdem.geometry ({exc})", "use explicit `blocks`"
        ) from None
    s = cfg.slope
    assert s is not None
    by_name = {j.name: j for j in joints}
    sets = [
        geometry.JointSet(
            name,
            js.dip,
            js.spacing,
            by_name[js.joint or name],
            origin=tuple(js.origin),
            trace_length=js.trace_length,
            gap=js.gap,
            stagger=js.stagger,
            spacing_sd=js.spacing_sd,
            dip_sd=js.dip_sd,
            seed=js.seed,
        )
        for name, js in s.joint_sets.items()
    ]
    kw: dict[str, Any] = {
        "depth": s.depth,
        "behind": s.behind or None,
        "unit_weight": _unit_weight(cfg, s.material, s.unit_weight),
        "boundary": tuple(s.boundary),
        "min_block_fraction": s.min_block_fraction,
        "slivers": s.slivers,
        "seed": s.seed,
        "max_blocks": max_blocks,
    }
    if s.ground_thickness is not None:
        kw["ground_thickness"] = s.ground_thickness
    if cfg.ground_joint is not None:
        kw["ground_joint"] = by_name[cfg.ground_joint]
    if s.bridge_joint is not None:
        kw["bridge_joint"] = by_name[s.bridge_joint]
    if s.fixed_region is not None:
        kw["fixed_region"] = [tuple(p) for p in s.fixed_region]
    geom = geometry.generate_slope(_profile(s.profile), sets, **kw)
    if cfg.remove.blocks:
        geom = geometry.remove_blocks(geom, list(cfg.remove.blocks))
    for k, region in enumerate(cfg.remove.regions):  # (hostile testing: named `slope`)
        geom = geometry.excavate(geom, [tuple(p) for p in region], where=f"remove.regions {k}")
    if cfg.remove.profile is not None:
        try:
            geom = geometry.cut_to_profile(geom, [tuple(p) for p in cfg.remove.profile])
        except InputError as exc:  # whatever the profile says of itself: at its key
            raise InputError("remove.profile", exc.problem, exc.fix) from None
    return geom.model(loads=loads, settings=settings, name=name)
