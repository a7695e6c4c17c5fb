"""The result rows of a study: one row per sample, written as it arrives.

``samples.csv`` gets every row appended, flushed and synced to disk as it
arrives (the record a rerun continues from: a row cut short by a kill is
dropped); ``samples.parquet`` is rewritten whole (to a temporary file, then
moved into place) at most every :data:`PARQUET_EVERY` seconds and at the
end, so both are complete files at any moment.  When the study ends both
hold the rows sorted by sample.  ``study.json`` records what was run (the
model, the spec, the columns) so that a rerun into the same folder
continues only the same study.
"""

from __future__ import annotations

import csv
import hashlib
import json
import math
import os
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..output import csv_text

#: Output columns after the inputs, and their kinds.
OUTPUTS: dict[str, str] = {
    "fs": "float",  # factor of safety (midpoint of the bracket)
    "fs_low": "float",  # bracket: largest factor found stable
    "fs_high": "float",  # bracket: smallest factor found unstable
    "mode": "str",  # strength | strength-independent | no-failure | verdict
    "proof": "str",  # how the failed end is known
    "failed": "bool",  # FS < 1 (compute: verdict: unstable at F = 1)
    "unstable_blocks": "int",  # blocks moving in the mechanism at the limit
    "unstable_area": "float",  # their area
    "bolt_utilisation": "float",  # largest bolt force / capacity at the last equilibrium
    "error": "str",  # why the sample has no result
    "warnings": "str",  # what the sample's analysis warned of (" | " between them)
    "seconds": "float",  # wall time of the sample
    "worker": "str",  # host:pid that ran it
}
#: Columns that depend on where and when a sample ran, not on the sample.
VOLATILE = ("seconds", "worker")
#: Shortest interval between rewrites of samples.parquet, in seconds.
PARQUET_EVERY = 2.0
FILES = ("study.json", "samples.csv", "samples.parquet", "summary.json")
#: the other files a study writes into its folder (pictures, report, worst samples)
WRITTEN = ("sweep.png", "fs-distribution.png", "sensitivity.png", "report.html")
WORST = "worst/sample-*.yaml"


def check_inputs_outside(folder: Path, inputs: list) -> None:
    """Refuse a study folder where a result would be written over an input
    (the model file, the spec file): a worst sample's file copied back and
    studied into the same folder, say.  Even with ``--overwrite``."""
    folder = Path(folder)
    for source in inputs:
        if source is None or not os.path.isfile(source):
            continue
        here = Path(os.path.realpath(source))
        top = Path(os.path.realpath(folder))
        worst = here.parent == top / "worst" and here.match("sample-*.yaml")
        if (here.parent == top and here.name in (*FILES, *WRITTEN)) or worst:
            raise InputError(
                f"--out {folder}",
                f"the study would write over its input {source}",
                "copy the file out of the folder, or write the study into another folder",
            )


def worst_digest(path: Path) -> str:
    """What a worst sample's file held when the study wrote it (summary.json)."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def check_worst_unedited(folder: Path) -> None:
    """Refuse a study folder whose ``worst/`` holds a file the study did not
    write as it is (a worst sample edited in place, say): every run rewrites
    that folder, and the edit would be lost.  Even with ``--overwrite``.
    (A folder whose summary.json records no digests, or none, is older or
    unfinished: nothing to compare with.)"""
    folder = Path(folder)
    try:
        digests = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
        digests = digests.get("worst_digests")
    except (OSError, ValueError, AttributeError):
        return
    if not isinstance(digests, dict):
        return
    for path in sorted((folder / "worst").glob("sample-*.yaml")):
        name = path.relative_to(folder).as_posix()
        if digests.get(name) != worst_digest(path):
            raise InputError(
                f"--out {folder}",
                f"{name} was changed after the study wrote it (every run rewrites worst/)",
                "move the file out of worst/ to keep it, then run again",
            )


def clashing_file(folder: Path) -> str | None:
    """The first file of a study's results in ``folder`` (None if none)."""
    for name in (*FILES, *WRITTEN):
        if os.path.lexists(folder / name):
            return name
    worst = sorted(folder.glob(WORST))
    return str(worst[0].relative_to(folder)) if worst else None


def columns(names: list[str]) -> list[str]:
    return ["sample", *names, *OUTPUTS]


def kinds(names: list[str]) -> dict[str, str]:
    return {"sample": "int", **dict.fromkeys(names, "float"), **OUTPUTS}


def _text(value: Any, kind: str) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    if kind == "float":
        return repr(float(value))  # round-trips exactly
    if kind == "bool":
        return "true" if value else "false"
    if kind == "str":  # an error naming a file `=x.yaml` first: not a formula
        return csv_text(str(value))
    return str(value)


def _value(text: str, kind: str) -> Any:
    if text == "":
        return math.nan if kind == "float" else None
    if kind == "float":
        return float(text)
    if kind == "int":
        return int(text)
    if kind == "bool":
        if text not in ("true", "false"):
            raise ValueError(text)
        return text == "true"
    if kind == "str" and text.startswith("'") and csv_text(text[1:]) == text:
        return text[1:]  # as _text quoted it
    return text


def _plausible(row: dict, n_samples: int) -> bool:
    """Could this study have written ``row``?  Its index is one of its samples
    and its factors of safety are missing (NaN) or >= 0, finite except the
    bracket's top (infinite where no failure was found)."""
    if not 0 <= row["sample"] < n_samples:
        return False
    for column in ("fs", "fs_low", "fs_high"):
        f = row.get(column)
        if f is None or math.isnan(f):
            continue
        if f < 0 or (math.isinf(f) and column != "fs_high"):
            return False
    return True


class Store:
    """Rows of one study, in memory and (with a folder) on disk."""

    def __init__(self, names: list[str], folder: Path | None, manifest: dict, overwrite: bool):
        self.names = names
        self.columns = columns(names)
        self.kinds = kinds(names)
        self.folder = folder
        self.rows: dict[int, dict] = {}
        self._fh = None
        self._writer = None
        self._parquet_at = 0.0
        self._dirty = False
        self._made: Path | None = None  # the topmost folder this store created
        if folder is not None:
            self._open(folder, manifest, overwrite)

    # ------------------------------------------------------------ folder
    def _open(self, folder: Path, manifest: dict, overwrite: bool) -> None:
        folder = Path(folder)
        if folder.exists() and not folder.is_dir():
            raise InputError(f"--out {folder}", "is a file", "give a folder")
        missing = [p for p in (folder, *folder.parents) if not os.path.lexists(p)]
        self._made = missing[-1] if missing else None
        folder.mkdir(parents=True, exist_ok=True)
        info, csv_path = folder / "study.json", folder / "samples.csv"
        if info.exists() and not overwrite:
            try:
                old = json.loads(info.read_text(encoding="utf-8"))
            except (OSError, ValueError):
                old = {}
            if not isinstance(old, dict):  # (hostile testing: `[]` was an AttributeError)
                old = {}
            if old.get("fingerprint") != manifest["fingerprint"]:
                raise InputError(
                    f"--out {folder}",
                    "holds the results of another study (the model or the study section changed)",
                    "give another folder, or --overwrite to start this study afresh",
                )
            if csv_path.exists():
                self._read(csv_path, int(manifest.get("samples", 0)))
        elif not info.exists() and not overwrite:
            clash = clashing_file(folder)
            if clash:
                raise InputError(
                    f"--out {folder}",
                    f"holds {clash} but no study.json (not a study's folder)",
                    "give another folder, or --overwrite to replace it",
                )
        if overwrite:
            for name in FILES:
                (folder / name).unlink(missing_ok=True)
        text = json.dumps(manifest, indent=1, allow_nan=False) + "\n"
        _atomic_write(info, lambda tmp: tmp.write_text(text, encoding="utf-8"))
        # the complete rows, then append (a row cut short by a kill is dropped here)
        self._rewrite_csv(csv_path, sorted(self.rows))
        self._fh = open(csv_path, "a", newline="", encoding="utf-8")
        self._writer = csv.writer(self._fh, lineterminator="\n")

    def _read(self, path: Path, n_samples: int) -> None:
        """The rows of an earlier run of this study; a row that is not one this
        study could have written (an index outside it, a negative or infinite
        factor: a hand-edited file, found by fuzzing) is dropped and run again."""
        try:
            with open(path, newline="", encoding="utf-8") as fh:
                text = fh.read()
        except UnicodeDecodeError:
            raise InputError(
                f"--out {path.parent}",
                "samples.csv is not UTF-8 text (was it edited?)",
                "give another folder, or --overwrite to start this study afresh",
            ) from None
        complete = text if text.endswith("\n") else text[: text.rfind("\n") + 1]
        lines = list(csv.reader(complete.splitlines()))
        if not lines:
            return
        if lines[0] != self.columns:
            raise InputError(
                f"--out {path.parent}",
                "samples.csv has other columns than this study",
                "give another folder, or --overwrite",
            )
        for fields in lines[1:]:
            if len(fields) != len(self.columns):
                continue
            try:
                row = {
                    c: _value(t, self.kinds[c]) for c, t in zip(self.columns, fields, strict=True)
                }
            except ValueError:
                continue
            if not _plausible(row, n_samples):
                continue
            self.rows[row["sample"]] = row

    def _rewrite_csv(self, path: Path, order: list[int]) -> None:
        def write(tmp: Path) -> None:
            with open(tmp, "w", newline="", encoding="utf-8") as fh:
                w = csv.writer(fh, lineterminator="\n")
                w.writerow(self.columns)
                for i in order:
                    w.writerow(self._fields(self.rows[i]))

        _atomic_write(path, write)

    def _fields(self, row: dict) -> list[str]:
        return [_text(row.get(c), self.kinds[c]) for c in self.columns]

    # ------------------------------------------------------------ rows
    @property
    def done(self) -> set[int]:
        return set(self.rows)

    def add(self, row: dict) -> None:
        """Keep a row; on disk, append it to samples.csv at once."""
        row = {c: row.get(c) for c in self.columns}
        self.rows[row["sample"]] = row
        if self._writer is not None:
            self._writer.writerow(self._fields(row))
            self._fh.flush()
            os.fsync(self._fh.fileno())
            self._dirty = True
            if time.monotonic() - self._parquet_at >= PARQUET_EVERY:
                self.write_parquet()

    def table(self):
        """The rows as a pandas DataFrame, sorted by sample."""
        import pandas as pd

        records = [self.rows[i] for i in sorted(self.rows)]
        df = pd.DataFrame.from_records(records, columns=self.columns)
        for c, kind in self.kinds.items():
            if kind == "float":
                df[c] = df[c].astype("float64")
            elif kind == "int":
                df[c] = df[c].astype("Int64")
            elif kind == "bool":
                df[c] = df[c].astype("boolean")
            else:
                df[c] = df[c].astype("string")
        return df

    def write_parquet(self) -> None:
        if self.folder is None:
            return
        table = self.table()
        _atomic_write(self.folder / "samples.parquet", lambda path: table.to_parquet(path))
        self._parquet_at = time.monotonic()
        self._dirty = False

    def close(self) -> None:
        """Sort both files by sample and close them (also after an interruption)."""
        if self._fh is None:
            return
        self._fh.close()
        self._fh = self._writer = None
        self._rewrite_csv(self.folder / "samples.csv", sorted(self.rows))
        self.write_parquet()

    def discard(self) -> None:
        """Remove what this store wrote (study.json, samples.csv, samples.parquet) and
        the folders it made, when they are empty: for a run that ends with no row
        worth keeping, so that the folder is as it was.  Nothing else is touched."""
        self.close()
        if self.folder is None:
            return
        for name in ("study.json", "samples.csv", "samples.parquet"):
            (self.folder / name).unlink(missing_ok=True)
        if self._made is None:
            return
        path = self.folder
        while True:
            try:
                path.rmdir()  # only when empty
            except OSError:
                return
            if path == self._made:
                return
            path = path.parent


def _atomic_write(path: Path, write: Callable[[Path], Any]) -> None:
    """``write(tmp)`` to a temporary file beside ``path``, then move it into place."""
    fd, name = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        write(tmp)
        mask = os.umask(0o022)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
