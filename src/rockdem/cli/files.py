"""Writing one output file all or nothing: to a temporary file beside it, then moved
into place (never over an existing file without ``--overwrite``); and checking a
destination before anything is computed (never over the model file)."""

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


def _special(target: Path) -> bool:
    """An existing path that is not a regular file or folder (a pipe, socket or
    device): writing "over" it would replace it with a file."""
    return target.exists() and not (target.is_file() or target.is_dir())


def _refuse_special(target: Path, option: str) -> None:
    from ..errors import InputError

    if _special(target):
        raise InputError(
            f"{option} {target}",
            "is not a regular file (a device, pipe or socket), so it is never replaced",
            "give a file name",
        )


def _check_new_file(target: Path, option: str, overwrite: bool) -> None:
    from ..errors import InputError

    if target.is_dir():
        raise InputError(f"{option} {target}", "is a folder", "give a file name")
    _refuse_special(target, option)
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


# ------------------------------------------------------ before computing
def _nearest_existing(path: Path) -> Path:
    """``path`` or its closest ancestor that exists (links are not followed)."""
    path = Path(os.path.abspath(path))
    while not os.path.lexists(path) and path != path.parent:
        path = path.parent
    return path


def _writable(folder: Path) -> bool:
    """A file can be made in ``folder``: tried with an empty temporary file,
    removed at once (found by fuzzing: permission bits let root "write" into
    /sys/kernel, which refused the report after its analysis)."""
    import tempfile

    if not os.access(folder, os.W_OK | os.X_OK):
        return False
    try:
        with tempfile.TemporaryFile(dir=folder, prefix=".rockdem-probe."):
            return True
    except OSError:
        return False


def _check_can_create(path: Path, option: str) -> None:
    """``path`` (a file or folder to be made) can be created: its closest existing
    ancestor is a folder we may write into."""
    from ..errors import InputError

    base = _nearest_existing(path.parent)
    if not base.is_dir():
        raise InputError(
            f"{option} {path}",
            f"cannot be created: {base} is a file, not a folder",
            "give a path in a folder",
        )
    if not _writable(base):
        raise InputError(
            f"{option} {path}",
            f"cannot be created: the folder {base} is not writable",
            "give a folder you may write into",
        )


def _same_file(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def _check_out_folder(
    folder: Path,
    names: tuple[str, ...],
    *,
    overwrite: bool,
    inputs: list[Path],
    option: str = "--out",
    temp_beside: bool = False,
    refuse_existing: bool = False,
) -> None:
    """Everything about a result folder that can be known before the computation.

    ``names`` are the files the command writes into ``folder`` (glob patterns
    allowed).  Refused: a folder that is a file or under one, one we may not
    write into (or, with ``temp_beside``, whose parent we may not write into:
    the results are first written to a temporary folder there), a result
    name taken by a folder (the set could not be written all or nothing), a
    result name that is one of ``inputs`` (never write over the model), and,
    with ``refuse_existing`` and without ``overwrite``, results that exist.
    """
    from ..errors import InputError

    where = f"{option} {folder}"
    if os.path.lexists(folder) and not folder.is_dir():
        raise InputError(where, "is a file, not a folder", "give a folder")
    if not folder.exists():
        _check_can_create(folder, option)
        return
    if not _writable(folder):
        raise InputError(where, "is not writable", "give a folder you may write into")
    parent = folder.resolve().parent
    if temp_beside and not _writable(parent):
        raise InputError(
            where,
            f"cannot be written: the results are first written to a temporary folder in "
            f"{parent}, which is not writable",
            "give a folder whose parent you may write into",
        )
    targets: list[Path] = []
    for name in names:
        targets += sorted(folder.glob(name)) if "*" in name else [folder / name]
    for path in targets:
        for source in inputs:
            if _same_file(path, source):
                raise InputError(
                    where,
                    f"would write {path.name} over the model file {source}",
                    "write the results into another folder",
                )
        _refuse_special(path, option)
        if path.is_dir():
            raise InputError(
                where,
                f"{path.name} is a folder, so the results could not be written all or nothing",
                "remove or rename it, or write the results into another folder",
            )
        if refuse_existing and not overwrite and os.path.lexists(path):
            raise InputError(
                where,
                f"already holds {path.name}",
                "use --overwrite to replace the results, or another folder",
            )


def _check_out_file(target: Path, *, inputs: list[Path], option: str = "--out") -> None:
    """A single output file: never one of ``inputs``; its folder can be made and written."""
    from ..errors import InputError

    for source in inputs:
        if _same_file(target, source):
            raise InputError(
                f"{option} {target}",
                f"is the model file {source}",
                "give another file name (the model is never overwritten)",
            )
    if target.is_dir():
        raise InputError(f"{option} {target}", "is a folder", "give a file name")
    _refuse_special(target, option)
    if target.parent.exists():
        if not target.parent.is_dir():
            raise InputError(
                f"{option} {target}",
                f"cannot be created: {target.parent} is a file, not a folder",
                "give a path in a folder",
            )
        if not _writable(target.parent):
            raise InputError(
                f"{option} {target}",
                f"cannot be written: the folder {target.parent} is not writable",
                "give a folder you may write into",
            )
    else:
        _check_can_create(target.parent, option)
