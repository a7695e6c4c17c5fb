"""Bundled example models (every ``*.yaml`` file in this folder).

>>> "wedge-verification" in list_examples()
True
>>> example_path("wedge-verification").name
'wedge-verification.yaml'
"""

from __future__ import annotations

import os
import shutil
import tempfile
from importlib import resources
from pathlib import Path

from ..errors import InputError

__all__ = ["copy_example", "example_path", "example_summary", "list_examples"]

SUFFIX = ".yaml"


def _folder():
    return resources.files(__name__)


def list_examples() -> list[str]:
    """Names of the bundled examples (file names without ``.yaml``), sorted."""
    return sorted(
        p.name[: -len(SUFFIX)]
        for p in _folder().iterdir()
        if p.is_file() and p.name.endswith(SUFFIX)
    )


def example_path(name: str) -> Path:
    """Path of the bundled example ``name`` (with or without ``.yaml``).

    Raises
    ------
    InputError
        No example has that name.
    """
    stem = name[: -len(SUFFIX)] if name.endswith(SUFFIX) else name
    names = list_examples()
    if stem not in names:
        raise InputError(
            f"example {name!r}", "does not exist", f"use one of: {', '.join(names)}"
        )
    return Path(str(_folder().joinpath(stem + SUFFIX)))


def example_summary(name: str) -> str:
    """First comment line of an example (its one-line description)."""
    for line in example_path(name).read_text(encoding="utf-8").splitlines():
        if line.startswith("#"):
            return line.lstrip("#").strip()
        if line.strip():
            break
    return ""


def copy_example(name: str, folder: str | Path, *, overwrite: bool = False) -> Path:
    """Copy an example into ``folder`` (created if needed); returns the new file.

    Raises
    ------
    InputError
        No such example, or the file exists and ``overwrite`` is False.
    """
    src = example_path(name)
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise InputError(str(folder), "is not a folder", "give a folder to copy into")
    target = folder / src.name
    if target.is_dir():
        raise InputError(str(target), "is a folder", "copy into another folder")
    if os.path.lexists(target) and not overwrite:  # (a link too, even a broken one)
        raise InputError(str(target), "already exists", "use --overwrite to replace it")
    folder.mkdir(parents=True, exist_ok=True)
    # a complete copy beside it, then moved into place: replaces a link itself,
    # never the file it points to
    fd, tmp = tempfile.mkstemp(prefix=f".{src.stem}.", suffix=src.suffix, dir=folder)
    os.close(fd)
    try:
        shutil.copyfile(src, tmp)
        mask = os.umask(0o022)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)
        os.replace(tmp, target)
    finally:
        if os.path.lexists(tmp):
            os.unlink(tmp)
    return target
