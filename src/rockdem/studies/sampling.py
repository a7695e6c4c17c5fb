"""Distributions, correlated samples (Gaussian copula) and sweep grids.

Samples are drawn as uniforms ``u`` in (0, 1)^d, by Monte Carlo (NumPy's
default generator) or Latin hypercube (:class:`scipy.stats.qmc.LatinHypercube`),
both from the study's seed; correlation is imposed on the normal scores
``z = Phi^-1(u)`` by the Cholesky factor of the correlation matrix, and each
input is the inverse CDF of its distribution at ``Phi(z)``.  The same seed,
sampler and number of samples give the same samples.
"""

from __future__ import annotations

import itertools

import numpy as np
from scipy import stats
from scipy.stats import qmc

from .spec import InputSpec, StudySpec

#: Uniforms are kept this far inside (0, 1), so that no inverse CDF is infinite.
_EPS = 1e-12


def distribution(spec: InputSpec):
    """The frozen :mod:`scipy.stats` distribution of an input."""
    d = spec.distribution
    if d == "normal":
        return stats.norm(loc=spec.mean, scale=spec.sd)
    if d == "lognormal":  # mean and sd of the value itself
        s2 = np.log1p((spec.sd / spec.mean) ** 2)
        return stats.lognorm(
            s=np.sqrt(s2), scale=spec.mean / np.sqrt(1.0 + (spec.sd / spec.mean) ** 2)
        )
    if d == "uniform":
        return stats.uniform(loc=spec.min, scale=spec.max - spec.min)
    if d == "triangular":
        width = spec.max - spec.min
        return stats.triang(c=(spec.mode - spec.min) / width, loc=spec.min, scale=width)
    if d == "truncated-normal":
        a, b = (spec.min - spec.mean) / spec.sd, (spec.max - spec.mean) / spec.sd
        return stats.truncnorm(a, b, loc=spec.mean, scale=spec.sd)
    raise ValueError(f"unknown distribution {d!r}")


def correlation_matrix(spec: StudySpec) -> np.ndarray:
    """The correlation matrix of the normal scores, in the order of ``spec.names``."""
    names = spec.names
    R = np.eye(len(names))
    for c in spec.correlations:
        i, j = names.index(c.inputs[0]), names.index(c.inputs[1])
        R[i, j] = R[j, i] = c.rho
    return R


def cholesky(spec: StudySpec) -> np.ndarray:
    """Lower Cholesky factor of the correlation matrix, or ValueError if it is not
    positive definite (correlations that contradict each other)."""
    R = correlation_matrix(spec)
    try:
        return np.linalg.cholesky(R)
    except np.linalg.LinAlgError:
        raise ValueError(
            "the correlations contradict each other (the correlation matrix is not "
            "positive definite)"
        ) from None


def uniforms(n: int, d: int, sampler: str, seed: int) -> np.ndarray:
    """``n x d`` uniforms in (0, 1): Monte Carlo or Latin hypercube, from ``seed``."""
    gen = np.random.default_rng(seed)
    if sampler == "latin-hypercube":
        try:
            engine = qmc.LatinHypercube(d=d, rng=gen)
        except TypeError:  # SciPy < 1.15
            engine = qmc.LatinHypercube(d=d, seed=gen)
        u = engine.random(n)
    elif sampler == "monte-carlo":
        u = gen.random((n, d))
    else:
        raise ValueError(f"unknown sampler {sampler!r}")
    return np.clip(u, _EPS, 1.0 - _EPS)


def draw(spec: StudySpec) -> np.ndarray:
    """The ``samples x inputs`` values of a probabilistic study (columns in the order
    of ``spec.names``)."""
    names = spec.names
    u = uniforms(spec.samples, len(names), spec.sampler, spec.seed)
    if spec.correlations:
        L = cholesky(spec)
        z = stats.norm.ppf(u) @ L.T
        u = np.clip(stats.norm.cdf(z), _EPS, 1.0 - _EPS)
    x = np.empty_like(u)
    for k, name in enumerate(names):
        x[:, k] = distribution(spec.inputs[name]).ppf(u[:, k])
    return x


def medians(spec: StudySpec) -> np.ndarray:
    """The median of every input (the nominal model checked before a study)."""
    if spec.kind == "sweep":
        return np.array([spec.sweep[n].points()[0] for n in spec.names])
    return np.array([float(distribution(spec.inputs[n]).median()) for n in spec.names])


def grid(spec: StudySpec) -> np.ndarray:
    """The points of a parametric sweep: the full grid, the first input slowest."""
    axes = [spec.sweep[n].points() for n in spec.names]
    return np.array(list(itertools.product(*axes)), dtype=float).reshape(-1, len(axes))


def samples(spec: StudySpec) -> np.ndarray:
    """Every sample of the study (``draw`` or ``grid``)."""
    return grid(spec) if spec.kind == "sweep" else draw(spec)
