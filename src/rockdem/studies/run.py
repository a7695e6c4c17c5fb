"""Running a study: the plan (inputs resolved, samples drawn, the nominal model
checked), one sample per Dask task, rows stored as they arrive, the summary.

The task (:func:`evaluate`) gets the parsed model file and the values of one
sample, sets them at their key paths in a copy, validates and builds the model
through :mod:`rockdem.config` and runs :func:`rockdem.factor_of_safety` (or
:func:`rockdem.analyse`).  It never raises: whatever goes wrong is the row's
``error``.
"""

from __future__ import annotations

import copy
import hashlib
import json
import os
import socket
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from ..config.errors import Loc, ModelFileError, _line
from ..errors import InputError
from ..geometry.size import MAX_BLOCKS
from . import keypath, sampling
from .spec import StudySpec
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


@dataclass
class Plan:
    """A study ready to run."""

    source: str
    base: dict  # the parsed model file without its study section
    spec: StudySpec
    places: list[list[Loc]]  # where each input is set
    values: np.ndarray  # samples x inputs
    fingerprint: str
    max_blocks: int | None = MAX_BLOCKS
    nominal: Any = None  # the Model with every input at its median (a sweep: first point)

    @property
    def names(self) -> list[str]:
        return self.spec.names

    def manifest(self) -> dict:
        from .. import __version__

        return {
            "rockdem_version": __version__,
            "model_file": self.source,
            "fingerprint": self.fingerprint,
            "kind": self.spec.kind,
            "samples": len(self.values),
            "inputs": self.names,
            "study": self.spec.model_dump(mode="json", exclude_defaults=False),
        }


# ================================================================ the plan
def _read_model(model) -> tuple[dict, Any, str]:
    from ..config import read_document

    if isinstance(model, str | os.PathLike):
        data, nodes = read_document(model)
        return data, nodes, str(model)
    if isinstance(model, dict):
        return copy.deepcopy(model), None, "<model>"
    raise InputError(
        "study model",
        f"is a {type(model).__name__}",
        "give the model file's path (or its parsed content as a dict): the inputs are "
        "varied by their key paths in the file",
    )


class _StudyOnly:
    """Validation of a study section alone, with the model file's messages."""

    @staticmethod
    def validate(data: Any, source: str, nodes: Any) -> StudySpec:
        from pydantic import ValidationError

        from ..config.validate import _from_validation
        from ..config.values import _Section

        class StudySection(_Section):
            study: StudySpec

        try:
            return StudySection.model_validate({"study": data}).study
        except ValidationError as exc:
            raise _from_validation(exc, source, nodes) from None


def prepare(model, spec=None, *, max_blocks: int | None = MAX_BLOCKS) -> Plan:
    """Read the model, validate the study, resolve the key paths, draw the samples and
    check the model with every input at its median (a bad study fails here, in one
    line, before any run)."""
    from ..config import build_model, read_document, validate_document

    data, nodes, source = _read_model(model)
    study_data, study_nodes, study_source = data.pop("study", None), nodes, source
    cfg = validate_document(data, source=source, nodes=nodes)
    if isinstance(spec, StudySpec):
        parsed = spec
    else:
        if isinstance(spec, str | os.PathLike):
            doc, study_nodes = read_document(spec)
            study_source = str(spec)
            if set(doc) != {"study"}:
                extra = sorted(set(doc) - {"study"})
                raise ModelFileError(
                    study_source,
                    extra[0] if extra else "study",
                    "unknown key" if extra else "required key is missing",
                    "a study file holds one `study:` section",
                )
            study_data = doc["study"]
        elif isinstance(spec, dict):
            study_data, study_nodes, study_source = spec, None, "<study>"
        elif spec is not None:
            raise InputError("study spec", f"is a {type(spec).__name__}", "give a dict or a file")
        if study_data is None:
            raise ModelFileError(
                source,
                "study",
                "the model file has no `study:` section",
                "add one (docs/file-format.md, `study`) or give the study separately",
            )
        parsed = _StudyOnly.validate(study_data, study_source, study_nodes)
    section = "inputs" if parsed.kind == "probabilistic" else "sweep"
    places = keypath.check_paths(data, parsed.names, section, study_source, study_nodes)
    try:
        values = sampling.samples(parsed)
    except ValueError as exc:  # contradictory correlations
        loc = ("study", "correlations")
        raise ModelFileError(
            study_source,
            "study.correlations",
            str(exc),
            "lower some of them",
            _line(study_nodes, loc),
        ) from None
    whole = [keypath.is_integer_key(locs[0]) for locs in places]
    for k, is_int in enumerate(whole):
        if is_int:
            values[:, k] = np.round(values[:, k])
    # the nominal model: every input at its median (a sweep: its first point)
    nominal = sampling.medians(parsed)
    nominal = [round(v) if w else float(v) for v, w in zip(nominal, whole, strict=True)]
    if cfg.name is None and isinstance(model, str | os.PathLike):
        data["name"] = Path(model).stem  # as load_model names it
    doc = keypath.apply(data, places, nominal)
    where = f"{source} (study inputs at their medians)"
    ncfg = validate_document(doc, source=where)
    nominal_model = build_model(ncfg, source=where, max_blocks=max_blocks)
    key = {
        "model": data,
        "study": parsed.model_dump(mode="json", exclude={"worst", "confidence"}),
    }
    text = json.dumps(key, sort_keys=True, default=str, allow_nan=True)
    fingerprint = hashlib.sha256(text.encode()).hexdigest()
    return Plan(source, data, parsed, places, values, fingerprint, max_blocks, nominal_model)


# ================================================================ one sample
def _value(v: float, whole: bool):
    return int(v) if whole else float(v)


def sample_document(plan: Plan, sample: int) -> dict:
    """The model file of one sample (parsed data, without the study section)."""
    whole = [keypath.is_integer_key(locs[0]) for locs in plan.places]
    vals = [_value(v, w) for v, w in zip(plan.values[sample], whole, strict=True)]
    return keypath.apply(plan.base, plan.places, vals)


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
    try:
        from ..config import build_model, validate_document

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
            state = f.failed_analysis
            row["bolt_utilisation"] = _bolt_use(f.stable_analysis)
        else:
            from ..analysis import analyse

            state = analyse(model)
            row.update(mode="verdict", failed=not state.stable)
            row["bolt_utilisation"] = _bolt_use(state)
            row["proof"] = None if state.stable else state.evidence.proof
        if state is not None:
            moving = np.asarray(state.unstable, dtype=bool)
            row["unstable_blocks"] = int(moving.sum())
            row["unstable_area"] = float(state.system.blocks.area[moving].sum())
    except InputError as exc:
        row["error"] = str(exc)
    except Exception as exc:  # a failing sample is a row, never a lost study
        row["error"] = f"{type(exc).__name__}: {exc}"
    row["seconds"] = time.perf_counter() - t0
    row["worker"] = f"{socket.gethostname()}:{os.getpid()}"
    return row


def _bolt_use(analysis) -> float:
    """The largest bolt utilisation of an analysis (NaN without bolts or analysis)."""
    bolts = None if analysis is None else analysis.bolts
    return float(bolts.utilisation.max()) if bolts is not None and bolts.n else float("nan")


def _error_row(plan: Plan, sample: int, error: str) -> dict:
    row = {"sample": sample, "error": error}
    row.update({n: float(v) for n, v in zip(plan.names, plan.values[sample], strict=True)})
    return row


# ================================================================ executors
def _args(plan: Plan, sample: int, base) -> tuple:
    whole = [keypath.is_integer_key(locs[0]) for locs in plan.places]
    vals = [_value(v, w) for v, w in zip(plan.values[sample], whole, strict=True)]
    return (
        base,
        plan.source,
        plan.places,
        plan.names,
        vals,
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
    if workers is not None and (isinstance(workers, bool) or workers < 0):
        raise InputError("workers", f"{workers!r} is out of range", "give 0 or more")
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
