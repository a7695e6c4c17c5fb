"""Building the engine model from a validated file, and mapping the engine's input
errors back to the key path at fault."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
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
        lines.append(LineLoad(tuple(ln.start), tuple(ln.end), ln.q[0], ln.q[1], name=name))
    return Loads(
        gravity=cfg.loads.gravity,
        seismic_h=cfg.loads.seismic_h,
        seismic_v=cfg.loads.seismic_v,
        points=tuple(points),
        lines=tuple(lines),
    )


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


def _joint_lines(cfg: ModelFile, vertices: np.ndarray) -> np.ndarray:
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    centre, size = 0.5 * (lo + hi), float(np.hypot(*(hi - lo))) or 1.0
    segments = []
    for line in cfg.joint_lines:
        if line.start is not None:
            segments.append([line.start, line.end])
        else:
            p = np.asarray(line.point, dtype=float)
            d = np.radians(line.dip)
            t = np.array([math.cos(d), -math.sin(d)])
            reach = size + float(np.hypot(*(p - centre)))
            segments.append([p - reach * t, p + reach * t])
    return np.asarray(segments, dtype=float).reshape(-1, 2, 2)


def build_model(cfg: ModelFile, *, source: str = "<string>", nodes: Any = None):
    """The :class:`rockdem.Model` a validated file describes.

    Raises
    ------
    ModelFileError
        Geometry problems found while building (overlapping or degenerate
        blocks, loads that miss every block, a slope that makes no blocks),
        mapped to the key path at fault.
    """
    names: dict[str, Loc] = {}
    ids: dict[int, int] = {}  # block id -> position in `blocks`
    try:
        loads = _loads(cfg, names)
        settings = _settings(cfg)
        joints = _joints(cfg)
        name = cfg.name or Path(source).stem
        if cfg.blocks is not None:
            model = _explicit_model(cfg, joints, loads, settings, name, ids)
        else:
            model = _slope_model(cfg, joints, loads, settings, name)
        _check_free(model, cfg, source, nodes)
        from ..solver import build_system

        build_system(model)  # interfaces, springs, loads on blocks: every input check
    except ModelFileError:
        raise
    except InputError as exc:
        raise _from_engine(exc, cfg, ids, names, source, nodes) from None
    return model


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


def _explicit_model(cfg: ModelFile, joints, loads, settings, name: str, positions: dict):
    import shapely

    from ..blocks import Blocks
    from ..model import Model

    assert cfg.blocks is not None
    specs = list(enumerate(cfg.blocks))
    removed = set(cfg.remove.blocks)
    specs = [(i, b) for i, b in specs if (i if b.id is None else b.id) not in removed]
    if cfg.remove.regions and specs:
        regions = shapely.union_all(
            [shapely.make_valid(shapely.Polygon(r)) for r in cfg.remove.regions]
        )
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
        lines = _joint_lines(cfg, blocks.vertices)
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


def _slope_model(cfg: ModelFile, joints, loads, settings, name: str):
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
    for region in cfg.remove.regions:
        geom = geometry.excavate(geom, [tuple(p) for p in region])
    if cfg.remove.profile is not None:
        geom = geometry.cut_to_profile(geom, [tuple(p) for p in cfg.remove.profile])
    return geom.model(loads=loads, settings=settings, name=name)


_BLOCK = re.compile(r"^blocks? (-?\d+)")


def _from_engine(
    exc: InputError,
    cfg: ModelFile,
    ids: dict[int, int],
    names: dict[str, Loc],
    source: str,
    nodes: Any,
) -> ModelFileError:
    """Map an engine InputError back to the key path of the file."""
    where = exc.where
    loc: Loc = ()
    m = _BLOCK.match(where)
    j = re.match(r"joint '(.+)' (\w+)$", where)
    if j and j.group(1) in cfg.joints:
        loc, label = ("joints", j.group(1), j.group(2)), ""
    elif cfg.blocks is not None and m and int(m.group(1)) in ids:
        loc = ("blocks", ids[int(m.group(1))])
        label = where
    elif where in names:
        loc, label = names[where], ""
    elif cfg.slope is not None:
        loc, label = ("slope",), ("" if where == "slope" else where)
    else:
        label = where
    problem = f"{label} {exc.problem}".strip() if label else exc.problem
    return ModelFileError(source, _keypath(loc), problem, exc.fix, _line(nodes, loc))
