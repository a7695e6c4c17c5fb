"""A study's plan: the model file read, the study section validated, the
inputs' key paths resolved, the samples drawn and the model checked with
every input at its median, before any run; and the model file of one sample."""

from __future__ import annotations

import copy
import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..config.errors import Loc, ModelFileError, _line
from ..errors import InputError
from ..geometry.size import MAX_BLOCKS
from . import keypath, sampling
from .spec import StudySpec


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
            try:
                doc, study_nodes = read_document(spec)
            except ModelFileError as exc:
                if exc.problem != "the file is empty":
                    raise
                # (the model file's advice, "write a model", is wrong here)
                raise ModelFileError(
                    str(spec), "", exc.problem, "write a `study:` section (docs/file-format.md)"
                ) from None
            study_source = str(spec)
            if set(doc) != {"study"}:
                extra = [k for k in doc if k != "study"]  # the first as written
                raise ModelFileError(
                    study_source,
                    extra[0] if extra else "study",
                    "unknown key" if extra else "required key is missing",
                    "a study file holds one `study:` section",
                    _line(study_nodes, (extra[0],)) if extra else None,
                )
            study_data = doc["study"]
        elif isinstance(spec, dict):
            study_data, study_nodes, study_source = spec, None, "<study>"
        elif spec is not None:
            raise InputError("study spec", f"is a {type(spec).__name__}", "give a dict or a file")
        if study_data is None and study_source != source:  # `study:` left empty in the spec
            raise ModelFileError(
                study_source,
                "study",
                "the section is empty",
                "write the study under it (docs/file-format.md, `study`)",
            )
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
    at = "medians" if parsed.kind == "probabilistic" else "sweep's first values"
    where = f"{source} (study inputs at their {at})"
    ncfg = validate_document(doc, source=where)
    nominal_model = build_model(ncfg, source=where, max_blocks=max_blocks)
    key = {
        "model": data,
        "study": parsed.model_dump(mode="json", exclude={"worst", "confidence"}),
        # the drawing the model is cut from (found by fuzzing: a changed drawing
        # was taken for the same study, and a resumed one mixed the two)
        "drawing": _drawing_digest(cfg, source),
    }
    text = json.dumps(key, sort_keys=True, default=str, allow_nan=True)
    fingerprint = hashlib.sha256(text.encode()).hexdigest()
    return Plan(source, data, parsed, places, values, fingerprint, max_blocks, nominal_model)


def sample_values(plan: Plan, sample: int) -> list:
    """The inputs of one sample, whole numbers where their keys take integers."""
    whole = [keypath.is_integer_key(locs[0]) for locs in plan.places]
    return [int(v) if w else float(v) for v, w in zip(plan.values[sample], whole, strict=True)]


def sample_document(plan: Plan, sample: int) -> dict:
    """The model file of one sample (parsed data, without the study section)."""
    return keypath.apply(plan.base, plan.places, sample_values(plan, sample))


def _drawing_digest(cfg, source: str) -> str | None:
    """SHA-256 of the DXF drawing a ``geometry: {dxf: ...}`` model is cut from."""
    if cfg.geometry is None:
        return None
    from ..config.geometry import dxf_path

    return hashlib.sha256(Path(dxf_path(cfg, source)).read_bytes()).hexdigest()
