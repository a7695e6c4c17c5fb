"""The sections that describe the slope: materials, joints, blocks, joint lines, a
generated slope, removal, loads and supports."""

# pydantic copies mutable defaults; ruff cannot see that _Section is a BaseModel
# ruff: noqa: RUF012

from __future__ import annotations

from typing import Literal

from pydantic import Field, field_validator, model_validator

from .values import (
    Angle,
    Dip,
    DipDeviation,
    Direction,
    Extent,
    FaceAngle,
    Fraction,
    Integer,
    Length,
    Magnitude,
    OptionalMagnitude,
    OptionalStiffness,
    Point,
    Polygon,
    Positive,
    Seed,
    Seismic,
    Share,
    Stiffness,
    StiffnessRatio,
    Stress,
    UnitWeight,
    Vector,
    _Section,
)


class MaterialSpec(_Section):
    """A rock material (referred to by name from blocks and slopes)."""

    unit_weight: UnitWeight
    """Weight per unit volume x the section's thickness (for example 26 kN/m^3 for a
    1 m slice); weight = unit_weight x block area."""
    description: str = ""
    """Free text."""


class JointSpec(_Section):
    """Strength and stiffness of one kind of interface (joint set, rock bridge, ground)."""

    normal_stiffness: Stiffness
    """kn: normal stiffness per unit length per unit closure (for example kN/m^2/m).
    Choose it large against the loads; its value hardly changes collapse results."""
    friction_angle: Angle
    """Peak friction angle in degrees, 0 <= phi < 90."""
    cohesion: Stress = 0.0
    """Peak cohesion (stress), >= 0."""
    tensile_strength: Stress = 0.0
    """Tension cut-off (stress), >= 0; 0 means an open joint that carries no tension."""
    shear_stiffness: Stiffness | None = None
    """ks; default normal_stiffness / stiffness_ratio."""
    stiffness_ratio: StiffnessRatio = 2.5
    """kn / ks used when shear_stiffness is not given (2 to 3 for rock)."""
    residual_cohesion: Stress | None = 0.0
    """Cohesion after a point has yielded; default 0 (brittle). null keeps the peak
    cohesion (ductile)."""
    residual_friction_angle: Angle | None = None
    """Friction angle after yield; default (null) the peak friction angle."""
    residual_tensile_strength: Stress | None = 0.0
    """Tensile strength after a point has yielded in shear; default 0. null keeps
    tensile_strength (ductile). A point broken in tension never carries tension again."""
    description: str = ""
    """Free text."""


class BlockSpec(_Section):
    """One rigid block given by its outline."""

    vertices: Polygon
    """Outline `[[x, y], ...]`, at least 3 vertices, in order around the block."""
    fixed: bool = False
    """True for immobile ground (no unit weight needed)."""
    material: str | None = None
    """Name of a material in `materials` (gives the unit weight)."""
    unit_weight: UnitWeight | None = None
    """Unit weight of this block (instead of `material`)."""
    id: Integer | None = None
    """Label reported in results; default the block's position in the list (0, 1, ...)."""


class JointLineSpec(_Section):
    """A joint trace: interfaces lying on it take its joint properties.

    Give either `start` and `end`, or `point` and `dip` (a line through the
    point, extended across the whole model).
    """

    joint: str
    """Name of a joint in `joints`."""
    start: Point | None = None
    """First end of the segment."""
    end: Point | None = None
    """Second end of the segment."""
    point: Point | None = None
    """A point the (infinite) line passes through."""
    dip: Dip | None = None
    """Dip of the line in degrees, 0 <= dip < 180, measured down from +x toward the
    face (the line runs along (cos dip, -sin dip)); dip < 90 dips out of the face."""

    @model_validator(mode="after")
    def _one_form(self) -> JointLineSpec:
        segment = self.start is not None or self.end is not None
        line = self.point is not None or self.dip is not None
        if segment and line:
            raise ValueError("give either start and end, or point and dip, not both")
        if segment and (self.start is None or self.end is None):
            raise ValueError("a segment needs both start and end")
        if line and (self.point is None or self.dip is None):
            raise ValueError("a line needs both point and dip")
        if not segment and not line:
            raise ValueError("give start and end, or point and dip")
        return self


class ProfileSpec(_Section):
    """The ground surface of the section: explicit points, or a simple slope.

    Give either `points`, or `height` and `face_angle` (with the optional keys
    of a simple slope).  The slope faces +x: crest on the left, toe on the right.
    """

    points: list[Point] | None = Field(default=None, min_length=2)
    """Surface points `[[x, y], ...]` from left (crest side) to right (toe side)."""
    height: Length | None = None
    """Simple slope: height from toe to crest."""
    face_angle: FaceAngle | None = None
    """Simple slope: inclination of the face in degrees (0 < angle <= 90)."""
    crest_length: Length | None = None
    """Simple slope: length of the flat ground behind the crest (default: the height)."""
    toe_length: Length | None = None
    """Simple slope: length of the flat ground in front of the toe (default: half the
    height)."""
    bench_width: Extent = 0.0
    """Simple slope: width of benches (0: no benches)."""
    bench_height: Length | None = None
    """Simple slope: vertical distance between benches, counted up from the toe
    (needed when bench_width > 0)."""
    toe: Point = (0.0, 0.0)
    """Simple slope: position of the toe."""

    @model_validator(mode="after")
    def _one_form(self) -> ProfileSpec:
        simple = self.height is not None or self.face_angle is not None
        if self.points is not None and simple:
            raise ValueError("give either points, or height and face_angle, not both")
        if self.points is None and not (self.height is not None and self.face_angle is not None):
            raise ValueError("give points, or both height and face_angle")
        return self


class JointSetSpec(_Section):
    """A set of parallel joints cutting the slope into blocks."""

    dip: Dip
    """Dip in degrees, 0 <= dip < 180 (trace along (cos dip, -sin dip); dip < 90 dips
    out of the face)."""
    spacing: Length
    """Mean distance between joints, measured normal to them."""
    joint: str | None = None
    """Name of the joint properties in `joints`; default the set's own name."""
    origin: Point = (0.0, 0.0)
    """A point one joint of the set passes through."""
    trace_length: Length | None = None
    """Length of each joint trace (null: persistent joints across the slope)."""
    gap: Extent = 0.0
    """Length of the rock bridges between traces of non-persistent joints (needs
    `slope.bridge_joint`)."""
    stagger: Share = 0.0
    """Shift of the trace pattern from one joint to the next, as a fraction of
    trace_length + gap."""
    spacing_sd: Extent = 0.0
    """Standard deviation of the spacing (0: regular)."""
    dip_sd: DipDeviation = 0.0
    """Standard deviation of the dip in degrees (0: all parallel)."""
    seed: Seed | None = None
    """Random seed of this set (default: from `slope.seed`)."""


class SlopeSpec(_Section):
    """A slope generated from a profile cut by joint sets (instead of `blocks`)."""

    profile: ProfileSpec
    """The ground surface."""
    joint_sets: dict[str, JointSetSpec] = Field(min_length=1)
    """Joint sets by name (at least one)."""
    material: str | None = None
    """Material of the rock mass (default: the only one in `materials`)."""
    unit_weight: UnitWeight | None = None
    """Unit weight of the rock mass (instead of `material`)."""
    depth: Length
    """Depth of the modelled rock below the lowest profile point."""
    behind: Extent = 0.0
    """Horizontal ground added behind (left of) the profile's first point."""
    boundary: list[Literal["base", "back", "front"]] = ["base", "back", "front"]
    """Sides of the section backed by a fixed strip of ground ([] for none)."""
    ground_thickness: Length | None = None
    """Thickness of the fixed strips (default 10% of the larger section size)."""
    bridge_joint: str | None = None
    """Joint (name in `joints`) for the rock bridges between non-persistent joints."""
    fixed_region: Polygon | None = None
    """Region of the section that is fixed ground (besides the `boundary` strips)."""
    min_block_fraction: Fraction = 0.05
    """Blocks smaller than this fraction of the median block area are slivers."""
    slivers: Literal["merge", "report"] = "merge"
    """Merge each sliver into the neighbour sharing its longest edge, or keep it and
    only report it."""
    seed: Seed = 0
    """Random seed of the joint generation (reproducible models)."""


class RemoveSpec(_Section):
    """Blocks taken out of the model before the analysis (excavation)."""

    blocks: list[Integer] = []
    """Ids of blocks to remove."""
    regions: list[Polygon] = []
    """Polygons to excavate.  Generated slopes are cut along the polygon; with
    explicit blocks, every block whose centroid lies inside is removed."""
    profile: list[Point] | None = Field(default=None, min_length=2)
    """Generated slopes only: cut the slope down to this new ground profile
    `[[x, y], ...]` (left to right; everything above it is excavated)."""

    @field_validator("blocks")
    @classmethod
    def _once(cls, blocks: list[int]) -> list[int]:
        # (hostile round 7: `[3, 3]` was taken silently, a typo for another id)
        seen: dict[int, int] = {}
        for k, bid in enumerate(blocks):
            if bid in seen:
                raise ValueError(
                    f"id {bid} is listed twice (items {seen[bid]} and {k}); list each block "
                    "once (was another id meant?)"
                )
            seen[bid] = k
        return blocks


class PointLoadSpec(_Section):
    """A force at a point on a block boundary (it acts on the block it pushes into)."""

    at: Point
    """Point of application `[x, y]`."""
    force: Vector
    """Force `[fx, fy]` (y up: a downward load has fy < 0)."""
    name: str = ""
    """Label reported with results."""


class LineLoadSpec(_Section):
    """A traction along a segment of the block boundaries (a foundation, a fill):
    uniform, or varying linearly from `q` at `start` to `q_end` at `end`."""

    start: Point
    """First end of the loaded segment."""
    end: Point
    """Second end of the loaded segment."""
    q: Vector
    """Traction `[qx, qy]`, force per unit length (y up); at `start` when `q_end` is
    given."""
    q_end: Vector | None = None
    """Traction at `end` for a linearly varying load (a trapezoid; null: uniform)."""
    name: str = ""
    """Label reported with results."""


class LoadsSpec(_Section):
    """External loads besides the self-weight."""

    gravity: bool = True
    """Apply the self-weight of the blocks."""
    seismic_h: Seismic = 0.0
    """Pseudo-static horizontal coefficient kh: a force kh x W toward +x (out of the face)."""
    seismic_v: Seismic = 0.0
    """Pseudo-static vertical coefficient kv: a force kv x W downward."""
    points: list[PointLoadSpec] = []
    """Point loads."""
    lines: list[LineLoadSpec] = []
    """Line loads."""
    water_table: list[Point] = []
    """Phreatic line `[[x, y], ...]` left to right (level beyond its ends): every
    joint below it carries the hydrostatic pressure gamma_w (h - y) on both faces
    (effective stress in the springs; not reduced by strength reduction)."""
    water_unit_weight: UnitWeight | None = None
    """Unit weight of water in the model's units (9.81 for kN and m, 1.0 for t and m);
    required with a water table."""
    pore_pressure_ratio: Fraction = 0.0
    """r_u, a quick check instead of a water table: every joint carries r_u x the
    vertical overburden pressure of the rock above it (gamma (s - y), s the top of the
    rock, gamma the free rock's mean unit weight)."""


class SupportSpec(_Section):
    """A bolt or anchor: a force of given magnitude and direction at a point."""

    at: Point
    """Point of application on the face `[x, y]`."""
    force: Magnitude
    """Magnitude of the support force."""
    angle: Direction
    """Direction in degrees counter-clockwise from +x (for example 165 pulls into a
    face looking toward +x, 15 degrees below horizontal)."""
    name: str = ""
    """Label reported with results."""


class BoltSpec(_Section):
    """A passive bolt or cable: a straight segment from its head on the face into
    the rock, tying the blocks together at every joint it crosses (an axial and a
    shear spring per crossing; forces per bolt, divided by `spacing` in the section)."""

    head: Point
    """Head of the bolt on the face `[x, y]`."""
    angle: Direction
    """Direction from the head into the rock, degrees counter-clockwise from +x (for
    example 195 runs into a face looking toward +x, 15 degrees below horizontal)."""
    length: Length
    """Total length."""
    capacity: Magnitude
    """Axial yield force of the steel, one bolt."""
    axial_stiffness: Stiffness
    """Axial force per unit opening of a crossed joint along the bolt, one bolt (about
    E A / L for a debonded length L each side of the joint)."""
    shear_stiffness: OptionalStiffness = 0.0
    """Dowel stiffness across a joint, one bolt (0: none)."""
    shear_capacity: OptionalMagnitude = 0.0
    """Dowel (shear) capacity, one bolt."""
    bond_strength: Positive | None = None
    """Grout bond force per unit length: the axial capacity at a joint is at most the
    bond over the length beyond it (null: the steel yields first)."""
    pretension: OptionalMagnitude = 0.0
    """Axial force locked in at installation."""
    spacing: Positive = 1.0
    """Out-of-plane spacing of the bolt row (the section carries force / spacing)."""
    kind: Literal["bolt", "cable"] = "bolt"
    """`cable`: no compression and no dowel action."""
    installed: Literal["before_loads", "after_loads"] = "before_loads"
    """`before_loads`: in the slope from the first load step, loaded by the rock's
    settlement too (the seed paper's bolted example); `after_loads`: put into the
    slope standing under its loads, it resists only further movement."""
    name: str = ""
    """Label reported with results."""
