"""Value types of the file (numbers without units, angles, points, polygons) and the
base of every section."""

from __future__ import annotations

import re
from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field
from pydantic_core import PydanticCustomError

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
