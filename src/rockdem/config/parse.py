"""Reading model files: YAML or TOML text to plain data, and the whole way to a model.

Reading is bounded, whatever the file holds:

* only a regular file is read (not a folder, a named pipe or a device such as
  ``/dev/zero``), of at most :data:`MAX_FILE_BYTES`;
* UTF-8, with or without a byte-order mark;
* YAML is read with the YAML 1.2 core schema (as JSON): ``1e6`` is a
  number, ``2_5``, ``1:30`` and ``yes`` are text, ``010`` is ten;
* a YAML document may nest at most ``MAX_DEPTH`` levels and hold at most
  ``MAX_NODES`` values *with its aliases expanded* (:mod:`.yaml_read`); an alias may not refer
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
from typing import Any

import yaml

from ..geometry.size import MAX_BLOCKS
from .build import build_model
from .errors import Loc, ModelFileError, _keypath, _kind, _line
from .spec import ModelFile
from .toml_lines import TomlLines
from .validate import validate_document
from .yaml_read import MAX_DEPTH, _check_depth, _load_yaml

#: File suffixes read as TOML; everything else is read as YAML (JSON is YAML too).
TOML_SUFFIXES = (".toml",)
#: Largest model file read, in bytes (a 100,000-block model is about 8 MB).
MAX_FILE_BYTES = 32 * 2**20


def read_document(path: str | Path) -> tuple[dict, Any]:
    """Parse a model file into plain data.

    Returns
    -------
    data : dict
    nodes : yaml.Node or TomlLines
        Where the keys are, for line numbers: the YAML node tree, or a
        :class:`.toml_lines.TomlLines` of a TOML file.

    Raises
    ------
    ModelFileError
        The file cannot be read or parsed, is not a regular file of at most
        :data:`MAX_FILE_BYTES`, or is not a mapping of keys.
    """
    path = Path(path)
    source = str(path)
    if path.suffix.lower() == ".dxf":  # (a study's --spec said "the top level is a string")
        raise ModelFileError(
            source,
            "",
            "is a DXF drawing, not a model file",
            f"make a model of it with `rockdem import {path.name} --out model.yaml`, or name "
            f"it in a model file (`geometry: {{dxf: {path.name}}}`)",
        )
    if path.suffix.lower() in (".py", ".pyw", ".ipynb"):  # it parsed as YAML: "a string"
        raise ModelFileError(
            source,
            "",
            "is a Python script, not a model file",
            f"run it with `python {path.name}` (a model built in Python is analysed there: "
            "rockdem.analyse, rockdem.factor_of_safety), or give a .yaml, .json or .toml file",
        )
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


def _check_keys(data: dict, source: str, nodes: Any = None) -> None:
    """Refuse control characters in every key, in the ``units`` note and in
    every ``name`` (the
    model's, a bolt's, a support's, a load's: printed in tables and reports;
    fuzzing: a bolt named "B1\\nFAKE LINE\\x1b[31m" wrote a line of its own and
    coloured the terminal).  Each is named at its line (hostile round 7: the
    line was left out)."""
    units = data.get("units") if isinstance(data, dict) else None
    if isinstance(units, str) and _CONTROL.search(units):
        # (hostile testing: an escape in the note coloured the terminal in
        # every command's header; a line break split it)
        raise ModelFileError(
            source,
            "units",
            f"the note {units!r} holds a control character (a line break, tab or escape)",
            "write the units on one line, for example 'kN, m, kPa'",
            _line(nodes, ("units",)),
        )
    todo: list[tuple[Any, Loc]] = [(data, ())]
    while todo:
        item, loc = todo.pop()
        if isinstance(item, dict):
            for key in item:
                _check_name(key, source, line=_line(nodes, (*loc, key)))
            if isinstance(item.get("name"), str):
                where = (*loc, "name")
                _check_name(item["name"], source, _keypath(where), _line(nodes, where))
            todo.extend((v, (*loc, k)) for k, v in item.items())
        elif isinstance(item, list):
            todo.extend((v, (*loc, i)) for i, v in enumerate(item))


#: control characters (line breaks, escapes): never in a key or a name, which
#: are printed in tables, CSV headings and DXF layers (an escape would drive
#: the terminal)
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f\u2028\u2029]")


def _check_name(key: Any, source: str, where: str | None = None, line: int | None = None) -> None:
    if isinstance(key, str) and _CONTROL.search(key):
        raise ModelFileError(
            source,
            where or "",
            f"the {'name' if where else 'key'} {key!r} holds a control character "
            "(a line break, tab or escape)",
            "use letters, digits, spaces, '-' and '_'",
            line,
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
        nodes = TomlLines(text)  # scanned only if a line is asked for
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
    _check_keys(data, source, nodes)
    return data, nodes


def parse_model(
    text: str,
    *,
    fmt: str = "yaml",
    source: str = "<string>",
    max_blocks: int | None = MAX_BLOCKS,
) -> tuple[Any, ModelFile]:
    """Model and validated file from the text of a model file."""
    data, nodes = parse_document(text, fmt=fmt, source=source)
    cfg = validate_document(data, source=source, nodes=nodes, fmt=fmt)
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
