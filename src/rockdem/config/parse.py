"""Reading model files: YAML or TOML text to plain data, and the whole way to a model.

Reading is bounded, whatever the file holds:

* only a regular file is read (not a folder, a named pipe or a device such as
  ``/dev/zero``), of at most :data:`MAX_FILE_BYTES`;
* UTF-8, with or without a byte-order mark;
* YAML is read with the YAML 1.2 core schema (as JSON): ``1e6`` is a
  number, ``2_5``, ``1:30`` and ``yes`` are text, ``010`` is ten;
* a YAML document may nest at most :data:`MAX_DEPTH` levels and hold at most
  :data:`MAX_NODES` values *with its aliases expanded*; an alias may not refer
  to the node it is part of.  Anchors and aliases are allowed within these
  bounds (to share joint properties, say), so an alias "bomb" is refused
  after a single pass over the file, before anything is expanded.
"""

from __future__ import annotations

import os
import re
import stat
import tomllib
from pathlib import Path
from typing import Any, ClassVar

import yaml

from ..geometry.size import MAX_BLOCKS
from .build import build_model
from .errors import Loc, ModelFileError, _keypath, _kind
from .spec import ModelFile
from .validate import validate_document

#: File suffixes read as TOML; everything else is read as YAML (JSON is YAML too).
TOML_SUFFIXES = (".toml",)
#: Largest model file read, in bytes (a 100,000-block model is about 8 MB).
MAX_FILE_BYTES = 32 * 2**20
#: Deepest nesting of lists and mappings (a model needs 8).
MAX_DEPTH = 32
#: Most values (scalars, lists, mappings) in a document with its aliases expanded.
MAX_NODES = 4_000_000


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
        The file cannot be read or parsed, is not a regular file of at most
        :data:`MAX_FILE_BYTES`, or is not a mapping of keys.
    """
    path = Path(path)
    source = str(path)
    raw = read_bounded(path, source)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ModelFileError(
            source, "", f"is not UTF-8 text ({exc.reason})", "save it as UTF-8 text"
        ) from None
    fmt = "toml" if path.suffix.lower() in TOML_SUFFIXES else "yaml"
    return parse_document(text, fmt=fmt, source=source)


def read_bounded(path: Path, source: str, limit: int = MAX_FILE_BYTES) -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes.

    Opened without blocking (a named pipe is refused, not waited on), checked
    to be a regular file, then read no further than ``limit``.
    """
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except FileNotFoundError:
        raise ModelFileError(source, "", "file not found", "check the path") from None
    except IsADirectoryError:
        raise ModelFileError(source, "", "is a folder", "give a model file") from None
    except OSError as exc:
        raise ModelFileError(
            source, "", f"cannot be read ({exc.strerror})", "check the path and permissions"
        ) from None
    try:
        info = os.fstat(fd)
    except OSError:
        os.close(fd)
        raise
    if not stat.S_ISREG(info.st_mode) or info.st_size > limit:
        os.close(fd)
        if stat.S_ISDIR(info.st_mode):
            raise ModelFileError(source, "", "is a folder", "give a model file")
        if stat.S_ISREG(info.st_mode):
            raise _too_large(source, limit)
        raise ModelFileError(
            source,
            "",
            "is not a regular file (a pipe, socket or device)",
            "save the model to a file and give its path",
        )
    with os.fdopen(fd, "rb") as fh:
        try:
            raw = fh.read(limit + 1)
        except OSError as exc:
            raise ModelFileError(source, "", f"cannot be read ({exc.strerror})", "") from None
    if len(raw) > limit:
        raise _too_large(source, limit)
    return raw


def _too_large(source: str, limit: int) -> ModelFileError:
    return ModelFileError(
        source,
        "",
        f"is larger than {limit / 2**20:g} MiB, the limit of a model file",
        "give the model file itself (not a result or a data file)",
    )


# ------------------------------------------------------------------ YAML
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


_Loader.add_implicit_resolver(
    _BOOL, re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), list("tTfF")
)
_Loader.add_implicit_resolver(
    _INT, re.compile(r"^[-+]?[0-9]+$|^0o[0-7]+$|^0x[0-9a-fA-F]+$"), list("-+0123456789")
)
_Loader.add_implicit_resolver(_FLOAT, _FLOAT_RE, list("-+0123456789."))


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


def _check_keys(data: dict, source: str) -> None:
    """Refuse control characters in every key and in every ``name`` (the
    model's, a bolt's, a support's, a load's: printed in tables and reports;
    fuzzing: a bolt named "B1\\nFAKE LINE\\x1b[31m" wrote a line of its own and
    coloured the terminal)."""
    todo: list[tuple[Any, str]] = [(data, "")]
    while todo:
        item, path = todo.pop()
        if isinstance(item, dict):
            for key in item:
                _check_name(key, source)
            if isinstance(item.get("name"), str):
                _check_name(item["name"], source, f"{path}.name" if path else "name")
            todo.extend((v, f"{path}.{k}" if path else str(k)) for k, v in item.items())
        elif isinstance(item, list):
            todo.extend((v, f"{path}[{i}]") for i, v in enumerate(item))


#: control characters (line breaks, escapes): never in a key or a name, which
#: are printed in tables, CSV headings and DXF layers (an escape would drive
#: the terminal)
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f\u2028\u2029]")


def _check_name(key: Any, source: str, where: str | None = None) -> None:
    if isinstance(key, str) and _CONTROL.search(key):
        raise ModelFileError(
            source,
            where or "",
            f"the {'name' if where else 'key'} {key!r} holds a control character "
            "(a line break, tab or escape)",
            "use letters, digits, spaces, '-' and '_'",
        )


def _too_many_digits(text: str, source: str) -> ModelFileError:
    """A number longer than Python converts (4,300 digits): where it is."""
    m = re.search(r"\d{1000,}", text)
    line = text[: m.start()].count("\n") + 1 if m else None
    return ModelFileError(
        source,
        "",
        "a number has thousands of digits (more than Python reads as an integer)",
        "write it in scientific notation (e.g. 1e300) or correct it",
        line,
    )


def parse_document(text: str, *, fmt: str = "yaml", source: str = "<string>") -> tuple[dict, Any]:
    """Parse the text of a model file (see :func:`read_document`)."""
    text = text.removeprefix("\ufeff")
    if len(text) > MAX_FILE_BYTES:
        raise _too_large(source, MAX_FILE_BYTES)
    try:
        return _parse_document(text, fmt, source)
    except ValueError as exc:
        if "integer string conversion" in str(exc):
            raise _too_many_digits(text, source) from None
        raise


def _parse_document(text: str, fmt: str, source: str) -> tuple[dict, Any]:
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
        except RecursionError:
            raise ModelFileError(
                source,
                "",
                f"nests arrays or tables more than {MAX_DEPTH} deep",
                "a model nests at most a few levels: check the brackets",
            ) from None
        _check_depth(data, source)
    else:
        try:
            data, nodes = _load_yaml(text, source)
        except yaml.MarkedYAMLError as exc:
            mark = exc.problem_mark or exc.context_mark
            line = mark.line + 1 if mark is not None else None
            problem = (exc.problem or exc.context or "syntax error").strip()
            if "nesting depth" in problem:  # libyaml's own limit (PyYAML >= 6.0.4)
                raise ModelFileError(
                    source,
                    "",
                    f"nests lists and mappings more than {MAX_DEPTH} deep",
                    "a model nests at most a few levels: check the brackets",
                    line,
                ) from None
            start = exc.context_mark
            if exc.context and start is not None and line is not None and start.line + 1 != line:
                problem += f" ({exc.context} started at line {start.line + 1})"
            raise ModelFileError(
                source,
                "",
                f"not valid YAML: {problem}",
                "check the indentation, colons and brackets",
                line,
            ) from None
        except yaml.reader.ReaderError as exc:  # a character YAML does not allow
            line = text[: exc.position].count("\n") + 1
            raise ModelFileError(
                source,
                "",
                f"not valid YAML: character #x{exc.character:04x} is not allowed "
                "(a control character)",
                "delete it (retype the line)",
                line,
            ) from None
        except yaml.YAMLError as exc:
            one_line = " ".join(str(exc).split())
            problem = f"not valid YAML: {one_line}"
            raise ModelFileError(source, "", problem, "fix the syntax") from None
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
    _check_keys(data, source)
    return data, nodes


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


def parse_model(
    text: str,
    *,
    fmt: str = "yaml",
    source: str = "<string>",
    max_blocks: int | None = MAX_BLOCKS,
) -> tuple[Any, ModelFile]:
    """Model and validated file from the text of a model file."""
    data, nodes = parse_document(text, fmt=fmt, source=source)
    cfg = validate_document(data, source=source, nodes=nodes)
    return build_model(cfg, source=source, nodes=nodes, max_blocks=max_blocks), cfg


def load_model(path: str | Path, *, max_blocks: int | None = MAX_BLOCKS) -> tuple[Any, ModelFile]:
    """Read, validate and build a model file.

    Parameters
    ----------
    path : str or Path
        A ``.yaml``/``.yml``/``.json`` or ``.toml`` model file.
    max_blocks : int or None
        Refuse a model of more blocks than this before building it (see
        :mod:`rockdem.geometry.size`); None: no limit.

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
    return build_model(cfg, source=str(path), nodes=nodes, max_blocks=max_blocks), cfg
