"""Reading model files: YAML or TOML text to plain data, and the whole way to a model."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path
from typing import Any

import yaml

from .build import build_model
from .errors import Loc, ModelFileError, _keypath, _kind
from .spec import ModelFile
from .validate import validate_document

#: File suffixes read as TOML; everything else is read as YAML (JSON is YAML).
TOML_SUFFIXES = (".toml",)


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
            if exc.context and start is not None and line is not None and start.line + 1 != line:
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


def parse_model(text: str, *, fmt: str = "yaml", source: str = "<string>") -> tuple[Any, ModelFile]:
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
