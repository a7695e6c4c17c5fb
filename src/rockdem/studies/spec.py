"""The `study:` section of a model file (defined with the file format, in
:mod:`rockdem.config.study`)."""

from ..config.study import (
    MAX_SAMPLES,
    MAX_SWEEP_STEPS,
    PARAMETERS,
    CorrelationSpec,
    InputSpec,
    StudySpec,
    SweepSpec,
)

__all__ = [
    "MAX_SAMPLES",
    "MAX_SWEEP_STEPS",
    "PARAMETERS",
    "CorrelationSpec",
    "InputSpec",
    "StudySpec",
    "SweepSpec",
]
