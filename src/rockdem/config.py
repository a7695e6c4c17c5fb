"""Model files: the plain-text format, its validation, and the model it builds.

A model file is YAML (``.yaml``, ``.yml``; JSON is YAML too) or TOML
(``.toml``).  Its structure is defined once, here, by pydantic models; the
JSON Schema that editors use for completion (``schema/rockdem-model.schema.json``)
is generated from the same models by :func:`json_schema`.

Every problem with a file is raised as a :class:`ModelFileError` that names
the file, the line (YAML only) and the key path, says what is wrong and how
to fix it, in one line::

    slope.yaml:12: joints.bedding.friction_angle: 95 is out of range; give a value < 90

Examples
--------
>>> from rockdem.config import parse_model
>>> text = '''
... units: kN, m, kPa
... materials: {rock: {unit_weight: 26}}
... joints: {joint: {normal_stiffness: 1.0e+6, friction_angle: 30}}
... blocks:
...   - {vertices: [[-5, -1], [5, -1], [5, 0], [-5, 0]], fixed: true}
...   - {vertices: [[0, 0], [1, 0], [1, 1], [0, 1]], material: rock}
... '''
>>> model, cfg = parse_model(text, source="box.yaml")
>>> model
<Model: 2 blocks, 1 joint types>
>>> cfg.units
'kN, m, kPa'
"""

from __future__ import annotations

import difflib
import math
import re
import tomllib
import types
import typing
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import yaml
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    ValidationError,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from .errors import InputError

#: Version of the file format this module reads (the ``format`` key).
FORMAT_VERSION = 1

#: File suffixes read as TOML; everything else is read as YAML (JSON is YAML).
TOML_SUFFIXES = (".toml",)

__all__ = [
    "FORMAT_VERSION",
    "ModelFile",
    "ModelFileError",
    "build_model",
    "json_schema",
    "load_model",
    "parse_model",
    "read_document",
    "validate_document",
]


# ============================================================== errors
class ModelFileError(InputError):
    """Bad model file: names the file, the line, the key path, the problem and the fix.

    Parameters
    ----------
    source : str
        File name (or ``"<string>"``).
    key : str
        Key path in the file, for example ``"joints.bedding.friction_angle"``
        or ``"blocks[2].vertices"`` (empty for the whole file).
    problem, fix : str
        What is wrong, and what to do about it.
    line : int, optional
        1-based line of the key in the file (YAML only).
    """

    def __init__(
        self, source: str, key: str, problem: str, fix: str = "", line: int | None = None
    ) -> None:
        self.source = source
        self.key = key
        self.line = line
        place = source if line is None else f"{source}:{line}"
        where = f"{place}: {key}" if key else place
        super().__init__(where, problem, fix)


# ======================================================= value types
_NUMBER_WITH_UNIT = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*[^\d\s.,].*$")


def _number(value: Any) -> Any:
    """Accept numbers (and numeric strings such as PyYAML's ``1e6``); reject
    booleans and numbers written with a unit, with a message that says so."""
    if isinstance(value, bool):
        raise PydanticCustomError(
            "number_type", "expected a number, got {value}", {"value": str(value).lower()}
        )
    if isinstance(value, str):
        text = value.strip()
        try:
            return float(text)
        except ValueError:
            pass
        if _NUMBER_WITH_UNIT.match(text):
            raise PydanticCustomError(
                "number_with_unit",
                "{value!r} has a unit",
                {"value!r": repr(value)},
            )
        raise PydanticCustomError(
            "number_type", "expected a number, got {value!r}", {"value!r": repr(value)}
        )
    return value


def _integer(value: Any) -> Any:
    if isinstance(value, bool):
        raise PydanticCustomError(
            "int_type", "expected a whole number, got {value}", {"value": str(value).lower()}
        )
    return value


_AS_NUMBER = BeforeValidator(_number)
_AS_INTEGER = BeforeValidator(_integer)
# constraints go before the validators, so that the JSON Schema shows them
Number = Annotated[float, Field(allow_inf_nan=False), _AS_NUMBER]
Integer = Annotated[int, _AS_INTEGER]
#: A point ``[x, y]`` (x to the right, y up).
Point = tuple[Number, Number]
#: Polygon vertices ``[[x, y], ...]`` in order around it (either sense, not closed).
Polygon = Annotated[list[Point], Field(min_length=3)]
Angle = Annotated[float, Field(ge=0.0, lt=90.0, allow_inf_nan=False), _AS_NUMBER]
Positive = Annotated[float, Field(gt=0.0, allow_inf_nan=False), _AS_NUMBER]
NonNegative = Annotated[float, Field(ge=0.0, allow_inf_nan=False), _AS_NUMBER]
Fraction = Annotated[float, Field(ge=0.0, lt=1.0, allow_inf_nan=False), _AS_NUMBER]
Dip = Annotated[float, Field(ge=0.0, lt=180.0, allow_inf_nan=False), _AS_NUMBER]


class _Section(BaseModel):
    """Base of every section: unknown keys are errors, every key documented."""

    model_config = ConfigDict(extra="forbid", use_attribute_docstrings=True)


# ======================================================= the sections
class MaterialSpec(_Section):
    """A rock material (referred to by name from blocks and slopes)."""

    unit_weight: NonNegative
    """Weight per unit volume x the section's thickness (for example 26 kN/m^3 for a
    1 m slice); weight = unit_weight x block area."""
    description: str = ""
    """Free text."""


class JointSpec(_Section):
    """Strength and stiffness of one kind of interface (joint set, rock bridge, ground)."""

    normal_stiffness: Positive
    """kn: normal stiffness per unit length per unit closure (for example kN/m^2/m).
    Choose it large against the loads; its value hardly changes collapse results."""
    friction_angle: Angle
    """Peak friction angle in degrees, 0 <= phi < 90."""
    cohesion: NonNegative = 0.0
    """Peak cohesion (stress), >= 0."""
    tensile_strength: NonNegative = 0.0
    """Tension cut-off (stress), >= 0; 0 means an open joint that carries no tension."""
    shear_stiffness: Positive | None = None
    """ks; default normal_stiffness / stiffness_ratio."""
    stiffness_ratio: Positive = 2.5
    """kn / ks used when shear_stiffness is not given (2 to 3 for rock)."""
    residual_cohesion: NonNegative | None = 0.0
    """Cohesion after a point has yielded; default 0 (brittle). null keeps the peak
    cohesion (ductile)."""
    residual_friction_angle: Angle | None = None
    """Friction angle after yield; default (null) the peak friction angle."""
    residual_tensile_strength: NonNegative | None = 0.0
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
    unit_weight: NonNegative | None = None
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
    height: Positive | None = None
    """Simple slope: height from toe to crest."""
    face_angle: (
        Annotated[float, Field(gt=0.0, le=90.0, allow_inf_nan=False), _AS_NUMBER] | None
    ) = None
    """Simple slope: inclination of the face in degrees (0 < angle <= 90)."""
    crest_length: Positive | None = None
    """Simple slope: length of the flat ground behind the crest (default: the height)."""
    toe_length: Positive | None = None
    """Simple slope: length of the flat ground in front of the toe (default: half the
    height)."""
    bench_width: NonNegative = 0.0
    """Simple slope: width of benches (0: no benches)."""
    bench_height: Positive | None = None
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
    spacing: Positive
    """Mean distance between joints, measured normal to them."""
    joint: str | None = None
    """Name of the joint properties in `joints`; default the set's own name."""
    origin: Point = (0.0, 0.0)
    """A point one joint of the set passes through."""
    trace_length: Positive | None = None
    """Length of each joint trace (null: persistent joints across the slope)."""
    gap: NonNegative = 0.0
    """Length of the rock bridges between traces of non-persistent joints (needs
    `slope.bridge_joint`)."""
    stagger: Annotated[float, Field(ge=0.0, le=1.0, allow_inf_nan=False), _AS_NUMBER] = 0.0
    """Shift of the trace pattern from one joint to the next, as a fraction of
    trace_length + gap."""
    spacing_sd: NonNegative = 0.0
    """Standard deviation of the spacing (0: regular)."""
    dip_sd: NonNegative = 0.0
    """Standard deviation of the dip in degrees (0: all parallel)."""
    seed: Integer | None = None
    """Random seed of this set (default: from `slope.seed`)."""


class SlopeSpec(_Section):
    """A slope generated from a profile cut by joint sets (instead of `blocks`)."""

    profile: ProfileSpec
    """The ground surface."""
    joint_sets: dict[str, JointSetSpec] = Field(min_length=1)
    """Joint sets by name (at least one)."""
    material: str | None = None
    """Material of the rock mass (default: the only one in `materials`)."""
    unit_weight: NonNegative | None = None
    """Unit weight of the rock mass (instead of `material`)."""
    depth: Positive
    """Depth of the modelled rock below the lowest profile point."""
    behind: NonNegative = 0.0
    """Horizontal ground added behind (left of) the profile's first point."""
    boundary: list[Literal["base", "back", "front"]] = ["base", "back", "front"]
    """Sides of the section backed by a fixed strip of ground ([] for none)."""
    ground_thickness: Positive | None = None
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
    seed: Integer = 0
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


class PointLoadSpec(_Section):
    """A force at a point on a block boundary (it acts on the block it pushes into)."""

    at: Point
    """Point of application `[x, y]`."""
    force: Point
    """Force `[fx, fy]` (y up: a downward load has fy < 0)."""
    name: str = ""
    """Label reported with results."""


class LineLoadSpec(_Section):
    """A uniform traction along a segment of the block boundaries (a foundation)."""

    start: Point
    """First end of the loaded segment."""
    end: Point
    """Second end of the loaded segment."""
    q: Point
    """Traction `[qx, qy]`, force per unit length (y up)."""
    name: str = ""
    """Label reported with results."""


class LoadsSpec(_Section):
    """External loads besides the self-weight."""

    gravity: bool = True
    """Apply the self-weight of the blocks."""
    seismic_h: Annotated[float, Field(gt=-1.0, lt=1.0, allow_inf_nan=False), _AS_NUMBER] = 0.0
    """Pseudo-static horizontal coefficient kh: a force kh x W toward +x (out of the face)."""
    seismic_v: Annotated[float, Field(gt=-1.0, lt=1.0, allow_inf_nan=False), _AS_NUMBER] = 0.0
    """Pseudo-static vertical coefficient kv: a force kv x W downward."""
    points: list[PointLoadSpec] = []
    """Point loads."""
    lines: list[LineLoadSpec] = []
    """Line loads."""


class SupportSpec(_Section):
    """A bolt or anchor: a force of given magnitude and direction at a point."""

    at: Point
    """Point of application on the face `[x, y]`."""
    force: Positive
    """Magnitude of the support force."""
    angle: Number
    """Direction in degrees counter-clockwise from +x (for example 165 pulls into a
    face looking toward +x, 15 degrees below horizontal)."""
    name: str = ""
    """Label reported with results."""


class StrengthReductionSpec(_Section):
    """Settings of the factor of safety by strength reduction (`rockdem fos`)."""

    width: Positive = 0.005
    """Stop when the bracket [stable, unstable] is narrower than this."""
    start: Positive = 1.0
    """First trial factor."""
    grow: Annotated[float, Field(gt=1.0, allow_inf_nan=False), _AS_NUMBER] = 1.5
    """Factor between trials while no failure has been found."""
    smallest: Positive = 0.05
    """Give up (strength-independent mechanism) below this factor."""
    largest: Positive = 100.0
    """Give up (no failure) above this factor."""

    @model_validator(mode="after")
    def _order(self) -> StrengthReductionSpec:
        if not self.smallest < self.start < self.largest:
            raise ValueError("needs smallest < start < largest")
        return self


class AnalysisSpec(_Section):
    """How the equations are integrated and solved."""

    quadrature: Literal["lobatto", "gauss"] = "lobatto"
    """Spring point rule along each interface: lobatto (includes the ends, exact
    pivoting) or gauss (2 points = the seed paper's lumped springs)."""
    points_per_interface: Annotated[int, Field(ge=2, le=5), _AS_INTEGER] = 3
    """Spring points per interface (3 with lobatto is Simpson's rule)."""
    load_steps: Annotated[int, Field(ge=1), _AS_INTEGER] = 5
    """Increments in which the loads are applied (staged gravity)."""
    tolerance: Annotated[float, Field(gt=0.0, lt=1e-2, allow_inf_nan=False), _AS_NUMBER] = 1e-8
    """Equilibrium when the out-of-balance force is below tolerance x the external force."""
    max_iterations: Annotated[int, Field(ge=1), _AS_INTEGER] = 100
    """Newton iterations per solve before a step is declared failed."""
    reduce_tensile: bool = True
    """Divide the tensile strength by the trial factor in strength reduction too."""
    strength_reduction: StrengthReductionSpec = StrengthReductionSpec()
    """Factor of safety search."""


class TrialSpec(_Section):
    """A stabilisation design to try: a removal from the model as it is."""

    name: str
    """Label of the trial in the report."""
    remove: RemoveSpec
    """What this design removes (blocks, regions and/or a new profile), counted from the
    model as it is (after the top-level `remove`)."""
    stabilise: bool = False
    """Then remove mechanism blocks until the target factor of safety is reached (as
    `rockdem stabilise` does), to see how much more removal the design needs."""


class SupportSearchSpec(_Section):
    """Where a support force is tried (the force itself is found by search)."""

    at: Point | None = None
    """Point of application on the face `[x, y]` (default: the free surface of the
    critical mechanism, nearest its centroid)."""
    angle: Number = 195.0
    """Direction of the force on the rock in degrees counter-clockwise from +x (195:
    into the slope, 15 degrees below horizontal, as a down-dipping anchor pulls)."""
    largest: Positive | None = None
    """Give up above this force (default: twice the weight of the free rock)."""


class StageSpec(_Section):
    """One excavation stage (bench): what it removes."""

    name: str
    """Label of the stage in the report."""
    remove: RemoveSpec
    """What this stage removes (blocks, regions and/or a new profile)."""


class StabilisationSpec(_Section):
    """Settings of `rockdem stabilise`: target, designs to compare, excavation stages."""

    target_fos: Positive = 1.3
    """Factor of safety the stabilisation must reach."""
    max_rounds: Annotated[int, Field(ge=1), _AS_INTEGER] = 6
    """Block-removal rounds before giving up."""
    max_removal: Annotated[float, Field(gt=0.0, le=1.0, allow_inf_nan=False), _AS_NUMBER] = 0.3
    """Largest share of the free rock (by area) that block removal may take."""
    smallest_set: bool = True
    """Look for a smaller set among the mechanism blocks (from the top down) when
    removing all of them reaches the target."""
    berm: list[Point] | None = Field(default=None, min_length=2)
    """A berm design: the new ground profile `[[x, y], ...]` (left to right), compared
    with the other measures."""
    support: SupportSearchSpec | None = None
    """Where to try a support force (null: on the critical mechanism, angle 195)."""
    trials: list[TrialSpec] = []
    """Removal designs to rate side by side (each from the model as it is)."""
    stages: list[StageSpec] = []
    """Excavation stages, analysed in order carrying the joint state forward."""


class ModelFile(_Section):
    """A rockdem model file: a jointed rock slope section and how to analyse it.

    Give the geometry either as explicit `blocks` or as a generated `slope`.
    Units are yours and must be consistent (state them in `units`); angles are
    in degrees; x points right, y up, and the slope faces +x.
    """

    format: Literal[1] = 1
    """Version of the file format."""
    name: str | None = None
    """Name of the model (default: the file name without suffix)."""
    description: str = ""
    """Free text."""
    units: str = ""
    """Note of the units used throughout, for example "kN, m, kPa" or "t, m"."""
    materials: dict[str, MaterialSpec] = {}
    """Rock materials by name."""
    joints: dict[str, JointSpec] = Field(min_length=1)
    """Joint properties by name (at least one).  The first (or `default_joint`) is
    used on every interface no other rule assigns."""
    default_joint: str | None = None
    """Joint for interfaces that no joint line, joint set or ground rule assigns
    (default: the first in `joints`)."""
    ground_joint: str | None = None
    """Joint on every contact with fixed ground (default: by the other rules)."""
    joint_lines: list[JointLineSpec] = []
    """Joint traces that assign joint properties to the interfaces on them (explicit
    blocks; the first listed wins where traces overlap)."""
    blocks: list[BlockSpec] | None = Field(default=None, min_length=1)
    """Explicit blocks (instead of `slope`)."""
    slope: SlopeSpec | None = None
    """A slope generated from a profile and joint sets (instead of `blocks`)."""
    remove: RemoveSpec = RemoveSpec()
    """Blocks to remove (excavation) before the analysis."""
    loads: LoadsSpec = LoadsSpec()
    """Self-weight, seismic coefficients, point and line loads."""
    supports: list[SupportSpec] = []
    """Bolts and anchors."""
    analysis: AnalysisSpec = AnalysisSpec()
    """Analysis settings."""
    stabilisation: StabilisationSpec = StabilisationSpec()
    """Stabilisation design (`rockdem stabilise`): target factor of safety, berm,
    support, removal trials and excavation stages."""

    @field_validator("joints", "materials")
    @classmethod
    def _names(cls, table: dict) -> dict:
        for key in table:
            if not str(key).strip():
                raise ValueError("a name must not be empty")
        return table

    @model_validator(mode="after")
    def _geometry(self) -> ModelFile:
        if (self.blocks is None) == (self.slope is None):
            raise PydanticCustomError(
                "geometry",
                "give the geometry as either `blocks` or `slope`"
                + (", not both" if self.blocks is not None else ""),
            )
        return self


# ============================================================ reading
def read_document(path: str | Path) -> tuple[dict, Any]:
    """Parse a model file into plain data.

    Returns
    -------
    data : dict
    nodes : yaml.Node or None
        The YAML node tree (for line numbers), None for TOML.

    Raises
    ------
    ModelFileError
        The file cannot be read or parsed, or is not a mapping of keys.
    """
    path = Path(path)
    source = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ModelFileError(source, "", "file not found", "check the path") from None
    except IsADirectoryError:
        raise ModelFileError(source, "", "is a directory", "give a model file") from None
    except UnicodeDecodeError as exc:
        raise ModelFileError(
            source, "", f"is not UTF-8 text ({exc.reason})", "save it as UTF-8 text"
        ) from None
    except OSError as exc:
        raise ModelFileError(source, "", f"cannot be read ({exc.strerror})", "") from None
    fmt = "toml" if path.suffix.lower() in TOML_SUFFIXES else "yaml"
    return parse_document(text, fmt=fmt, source=source)


def parse_document(text: str, *, fmt: str = "yaml", source: str = "<string>") -> tuple[dict, Any]:
    """Parse the text of a model file (see :func:`read_document`)."""
    nodes = None
    if fmt == "toml":
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            msg = str(exc)
            m = re.search(r"\(at line (\d+)", msg)
            line = int(m.group(1)) if m else None
            msg = re.sub(r"\s*\(at line.*\)$", "", msg)
            raise ModelFileError(
                source, "", f"not valid TOML: {msg}", "fix the syntax", line
            ) from None
    else:
        try:
            nodes = yaml.compose(text, Loader=yaml.SafeLoader)
            data = yaml.safe_load(text)
        except yaml.MarkedYAMLError as exc:
            mark = exc.problem_mark or exc.context_mark
            line = mark.line + 1 if mark is not None else None
            problem = (exc.problem or exc.context or "syntax error").strip()
            start = exc.context_mark
            if exc.context and start is not None and line is not None \
                    and start.line + 1 != line:
                problem += f" ({exc.context} started at line {start.line + 1})"
            raise ModelFileError(
                source,
                "",
                f"not valid YAML: {problem}",
                "check the indentation, colons and brackets",
                line,
            ) from None
        except yaml.YAMLError as exc:
            raise ModelFileError(source, "", f"not valid YAML: {exc}", "fix the syntax") from None
        _check_duplicates(nodes, source)
    if data is None:
        raise ModelFileError(
            source, "", "the file is empty", "write a model (see `rockdem example list`)"
        )
    if not isinstance(data, dict):
        raise ModelFileError(
            source,
            "",
            f"the top level is a {_kind(data)}, not a mapping of keys",
            "start with keys such as `units:`, `joints:` and `blocks:`",
            1,
        )
    return data, nodes


def _check_duplicates(node: Any, source: str, path: Loc = ()) -> None:
    """PyYAML keeps the last of repeated keys silently; a repeated key is a mistake."""
    if isinstance(node, yaml.MappingNode):
        seen: set[str] = set()
        for k, v in node.value:
            key = k.value if isinstance(k, yaml.ScalarNode) else str(k)
            if key in seen:
                raise ModelFileError(
                    source,
                    _keypath((*path, key)),
                    "the key is repeated",
                    "keep only one of them",
                    k.start_mark.line + 1,
                )
            seen.add(key)
            _check_duplicates(v, source, (*path, key))
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            _check_duplicates(item, source, (*path, i))


def validate_document(data: dict, *, source: str = "<string>", nodes: Any = None) -> ModelFile:
    """Validate parsed data against the file format and its cross-references.

    Raises
    ------
    ModelFileError
        For the first problem found (with the number of further problems).
    """
    try:
        cfg = ModelFile.model_validate(data)
    except ValidationError as exc:
        raise _from_validation(exc, source, nodes) from None
    _check_references(cfg, source, nodes)
    return cfg


def parse_model(
    text: str, *, fmt: str = "yaml", source: str = "<string>"
) -> tuple[Any, ModelFile]:
    """Model and validated file from the text of a model file."""
    data, nodes = parse_document(text, fmt=fmt, source=source)
    cfg = validate_document(data, source=source, nodes=nodes)
    return build_model(cfg, source=source, nodes=nodes), cfg


def load_model(path: str | Path) -> tuple[Any, ModelFile]:
    """Read, validate and build a model file.

    Parameters
    ----------
    path : str or Path
        A ``.yaml``/``.yml``/``.json`` or ``.toml`` model file.

    Returns
    -------
    model : rockdem.Model
    config : ModelFile
        The validated file (defaults filled in), for the echo in results and
        the strength-reduction settings.

    Raises
    ------
    ModelFileError
        Anything wrong with the file, in one line naming file, line, key and fix.
    """
    path = Path(path)
    data, nodes = read_document(path)
    cfg = validate_document(data, source=str(path), nodes=nodes)
    if cfg.name is None:
        cfg = cfg.model_copy(update={"name": path.stem})
    return build_model(cfg, source=str(path), nodes=nodes), cfg


def json_schema() -> dict:
    """The JSON Schema of the model file (for editors), generated from :class:`ModelFile`."""
    schema = ModelFile.model_json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["$id"] = "https://rockdem.invalid/schema/rockdem-model.schema.json"
    schema["title"] = "rockdem model file"
    return schema


# ===================================================== error messages
Loc = tuple[str | int, ...]


def _keypath(loc: Loc) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out


def _line(nodes: Any, loc: Loc, *, key_line: bool = True) -> int | None:
    """1-based line of the key (or the value) at ``loc`` in the YAML node tree."""
    if nodes is None or not loc:
        return None
    node = nodes
    for part in loc:
        if isinstance(node, yaml.MappingNode):
            for k, v in node.value:
                if isinstance(k, yaml.ScalarNode) and k.value == str(part):
                    node = v
                    last_key = k
                    break
            else:
                return node.start_mark.line + 1
        elif isinstance(node, yaml.SequenceNode) and isinstance(part, int):
            if not 0 <= part < len(node.value):
                return node.start_mark.line + 1
            node = node.value[part]
            last_key = None
        else:
            break
    else:
        if key_line and loc and last_key is not None:
            return last_key.start_mark.line + 1
    return node.start_mark.line + 1


def _kind(value: Any) -> str:
    if isinstance(value, dict):
        return "mapping"
    if isinstance(value, list | tuple):
        return "list"
    if isinstance(value, str):
        return "string"
    if isinstance(value, bool):
        return "boolean"
    if value is None:
        return "null"
    return type(value).__name__


def _unwrap(tp: Any) -> Any:
    """Strip Annotated and Optional from a type annotation."""
    while True:
        origin = typing.get_origin(tp)
        if origin is Annotated:
            tp = typing.get_args(tp)[0]
        elif origin in (typing.Union, types.UnionType):
            args = [a for a in typing.get_args(tp) if a is not type(None)]
            if len(args) != 1:
                return tp
            tp = args[0]
        else:
            return tp


def _type_at(loc: Loc) -> Any:
    """The annotation of the value at ``loc`` in :class:`ModelFile` (None if unknown)."""
    tp: Any = ModelFile
    for part in loc:
        tp = _unwrap(tp)
        if isinstance(tp, type) and issubclass(tp, BaseModel):
            field = tp.model_fields.get(str(part))
            if field is None:
                return None
            tp = field.annotation
        elif typing.get_origin(tp) is dict:
            tp = typing.get_args(tp)[1]
        elif typing.get_origin(tp) in (list, tuple):
            tp = typing.get_args(tp)[0]
        else:
            return None
    return _unwrap(tp)


def _field_doc(loc: Loc) -> str:
    parent = _type_at(loc[:-1])
    if isinstance(parent, type) and issubclass(parent, BaseModel):
        field = parent.model_fields.get(str(loc[-1]))
        if field is not None and field.description:
            return field.description.split(".")[0].replace("\n", " ")
    return ""


def _describe(err: dict) -> tuple[Loc, str, str]:
    """(loc, problem, fix) for one pydantic error."""
    loc: Loc = tuple(p for p in err["loc"] if not _is_internal(p))
    kind = err["type"]
    value = err.get("input")
    ctx = err.get("ctx") or {}
    shown = repr(value) if isinstance(value, str) else _short(value)
    if kind == "extra_forbidden":
        parent = _type_at(loc[:-1])
        allowed = list(parent.model_fields) if isinstance(parent, type) else []
        close = difflib.get_close_matches(str(loc[-1]), allowed, n=1, cutoff=0.6)
        fix = f"did you mean `{close[0]}`?" if close else f"allowed keys: {', '.join(allowed)}"
        return loc, "unknown key", fix
    if kind == "missing":
        doc = _field_doc(loc)
        fix = f"add `{loc[-1]}:`" + (f" ({doc})" if doc else "")
        return loc, "required key is missing", fix
    if kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
        op = {"greater_than": ">", "greater_than_equal": ">=", "less_than": "<",
              "less_than_equal": "<="}[kind]
        bound = next(iter(ctx.values()))
        return loc, f"{shown} is out of range", f"give a value {op} {bound:g}"
    if kind == "number_with_unit":
        fix = "write the bare number in the units stated in `units` (angles in degrees)"
        return loc, err["msg"], fix
    if kind == "geometry":
        fix = "use `blocks:` (explicit polygons) or `slope:` (a profile cut by joint sets)"
        return loc, err["msg"], fix
    if kind in ("number_type", "float_type", "float_parsing"):
        msg = err["msg"] if kind == "number_type" else f"expected a number, got {shown}"
        return loc, msg, "write a plain number, for example 30 or 1.0e+6"
    if kind == "finite_number":
        return loc, f"{shown} is not a finite number", "give a finite number"
    if kind in ("int_type", "int_parsing", "int_from_float"):
        return loc, f"expected a whole number, got {shown}", "write an integer such as 3"
    if kind in ("bool_type", "bool_parsing"):
        return loc, f"expected true or false, got {shown}", "write true or false"
    if kind in ("string_type", "string_parsing"):
        return loc, f"expected text, got {shown}", "write a name in quotes"
    if kind == "literal_error":
        return loc, f"{shown} is not allowed", f"use {ctx.get('expected', '')}"
    if kind in ("dict_type", "model_type", "model_attributes_type"):
        fix = "write `key: value` lines indented under it"
        return loc, f"expected a mapping of keys, got a {_kind(value)}", fix
    if kind in ("list_type", "tuple_type"):
        if _is_point(loc):
            return loc, f"expected a point [x, y], got a {_kind(value)}", "write [x, y]"
        return loc, f"expected a list, got a {_kind(value)}", "write [a, b, ...] or `- ` items"
    if kind in ("too_short", "too_long"):
        if _is_point(loc):
            return loc, f"expected a point [x, y], got {_short(value)}", "write [x, y]"
        n = ctx.get("min_length") if kind == "too_short" else ctx.get("max_length")
        word = "at least" if kind == "too_short" else "at most"
        return loc, f"has {ctx.get('actual_length')} items", f"give {word} {n}"
    if kind in ("value_error", "assertion_error"):
        msg = err["msg"].removeprefix("Value error, ")
        return loc, msg, "see `rockdem check --help` and docs/file-format.md"
    return loc, err["msg"], "see docs/file-format.md"


def _is_internal(part: Any) -> bool:
    return isinstance(part, str) and ("[" in part or part.startswith("function-"))


def _is_point(loc: Loc) -> bool:
    tp = _type_at(loc)
    return typing.get_origin(tp) is tuple


def _short(value: Any) -> str:
    text = repr(value)
    if isinstance(value, bool) or value is None:
        text = {True: "true", False: "false", None: "null"}[value]
    return text if len(text) <= 40 else text[:37] + "..."


def _from_validation(exc: ValidationError, source: str, nodes: Any) -> ModelFileError:
    errors = exc.errors(include_url=False)
    # report the most specific error first (deepest key path)
    errors.sort(key=lambda e: -len(e["loc"]))
    err = errors[0]
    loc, problem, fix = _describe(err)
    if len(errors) > 1:
        fix += f" ({len(errors) - 1} more problem{'s' if len(errors) > 2 else ''} in the file)"
    return ModelFileError(source, _keypath(loc) or "(top level)", problem, fix, _line(nodes, loc))


# ======================================================== cross-checks
def _check_references(cfg: ModelFile, source: str, nodes: Any) -> None:
    """Names that refer to other entries must exist."""

    def fail(loc: Loc, problem: str, fix: str) -> None:
        raise ModelFileError(source, _keypath(loc), problem, fix, _line(nodes, loc))

    joints, materials = list(cfg.joints), list(cfg.materials)

    def joint(loc: Loc, name: str | None) -> None:
        if name is not None and name not in cfg.joints:
            close = difflib.get_close_matches(name, joints, n=1)
            hint = f"did you mean {close[0]!r}?" if close else f"use one of {joints}"
            fail(loc, f"joint {name!r} is not defined in `joints`", hint)

    def material(loc: Loc, name: str | None) -> None:
        if name is not None and name not in cfg.materials:
            hint = f"use one of {materials}" if materials else "define it under `materials`"
            fail(loc, f"material {name!r} is not defined in `materials`", hint)

    joint(("default_joint",), cfg.default_joint)
    joint(("ground_joint",), cfg.ground_joint)
    for i, line in enumerate(cfg.joint_lines):
        joint(("joint_lines", i, "joint"), line.joint)
    if cfg.blocks is not None:
        ids = set()
        for i, b in enumerate(cfg.blocks):
            material((("blocks", i, "material")), b.material)
            if b.material is not None and b.unit_weight is not None:
                fail(("blocks", i), "has both `material` and `unit_weight`", "give only one")
            if not b.fixed and b.material is None and b.unit_weight is None \
                    and len(cfg.materials) != 1:
                fail(
                    ("blocks", i),
                    "free block without a unit weight",
                    "give `material:` or `unit_weight:` (or define exactly one material)",
                )
            bid = i if b.id is None else b.id
            if bid in ids:
                fail(("blocks", i, "id"), f"id {bid} is used twice", "give every block its own id")
            ids.add(bid)
        if all(b.fixed for b in cfg.blocks):
            fail(("blocks",), "every block is fixed", "set `fixed: false` on the blocks that move")
        if cfg.remove.profile is not None:
            fail(("remove", "profile"), "is for generated slopes",
                 "use `remove.regions` or `remove.blocks` with explicit blocks")
        for k, bid in enumerate(cfg.remove.blocks):
            if bid not in ids:
                fail(("remove", "blocks", k), f"no block has id {bid}", "use an id of `blocks`")
    if cfg.slope is not None:
        s = cfg.slope
        material(("slope", "material"), s.material)
        if s.material is not None and s.unit_weight is not None:
            fail(("slope",), "has both `material` and `unit_weight`", "give only one")
        if s.material is None and s.unit_weight is None and len(cfg.materials) != 1:
            fail(
                ("slope",),
                "no unit weight for the rock mass",
                "give `material:` or `unit_weight:` (or define exactly one material)",
            )
        joint(("slope", "bridge_joint"), s.bridge_joint)
        for name, js in s.joint_sets.items():
            key = js.joint or name
            if key not in cfg.joints:
                loc: Loc = ("slope", "joint_sets", name) + (("joint",) if js.joint else ())
                fix = "add it under `joints` or set `joint:` to a defined joint"
                fail(loc, f"joint {key!r} is not defined in `joints`", fix)
        if cfg.joint_lines:
            fail(("joint_lines",), "is for explicit blocks", "use `slope.joint_sets` instead")
        if cfg.default_joint is not None:
            fail(
                ("default_joint",),
                "is for explicit blocks",
                "generated slopes take each set's joint (and `slope.bridge_joint`)",
            )


# ============================================================= building
def _unit_weight(cfg: ModelFile, material: str | None, value: float | None) -> float | None:
    if value is not None:
        return value
    if material is not None:
        return cfg.materials[material].unit_weight
    if len(cfg.materials) == 1:
        return next(iter(cfg.materials.values())).unit_weight
    return None


def _joints(cfg: ModelFile) -> tuple:
    from .joints import Joint

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
    from .model import LineLoad, Loads, PointLoad

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
    from .model import Settings

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
        from .solver import build_system

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

    from .blocks import Blocks
    from .model import Model

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
    from .geometry import Profile

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
        from . import geometry
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
