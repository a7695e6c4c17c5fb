"""Key paths into a model file: ``joints.bedding.friction_angle``, ``blocks[3].unit_weight``,
``loads.water_table[*][1]`` (``[*]``: every item of a list, for example the level of
every point of a water table).

A path is resolved once against the parsed file (every name and index must
exist, or, for the last name, be a number key the format knows), then a
sample is applied by setting the value at each resolved place in a copy of
the parsed data; the copy goes through the normal validation and build.
"""

from __future__ import annotations

import copy
import difflib
import re
from typing import Any

from pydantic import BaseModel

from ..config.errors import Loc, ModelFileError, _keypath, _kind
from ..config.validate import _type_at

_PART = re.compile(r"\[(\*|\d+)\]|([^.\[\]]+)")


def parse_path(path: str) -> list[str | int]:
    """The parts of a key path (names, list indices, ``"*"``), or ValueError."""
    text = path.strip()
    parts: list[str | int] = []
    pos = 0
    while pos < len(text):
        if parts and text[pos] == "." and not text.startswith("[", pos):
            pos += 1
            if pos == len(text) or text[pos] in ".[":
                raise ValueError("a name is missing after a `.`")
        elif parts and text[pos] != "[":
            raise ValueError(f"unexpected {text[pos]!r}")
        m = _PART.match(text, pos)
        if m is None:
            raise ValueError(f"unexpected {text[pos]!r} (names are joined by `.`; indices `[2]`)")
        if m.group(1) is not None:
            if not parts:
                raise ValueError("a path starts with a key name")
            parts.append("*" if m.group(1) == "*" else int(m.group(1)))
        else:
            parts.append(m.group(2).strip())
        pos = m.end()
    if not parts:
        raise ValueError("the path is empty")
    return parts


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _is_section(tp: Any) -> bool:
    return isinstance(tp, type) and issubclass(tp, BaseModel)


def _numeric_type(loc: Loc) -> type | None:
    """``float`` or ``int`` if the format has a number at ``loc`` (None otherwise)."""
    tp = _type_at(loc)
    return tp if tp in (float, int) else None


def is_integer_key(loc: Loc) -> bool:
    """The format takes a whole number at ``loc`` (a seed, a count, an id)."""
    return _type_at(loc) is int


def _all_defaults(section: type) -> bool:
    """A section the file may leave out: it has no required key (`loads`,
    `analysis`), unlike `slope`, which is a geometry of its own."""
    return not any(field.is_required() for field in section.model_fields.values())


def resolve(doc: dict, path: str) -> list[Loc]:
    """The places in ``doc`` a key path names (several with ``[*]``).

    Raises
    ------
    ValueError
        With a one-line reason (the caller names the file and the path).
    """
    parts = parse_path(path)
    if parts[0] == "study":
        raise ValueError("the study cannot vary itself")
    found: list[Loc] = []

    def walk(node: Any, rest: list[str | int], loc: Loc) -> None:
        if not rest:
            if not _is_number(node):
                raise ValueError(f"`{_keypath(loc)}` is a {_kind(node)}, not a number")
            found.append(loc)
            return
        part, more = rest[0], rest[1:]
        if part == "*" or isinstance(part, int):
            if not isinstance(node, list):
                raise ValueError(f"`{_keypath(loc)}` is a {_kind(node)}, not a list")
            if part == "*":
                if not node:
                    raise ValueError(f"`{_keypath(loc)}` is an empty list")
                for i, item in enumerate(node):
                    walk(item, more, (*loc, i))
                return
            if not 0 <= part < len(node):
                raise ValueError(
                    f"`{_keypath(loc)}` has {len(node)} items: no index [{part}] "
                    f"(use 0 to {len(node) - 1})"
                )
            walk(node[part], more, (*loc, part))
            return
        if not isinstance(node, dict):
            raise ValueError(f"`{_keypath(loc)}` is a {_kind(node)}, not a mapping of keys")
        if part in node:
            walk(node[part], more, (*loc, part))
            return
        here = (*loc, part)
        parent = _type_at(loc)
        if _is_section(parent) and part in parent.model_fields:  # a key the file leaves out
            if not more and _numeric_type(here) is not None:
                found.append(here)  # a number at its default
                return
            section = _type_at(here)
            if more and _is_section(section) and _all_defaults(section):
                walk({}, more, here)  # a section at its defaults
                return
            if more and _is_section(section):  # (found by fuzzing: slope.seed on blocks)
                raise ValueError(
                    f"the file has no `{_keypath(here)}` section, so `{path}` does nothing "
                    "in this model"
                )
            raise ValueError(
                f"`{_keypath(here)}` is not in the file"
                + (": write it there to vary its items" if more else " and is not a number")
            )
        known = list(node)
        if _is_section(parent):
            known += [k for k in parent.model_fields if k not in node and k != "study"]
        close = difflib.get_close_matches(str(part), [str(k) for k in known], n=1, cutoff=0.6)
        where = f"`{_keypath(loc)}`" if loc else "the file"
        hint = f" (did you mean `{close[0]}`?)" if close else ""
        # (found by hostile testing: a joint named `a.b` read "`joints` has no
        # key `a`", though the file has it: a path cannot name it)
        split = [str(k) for k in node if re.match(rf"{re.escape(str(part))}\s*[.\[]", str(k))]
        if split:
            hint = (
                f" (the key `{split[0]}` holds a `.` or `[`, which a key path reads as a "
                "separator: rename it to vary it)"
            )
        raise ValueError(f"{where} has no key `{part}`{hint}")

    walk(doc, parts, ())
    return found


def check_paths(doc: dict, names: list[str], section: str, source: str, nodes: Any) -> list:
    """Resolve every input's key path; a bad one is a :class:`ModelFileError` naming it."""
    from ..config.errors import _line

    out = []
    owner: dict[Loc, str] = {}  # each number of the model is set by one input
    for name in names:
        loc = ("study", section, name)
        try:
            places = resolve(doc, name)
        except ValueError as exc:
            raise ModelFileError(
                source,
                f"study.{section}.{name}",
                f"no such number in the model: {exc}",
                "name a number key of this file by its path, for example "
                "`joints.bedding.friction_angle` or `loads.water_table[*][1]`",
                _line(nodes, loc),
            ) from None
        for place in places:  # found by fuzzing: the later input won, silently
            other = owner.setdefault(place, name)
            if other != name:
                raise ModelFileError(
                    source,
                    f"study.{section}.{name}",
                    f"sets `{_keypath(place)}`, which `{other.strip()}` sets too "
                    "(only one of them would be used)",
                    "vary each number of the model by one input: remove one of the two",
                    _line(nodes, loc),
                )
        out.append(places)
    return out


def apply(doc: dict, places: list[list[Loc]], values) -> dict:
    """A copy of ``doc`` with ``values[k]`` set at every place of input ``k``."""
    new = copy.deepcopy(doc)
    for locs, value in zip(places, values, strict=True):
        for loc in locs:
            node: Any = new
            for part in loc[:-1]:
                if isinstance(node, dict) and part not in node:
                    node[part] = {}
                node = node[part]
            node[loc[-1]] = value
    return new
