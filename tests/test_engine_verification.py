"""Verification against closed-form solutions (docs/method.md, section 5).

Each assert holds the closed form; tolerances are stated with their reason.
The factor of safety is the midpoint of a bracket of width <= 0.005 by
default, so it is within 0.25% of the limit by construction; the 0.5%
tolerances below leave room for nothing else.
"""

import numpy as np
import pytest

import rockdem as rd
from rockdem import verification as V

TAN = lambda deg: np.tan(np.radians(deg))  # noqa: E731


def joint(phi, c=0.0, **kw):
    return rd.Joint(normal_stiffness=1e6, friction_angle=phi, cohesion=c, **kw)


# ----------------------------------------------------------- single block
@pytest.mark.parametrize(
    "dip,phi", [(20, 30), (30, 35), (35, 35.4), (10, 40), (40, 45), (25, 24.6)]
)
def test_block_on_plane_factor_of_safety(dip, phi):
    """FS = tan(phi) / tan(dip) within 0.5% (one pair within 0.5 degree of the
    limit).  The stable end is an equilibrium to the solver's tolerance (1e-8
    of the loads): where work control finds the limit it lies within that
    share of the exact value (25 / 24.6: 1.3e-9 above it)."""
    fos = rd.factor_of_safety(V.block_on_plane(dip, joint(phi)))
    assert fos.mode == "strength"
    assert fos.value == pytest.approx(TAN(phi) / TAN(dip), rel=0.005)
    lo, hi = fos.bracket
    assert lo * (1 - 1e-8) <= TAN(phi) / TAN(dip) <= hi + 1e-9
    assert hi - lo <= 0.005


@pytest.mark.parametrize("dip,phi", [(35, 35.4), (35.4, 35), (20, 30), (30, 20)])
def test_block_on_plane_verdict(dip, phi):
    """Stable iff tan(phi) > tan(dip), also 0.4 degree either side of the limit."""
    a = rd.analyse(V.block_on_plane(dip, joint(phi)))
    assert a.stable == (TAN(phi) > TAN(dip))
    if not a.stable:
        assert a.unstable_blocks.tolist() == [1]
        # the mechanism slides down the dip (+x, -y), parallel to the plane
        ux, uy, _ = a.mechanism[1]
        assert ux > 0 and uy < 0
        assert np.degrees(np.arctan2(-uy, ux)) == pytest.approx(dip, abs=0.5)


@pytest.mark.parametrize("dip,phi,c", [(30, 20, 5.0), (40, 30, 10.0), (25, 15, 2.0)])
def test_block_on_plane_with_cohesion(dip, phi, c):
    """Ductile cohesion, no tension cut-off: FS = (c L + W cos d tan phi) / (W sin d)
    within 0.5%.  (With a cut-off the uphill end of the base opens where the
    weight acts outside the middle third, and loses its cohesion: a lower FS.)"""
    width, height, gamma = 2.0, 1.0, 25.0
    ductile = joint(phi, c, tensile_strength=1e4).ductile
    model = V.block_on_plane(dip, ductile, width=width, height=height, unit_weight=gamma)
    W = gamma * width * height
    exact = (c * width + W * np.cos(np.radians(dip)) * TAN(phi)) / (W * np.sin(np.radians(dip)))
    assert V.sliding_fos(dip, phi, cohesion=c, length=width, weight=W) == pytest.approx(exact)
    assert rd.factor_of_safety(model).value == pytest.approx(exact, rel=0.005)


@pytest.mark.parametrize("dip,phi,k", [(20, 35, 0.1), (25, 40, 0.15), (15, 30, 0.2)])
def test_block_on_plane_pseudo_static(dip, phi, k):
    """FS = tan(phi)(cos d - k sin d) / (sin d + k cos d) within 0.5% (kh toward +x)."""
    d = np.radians(dip)
    exact = TAN(phi) * (np.cos(d) - k * np.sin(d)) / (np.sin(d) + k * np.cos(d))
    model = V.block_on_plane(dip, joint(phi), loads=rd.Loads(seismic_h=k))
    assert rd.factor_of_safety(model).value == pytest.approx(exact, rel=0.005)


# --------------------------------------------------------------- toppling
@pytest.mark.parametrize("psi", [20.0, 30.0])
def test_toppling_limit_is_tan_psi(psi):
    """A b x h block on a base dipping psi topples iff b/h < tan(psi): checked 1% either side."""
    h = 2.0
    for ratio, stable in ((0.99, False), (1.01, True)):
        b = ratio * TAN(psi) * h
        a = rd.analyse(V.toppling_block(psi, b, h))
        assert a.stable == stable, (psi, ratio)
        if not stable:
            # the block rotates clockwise (toward the downhill side) about its toe
            assert a.mechanism[1, 2] < 0


def test_toppling_is_not_rated_by_strength_reduction():
    """Strength cannot control toppling: no misleading factor is returned."""
    fos = rd.factor_of_safety(V.toppling_block(30.0, 0.9 * TAN(30) * 2.0, 2.0))
    assert fos.value is None and fos.mode == "strength-independent"


# ---------------------------------------------------------- two-block wedge
@pytest.mark.parametrize(
    "p1,p2,stable", [(35, 30, False), (35, 31, False), (36, 30, True), (35, 32, True)]
)
def test_wedge_verdicts(p1, p2, stable):
    """The four rows of docs/method.md, section 5: unstable where the thrust F > 0."""
    thrust = V.wedge_thrust(200, 75, 37, 27, p1, p2, 35)
    assert (thrust < 0) == stable
    assert rd.analyse(V.two_block_wedge(p1, p2)).stable == stable


@pytest.mark.parametrize(
    "p1,p2,p3",
    [
        (35, 30, 35),
        (35, 31, 35),
        (36, 30, 35),
        (35, 32, 35),
        (30, 35, 35),
        (40, 25, 30),
        (38, 22, 35),
    ],
)
def test_wedge_factor_of_safety(p1, p2, p3):
    """SSR factor within 0.5% of the analytic root of Eq. 7 (tan(phi) / f);
    (38, 22) separates: the passive block slides alone at tan22/tan27."""
    exact = V.wedge_fos(200, 75, 37, 27, p1, p2, p3)
    fos = rd.factor_of_safety(V.two_block_wedge(p1, p2, p3))
    assert fos.value == pytest.approx(exact, rel=0.005)
    if exact == pytest.approx(TAN(p2) / TAN(27)):  # separation: the passive block alone
        assert fos.failed_analysis.unstable_blocks.tolist() == [2]
    else:
        assert sorted(fos.failed_analysis.unstable_blocks.tolist()) == [1, 2]


def _random_wedges(count: int, seed: int = 3):
    """Seeded random two-block wedges whose Eq. 7 factor lies in 0.3-3:
    active plane 25-50 degrees, passive 5 degrees flatter or more, friction
    15-45 on each surface, weights 50-300 and 20-200."""
    rng = np.random.default_rng(seed)
    while count:
        d1 = rng.uniform(25, 50)
        d2 = rng.uniform(5, d1 - 5)
        p = rng.uniform(15, 45, 3)
        w1, w2 = rng.uniform(50, 300), rng.uniform(20, 200)
        try:
            exact = V.wedge_fos(w1, w2, d1, d2, *p)
        except ValueError:  # no root in 0.2-5
            continue
        if 0.3 < exact < 3:
            count -= 1
            yield V.two_block_wedge(*p, w1=w1, w2=w2, d1=d1, d2=d2), exact


def test_random_wedges_read_eq7():
    """Not tuned to the paper's wedge: 8 random wedges, each within 0.2% of
    Eq. 7's root and proven by the LP (measured on 20: <= 0.04%).  (None of
    the eight separates; test_wedge_factor_of_safety's (38, 22) does.)"""
    for model, exact in _random_wedges(8):
        fos = rd.factor_of_safety(model)
        assert fos.value == pytest.approx(exact, rel=0.002)
        assert fos.proof == "lp-certificate"


# --------------------------------------------------------- jointed slope
def test_bedded_slope_factor_of_safety():
    """Bedding dipping 30 deg out of a 60 deg face, phi = 40, c = 0, vertical cross
    joints, >= 400 blocks: FS within 1% of tan40 / tan30 = 1.4534."""
    model = V.bedding_slope(bedding_spacing=1.0, cross_spacing=1.5)
    assert model.blocks.n_blocks >= 400
    fos = rd.factor_of_safety(model)
    assert fos.value == pytest.approx(TAN(40) / TAN(30), rel=0.01)
    # the mechanism: layers sliding down the bedding, out of the face
    mech = fos.failed_analysis.mechanism[fos.failed_analysis.unstable]
    moving = np.hypot(mech[:, 0], mech[:, 1]) > 0.5
    angle = np.degrees(np.arctan2(-mech[moving, 1], mech[moving, 0]))
    assert np.median(angle) == pytest.approx(30.0, abs=2.0)


# --------------------------------------------------------- iteration headroom
def test_newton_converges_with_headroom_on_the_wedge():
    """Each stable wedge solve needs far fewer Newton iterations than the limit."""
    fos = rd.factor_of_safety(V.two_block_wedge(36, 30))
    limit = rd.Settings().max_iterations
    for trial in fos.trials:
        if trial.stable:
            assert trial.evidence.iterations <= limit // 5


def test_gravity_from_scratch_needs_few_newton_iterations():
    """The 2,952-block brick slope (c = 0, FS 1.92): the staged gravity
    analysis from zero displacement converges in at most 80 Newton
    iterations.  Measured 45 with the trust radius on the Newton step and
    162 without it (the line search crawling while the shift rose x10 per
    failed search, for blocks whose springs all slide or open)."""
    system = rd.build_system(V.brick_slope(3000))
    a = rd.analyse(system)
    assert a.stable
    assert sum(step.evidence.iterations for step in a.steps) <= 80


# ---------------------------------------------- active and passive blocks
# Kovari & Fritz (1975) / Hoek & Bray (1981, "active and passive block"): an
# active block on a steep plane pushes a passive block along a flat one
# across a joint that here leans 20 degrees from the vertical (the seed
# paper's wedge, above, has a vertical one).  Upper plane 50 deg, lower 15
# deg, top at 8 m, face 60 deg, unit weight 25; c = 0.
AP_UPPER, AP_LOWER, AP_LEAN, AP_TOP, AP_GAMMA = 50.0, 15.0, 20.0, 8.0, 25.0


def _active_passive_corners():
    up, low, lean = np.radians([AP_UPPER, AP_LOWER, AP_LEAN])
    junction = np.zeros(2)  # where the joint meets both planes
    back = np.array([-AP_TOP / np.tan(up), AP_TOP])  # upper plane at the top
    head = np.array([AP_TOP * np.tan(lean), AP_TOP])  # the joint at the top
    toe = 20.0 * np.array([np.cos(low), -np.sin(low)])  # lower plane at the face
    crest = np.array([toe[0] - (AP_TOP - toe[1]) / np.tan(np.radians(60.0)), AP_TOP])
    return junction, back, head, toe, crest


def _active_passive_limit(phi: float) -> float:
    """The factor F dividing tan(phi) on all three joints at which the two
    blocks, each sliding on its plane (the active one along the upper plane,
    the passive one along the lower; their relative slip along the joint from
    the velocity triangle), are in limiting equilibrium: the force
    directions of the three joints and the total weight are then linearly
    dependent (a 4 x 4 determinant vanishes)."""
    from scipy.optimize import brentq

    junction, back, head, toe, crest = _active_passive_corners()

    def area(*p):
        x, y = np.array(p).T
        return 0.5 * abs(x @ np.roll(y, -1) - y @ np.roll(x, -1))

    w1, w2 = AP_GAMMA * area(junction, head, back), AP_GAMMA * area(junction, toe, crest, head)
    up, low, lean = np.radians([AP_UPPER, AP_LOWER, AP_LEAN])
    t1, n1 = np.array([np.cos(up), -np.sin(up)]), np.array([np.sin(up), np.cos(up)])
    t2, n2 = np.array([np.cos(low), -np.sin(low)]), np.array([np.sin(low), np.cos(low)])
    e3, n3 = np.array([np.sin(lean), np.cos(lean)]), np.array([-np.cos(lean), np.sin(lean)])
    # velocity triangle: t1 = a2 t2 + a3 e3 (active relative to passive: a3 e3)
    _, a3 = np.linalg.solve(np.column_stack([t2, e3]), t1)
    s3 = np.sign(a3)

    def matrix(F):
        mu = np.tan(np.radians(phi)) / F
        m = np.zeros((4, 4))
        m[0:2, 0] = n1 - mu * t1  # upper plane on the active block
        m[2:4, 1] = n2 - mu * t2  # lower plane on the passive block
        m[0:2, 2] = n3 - s3 * mu * e3  # the joint, on each block
        m[2:4, 2] = -(n3 - s3 * mu * e3)
        m[0:2, 3] = (0.0, -w1)
        m[2:4, 3] = (0.0, -w2)
        return m

    def det(F):
        return np.linalg.det(matrix(F))

    # the root at which the three normal forces press (N >= 0)
    grid = np.geomspace(0.2, 10.0, 400)
    sign = np.sign([det(F) for F in grid])
    for k in np.flatnonzero(sign[1:] != sign[:-1]):
        F = brentq(det, grid[k], grid[k + 1], xtol=1e-12)
        m = matrix(F)
        normal = np.linalg.lstsq(m[:, :3], -m[:, 3], rcond=None)[0]
        if np.all(normal >= 0):
            return F
    raise AssertionError("no limit with compressive joints")


@pytest.mark.parametrize("phi", [30.0, 25.0])
def test_active_and_passive_blocks_across_a_leaning_joint(phi):
    """The DEM's factor of safety matches the closed form within the search's
    bracket width (measured: 1.5511 against 1.5510 at phi 30, 1.2527 against
    1.2527 at phi 25)."""
    junction, back, head, toe, crest = _active_passive_corners()
    ground = [(-40.0, AP_TOP), back, junction, toe, (40.0, toe[1]), (40.0, -30.0), (-40.0, -30.0)]
    blocks = rd.Blocks.from_polygons(
        [ground, [junction, head, back], [junction, toe, crest, head]],
        fixed=[True, False, False],
        unit_weight=AP_GAMMA,
    )
    joint = rd.Joint(normal_stiffness=1e6, friction_angle=phi)
    fos = rd.factor_of_safety(rd.Model(blocks, joint), width=0.002)
    exact = _active_passive_limit(phi)
    assert fos.bracket[0] - 1e-9 <= exact <= fos.bracket[1] + 1e-9, (fos, exact)
    assert fos.value == pytest.approx(exact, abs=0.001)
