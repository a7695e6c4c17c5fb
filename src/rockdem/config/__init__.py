"""Model files: the plain-text format, its validation, and the model it builds.

A model file is YAML (``.yaml``, ``.yml``; JSON is YAML too) or TOML
(``.toml``).  Its structure is defined once, here, by pydantic models; the
JSON Schema that editors use for completion (``schema/rockdem-model.schema.json``)
is generated from the same models by :func:`json_schema`.

Every problem with a file is raised as a :class:`ModelFileError` that names
the file, the line and the key path, says what is wrong and how
to fix it, in one line::

    slope.yaml:12: joints.bedding.friction_angle: 95 is out of range; give a value >= 0 and < 90

The package is split by stage: :mod:`~rockdem.config.values`,
:mod:`~rockdem.config.sections`, :mod:`~rockdem.config.settings` and
:mod:`~rockdem.config.spec` define the format; :mod:`~rockdem.config.parse`
reads a file, :mod:`~rockdem.config.validate` checks it and
:mod:`~rockdem.config.build` makes the model; :mod:`~rockdem.config.errors`
holds :class:`ModelFileError` and the key paths and lines it names.

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

from .build import build_model
from .errors import Loc as Loc
from .errors import ModelFileError
from .parse import TOML_SUFFIXES as TOML_SUFFIXES
from .parse import load_model, parse_model, read_document
from .parse import parse_document as parse_document
from .sections import BlockSpec as BlockSpec
from .sections import BoltSpec as BoltSpec
from .sections import JointLineSpec as JointLineSpec
from .sections import JointSetSpec as JointSetSpec
from .sections import JointSpec as JointSpec
from .sections import LineLoadSpec as LineLoadSpec
from .sections import LoadsSpec as LoadsSpec
from .sections import MaterialSpec as MaterialSpec
from .sections import PointLoadSpec as PointLoadSpec
from .sections import ProfileSpec as ProfileSpec
from .sections import RemoveSpec as RemoveSpec
from .sections import SlopeSpec as SlopeSpec
from .sections import SupportSpec as SupportSpec
from .settings import AnalysisSpec as AnalysisSpec
from .settings import StabilisationSpec as StabilisationSpec
from .settings import StageSpec as StageSpec
from .settings import StrengthReductionSpec as StrengthReductionSpec
from .settings import SupportSearchSpec as SupportSearchSpec
from .settings import TrialSpec as TrialSpec
from .spec import FORMAT_VERSION, ModelFile, json_schema
from .validate import validate_document
from .values import Angle as Angle
from .values import Dip as Dip
from .values import Fraction as Fraction
from .values import Integer as Integer
from .values import NonNegative as NonNegative
from .values import Number as Number
from .values import Point as Point
from .values import Polygon as Polygon
from .values import Positive as Positive

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
