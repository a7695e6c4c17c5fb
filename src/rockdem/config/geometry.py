"""The ``geometry`` section: a slope section drawn in CAD (DXF), and how a model file
that gives it becomes explicit blocks and joint lines."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

from .errors import ModelFileError, _keypath, _line
from .values import (
    Magnitude,
    OptionalMagnitude,
    OptionalStiffness,
    Positive,
    Stiffness,
    UnitWeight,
    _Section,
)


class DxfLayersSpec(_Section):
    """The layers of the drawing that hold each part of the section (names compare
    without regard to case)."""

    outline: str | None = None
    """Layer of the section outline, one closed polyline (default `OUTLINE`)."""
    fixed: str | None = None
    """Layer of the fixed ground, closed polylines (default `FIXED`)."""
    water: str | None = None
    """Layer of the water table, one polyline (default `WATER`, if the drawing has it)."""
    bolts: str | None = None
    """Layer of the bolts, lines from the head on the face into the rock (default
    `BOLTS`, if the drawing has it)."""
    joints: dict[str, str] | None = None
    """Joint trace layers and the joint (name in `joints`) each takes, `{LAYER: joint}`
    (default: every layer `JOINT_<name>` takes the joint `<name>`)."""


class DxfBoltSpec(_Section):
    """Properties of the passive bolts drawn on the bolts layer (each line gives a
    bolt's head, direction and length; see `bolts[i]` for the meaning)."""

    capacity: Magnitude
    """Axial yield force of the steel, one bolt."""
    axial_stiffness: Stiffness
    """Axial force per unit opening of a crossed joint along the bolt, one bolt."""
    shear_stiffness: OptionalStiffness = 0.0
    """Dowel stiffness across a joint, one bolt (0: none)."""
    shear_capacity: OptionalMagnitude = 0.0
    """Dowel (shear) capacity, one bolt."""
    bond_strength: Positive | None = None
    """Grout bond force per unit length (null: the steel yields first)."""
    pretension: OptionalMagnitude = 0.0
    """Axial force locked in at installation."""
    spacing: Positive = 1.0
    """Out-of-plane spacing of the bolt row."""
    kind: Literal["bolt", "cable"] = "bolt"
    """`cable`: no compression and no dowel action."""
    installed: Literal["before_loads", "after_loads"] = "before_loads"
    """When the drawn bolts go in: with the loads, or into the slope standing
    under them (see `bolts[i]`)."""


class GeometrySpec(_Section):
    """A section drawn in CAD: the outline, joint traces, fixed ground, water table
    and bolts read from the layers of a DXF file and cut into explicit blocks."""

    dxf: str
    """Path of the DXF file (relative to the model file)."""
    layers: DxfLayersSpec = DxfLayersSpec()
    """Layer names, when they differ from the defaults (`OUTLINE`, `FIXED`,
    `JOINT_<name>`, `WATER`, `BOLTS`)."""
    material: str | None = None
    """Material of the free blocks (default: the only one in `materials`)."""
    unit_weight: UnitWeight | None = None
    """Unit weight of the free blocks (instead of `material`)."""
    bolt: DxfBoltSpec | None = None
    """Properties of the passive bolts drawn on the bolts layer (give this or
    `bolt_force` when the drawing has bolts)."""
    bolt_force: Magnitude | None = None
    """Instead of `bolt`: the bolts drawn are active anchors, each this force at its
    head pulling along the line (`supports`)."""


def dxf_path(cfg: Any, source: str) -> Path:
    """The drawing's path: as given if absolute, else beside the model file."""
    path = Path(cfg.geometry.dxf).expanduser()
    if path.is_absolute() or source.startswith("<"):
        return path
    return Path(source).parent / path


def with_dxf_blocks(cfg: Any, source: str, nodes: Any, max_blocks: int | None) -> Any:
    """A copy of ``cfg`` whose ``blocks`` and ``joint_lines`` are cut from its drawing
    (the file's own joint lines first), with the water table and bolts as loads.

    Raises
    ------
    ModelFileError
        Anything wrong with the drawing, at ``geometry`` (or the layer key at fault).
    """
    from ..exchange.dxf_cut import cut_section
    from ..exchange.dxf_in import DxfError, read_section
    from ..units import length_of
    from .sections import BlockSpec, BoltSpec, JointLineSpec, SupportSpec

    g = cfg.geometry

    def fail(key: str, problem: str, fix: str) -> ModelFileError:
        loc = ("geometry", *key.split(".")) if key else ("geometry", "dxf")
        return ModelFileError(source, _keypath(loc), problem, fix, _line(nodes, loc))

    if not str(g.dxf).strip():  # found by fuzzing: '' was "is a folder" (the model's own)
        raise fail("dxf", "is empty", "give the drawing's file name, for example section.dxf")
    path = dxf_path(cfg, source)
    layers = g.layers.model_dump(exclude_none=True)
    try:
        section = read_section(
            path,
            layers=layers,
            joints=list(cfg.joints),
            length_unit=length_of(cfg.units),
        )
        cut = cut_section(section, max_blocks=max_blocks)
    except DxfError as exc:
        raise fail(exc.key, f"{exc.where}: {exc.problem}", exc.fix) from None
    except ModelFileError as exc:  # the file itself: missing, a folder, too large
        raise fail("", f"{exc.where}: {exc.problem}", exc.fix) from None
    gamma = g.unit_weight
    blocks = [
        BlockSpec(
            vertices=[tuple(p) for p in poly.tolist()],
            fixed=bool(fixed),
            material=None if fixed or gamma is not None else g.material,
            unit_weight=None if fixed else gamma,
        )
        for poly, fixed in zip(cut.polygons, cut.fixed, strict=True)
    ]
    ids = set(range(len(blocks)))
    for k, bid in enumerate(cfg.remove.blocks):
        if bid not in ids:
            loc = ("remove", "blocks", k)
            raise ModelFileError(
                source,
                _keypath(loc),
                f"no block has id {bid}",
                f"the drawing makes blocks 0 to {len(blocks) - 1} (see `rockdem check`)",
                _line(nodes, loc),
            )
    lines = list(cfg.joint_lines) + [
        JointLineSpec(joint=joint, start=tuple(a.tolist()), end=tuple(b.tolist()))
        for joint, a, b in cut.lines
    ]
    loads = cfg.loads
    if section.water_table is not None:
        if cfg.loads.water_table:
            raise fail(
                "layers.water",
                f"the drawing has a water table (layer {section.layers['water']}) and so has "
                "loads.water_table",
                "keep one of them",
            )
        if cfg.loads.water_unit_weight is None:
            raise fail(
                "layers.water",
                f"the drawing has a water table (layer {section.layers['water']})",
                "give loads.water_unit_weight (9.81 for kN and m)",
            )
        table = [tuple(p) for p in section.water_table.tolist()]
        loads = cfg.loads.model_copy(update={"water_table": table})
    supports, bolts = list(cfg.supports), list(cfg.bolts)
    if section.bolts:
        drawn = f"the drawing has {len(section.bolts)} bolts (layer {section.layers['bolts']})"
        if (g.bolt is None) == (g.bolt_force is None):
            raise fail(
                "bolt" if g.bolt is None else "bolt_force",
                drawn + (" and both `bolt` and `bolt_force`" if g.bolt else ""),
                "give geometry.bolt (passive bolts: capacity, axial_stiffness, ...) or "
                "geometry.bolt_force (active anchors)",
            )
        if g.bolt is not None:
            bolts += [
                BoltSpec(
                    head=tuple(b.head.tolist()),
                    angle=b.angle,
                    length=b.length,
                    name=f"drawn bolt {k + 1}",
                    **g.bolt.model_dump(),
                )
                for k, b in enumerate(section.bolts)
            ]
        else:
            supports += [
                SupportSpec(
                    at=tuple(b.head.tolist()),
                    force=g.bolt_force,
                    angle=b.angle,
                    name=f"drawn bolt {k + 1}",
                )
                for k, b in enumerate(section.bolts)
            ]
    update = {"blocks": blocks, "joint_lines": lines, "loads": loads, "supports": supports}
    return cfg.model_copy(update={**update, "bolts": bolts})
