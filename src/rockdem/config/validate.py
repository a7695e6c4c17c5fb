"""Validation of parsed data: pydantic errors as one-line messages naming the key, and
the cross-references between sections."""

from __future__ import annotations

import difflib
import re
import types
import typing
from pathlib import Path
from typing import Annotated, Any

from pydantic import BaseModel, ValidationError
from pydantic.fields import FieldInfo

from .errors import Loc, ModelFileError, _keypath, _kind, _line
from .spec import ModelFile
from .values import document_keys


def validate_document(
    data: dict, *, source: str = "<string>", nodes: Any = None, fmt: str | None = None
) -> ModelFile:
    """Validate parsed data against the file format and its cross-references.

    ``fmt`` ("yaml" or "toml"; default: by the suffix of ``source``) words
    the fixes in the file's own syntax.

    Raises
    ------
    ModelFileError
        For the first problem found (with the number of further problems).
    """
    try:
        cfg = ModelFile.model_validate(data)
    except ValidationError as exc:
        toml = (fmt or Path(source).suffix.lstrip(".")).lower() == "toml"
        raise _from_validation(exc, source, nodes, toml) from None
    try:
        _check_references(cfg, source, nodes)
        _check_unique_names(cfg, source, nodes)
        _check_units(cfg, source, nodes)
    except ModelFileError as exc:
        if (fmt or Path(source).suffix.lstrip(".")).lower() != "toml":
            raise
        # the fix in TOML's syntax ("set `joint:` to a defined joint" in a .toml file)
        fix = _in_toml(exc.fix, ())
        raise ModelFileError(exc.source, exc.key, exc.problem, fix, exc.line) from None
    return cfg


def _check_unique_names(cfg: ModelFile, source: str, nodes: Any) -> None:
    """Bolts, loads, supports, stabilisation trials and stages are reported by
    name: two of one name would be one row (found by fuzzing: two bolts named
    B1 were merged in the results).  Empty names are not compared (an unnamed
    bolt is named by its position)."""
    lists: list[tuple[Loc, list, str]] = [
        (("bolts",), cfg.bolts, "bolt"),
        (("loads", "points"), cfg.loads.points, "point load"),
        (("loads", "lines"), cfg.loads.lines, "line load"),
        (("supports",), cfg.supports, "support"),
        (("stabilisation", "trials"), cfg.stabilisation.trials, "trial"),
        (("stabilisation", "stages"), cfg.stabilisation.stages, "stage"),
    ]
    for where, items, label in lists:
        first: dict[str, int] = {}
        for i, item in enumerate(items):
            if not item.name:
                continue
            if item.name in first:
                loc: Loc = (*where, i, "name")
                problem = (
                    f"{item.name!r} is already the name of {_keypath((*where, first[item.name]))}"
                )
                fix = f"give each {label} its own name"
                raise ModelFileError(source, _keypath(loc), problem, fix, _line(nodes, loc))
            first[item.name] = i


def _check_units(cfg: ModelFile, source: str, nodes: Any) -> None:
    """The ``units`` note labels every number printed: it must be one
    consistent system (rockdem computes in the units of the numbers given)."""
    from ..units import contradiction

    problem = contradiction(cfg.units)
    if problem is not None:
        fix = "state one consistent system, for example `kN, m, kPa` or `MN, m, MPa`"
        raise ModelFileError(source, "units", problem, fix, _line(nodes, ("units",)))


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


def _annotation_at(loc: Loc) -> tuple[Any, list]:
    """The annotation of the value at ``loc`` in :class:`ModelFile` (None if unknown),
    and the constraints pydantic took out of it (for a field)."""
    tp: Any = ModelFile
    meta: list = []
    for part in loc:
        tp = _unwrap(tp)
        meta = []
        if isinstance(tp, type) and issubclass(tp, BaseModel):
            field = tp.model_fields.get(str(part))
            if field is None:
                return None, []
            tp, meta = field.annotation, list(field.metadata)
        elif typing.get_origin(tp) is dict:
            tp = typing.get_args(tp)[1]
        elif typing.get_origin(tp) in (list, tuple):
            tp = typing.get_args(tp)[0]
        else:
            return None, []
    return tp, meta


def _type_at(loc: Loc) -> Any:
    """The annotation of the value at ``loc`` in :class:`ModelFile` (None if unknown)."""
    tp, _ = _annotation_at(loc)
    return None if tp is None else _unwrap(tp)


def _bounds(loc: Loc) -> dict[str, float]:
    """The range constraints (gt, ge, lt, le) of the value at ``loc``."""
    tp, items = _annotation_at(loc)
    todo = [tp]
    while todo:
        t = todo.pop()
        origin = typing.get_origin(t)
        if origin is Annotated:
            args = typing.get_args(t)
            todo.append(args[0])
            items.extend(args[1:])
        elif origin in (typing.Union, types.UnionType):
            todo.extend(typing.get_args(t))
    out: dict[str, float] = {}
    for item in items:
        for c in item.metadata if isinstance(item, FieldInfo) else [item]:
            for attr in ("gt", "ge", "lt", "le"):
                value = getattr(c, attr, None)
                if isinstance(value, int | float):
                    out[attr] = value
    return out


def _range(loc: Loc, kind: str, bound: Any) -> str:
    """``give a value >= lo and <= hi``: the whole range of the key, not only the side
    that was crossed."""
    ops = {"gt": ">", "ge": ">=", "lt": "<", "le": "<="}
    found = _bounds(loc)
    key = {
        "greater_than": "gt",
        "greater_than_equal": "ge",
        "less_than": "lt",
        "less_than_equal": "le",
    }[kind]
    found.setdefault(key, bound)
    parts = [
        f"{ops[k]} {found[k]}" if isinstance(found[k], int) else f"{ops[k]} {found[k]:g}"
        for k in ("gt", "ge", "lt", "le")
        if k in found
    ]
    return "give a value " + " and ".join(parts)


def _field_doc(loc: Loc) -> str:
    document_keys()
    parent = _type_at(loc[:-1])
    if isinstance(parent, type) and issubclass(parent, BaseModel):
        field = parent.model_fields.get(str(loc[-1]))
        if field is not None and field.description:
            # its first sentence (a period then a space or the end: not the
            # dots of `[[x, y], ...]`, which cut "Outline `[[x, y], " short)
            return re.split(r"\.(?:\s|$)", field.description)[0].replace("\n", " ")
    return ""


def _describe(err: dict) -> tuple[Loc, str, str]:
    """(loc, problem, fix) for one pydantic error."""
    loc: Loc = tuple(p for p in err["loc"] if not _is_internal(p))
    kind = err["type"]
    value = err.get("input")
    ctx = err.get("ctx") or {}
    shown = repr(value) if isinstance(value, str) else _short(value)
    if "[key]" in err["loc"] or kind == "invalid_key":  # a key that is no name (`null:`, `12:`)
        key = loc[-1] if loc else None
        key = "null" if key in (None, "None") else key  # pydantic names a null key 'None'
        fix = "write a name (in quotes if it is a number)"
        return loc[:-1], f"a key must be a name, got `{key}`", fix
    if kind == "extra_forbidden":
        allowed = _allowed_keys(loc)
        close = _meant_key(loc, allowed)
        fix = f"did you mean `{close}`?" if close else f"allowed keys: {', '.join(allowed)}"
        return loc, "unknown key", fix
    if kind == "missing" and loc and isinstance(loc[-1], int) and _is_point(loc[:-1]):
        # a point with a coordinate missing (`origin: []`, a vertex `[x]`)
        return loc[:-1], "expected a point [x, y] with two numbers", "write [x, y]"
    if kind == "missing" and loc and isinstance(loc[-1], int):
        # an item of a fixed-length list (`inputs: [a]` for two inputs)
        tp = _type_at(loc[:-1])
        args = typing.get_args(tp) if typing.get_origin(tp) is tuple else ()
        count = len(args) if args and Ellipsis not in args else loc[-1] + 1
        got = len(value) if isinstance(value, list | tuple) else loc[-1]
        fix = "write both: [a, b]" if count == 2 else f"write all {count}: [a, b, ...]"
        return loc[:-1], f"expected {count} items, got {got}", fix
    if kind == "missing":
        doc = _field_doc(loc)
        fix = f"add `{loc[-1]}:`" + (f" ({doc})" if doc else "")
        return loc, "required key is missing", fix
    if kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
        bound = next(iter(ctx.values()))
        return loc, f"{shown} is out of range", _range(loc, kind, bound)
    if kind == "number_with_unit":
        fix = "write the bare number in the units stated in `units` (angles in degrees)"
        return loc, err["msg"], fix
    if kind == "geometry":
        fix = (
            "use `blocks:` (explicit polygons), `slope:` (a profile cut by joint sets) "
            "or `geometry: {dxf: FILE}` (a section drawn in CAD)"
        )
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
        got = ctx.get("actual_length")
        if got is None:  # pydantic stops counting a mapping at the first one too many
            got = len(value) if hasattr(value, "__len__") else f"more than {n}"
        return loc, f"has {got} items", f"give {word} {n}"
    if kind == "format_bool":
        return loc, err["msg"], "write `format: 1` (or leave it out)"
    if kind in ("value_error", "assertion_error"):
        msg = err["msg"].removeprefix("Value error, ")
        section = str(loc[0]) if loc else ""
        where = f"docs/file-format.md, `{section}`" if section else "docs/file-format.md"
        return loc, msg, f"see {where}"
    return loc, err["msg"], "see docs/file-format.md"


def _allowed_keys(loc: Loc) -> list[str]:
    """The keys the format allows beside the key at ``loc``."""
    parent = _type_at(loc[:-1])
    return list(parent.model_fields) if isinstance(parent, type) else []


def _meant_key(loc: Loc, allowed: list[str]) -> str | None:
    """The allowed key the unknown key at ``loc`` is likely a misspelling of."""
    close = difflib.get_close_matches(str(loc[-1]), allowed, n=1, cutoff=0.6)
    return close[0] if close else None


def _is_internal(part: Any) -> bool:
    return isinstance(part, str) and ("[" in part or part.startswith("function-"))


def _is_point(loc: Loc) -> bool:
    """The format has a pair of numbers at ``loc`` (a pair of names is no point:
    a correlation's three inputs were asked for as ``[x, y]``)."""
    tp = _type_at(loc)
    args = typing.get_args(tp)
    return typing.get_origin(tp) is tuple and str not in args


def _short(value: Any) -> str:
    text = repr(value)
    if isinstance(value, bool) or value is None:
        text = {True: "true", False: "false", None: "null"}[value]
    return text if len(text) <= 40 else text[:37] + "..."


#: the fixes _describe words in YAML, as they read in TOML
TOML_FIXES = {
    "write `key: value` lines indented under it": (
        "write it as a table: a [{path}] header (or [{path}.NAME] ones) above `key = value` lines"
    ),
    "write [a, b, ...] or `- ` items": "write [a, b, ...] or [[{path}]] tables",
}


def _in_toml(fix: str, loc: Loc) -> str:
    """A fix of :func:`_describe` in TOML's syntax."""
    path = ".".join(str(p) for p in loc if not isinstance(p, int)) or "table"
    for yaml, toml in TOML_FIXES.items():
        fix = fix.replace(yaml, toml.format(path=path))
    # `friction_angle:` -> `friction_angle = ...`, wherever the fix names a key
    return re.sub(r"`([A-Za-z_][\w.]*):`", r"`\1 = ...`", fix)


def _from_validation(
    exc: ValidationError, source: str, nodes: Any, toml: bool = False
) -> ModelFileError:
    errors = exc.errors(include_url=False)
    # report the most specific error first (deepest key path), and an unknown key
    # before the missing key it is a misspelling of: the cause before its
    # consequence (found by fuzzing: `friction_angel: 30` was reported only as
    # "friction_angle: required key is missing")
    missing = {e["loc"] for e in errors if e["type"] == "missing"}

    def misspelt(e: dict) -> bool:
        if e["type"] != "extra_forbidden":
            return False
        loc = tuple(p for p in e["loc"] if not _is_internal(p))
        meant = _meant_key(loc, _allowed_keys(loc))
        return meant is not None and (*e["loc"][:-1], meant) in missing

    errors.sort(key=lambda e: (-len(e["loc"]), not misspelt(e)))
    err = errors[0]
    loc, problem, fix = _describe(err)
    if toml:
        fix = _in_toml(fix, loc)
    # the same problem reported twice (both coordinates of a short point) is one
    others = len({(d[0], d[1]) for d in map(_describe, errors)} - {(loc, problem)})
    if others:
        fix += f" ({others} more problem{'s' if others > 1 else ''} in the file)"
    line = _line(nodes, loc)
    if "[key]" in err["loc"] or err["type"] == "invalid_key":  # the bad key's own line
        line = _line(nodes, tuple(p for p in err["loc"] if not _is_internal(p))) or line
    return ModelFileError(source, _keypath(loc) or "(top level)", problem, fix, line)


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
            if (
                not b.fixed
                and b.material is None
                and b.unit_weight is None
                and len(cfg.materials) != 1
            ):
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
            fail(
                ("remove", "profile"),
                "is for generated slopes",
                "use `remove.regions` or `remove.blocks` with explicit blocks",
            )
        for k, bid in enumerate(cfg.remove.blocks):
            if bid not in ids:
                fail(("remove", "blocks", k), f"no block has id {bid}", "use an id of `blocks`")
    if cfg.geometry is not None:
        g = cfg.geometry
        material(("geometry", "material"), g.material)
        if g.material is not None and g.unit_weight is not None:
            fail(("geometry",), "has both `material` and `unit_weight`", "give only one")
        if g.material is None and g.unit_weight is None and len(cfg.materials) != 1:
            fail(
                ("geometry",),
                "no unit weight for the blocks",
                "give `material:` or `unit_weight:` (or define exactly one material)",
            )
        for layer, name in (g.layers.joints or {}).items():
            joint(("geometry", "layers", "joints", layer), name)
        if cfg.remove.profile is not None:
            fail(
                ("remove", "profile"),
                "is for generated slopes",
                "use `remove.regions` or `remove.blocks` with a drawn section",
            )
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
