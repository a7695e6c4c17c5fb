"""The `study:` section of a model file: which inputs vary, how, and how many runs.

A probabilistic study gives `inputs` (key path -> distribution), optional
`correlations`, a `sampler`, a `seed` and the number of `samples`; a
parametric study gives a `sweep` (a grid over one or two inputs) instead.
It lives with the rest of the file format (the model file may carry the
section; :mod:`rockdem.studies` runs it) and needs only pydantic: reading a
model file never loads Dask or pandas.
"""

# pydantic copies mutable defaults; ruff cannot see that _Section is a BaseModel
# ruff: noqa: RUF012

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from .values import Number, Seed, _Section, bounded, whole

#: Most samples (or sweep points) one study may ask for.
MAX_SAMPLES = 1_000_000
#: Most points along one sweep axis.
MAX_SWEEP_STEPS = 1_000

#: Largest parameter of a distribution or a sweep (every quantity of a model is
#: within 1e15: stiffnesses, forces).
MAX_PARAMETER = 1e15
#: Largest coefficient of variation (sd / mean) of a lognormal input.
MAX_LOGNORMAL_COV = 100.0
#: ... and the smallest (below it the log-spread underflows to zero)
MIN_LOGNORMAL_COV = 1e-9

#: Parameters each distribution takes (all of them required).
PARAMETERS: dict[str, tuple[str, ...]] = {
    "normal": ("mean", "sd"),
    "lognormal": ("mean", "sd"),
    "uniform": ("min", "max"),
    "triangular": ("min", "mode", "max"),
    "truncated-normal": ("mean", "sd", "min", "max"),
}


class InputSpec(_Section):
    """One uncertain input: its distribution and the distribution's parameters.

    normal: `mean`, `sd`; lognormal: `mean`, `sd` of the value itself (> 0);
    uniform: `min`, `max`; triangular: `min`, `mode`, `max`; truncated-normal:
    `mean`, `sd` of the parent normal, cut to [`min`, `max`].
    """

    distribution: Literal["normal", "lognormal", "uniform", "triangular", "truncated-normal"]
    """normal, lognormal, uniform, triangular or truncated-normal."""
    mean: Number | None = None
    """Mean (normal, lognormal; truncated-normal: of the normal before truncation)."""
    sd: Number | None = None
    """Standard deviation, > 0 (normal, lognormal, truncated-normal)."""
    min: Number | None = None
    """Smallest value (uniform, triangular, truncated-normal)."""
    max: Number | None = None
    """Largest value (uniform, triangular, truncated-normal)."""
    mode: Number | None = None
    """Most likely value (triangular)."""

    @model_validator(mode="after")
    def _parameters(self) -> InputSpec:
        d = self.distribution
        need = PARAMETERS[d]
        given = {k for k in ("mean", "sd", "min", "max", "mode") if getattr(self, k) is not None}
        missing = [k for k in need if k not in given]
        extra = sorted(given - set(need))
        takes = ", ".join(f"`{k}`" for k in need)
        if missing:
            raise ValueError(f"{d} needs {takes}: `{missing[0]}` is missing")
        if extra:
            raise ValueError(f"{d} takes {takes}, not `{extra[0]}`")
        if self.sd is not None and not self.sd > 0:
            raise ValueError(f"{d}: sd = {self.sd:g} must be > 0")
        if d == "lognormal" and not self.mean > 0:
            raise ValueError(f"lognormal: mean = {self.mean:g} must be > 0")
        if d == "lognormal" and self.sd > MAX_LOGNORMAL_COV * self.mean:
            # (sd / mean)^2 overflowed at sd = 1e200 (found by fuzzing)
            raise ValueError(
                f"lognormal: sd / mean = {self.sd / self.mean:.3g} is over "
                f"{MAX_LOGNORMAL_COV:g} (its values would span more orders of magnitude "
                "than a rock property does); give a smaller sd"
            )
        if d == "lognormal" and self.sd < MIN_LOGNORMAL_COV * self.mean:
            # sd = 1e-300 gave a log-spread of 0 and NaN samples (found by fuzzing)
            raise ValueError(
                f"lognormal: sd / mean = {self.sd / self.mean:.3g} is below "
                f"{MIN_LOGNORMAL_COV:g}, too small to sample; give a larger sd, or the "
                "value itself in the model (no study input)"
            )
        if self.min is not None and not self.min < self.max:
            raise ValueError(f"{d}: min = {self.min:g} must be < max = {self.max:g}")
        if d == "triangular" and not self.min <= self.mode <= self.max:
            raise ValueError(f"triangular: mode = {self.mode:g} must lie in [min, max]")
        if d == "truncated-normal":
            # the parent normal must put some weight inside [min, max]
            lo, hi = (self.min - self.mean) / self.sd, (self.max - self.mean) / self.sd
            if lo > 8 or hi < -8:
                raise ValueError(
                    "truncated-normal: [min, max] lies more than 8 sd from the mean "
                    "(no probability inside)"
                )
        values = [abs(v) for v in (self.mean, self.sd, self.min, self.max, self.mode) if v]
        if values and max(values) > MAX_PARAMETER:
            # (found by fuzzing: mean and sd of 1e308 overflowed in the sampler,
            # uniform +-1.7e308 read as "inf is not a finite number")
            raise ValueError(
                f"{d}: a parameter of {max(values):g} is beyond {MAX_PARAMETER:g}, the largest "
                "value of any quantity of a model; give the distribution of the value itself"
            )
        return self


class CorrelationSpec(_Section):
    """A rank correlation between two inputs (Gaussian copula: the correlation of
    their normal scores), for example cohesion and friction angle."""

    inputs: tuple[str, str]
    """The two inputs, by their key paths as written under `inputs`."""
    rho: bounded(-1.0, 1.0, open_lo=True, open_hi=True)
    """Correlation coefficient of the normal scores, -1 < rho < 1."""


class SweepSpec(_Section):
    """The values one input takes in a parametric sweep: a list, or a range."""

    values: list[Number] | None = Field(default=None, min_length=1, max_length=MAX_SWEEP_STEPS)
    """The values, in order."""
    start: Number | None = None
    """First value of an evenly spaced range."""
    stop: Number | None = None
    """Last value of the range (included)."""
    steps: whole(2, MAX_SWEEP_STEPS) | None = None
    """Number of values in the range (start and stop included)."""

    @model_validator(mode="after")
    def _one_form(self) -> SweepSpec:
        ranged = [k for k in ("start", "stop", "steps") if getattr(self, k) is not None]
        if self.values is not None and ranged:
            raise ValueError("give either `values`, or `start`, `stop` and `steps`, not both")
        if self.values is None and len(ranged) != 3:
            raise ValueError("give `values: [...]`, or `start`, `stop` and `steps`")
        if self.values is None and self.start == self.stop:
            # (hostile round 5: the same sample run `steps` times, unsaid)
            raise ValueError(
                f"start and stop are both {self.start:g}: every value would be the same; "
                "give a stop other than the start, or `values: [...]`"
            )
        values = [abs(v) for v in (*(self.values or ()), self.start, self.stop) if v]
        if values and max(values) > MAX_PARAMETER:
            raise ValueError(
                f"a value of {max(values):g} is beyond {MAX_PARAMETER:g}, the largest value of "
                "any quantity of a model"
            )
        return self

    def points(self) -> list[float]:
        """The values of the sweep, in order."""
        if self.values is not None:
            return [float(v) for v in self.values]
        n = int(self.steps)
        return [self.start + (self.stop - self.start) * k / (n - 1) for k in range(n)]


class StudySpec(_Section):
    """A probabilistic or parametric study (`rockdem study`): many runs of the model
    with some inputs varied, each named by its key path in this file (for example
    `joints.bedding.friction_angle` or `loads.water_table[*][1]`)."""

    inputs: dict[str, InputSpec] = {}
    """Probabilistic study: the uncertain inputs, key path -> distribution."""
    correlations: list[CorrelationSpec] = []
    """Correlations between inputs (for example cohesion and friction angle)."""
    sampler: Literal["monte-carlo", "latin-hypercube"] = "monte-carlo"
    """How the samples are drawn: monte-carlo (independent) or latin-hypercube
    (stratified: fewer samples for the same accuracy)."""
    samples: whole(1, MAX_SAMPLES) = 100
    """Number of samples (probabilistic study)."""
    seed: Seed = 0
    """Random seed: the same seed draws the same samples."""
    sweep: dict[str, SweepSpec] = Field(default={}, max_length=2)
    """Parametric study instead of `inputs`: the values of one or two inputs, run
    on their full grid."""
    compute: Literal["fos", "verdict"] = "fos"
    """Per run: fos (factor of safety by strength reduction) or verdict (the
    staged analysis at F = 1 only: faster, gives the probability of failure but
    no factor of safety)."""
    confidence: bounded(0.5, 1.0, open_hi=True) = 0.95
    """Confidence level of the interval on the probability of failure."""
    worst: whole(0, 1000) = 5
    """Write the model files of this many lowest-factor samples, for replay."""

    @model_validator(mode="after")
    def _kind(self) -> StudySpec:
        if bool(self.inputs) == bool(self.sweep):
            raise ValueError(
                "give either `inputs` (a probabilistic study) or `sweep` (a parametric one)"
                + (", not both" if self.inputs else "")
            )
        seen: set[frozenset] = set()
        for c in self.correlations:
            a, b = c.inputs
            for name in (a, b):
                if name not in self.inputs:
                    raise ValueError(f"correlations: {name!r} is not one of `inputs`")
            if a == b:
                raise ValueError(f"correlations: {a!r} with itself")
            pair = frozenset((a, b))
            if pair in seen:
                raise ValueError(f"correlations: {a!r} and {b!r} are given twice")
            seen.add(pair)
        n = 1
        for axis in self.sweep.values():
            n *= len(axis.points())
        if n > MAX_SAMPLES:
            raise ValueError(f"the sweep has {n:,} points, more than {MAX_SAMPLES:,}")
        return self

    @property
    def names(self) -> list[str]:
        """The key paths varied, in the order of the file."""
        return list(self.inputs or self.sweep)

    @property
    def kind(self) -> str:
        """``"probabilistic"`` or ``"sweep"``."""
        return "probabilistic" if self.inputs else "sweep"
