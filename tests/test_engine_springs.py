"""Winkler springs: quadrature, the paper's lumped stiffness, the spring law, the tangent."""

import numpy as np
import pytest

import rockdem as rd
from rockdem import verification
from rockdem.solver import build_system, residual
from rockdem.spring_law import SpringState
from rockdem.springs import quadrature


def _two_blocks(L=2.0, h=1.0, kn=3e6, ks=1.2e6, rule="lobatto", n=3, x0=0.3, y0=-0.7):
    """Block b sits on fixed block a along an interface of length L (from x0, y0)."""
    a = [(x0 - 1, y0 - 1), (x0 + L + 1, y0 - 1), (x0 + L + 1, y0), (x0 - 1, y0)]
    b = [(x0, y0), (x0 + L, y0), (x0 + L, y0 + h), (x0, y0 + h)]
    blocks = rd.Blocks.from_polygons([a, b], fixed=[True, False])
    joint = rd.Joint(normal_stiffness=kn, shear_stiffness=ks, friction_angle=30)
    model = rd.Model(blocks, joint, settings=rd.Settings(quadrature=rule, points_per_interface=n))
    return build_system(model)


@pytest.mark.parametrize("rule,n", [("lobatto", 3), ("lobatto", 5), ("gauss", 2), ("gauss", 4)])
def test_quadrature_weights_sum_to_length_and_integrate_quadratics(rule, n):
    xi, w = quadrature(rule, n)
    assert w.sum() == pytest.approx(2.0, rel=1e-14)
    assert np.dot(w, xi**2) == pytest.approx(2.0 / 3.0, rel=1e-14)


@pytest.mark.parametrize("rule,n", [("lobatto", 3), ("gauss", 2), ("lobatto", 4), ("gauss", 3)])
def test_elastic_stiffness_equals_the_papers_lumped_form(rule, n):
    """Seed paper Eq. 3 (with Eq. 1-2 corrected, docs/method.md section 2): at the interface
    midpoint P the stiffness is diag(kn L, ks L, kn L^3 / 12) in (n, s, w)."""
    L, kn, ks = 2.0, 3e6, 1.2e6
    system = _two_blocks(L=L, kn=kn, ks=ks, rule=rule, n=n)
    K = system.K0.toarray()  # 3 x 3: the free block's (ux, uy, w) at its centroid
    c = system.blocks.centroid[1]
    P = system.interfaces.midpoint[0]
    r = P - c
    # (dn, ds, dw) at P from centroid dofs: n = (0, 1), t = (1, 0) for this interface
    n, t = system.interfaces.normal[0], system.interfaces.tangent[0]
    T = np.array(
        [
            [-n[0], -n[1], -(r[0] * n[1] - r[1] * n[0])],
            [-t[0], -t[1], -(r[0] * t[1] - r[1] * t[0])],
            [0.0, 0.0, -1.0],
        ]
    )
    lumped = np.diag([kn * L, ks * L, kn * L**3 / 12])
    assert np.allclose(K, T.T @ lumped @ T, rtol=1e-12, atol=1e-6 * kn)


def test_one_point_rule_leaves_the_block_free_to_rotate_and_is_rejected():
    """One spring point per interface gives no rotational stiffness (Kw = 0)."""
    with pytest.raises(rd.InputError, match="singular"):
        _two_blocks(rule="gauss", n=1)


def _state(system):
    return SpringState.initial(system.springs.n_springs)


def test_tension_cut_off_and_no_yield_in_compression():
    system = _two_blocks()
    asm = system.assembly
    # push the block down by 1e-3 (compression) and lift by 1e-3 (tension)
    for uy, expect_open in ((-1e-3, False), (1e-3, True)):
        q = np.array([0.0, uy, 0.0])
        resp, _ = residual(system, q, _state(system), 0.0, 1.0)
        assert np.all(resp.open == expect_open)
        if not expect_open:
            assert np.allclose(resp.sigma, 3e6 * 1e-3)  # compression positive, no cap
        else:
            assert np.allclose(resp.sigma, 0.0) and np.allclose(resp.tau, 0.0)
    assert asm.n_dof == 3


def test_mohr_coulomb_return_mapping_caps_shear_at_the_strength():
    system = _two_blocks()
    sigma = 3e6 * 1e-3
    for ux in (1e-5, 1e-2, -1e-2):
        q = np.array([ux, -1e-3, 0.0])
        resp, _ = residual(system, q, _state(system), 0.0, 1.0)
        cap = sigma * np.tan(np.radians(30))
        trial = 1.2e6 * ux  # ds = -ux: block b moves +x relative to a along t
        assert np.allclose(np.abs(resp.tau), min(abs(trial), cap), rtol=1e-12)
        assert np.all(resp.sliding == (abs(trial) > cap))


def test_consistent_tangent_matches_finite_differences():
    """The assembled (non-symmetric) tangent is the derivative of the
    out-of-balance force, checked on a state with open, sliding and elastic points."""
    model = verification.bedding_slope(bedding_spacing=4, cross_spacing=6, height=12)
    system = build_system(model)
    asm = system.assembly
    rng = np.random.default_rng(1)
    q = rng.normal(size=asm.n_dof) * system.elastic_scale * asm.dof_scale * 2
    state = _state(system)
    resp, r = residual(system, q, state, 1.0, 1.0)
    assert resp.open.any() and resp.sliding.any() and (~resp.open & ~resp.sliding).any()
    J = asm.stiffness(resp.d_nn, resp.d_sn, resp.d_ss).toarray()
    assert not np.allclose(J, J.T)  # friction couples shear to normal stress
    for _ in range(3):
        d = rng.normal(size=asm.n_dof) * system.elastic_scale * asm.dof_scale * 1e-7
        _, r2 = residual(system, q + d, state, 1.0, 1.0)
        # r = f - f_int, so dr = -J d (away from kinks the law is linear)
        assert np.linalg.norm((r2 - r) + J @ d) <= 1e-6 * np.linalg.norm(J @ d)


def test_tension_breaks_widest_opening_beyond_the_strength_in_force_first():
    """Of two bonded points open at the end of a solve, the one opened
    farther beyond its tensile strength as it stands (here divided by a
    strength-reduction factor of 2) breaks first; the other is re-judged
    after the loads have moved.  (Measured against the peak strength, the
    order reversed: A, 4e-5 beyond its reduced strength, was deferred
    behind B, 1e-6 beyond.)"""
    from types import SimpleNamespace

    from rockdem.spring_law import Response, widest_openings_first

    kn = np.array([1e6, 1e6, 1e6])
    springs = SimpleNamespace(kn=kn)
    from dataclasses import replace

    state = replace(SpringState.initial(3), broken=np.array([False, False, True]))
    tensile = np.array([100.0, 0.0, 0.0]) / 2.0  # A: T 100 at F = 2; B: T 0, cohesive
    cohesion = np.array([10.0, 10.0, 0.0]) / 2.0
    dn = np.array([9e-5, 1e-6, 1e-3])  # C: broken already, wide open
    zero = np.zeros(3)
    response = Response(zero, zero, zero, kn * dn > tensile, zero > 0, zero, zero, zero)
    out, deferred = widest_openings_first(springs, state, response, dn, (cohesion, zero, tensile))
    assert deferred and out.open.tolist() == [True, False, True]
    # one point open: nothing deferred, the response as it was
    alone = Response(zero, zero, zero, np.array([False, True, False]), zero > 0, zero, zero, zero)
    same, deferred = widest_openings_first(springs, state, alone, dn, (cohesion, zero, tensile))
    assert not deferred and same is alone


def test_a_cascade_of_failures_cut_short_is_warned(monkeypatch):
    """Failures redistributed round after round up to MAX_CASCADE: the last
    round's are not committed, and the analysis says so (set to 1 here; the
    heel of a block lifted by a seismic load opens, and the base then
    yields)."""
    from rockdem import redistribution
    from rockdem.verification import block_on_plane

    joint = rd.Joint(normal_stiffness=1e6, friction_angle=35, cohesion=5, tensile_strength=0.0)
    loads = rd.Loads(seismic_h=0.1, seismic_v=0.05)
    model = block_on_plane(30, joint, width=2.0, height=2.0, unit_weight=25, loads=loads)
    monkeypatch.setattr(redistribution, "MAX_CASCADE", 1)
    with pytest.warns(rd.ModelWarning, match="kept spreading for 1 rounds") as said:
        a = rd.analyse(model)
    assert a.stable and len([w for w in said if "kept spreading" in str(w.message)]) >= 1
