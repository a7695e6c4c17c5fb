"""Sparse factorisation (rockdem.linalg) and its reuse inside Newton (rockdem.solver)."""

import os
from dataclasses import replace

import numpy as np
import pytest

import rockdem as rd
from rockdem import linalg, solver, verification
from rockdem.spring_law import SpringState


@pytest.fixture(scope="module")
def system():
    """A 1,000-block brick slope: ~3,000 unknowns, PARDISO's range where installed."""
    return rd.build_system(verification.brick_slope(1000))


def _sliding_tangent(system):
    """A non-symmetric tangent with sliding and open springs (strengths / 3)."""
    state = SpringState.initial(system.springs.n_springs)
    q = system.u_elastic
    resp, _ = solver.residual(system, q, state, 1.0, 3.0)
    assert resp.sliding.any()
    return resp, q, solver.tangent(system, resp, q, 1e-3)


@pytest.mark.parametrize("forced", ["", "superlu"])
def test_refactorised_tangents_are_solved_to_round_off(system, monkeypatch, forced):
    """One factorizer, two matrices on one pattern (symbolic analysis reused by
    PARDISO): each solution has a relative residual below 1e-10, without
    PARDISO's default iterative refinement."""
    monkeypatch.setenv("ROCKDEM_SOLVER", forced)
    _, _, J = _sliding_tangent(system)
    fz = linalg.Factorizer()
    b = system.f_ext
    for A in (system.K0, J, system.K0):
        x = fz.factorize(A).solve(b)
        assert np.linalg.norm(A @ x - b) <= 1e-10 * np.linalg.norm(b)
    assert fz.count == 3


def test_superlu_keeps_its_fill_reducing_order_on_large_systems(system):
    """Above PARDISO_FROM unknowns SuperLU takes the diagonal pivots of its
    minimum-degree order (no row swaps on a sliding tangent), so the fill
    stays that of the order: with SciPy's default partial pivoting a
    9,638-block slope's tangent filled to 159 million entries (110 s per
    factorisation) against 5.5 million (0.3-0.4 s)."""
    _, _, J = _sliding_tangent(system)
    assert J.shape[0] > linalg.PARDISO_FROM
    lu = linalg._SuperLU(J).lu
    assert np.array_equal(lu.perm_r, lu.perm_c)
    b = system.f_ext
    x = lu.solve(b)
    assert np.linalg.norm(J @ x - b) <= 1e-10 * np.linalg.norm(b)


def test_a_stale_pardiso_factor_refuses_to_solve(system):
    if linalg.backend(system.assembly.n_dof) != "pardiso":
        pytest.skip("PARDISO is not installed here")
    fz = linalg.Factorizer()
    first = fz.factorize(system.K0)
    fz.factorize(system.K0)
    with pytest.raises(RuntimeError, match="stale"):
        first.solve(system.f_ext)


def test_newton_reuses_the_factor_while_the_tangent_is_unchanged(system):
    """The spring law is piecewise linear: the same springs sliding and open and
    the same shift give the same tangent, and no new factorisation."""
    resp, q, J = _sliding_tangent(system)
    tangents = solver._Tangents(system)
    before = system.factorizer.count
    lu = tangents.factor(resp, q, 1e-3)
    assert tangents.factor(resp, q, 1e-3) is lu
    assert system.factorizer.count == before + 1 and tangents.reused == 1
    x = lu.solve(system.f_ext)
    assert np.linalg.norm(J @ x - system.f_ext) <= 1e-10 * np.linalg.norm(system.f_ext)
    # another shift, or another spring sliding: a new factorisation
    assert tangents.factor(resp, q, 1e-2) is not lu
    d_ss = resp.d_ss.copy()
    k = int(np.flatnonzero(d_ss == 0)[0])
    d_ss[k] = system.springs.ks[k]  # one spring back to elastic
    changed = replace(resp, d_ss=d_ss)
    tangents.factor(changed, q, 1e-2)
    assert system.factorizer.count == before + 3 and tangents.reused == 1


def test_the_stiffness_map_is_the_sum_over_spring_points():
    """``Assembly.stiffness`` (one precomputed sparse product of the spring
    moduli) equals ``sum_k w_k B_k^T D_k B_k`` summed spring by spring, for a
    non-symmetric ``D = [[d_nn, 0], [d_sn, d_ss]]`` with random entries."""
    system = rd.build_system(verification.bedding_slope(bedding_spacing=3.0, cross_spacing=4.5))
    asm = system.assembly
    n = system.springs.n_springs
    d_nn, d_sn, d_ss = np.random.default_rng(7).normal(size=(3, n))
    K = np.zeros((asm.n_dof, asm.n_dof))
    for k in range(n):
        D = np.array([[d_nn[k], 0.0], [d_sn[k], d_ss[k]]])
        local = asm.weight[k] * asm.B[k].T @ D @ asm.B[k]
        cols = asm.columns[k]
        keep = cols >= 0
        K[np.ix_(cols[keep], cols[keep])] += local[np.ix_(keep, keep)]
    assembled = asm.stiffness(d_nn, d_sn, d_ss).toarray()
    tol = 1e-12 * np.abs(K).max()
    assert np.allclose(assembled, K, rtol=0, atol=tol)
    shifted = asm.stiffness(d_nn, d_sn, d_ss, 0.25, system.K0).toarray()
    assert np.allclose(shifted, K + 0.25 * system.K0.toarray(), rtol=0, atol=tol)


def test_a_solve_ending_within_the_relaxation_tolerance_is_labelled_an_equilibrium():
    """Newton that stops (stall or iteration limit) with the out-of-balance
    force between the tolerance (1e-8) and dynamic relaxation's (1e-7) has
    found an equilibrium to 1e-7 and says so (``KINKED``); above 1e-7 it has
    not.  (A 2,322-block slope stalled at 2.4e-8 on a kink of the spring law,
    and the search took that for its limit.)"""
    model = verification.bedding_slope(bedding_spacing=3.0, cross_spacing=4.5)
    system = rd.build_system(model)
    state = SpringState.initial(system.springs.n_springs)
    exact = solver.newton(system, state, 1.0, 1.0, np.zeros(system.assembly.n_dof), 50)
    assert exact.converged and exact.reason == "converged"
    direction = np.random.default_rng(5).normal(size=exact.q.size) * system.assembly.dof_scale

    def merit_after(t):
        _, r = solver.residual(system, exact.q + t * direction, state, 1.0, 1.0)
        s = system.assembly.dof_scale
        return np.linalg.norm(r * s) / np.linalg.norm(system.f_ext * s)

    # displacements off the equilibrium by t x a random direction: merit ~ t
    scale = 1e-6 / merit_after(1e-6)
    for target, converged in ((5e-8, True), (5e-7, False)):
        q = exact.q + target * scale * direction
        out = solver.newton(system, state, 1.0, 1.0, q, 0)  # no iteration: judge q as it is
        assert out.converged is converged, (target, out.residuals)
        assert (out.reason == solver.KINKED) is converged


@pytest.mark.parametrize("value", ["bogus", "pardsio", "umfpack"])
def test_a_solver_choice_that_would_be_ignored_is_refused(monkeypatch, value):
    """Found by fuzzing: ROCKDEM_SOLVER=bogus was ignored silently (PARDISO ran).
    The API refuses it where the solver is chosen; the command line before any
    work, naming the variable rather than the model file."""
    from typer.testing import CliRunner

    from _cli import assert_refused
    from rockdem.cli import app

    monkeypatch.setenv("ROCKDEM_SOLVER", value)
    with pytest.raises(rd.InputError, match=r"ROCKDEM_SOLVER: .* is not a solver"):
        linalg.backend(10_000)
    r = CliRunner().invoke(app, ["fos", "--example", "wedge-verification"])
    assert_refused(r, "error: ROCKDEM_SOLVER:", "auto, pardiso, superlu")
    monkeypatch.setenv("ROCKDEM_SOLVER", " SuperLU ")
    assert linalg.backend(10_000) == "superlu"


def test_the_mkl_library_is_found_from_its_package_not_by_a_walk(monkeypatch):
    """pypardiso walks the whole environment for ``mkl_rt`` when it is not
    told where it is (0.15-0.3 s per process); rockdem reads the path from
    the ``mkl`` package's file list, and PARDISO loads that library."""
    if linalg._pardiso_module() is None:
        pytest.skip("PARDISO is not installed here")
    path = linalg._mkl_runtime()
    assert path is not None and os.path.isfile(path) and "mkl_rt" in os.path.basename(path)
    monkeypatch.setattr(linalg, "_MKL_RT", None)
    monkeypatch.setenv("PYPARDISO_MKL_RT", path)
    handle = linalg._pardiso_handle()
    assert handle.libmkl._name == path
