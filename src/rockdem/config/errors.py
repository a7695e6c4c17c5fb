"""The error of a bad model file, and how a key path is named and found in the file."""

from __future__ import annotations

from typing import Any

import yaml

from ..errors import InputError
from .toml_lines import TomlLines


class ModelFileError(InputError):
    """Bad model file: names the file, the line, the key path, the problem and the fix.

    Parameters
    ----------
    source : str
        File name (or ``"<string>"``).
    key : str
        Key path in the file, for example ``"joints.bedding.friction_angle"``
        or ``"blocks[2].vertices"`` (empty for the whole file).
    problem, fix : str
        What is wrong, and what to do about it.
    line : int, optional
        1-based line of the key in the file.
    """

    def __init__(
        self, source: str, key: str, problem: str, fix: str = "", line: int | None = None
    ) -> None:
        self.source = source
        self.key = key
        self.line = line
        place = source if line is None else f"{source}:{line}"
        where = f"{place}: {key}" if key else place
        super().__init__(where, problem, fix)


Loc = tuple[str | int, ...]


def _keypath(loc: Loc) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out


def _line(nodes: Any, loc: Loc, *, key_line: bool = True) -> int | None:
    """1-based line of the key (or the value) at ``loc`` in the YAML node tree
    (or a TOML file's :class:`.toml_lines.TomlLines`)."""
    if nodes is None or not loc:
        return None
    if isinstance(nodes, TomlLines):
        return nodes.line(loc)
    node = nodes
    for part in loc:
        if isinstance(node, yaml.MappingNode):
            for k, v in node.value:
                if isinstance(k, yaml.ScalarNode) and k.value == str(part):
                    node = v
                    last_key = k
                    break
            else:
                return node.start_mark.line + 1
        elif isinstance(node, yaml.SequenceNode) and isinstance(part, int):
            if not 0 <= part < len(node.value):
                return node.start_mark.line + 1
            node = node.value[part]
            last_key = None
        else:
            break
    else:
        if key_line and loc and last_key is not None:
            return last_key.start_mark.line + 1
    return node.start_mark.line + 1


def _kind(value: Any) -> str:
    if isinstance(value, dict):
        return "mapping"
    if isinstance(value, list | tuple):
        return "list"
    if isinstance(value, str):
        return "string"
    if isinstance(value, bool):
        return "boolean"
    if value is None:
        return "null"
    return type(value).__name__
