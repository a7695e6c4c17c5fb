"""Writing one output file all or nothing: to a temporary file beside it, then moved
into place (never over an existing file without ``--overwrite``)."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _check_new_file(target: Path, option: str, overwrite: bool) -> None:
    from ..errors import InputError

    if target.is_dir():
        raise InputError(f"{option} {target}", "is a folder", "give a file name")
    if target.exists() and not overwrite:
        raise InputError(
            f"{option} {target}", "exists already", "use --overwrite to replace it, or another name"
        )


def _replace(tmp: Path, target: Path, option: str, overwrite: bool) -> None:
    """Move a complete file into place (atomic on one file system)."""
    _check_new_file(target, option, overwrite)  # it may have appeared meanwhile
    os.chmod(tmp, 0o666 & ~_umask())
    os.replace(tmp, target)


def _save_file(target: Path, overwrite: bool, write: Callable[[Path], Any]) -> Path:
    """Write through ``write(tmp)`` to a temporary file beside ``target``, then move it."""
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(prefix=f".{target.stem}.", suffix=target.suffix, dir=target.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        write(tmp)
        _replace(tmp, target, "--out", overwrite)
    finally:
        tmp.unlink(missing_ok=True)
    return target
