"""The whole model file (:class:`ModelFile`) and its JSON Schema."""

# pydantic copies mutable defaults; ruff cannot see that _Section is a BaseModel
# ruff: noqa: RUF012

from __future__ import annotations

from typing import Literal

from pydantic import Field, field_validator, model_validator
from pydantic_core import PydanticCustomError

from .geometry import GeometrySpec
from .sections import (
    BlockSpec,
    BoltSpec,
    JointLineSpec,
    JointSpec,
    LoadsSpec,
    MaterialSpec,
    RemoveSpec,
    SlopeSpec,
    SupportSpec,
)
from .settings import AnalysisSpec, StabilisationSpec
from .study import StudySpec
from .values import _Section, document_keys

#: Version of the file format this module reads (the ``format`` key).
FORMAT_VERSION = 1


class ModelFile(_Section):
    """A rockdem model file: a jointed rock slope section and how to analyse it.

    Give the geometry either as explicit `blocks` or as a generated `slope`.
    Units are yours and must be consistent (state them in `units`); angles are
    in degrees; x points right, y up, and the slope faces +x.
    """

    format: Literal[1] = 1
    """Version of the file format."""

    @field_validator("format", mode="before")
    @classmethod
    def _format_is_a_number(cls, v):
        if isinstance(v, bool):  # `true` equals 1 in Python, not in a file (fuzzing)
            raise PydanticCustomError("format_bool", f"{str(v).lower()} is not a format version")
        return v

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
    geometry: GeometrySpec | None = None
    """A section drawn in CAD (a DXF file), cut into blocks (instead of `blocks` or
    `slope`)."""
    remove: RemoveSpec = RemoveSpec()
    """Blocks to remove (excavation) before the analysis."""
    loads: LoadsSpec = LoadsSpec()
    """Self-weight, seismic coefficients, point and line loads."""
    supports: list[SupportSpec] = []
    """Active supports: anchor forces of given magnitude and direction."""
    bolts: list[BoltSpec] = []
    """Passive bolts and cables: their force rises as the joints they cross move."""
    analysis: AnalysisSpec = AnalysisSpec()
    """Analysis settings."""
    stabilisation: StabilisationSpec = StabilisationSpec()
    """Stabilisation design (`rockdem stabilise`): target factor of safety, berm,
    support, removal trials and excavation stages."""
    study: StudySpec | None = None
    """Probabilistic or parametric study (`rockdem study`): inputs varied by key
    path, their distributions or sweep values, the sampler and the number of runs."""

    @field_validator("joints", "materials")
    @classmethod
    def _names(cls, table: dict) -> dict:
        for key in table:
            if not str(key).strip():
                raise ValueError("a name must not be empty")
        return table

    @model_validator(mode="after")
    def _geometry(self) -> ModelFile:
        given = [k for k in ("blocks", "slope", "geometry") if getattr(self, k) is not None]
        if len(given) != 1:
            raise PydanticCustomError(
                "geometry",
                "give the geometry as either `blocks` or `slope` (or a `geometry` drawing)"
                + (f", not both {given[0]} and {given[1]}" if given else ""),
            )
        return self


def json_schema() -> dict:
    """The JSON Schema of the model file (for editors), generated from :class:`ModelFile`."""
    document_keys()
    schema = ModelFile.model_json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["$id"] = "https://rockdem.invalid/schema/rockdem-model.schema.json"
    schema["title"] = "rockdem model file"
    return schema
