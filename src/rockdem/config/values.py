"""Value types of the file (numbers without units, angles, points, polygons) and the
base of every section.

Numbers are read as the file format writes them: a YAML or TOML number, or a
string holding a plain decimal number (``30``, ``-1.5``, ``1.0e+6``).  Python's
own spellings (``"2_5"``, ``"0x1A"``, ``"infinity"``) are not numbers of the
format and are refused.

Every quantity has a range where its numbers mean something in any
consistent unit system (see :data:`LIMITS`); beyond it a value is an input
error naming the key and the range, never a computation that overflows or
runs for ever.
"""

from __future__ import annotations

import functools
import re
from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field
from pydantic_core import PydanticCustomError

from ..blocks import MAX_UNIT_WEIGHT

_NUMBER_WITH_UNIT = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*[^\d\s.,_:].*$")
_PREFIXED = re.compile(r"^[-+]?0[xXoObB]")
#: A decimal number as YAML 1.2, JSON and TOML write it (no "_", no hex, no "inf").
_DECIMAL = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")
_WHOLE = re.compile(r"^[-+]?\d+$")

#: Smallest and largest 64-bit integer (block ids, removal ids).
INT64_MIN, INT64_MAX = -(2**63), 2**63 - 1
#: Largest coordinate magnitude (site grids reach 1e7; shift further ones to a local origin).
COORDINATE_MAX = 1e9
#: Range of lengths (spacings, trace lengths, depths, heights, thicknesses).
LENGTH_MIN, LENGTH_MAX = 1e-6, 1e9
#: Largest unit weight, stress, stiffness and force: far beyond any unit system, far
#: below where squares of forces overflow.
UNIT_WEIGHT_MAX = MAX_UNIT_WEIGHT
STRESS_MAX = 1e12
STIFFNESS_MIN, STIFFNESS_MAX = 1e-6, 1e15
FORCE_MAX = 1e15

#: The ranges, by quantity (for the documentation and the tests).
LIMITS = {
    "coordinate": (-COORDINATE_MAX, COORDINATE_MAX),
    "length": (LENGTH_MIN, LENGTH_MAX),
    "unit weight": (0.0, UNIT_WEIGHT_MAX),
    "stress": (0.0, STRESS_MAX),
    "stiffness": (STIFFNESS_MIN, STIFFNESS_MAX),
    "force": (-FORCE_MAX, FORCE_MAX),
    "id": (INT64_MIN, INT64_MAX),
    "seed": (0, INT64_MAX),
}


def _number(value: Any) -> Any:
    """Accept numbers (and strings holding a plain decimal number); reject booleans,
    numbers written with a unit and spellings that are not the format's."""
    if isinstance(value, bool):
        raise PydanticCustomError(
            "number_type", "expected a number, got {value}", {"value": str(value).lower()}
        )
    if isinstance(value, str):
        text = value.strip()
        if _DECIMAL.match(text):
            return float(text)
        if _NUMBER_WITH_UNIT.match(text) and not _PREFIXED.match(text):
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
    """Accept whole numbers (and strings of digits); reject booleans and other spellings."""
    if isinstance(value, bool):
        raise PydanticCustomError(
            "int_type", "expected a whole number, got {value}", {"value": str(value).lower()}
        )
    if isinstance(value, str):
        text = value.strip()
        if _WHOLE.match(text):
            return int(text)
        raise PydanticCustomError(
            "int_type", "expected a whole number, got {value!r}", {"value!r": repr(value)}
        )
    if isinstance(value, float) and value.is_integer() and abs(value) >= 2**63:
        # pydantic parses no float beyond 64 bits: "Unable to parse input string as
        # an integer, exceeded maximum size", with no range (found by hostile
        # testing: `samples: 1e30`); every whole-number key lies within 64 bits
        kind, ctx = (
            ("less_than_equal", {"le": INT64_MAX})
            if value > 0
            else (
                "greater_than_equal",
                {"ge": INT64_MIN},
            )
        )
        raise PydanticCustomError(kind, "{value} is out of range", {**ctx, "value": value})
    return value


_AS_NUMBER = BeforeValidator(_number)
_AS_INTEGER = BeforeValidator(_integer)


def bounded(
    lo: float | None = None,
    hi: float | None = None,
    *,
    open_lo: bool = False,
    open_hi: bool = False,
) -> Any:
    """A finite number type within ``[lo, hi]`` (open ends as asked)."""
    kw: dict[str, Any] = {"allow_inf_nan": False}
    if lo is not None:
        kw["gt" if open_lo else "ge"] = lo
    if hi is not None:
        kw["lt" if open_hi else "le"] = hi
    return Annotated[float, Field(**kw), _AS_NUMBER]


def whole(lo: int, hi: int) -> Any:
    """An integer type within ``[lo, hi]``."""
    return Annotated[int, Field(ge=lo, le=hi), _AS_INTEGER]


# constraints go before the validators, so that the JSON Schema shows them
Number = Annotated[float, Field(allow_inf_nan=False), _AS_NUMBER]
#: An integer that fits 64 bits (ids).
Integer = whole(INT64_MIN, INT64_MAX)
#: A random seed (>= 0).
Seed = whole(0, INT64_MAX)
Coordinate = bounded(-COORDINATE_MAX, COORDINATE_MAX)
#: A point ``[x, y]`` (x to the right, y up).
Point = tuple[Coordinate, Coordinate]
#: Polygon vertices ``[[x, y], ...]`` in order around it (either sense, not closed).
Polygon = Annotated[list[Point], Field(min_length=3)]
Force = bounded(-FORCE_MAX, FORCE_MAX)
#: A force or traction vector ``[fx, fy]``.
Vector = tuple[Force, Force]
Angle = bounded(0.0, 90.0, open_hi=True)
Positive = Annotated[float, Field(gt=0.0, allow_inf_nan=False), _AS_NUMBER]
NonNegative = Annotated[float, Field(ge=0.0, allow_inf_nan=False), _AS_NUMBER]
Fraction = bounded(0.0, 1.0, open_hi=True)
Dip = bounded(0.0, 180.0, open_hi=True)
Length = bounded(LENGTH_MIN, LENGTH_MAX)
#: A length that may be 0 (gaps, benches, ground behind the crest).
Extent = bounded(0.0, LENGTH_MAX)
UnitWeight = bounded(0.0, UNIT_WEIGHT_MAX)
Stress = bounded(0.0, STRESS_MAX)
Stiffness = bounded(STIFFNESS_MIN, STIFFNESS_MAX)
#: A stiffness that may be 0 (none): a bolt's dowel stiffness.
OptionalStiffness = bounded(0.0, STIFFNESS_MAX)
StiffnessRatio = bounded(0.01, 100.0)
FaceAngle = bounded(0.0, 90.0, open_lo=True)
Share = bounded(0.0, 1.0)
DipDeviation = bounded(0.0, 90.0)
Seismic = bounded(-1.0, 1.0, open_lo=True, open_hi=True)
#: A force magnitude (> 0).
Magnitude = bounded(0.0, FORCE_MAX, open_lo=True)
#: A force magnitude that may be 0 (none).
OptionalMagnitude = bounded(0.0, FORCE_MAX)
#: A direction in degrees counter-clockwise from +x.
Direction = bounded(-360.0, 360.0)


class _Section(BaseModel):
    """Base of every section: unknown keys are errors, every key documented.

    A key's documentation is the string under it in the class body; it is
    read on demand (:func:`document_keys`: error messages, the JSON Schema),
    not at import, where pydantic's ``use_attribute_docstrings`` parses the
    source of every section (50-60 ms of every command's start-up).
    """

    model_config = ConfigDict(extra="forbid", defer_build=True)


def _attribute_docs(cls: type) -> dict[str, str]:
    """``{key: its docstring}`` of the keys declared in ``cls``'s own body:
    a string statement right after an annotated assignment (pydantic's rule
    for ``use_attribute_docstrings``)."""
    import ast
    import inspect
    import textwrap

    try:
        source = inspect.getsource(cls)
    except (OSError, TypeError):  # no source shipped (a frozen application)
        return {}
    tree = ast.parse(textwrap.dedent(source))
    docs, target = {}, None
    for node in tree.body[0].body:
        if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            target = node.target.id
            continue
        if (
            target is not None
            and isinstance(node, ast.Expr)
            and isinstance(node.value, ast.Constant)
            and isinstance(node.value.value, str)
        ):
            docs[target] = inspect.cleandoc(node.value.value)
        target = None
    return docs


@functools.cache
def document_keys() -> None:
    """Give every section's keys their docstrings as descriptions (once), and
    rebuild the sections' schemas so that the JSON Schema carries them."""
    import inspect

    sections, todo = [], [_Section]
    while todo:
        cls = todo.pop()
        sections.append(cls)
        todo.extend(cls.__subclasses__())
    own = {cls: _attribute_docs(cls) for cls in sections}
    for cls in sections:
        for name, field in cls.model_fields.items():
            if field.description is not None:
                continue
            # the class that declares the key (the nearest in the MRO)
            owner = next(c for c in cls.__mro__ if name in inspect.get_annotations(c))
            if owner in own and name in own[owner]:
                field.description = own[owner][name]
    # rebuilt inner sections first: an outer one takes an inner one's schema
    # as it was built (a default instance builds it at import)
    done: set[type] = set()

    def rebuild(cls: type) -> None:
        if cls in done:
            return
        done.add(cls)
        for field in cls.model_fields.values():
            for inner in _section_types(field.annotation):
                rebuild(inner)
        cls.model_rebuild(force=True)

    for cls in sections:
        rebuild(cls)


def _section_types(annotation) -> list[type]:
    """The section classes an annotation refers to (in unions, lists, ...)."""
    import typing

    if isinstance(annotation, type) and issubclass(annotation, _Section):
        return [annotation]
    return [t for arg in typing.get_args(annotation) for t in _section_types(arg)]
