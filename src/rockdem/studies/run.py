"""Running a study: one sample per Dask task (the plan: :mod:`.plan`), rows
stored as they arrive, the summary.

The task (:func:`evaluate`) gets the parsed model file and the values of one
sample, sets them at their key paths in a copy, validates and builds the model
through :mod:`rockdem.config` and runs :func:`rockdem.factor_of_safety` (or
:func:`rockdem.analyse`).  It never raises: whatever goes wrong is the row's
``error``.
"""

from __future__ import annotations

import json
import numbers
import os
import socket
import time
import warnings
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from ..config.errors import Loc
from ..errors import InputError, ModelWarning
from ..geometry.size import MAX_BLOCKS
from . import keypath
from .plan import Plan, prepare, sample_values
from .store import Store

#: What ``pip`` needs for a study.
INSTALL_HINT = "install them with: pip install 'rockdem[study]'"


class StudyResult(NamedTuple):
    """What :func:`study` returns: ``table, summary = rockdem.study(...)``."""

    table: Any
    """pandas DataFrame, one row per sample (sorted): the inputs, fs, fs_low, fs_high,
    mode, proof, failed, unstable_blocks, unstable_area, bolt_utilisation, error,
    seconds, worker."""
    summary: dict
    """Probability of failure and its interval, FS statistics, reliability indices,
    sensitivity, worst samples (see :func:`rockdem.studies.stats.summarise`), and
    ``folder``: the results folder (None when nothing was written)."""


@dataclass(frozen=True)
class Progress:
    """Passed to the ``progress`` callback after every row."""

    done: int
    total: int
    ok: int
    errors: int
    failed: int
    row: dict

    @property
    def pf(self) -> float | None:
        """Running probability of failure (among samples without error)."""
        return self.failed / self.ok if self.ok else None


# ================================================================ one sample
def evaluate(
    base: dict,
    source: str,
    places: list[list[Loc]],
    names: list[str],
    values: list,
    compute: str,
    sample: int,
    max_blocks: int | None = MAX_BLOCKS,
) -> dict:
    """One sample: its row (never raises; a failure is the row's ``error``)."""
    t0 = time.perf_counter()
    row: dict[str, Any] = {"sample": int(sample)}
    row.update({n: float(v) for n, v in zip(names, values, strict=True)})
    noted = None
    with warnings.catch_warnings(record=True) as heard:
        warnings.simplefilter("always", ModelWarning)
        try:
            outputs, noted = _analyse(base, source, places, values, compute, sample, max_blocks)
            row.update(outputs)
        except InputError as exc:
            row["error"] = str(exc)
        except Exception as exc:  # a failing sample is a row, never a lost study
            row["error"] = f"{type(exc).__name__}: {exc}"
    own = [w for w in heard if issubclass(w.category, ModelWarning)]
    for w in heard:  # other warnings as Python shows them
        if w not in own:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno, source=w.source)
    if noted is not None:
        # the sample's ModelWarnings are its row's, not one line each on the
        # terminal (a thousand samples, a thousand lines); its place is the row
        prefix = f"{source} (sample {sample}): "
        texts = [" ".join(str(w.message).split()).removeprefix(prefix) for w in own]
        row["warnings"] = " | ".join(dict.fromkeys([*texts, *noted])) or None
    row["seconds"] = time.perf_counter() - t0
    row["worker"] = f"{socket.gethostname()}:{os.getpid()}"
    return row


def _analyse(base, source, places, values, compute, sample, max_blocks):
    """The outputs of one sample, and what its result warns of besides the
    ModelWarnings (raises what its model or analysis raises)."""
    from ..config import build_model, validate_document

    row: dict[str, Any] = {}
    doc = keypath.apply(base, places, values)
    where = f"{source} (sample {sample})"
    cfg = validate_document(doc, source=where)
    model = build_model(cfg, source=where, max_blocks=max_blocks)
    if compute == "fos":
        from ..strength_reduction import factor_of_safety

        f = factor_of_safety(model, **cfg.analysis.strength_reduction.options())
        lo, hi = f.bracket
        row.update(fs=f.value, fs_low=lo, fs_high=hi, mode=f.mode, proof=f.proof)
        if f.value is not None:
            row["failed"] = bool(f.value < 1.0)
        else:
            row["failed"] = f.mode == "strength-independent"
        state, limit = f.failed_analysis, f.stable_analysis
        row["bolt_utilisation"] = _bolt_use(limit)
    else:
        from ..analysis import analyse

        state = limit = analyse(model)
        row.update(mode="verdict", failed=not state.stable)
        row["bolt_utilisation"] = _bolt_use(state)
        row["proof"] = None if state.stable else state.evidence.proof
    if state is not None:
        moving = np.asarray(state.unstable, dtype=bool)
        row["unstable_blocks"] = int(moving.sum())
        row["unstable_area"] = float(state.system.blocks.area[moving].sum())
    return row, _result_warnings(state, limit)


def _result_warnings(failed, limit) -> list[str]:
    """A mechanism bounded by the model's cut, and spring points that lost
    their bond (the result depends on their number): the warnings of a
    result that are not ModelWarnings."""
    from ..modes import boundary_contacts
    from ..result_tables import bond_lost

    texts = [c.message for c in boundary_contacts(failed)] if failed is not None else []
    shown = limit if limit is not None else failed  # the state at the limit
    return texts + (bond_lost(shown) if shown is not None else [])


def _bolt_use(analysis) -> float:
    """The largest bolt utilisation of an analysis (NaN without bolts in place
    or analysis: an after_loads bolt that never went in is none, not 0)."""
    bolts = None if analysis is None else analysis.bolts
    if bolts is None or not bolts.n:
        return float("nan")
    use = bolts.utilisation if bolts.installed is None else bolts.utilisation[bolts.installed]
    return float(use.max()) if use.size else float("nan")


def _error_row(plan: Plan, sample: int, error: str) -> dict:
    row = {"sample": sample, "error": error}
    row.update({n: float(v) for n, v in zip(plan.names, plan.values[sample], strict=True)})
    return row


# ================================================================ executors
def _args(plan: Plan, sample: int, base) -> tuple:
    return (
        base,
        plan.source,
        plan.places,
        plan.names,
        sample_values(plan, sample),
        plan.spec.compute,
        sample,
        plan.max_blocks,
    )


def _run_serial(plan: Plan, todo: Iterable[int], on_row: Callable[[dict], None]) -> int:
    for i in todo:
        on_row(evaluate(*_args(plan, i, plan.base)))
    return 0


# ================================================================ the study
def study(
    model,
    spec=None,
    client=None,
    *,
    out: str | os.PathLike | None = None,
    workers: int | None = None,
    overwrite: bool = False,
    progress: Callable[[Progress], None] | None = None,
    max_blocks: int | None = MAX_BLOCKS,
) -> StudyResult:
    """Run a probabilistic or parametric study of a model file.

    Parameters
    ----------
    model : path or dict
        The model file (or its parsed content).  Inputs are varied by their key
        paths in it.
    spec : dict, StudySpec, path, optional
        The study (the content of a `study:` section, or a file holding one);
        default: the model file's own `study:` section.
    client : dask.distributed.Client or str, optional
        Where the samples run: a client, or a scheduler address (reached before
        anything is written, so that one that cannot be reached leaves ``out``
        as it was); default a local cluster of ``workers`` processes.
    out : path, optional
        Results folder: samples.csv (a row appended as each sample finishes),
        samples.parquet, summary.json, pictures and the worst samples' model
        files.  A rerun into the same folder continues the same study.
    workers : int, optional
        Processes of the local cluster (default: the number of CPUs);
        ``0`` runs the samples one by one in this process, without Dask.
    overwrite : bool
        Start afresh in a folder holding another study's results.
    progress : callable, optional
        Called with a :class:`Progress` after every row.

    Returns
    -------
    StudyResult
        ``(table, summary)``: a pandas DataFrame (one row per sample, sorted)
        and the summary dict.  A sample that cannot be analysed (an input out
        of its valid range, say) is a row with its ``error``, left out of the
        statistics; ``summary["left_out"]`` says how many, why, and which way
        that likely biases the probability of failure (see
        :func:`rockdem.studies.stats.left_out`).

    Raises
    ------
    InputError
        For a bad study or folder, a scheduler that cannot be reached, and when
        no sample at all could be analysed (its most common reason and the fix;
        the files this run wrote are removed unless it continued an earlier
        run).  A run stopped before any sample gave a row also removes them.
    """
    try:
        import pandas  # noqa: F401
        import pyarrow  # noqa: F401
    except ImportError:
        raise InputError("rockdem study", "needs pandas and pyarrow", INSTALL_HINT) from None
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, numbers.Integral)
    ):  # (hostile round 7: 1.5 and "2" were TypeErrors from deep inside)
        raise InputError("workers", f"{workers!r} is not a whole number", "give 0 or more")
    if workers is not None and workers < 0:
        raise InputError("workers", f"{workers!r} is out of range", "give 0 or more")
    if out is not None and not isinstance(out, str | os.PathLike):
        raise InputError("out", f"{out!r} is not a folder's path", "give a path, or None")
    if workers is not None and client is not None:
        raise InputError("workers", "is for the local cluster", "give workers or a client")
    if isinstance(client, str):
        from .on_dask import check_address

        check_address(client)  # before any folder is made
    plan = model if isinstance(model, Plan) else prepare(model, spec, max_blocks=max_blocks)
    folder = Path(out) if out is not None else None
    if folder is not None:
        from .store import check_inputs_outside, check_worst_unedited

        spec_file = spec if isinstance(spec, str | os.PathLike) else None
        check_inputs_outside(folder, [plan.source, spec_file])
        check_worst_unedited(folder)
    own_client = None
    if isinstance(client, str):
        from .on_dask import connect

        # reached before anything is written: an unreachable scheduler left the
        # folder holding study.json and empty tables (found by fuzzing)
        client = own_client = connect(client)
    try:
        return _run(plan, client, folder, workers, overwrite, progress)
    finally:
        if own_client is not None:
            own_client.close()


def _run(plan: Plan, client, folder: Path | None, workers, overwrite, progress) -> StudyResult:
    """The rest of :func:`study`: the samples not done yet, the summary, the files."""
    store = Store(plan.names, folder, plan.manifest(), overwrite)
    total = len(plan.values)
    resumed = len(store.done)
    todo = [i for i in range(total) if i not in store.done]
    counts = {"ok": 0, "errors": 0, "failed": 0}
    for row in store.rows.values():
        _count(counts, row)

    def on_row(row: dict) -> None:
        store.add(row)
        _count(counts, row)
        if progress is not None:
            progress(Progress(len(store.rows), total, row=row, **counts))

    n_workers = 0
    started = time.perf_counter()
    ended = False
    try:
        if todo and workers == 0 and client is None:
            _run_serial(plan, todo, on_row)
        elif todo:
            from .on_dask import run_on_dask

            n_workers = run_on_dask(plan, todo, on_row, client, workers)
        ended = True
    finally:
        if not ended and not store.rows:
            store.discard()  # stopped before any row: the folder as it was
        else:
            store.close()
    from .stats import summarise

    table = store.table()
    s = plan.spec
    summary = summarise(
        table,
        plan.names,
        kind=s.kind,
        compute=s.compute,
        confidence=s.confidence,
        worst=s.worst,
        planned=total,
        distributions={n: i.distribution for n, i in s.inputs.items()},
    )
    if summary["done"] and not summary["ok"]:
        if not resumed:
            store.discard()  # nothing worth keeping: the folder as it was
        raise _nothing_analysed(plan, summary)
    summary.update(
        model_file=plan.source,
        inputs=plan.names,
        sampler=s.sampler if s.kind == "probabilistic" else "grid",
        seed=s.seed,
        resumed=resumed,
        ran=len(todo),
        workers=n_workers,
        seconds=time.perf_counter() - started,
        folder=None if folder is None else str(folder),
    )
    if folder is not None:
        from .outputs import write_outputs

        write_outputs(folder, plan, table, summary)
    return StudyResult(table, summary)


def _nothing_analysed(plan: Plan, summary: dict) -> InputError:
    """The error of a study none of whose samples could be analysed (every one out of
    range, say): its most common reason and the fix, in one line."""
    left = summary["left_out"]
    top = left["reasons"][0]
    n, done = top["n"], summary["done"]
    if top.get("input"):
        name = top["input"]
        valid = f" ({top['range']})" if top.get("range") else ""
        problem = f"{name} was out of its valid range{valid} in {n} of {done}"
        fix = top["fix"]
    else:
        from .stats import _short

        problem = f"{n} of {done} stopped with: {_short(top['example'])}"
        fix = "fix what that names, or give inputs whose samples are valid models"
    return InputError(f"study {plan.source}", f"no sample could be analysed: {problem}", fix)


def _count(counts: dict, row: dict) -> None:
    if row.get("error") is not None:
        counts["errors"] += 1
    else:
        counts["ok"] += 1
        counts["failed"] += bool(row.get("failed"))


def read_study(folder: str | os.PathLike) -> StudyResult:
    """The table and summary of a finished (or interrupted) study folder."""
    import pandas as pd

    folder = Path(folder)
    try:
        summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
        table = pd.read_parquet(folder / "samples.parquet")
    except (OSError, ValueError) as exc:
        raise InputError(
            f"study {folder}", f"cannot be read ({exc})", "give a `rockdem study --out` folder"
        ) from None
    summary["folder"] = str(folder)
    return StudyResult(table, summary)
