"""YAML read safely: the YAML 1.2 core schema on PyYAML's C loader, and a
single bounded pass over the events before anything is built, so that a
file of too many values, or an alias "bomb", is refused before it is
expanded; repeated keys are refused too (PyYAML keeps the last silently).
"""

from __future__ import annotations

import re
from typing import Any, ClassVar

import yaml

from .errors import Loc, ModelFileError, _keypath

#: Deepest nesting of lists and mappings (a model needs 8).
MAX_DEPTH = 32

#: Most values (scalars, lists, mappings) in a document with its aliases expanded.
MAX_NODES = 4_000_000


_LoaderBase: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
_INT, _FLOAT, _BOOL, _TIME = (
    f"tag:yaml.org,2002:{t}" for t in ("int", "float", "bool", "timestamp")
)
_DEC_INT = re.compile(r"^[-+]?[0-9]+$")
_OCT_INT = re.compile(r"^0o[0-7]+$")
_HEX_INT = re.compile(r"^0x[0-9a-fA-F]+$")
_FLOAT_RE = re.compile(
    r"^[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?$"
    r"|^[-+]?\.(?:inf|Inf|INF)$|^\.(?:nan|NaN|NAN)$"
)


class _Loader(_LoaderBase):
    """Safe YAML with the YAML 1.2 core schema's numbers and booleans (as JSON has
    them), and no timestamps (YAML 1.1's: `name: 2001-12-14` was refused as a date)."""

    yaml_implicit_resolvers: ClassVar[dict] = {
        first: [(tag, rx) for tag, rx in rules if tag not in (_INT, _FLOAT, _BOOL, _TIME)]
        for first, rules in _LoaderBase.yaml_implicit_resolvers.items()
    }


def add_core_resolvers(cls) -> None:
    """Teach a PyYAML loader or dumper class the YAML 1.2 core schema's numbers
    and booleans: the reader resolves them, and a dumper given them quotes a
    string that would read back as one (found by fuzzing: `rockdem import
    --name 1e3` wrote `name: 1e3`, which its own reader took for 1000.0)."""
    cls.add_implicit_resolver(
        _BOOL, re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), list("tTfF")
    )
    cls.add_implicit_resolver(
        _INT, re.compile(r"^[-+]?[0-9]+$|^0o[0-7]+$|^0x[0-9a-fA-F]+$"), list("-+0123456789")
    )
    cls.add_implicit_resolver(_FLOAT, _FLOAT_RE, list("-+0123456789."))


add_core_resolvers(_Loader)


def _construct_int(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> int:
    value = str(loader.construct_scalar(node))
    if _DEC_INT.match(value):
        return int(value, 10)
    if _OCT_INT.match(value):
        return int(value[2:], 8)
    if _HEX_INT.match(value):
        return int(value[2:], 16)
    raise yaml.constructor.ConstructorError(
        None, None, f"{value!r} is not a whole number", node.start_mark
    )


def _construct_float(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> float:
    value = str(loader.construct_scalar(node))
    if _FLOAT_RE.match(value) or _DEC_INT.match(value):
        if value.lstrip("+-").startswith("."):
            low = value.lower()
            if low.endswith("inf"):
                return float("-inf") if low.startswith("-") else float("inf")
            if low.endswith("nan"):
                return float("nan")
        return float(value)
    raise yaml.constructor.ConstructorError(
        None, None, f"{value!r} is not a number", node.start_mark
    )


def _construct_bool(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> bool:
    return str(loader.construct_scalar(node)).lower() == "true"


_Loader.add_constructor(_INT, _construct_int)
_Loader.add_constructor(_FLOAT, _construct_float)
_Loader.add_constructor(_BOOL, _construct_bool)


def _check_yaml_bounds(text: str, source: str) -> None:
    """One pass over the YAML events: refuse deep nesting, self-referring aliases and
    documents that would hold more than :data:`MAX_NODES` values once expanded.

    Too many values are blamed on the key that holds them, and on aliases only
    when aliases gave most of them (found by fuzzing: a water table of 1.5
    million points, without an alias, was called an alias bomb)."""
    sizes: dict[str, int | None] = {}  # anchor -> expanded size (None while still open)
    # open collections: [expanded size so far, anchor, is a mapping, children so far,
    # the mapping's current key, its line, the line naming the collection, values
    # from aliases]
    stack: list[list] = []

    def fail(event: Any, problem: str, fix: str) -> None:
        raise ModelFileError(source, "", problem, fix, event.start_mark.line + 1)

    def too_many() -> None:
        path: list[str | int] = []
        for parent in stack[:-1]:
            key = parent[4] if parent[2] else parent[3] - 1
            if key is None:  # a key that is no scalar: the path ends here
                break
            path.append(key)
        top = stack[-1]
        if 2 * top[7] > top[0]:  # most of them from aliases
            problem = f"holds more than {MAX_NODES:,} values once its aliases are expanded"
            fix = "write the model without aliases that multiply (an alias bomb)"
        else:
            problem = f"holds more than {MAX_NODES:,} values"
            fix = (
                "a model needs far fewer: thin out its long lists (a water table or an "
                "outline needs tens or hundreds of points, not millions)"
            )
        raise ModelFileError(source, _keypath(tuple(path)), problem, fix, top[6])

    def child(event: Any) -> list | None:
        """Count ``event`` as a child of the innermost collection (its key, if the
        collection is a mapping and the event a key); that collection."""
        if not stack:
            return None
        top = stack[-1]
        if top[2] and not top[3] % 2:  # a key of a mapping
            top[4] = event.value if type(event) is yaml.ScalarEvent else None
            top[5] = event.start_mark.line + 1
        top[3] += 1
        return top

    scalar, alias = yaml.ScalarEvent, yaml.AliasEvent
    starts = (yaml.SequenceStartEvent, yaml.MappingStartEvent)
    ends = (yaml.SequenceEndEvent, yaml.MappingEndEvent)
    loader = _Loader(text)
    try:
        while loader.check_event():
            event = loader.get_event()
            kind = type(event)
            if kind is scalar:  # the most frequent: inline
                if event.anchor is not None:
                    sizes[event.anchor] = 1
                if stack:
                    top = stack[-1]
                    if top[2] and not top[3] % 2:  # a key of a mapping
                        top[4] = event.value
                        top[5] = event.start_mark.line + 1
                    top[3] += 1
                    top[0] += 1
                    if top[0] > MAX_NODES:
                        too_many()
            elif kind in starts:
                if len(stack) >= MAX_DEPTH:
                    fail(
                        event,
                        f"nests lists and mappings more than {MAX_DEPTH} deep",
                        "a model nests at most a few levels: check the brackets",
                    )
                if event.anchor is not None:
                    sizes[event.anchor] = None
                parent = child(event)
                line = parent[5] if parent and parent[2] else event.start_mark.line + 1
                mapping = kind is yaml.MappingStartEvent
                stack.append([1, event.anchor, mapping, 0, None, None, line, 0])
            elif kind in ends:
                size, anchor, *_, aliased = stack.pop()
                if anchor is not None:
                    sizes[anchor] = size
                if stack:
                    stack[-1][0] += size
                    stack[-1][7] += aliased
                    if stack[-1][0] > MAX_NODES:
                        too_many()
            elif kind is alias:
                parent = child(event)
                if event.anchor not in sizes:
                    continue  # undefined: the composer says so
                size = sizes[event.anchor]
                if size is None:
                    fail(
                        event,
                        f"the alias *{event.anchor} refers to the node it is part of",
                        "an alias must refer to a complete node defined before it",
                    )
                if parent is not None:
                    parent[0] += size
                    parent[7] += size
                    if parent[0] > MAX_NODES:
                        too_many()
    finally:
        loader.dispose()


def _load_yaml(text: str, source: str) -> tuple[Any, Any]:
    """(data, node tree) of a YAML document, within the bounds."""
    _check_yaml_bounds(text, source)
    loader = _Loader(text)
    try:
        nodes = loader.get_single_node()
        if nodes is None:
            return None, None
        _check_duplicates(nodes, source)  # before construction merges `<<` keys in
        return loader.construct_document(nodes), nodes
    finally:
        loader.dispose()


def _check_depth(data: Any, source: str) -> None:
    """Refuse data nested more than :data:`MAX_DEPTH` levels (iteratively: no recursion)."""
    todo = [(data, 1)]
    while todo:
        item, depth = todo.pop()
        if isinstance(item, dict | list):
            if depth > MAX_DEPTH:
                raise ModelFileError(
                    source,
                    "",
                    f"nests lists and tables more than {MAX_DEPTH} deep",
                    "a model nests at most a few levels: check the brackets",
                )
            values = item.values() if isinstance(item, dict) else item
            todo.extend((v, depth + 1) for v in values)


def _check_duplicates(root: Any, source: str) -> None:
    """PyYAML keeps the last of repeated keys silently; a repeated key is a mistake.

    Every node is visited once, however many aliases refer to it.
    """
    seen_nodes: set[int] = set()
    todo: list[tuple[Any, Loc]] = [(root, ())]
    while todo:
        node, path = todo.pop()
        if id(node) in seen_nodes:
            continue
        seen_nodes.add(id(node))
        if isinstance(node, yaml.MappingNode):
            seen: set[str] = set()
            children = []
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
                children.append((v, (*path, key)))
            todo.extend(reversed(children))  # in the order of the file
        elif isinstance(node, yaml.SequenceNode):
            todo.extend(reversed([(item, (*path, i)) for i, item in enumerate(node.value)]))
