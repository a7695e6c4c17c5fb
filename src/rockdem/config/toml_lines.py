"""Line numbers of the keys of a TOML model file, for its error messages.

``tomllib`` gives plain data without positions, so an error found after
parsing (validation, the cross-references, building the model) could name a
TOML file's key path but not its line, where a YAML file's error names both
(:func:`.errors._line` walks the YAML node tree).  :class:`TomlLines` scans
the text of a file that ``tomllib`` has read and records, for every key path
(str keys and int array indices, as in a pydantic error's ``loc``), the line
where the key or the array element starts: table headers ``[a.b]`` and
``[[a]]`` (numbered per array, also when nested), dotted and quoted keys,
inline tables, arrays, and the four kinds of string (a ``[``, ``#`` or ``=``
inside a string is skipped with it).  ``tomlkit`` keeps no positions.

The text is scanned only when a line is asked for (an error or a warning),
so a large model costs nothing to read.  The scanner trusts the text to be
valid TOML; should it still meet something it does not expect, it keeps the
lines found so far (a message without its line, never a crash).
"""

from __future__ import annotations

import bisect
import re
import tomllib

Loc = tuple[str | int, ...]

_GAP = re.compile(r"(?:[ \t\r\n]|#[^\n]*)*")  # white space, line ends and comments
_SPACE = re.compile(r"[ \t]*")
_BARE = re.compile(r"[A-Za-z0-9_-]+")
_BASIC = re.compile(r'"(?:[^"\\\n]|\\.)*"')
_LITERAL = re.compile(r"'[^'\n]*'")
_ML_BASIC = re.compile(r'"""(?:[^"\\]|\\.|""?(?!"))*"{3,5}', re.S)
_ML_LITERAL = re.compile(r"'''(?:[^']|''?(?!'))*'{3,5}")
_SCALAR = re.compile(r"[^,\]}\n#]+")  # number, boolean, date and time


class TomlLines:
    """Where the keys of a TOML text are: ``line(loc)``, as :func:`.errors._line`."""

    def __init__(self, text: str) -> None:
        self._text = text
        self._lines: dict[Loc, int] | None = None

    def line(self, loc: Loc) -> int | None:
        """1-based line of the deepest prefix of ``loc`` in the file (a missing
        key: its table's line; an index past the end: the array's line)."""
        if self._lines is None:
            self._lines = {}
            try:
                _Scanner(self._text, self._lines).scan()
            except (ValueError, IndexError):  # pragma: no cover - not valid TOML
                pass
        for n in range(len(loc), 0, -1):
            if (found := self._lines.get(tuple(loc[:n]))) is not None:
                return found
        return self._lines.get(())


def toml_lines(text: str) -> dict[Loc, int]:
    """Every key path of a valid TOML text and its 1-based line."""
    lines: dict[Loc, int] = {}
    _Scanner(text, lines).scan()
    return lines


class _Scanner:
    def __init__(self, text: str, lines: dict[Loc, int]) -> None:
        self.text, self.pos, self.lines = text, 0, lines
        self.ends = [m.start() for m in re.finditer("\n", text)]
        self.count: dict[Loc, int] = {}  # tables so far of each array of tables

    def here(self) -> int:
        return bisect.bisect_left(self.ends, self.pos) + 1

    def skip(self, pattern: re.Pattern) -> None:
        self.pos = pattern.match(self.text, self.pos).end()

    def at(self, token: str) -> bool:
        """Past white space and comments, whether ``token`` comes next."""
        self.skip(_GAP)
        return self.text.startswith(token, self.pos)

    def take(self, token: str) -> None:
        if not self.text.startswith(token, self.pos):
            raise ValueError(f"expected {token!r} at {self.pos}")
        self.pos += len(token)

    def token(self, *patterns: re.Pattern) -> str:
        for pattern in patterns:
            if m := pattern.match(self.text, self.pos):
                self.pos = m.end()
                return m.group()
        raise ValueError(f"unexpected text at {self.pos}")

    def scan(self) -> None:
        table: Loc = ()
        while True:
            self.skip(_GAP)
            if self.pos == len(self.text):
                return
            line = self.here()
            self.lines.setdefault((), line)
            if self.text.startswith("[", self.pos):
                array = self.text.startswith("[[", self.pos)
                self.take("[[" if array else "[")
                table = self.header(self.key(), line, array)
                self.take("]]" if array else "]")
            else:
                self.value(self.define(table, self.key(), line), line)

    def key(self) -> list[str]:
        """A dotted key, its parts unquoted."""
        parts = []
        while True:
            self.skip(_SPACE)
            part = self.token(_BASIC, _LITERAL, _BARE)
            if part.startswith('"'):
                part = tomllib.loads(f"k = {part}")["k"]
            elif part.startswith("'"):
                part = part[1:-1]
            parts.append(part)
            self.skip(_SPACE)
            if not self.text.startswith(".", self.pos):
                return parts
            self.pos += 1

    def header(self, keys: list[str], line: int, array: bool) -> Loc:
        """The path of the table a header opens (into the last table of each
        array of tables on the way)."""
        path: Loc = ()
        for k in keys[:-1]:
            path = (*path, k)
            if path in self.count:
                path = (*path, self.count[path] - 1)
            self.lines.setdefault(path, line)
        path = (*path, keys[-1])
        if array:
            self.lines.setdefault(path, line)  # the array: its first table
            self.count[path] = self.count.get(path, 0) + 1
            path = (*path, self.count[path] - 1)
        self.lines[path] = line
        return path

    def define(self, table: Loc, keys: list[str], line: int) -> Loc:
        """``keys = `` in ``table``: the value's path, the cursor at the value."""
        path = table
        for k in keys:  # a dotted key defines its tables too
            path = (*path, k)
            self.lines.setdefault(path, line)
        self.take("=")
        self.skip(_SPACE)
        return path

    def value(self, path: Loc, start: int) -> None:
        """The value at ``path``, starting on line ``start``."""
        char = self.text[self.pos]
        if char == "{":
            self.pos += 1
            while not self.at("}"):
                line = self.here()
                self.value(self.define(path, self.key(), line), line)
                if self.at(","):
                    self.pos += 1
            self.pos += 1
        elif char == "[":
            self.pos += 1
            i = 0
            while not self.at("]"):
                line = self.here()
                if line != start:  # else the array's line serves (and a large
                    self.lines[(*path, i)] = line  # file's numbers cost nothing)
                self.value((*path, i), line)
                i += 1
                if self.at(","):
                    self.pos += 1
            self.pos += 1
        else:
            self.token(_ML_BASIC, _ML_LITERAL, _BASIC, _LITERAL, _SCALAR)
