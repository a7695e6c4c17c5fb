"""Literature cross-check, round 6: the DEM against rigid-block benchmarks
rounds 1-5 did not cover.  Each test names its source; the reference values
are computed here, from the source's statics, not by rockdem.

* a sliding plane of joint segments and intact rock bridges in line
  (Jennings 1970, "A mathematical theory for the calculation of the
  stability of slopes in open cast mines", Proc. Symp. on the Theoretical
  Background to the Planning of Open Pit Mines, Johannesburg; the coplanar
  case as restated by Einstein et al. 1983, Int. J. Rock Mech. Min. Sci.
  20(5)): c and tan(phi) weighted by the joint persistence k,
  c_eq = k c_j + (1 - k) c_r, tan(phi_eq) = k tan(phi_j) + (1 - k)
  tan(phi_r).  Jennings' weighting by length is exact where the normal
  stress is uniform (a block whose weight acts through the middle of its
  base: a parallelogram with vertical sides); under a rectangular block it
  is not, and the reference weights each segment by the normal force the
  rigid-block statics gives it (linear stress, resultant under the weight);
* a rigid block wedged in a V-shaped notch (the DDA validation problem of
  MacLaughlin & Doolin 2006, Int. J. Numer. Anal. Meth. Geomech. 30;
  Yagoda-Biran & Hatzor 2010's blocks on inclines under pseudo-static load)
  pushed out by a horizontal acceleration kh: the least kh from the rigid
  block limit analysis of Livesley (1978, Int. J. Numer. Meth. Eng. 12) -
  contact forces at the ends of each contact, N >= 0, |S| <= N tan(phi),
  the largest kh with force and moment equilibrium - written here as a
  linear program and checked against its two closed forms, sliding up the
  far wall (kh = tan(beta + phi), the near wall lifting off) and
  overturning about the far lip (Housner 1963); where a block slides and
  turns at once it needs less than either;
* a semicircular arch of voussoirs under a horizontal acceleration
  (Oppenheim 1992, Earthquake Eng. Struct. Dyn. 21; De Jong 2009's and
  Alexakis & Makris 2014's rigid-block limit analyses, radial joints): the
  least kh for a given thickness by the same linear program, checked to
  give round 5's least thickness (Milankovitch / Heyman) at kh = 0.

Equation numbers are not quoted: the papers were not at hand to check them.

Tolerances: factors of safety 0.5% (the search's bracket is 0.002 wide;
rigid-block limit equilibrium and the DEM's ductile springs share their
assumptions).  The notch and the arch are decided 0.2% and 0.5% either
side of the critical kh (Lobatto spring points sit on the contacts' ends,
where the limit analysis puts its forces; stiff springs, so the drawn
geometry is the deformed one): as sharp as the runs allow, measured.

Findings.  (1) With brittle bridges (cohesion lost where a point yields)
under a rectangular block the DEM reads 9-13% below the ductile statics: the shear
displacement, so the elastic shear stress, is uniform along the base while
the normal stress is not, so the bridge points of least normal stress yield
first and lose their cohesion before the rest is mobilised - progressive
failure, which Jennings' simultaneous mobilisation leaves out (under the
parallelogram, where the normal stress is uniform, brittle and ductile
agree).  (2) With 2 spring points (Lobatto: the ends only) the ductile
rectangular case reads 0.3-0.8% off the statics, the trapezoid rule's moment of the
linear stress (3 and 5 points: 0.02%).  (3) Marked xfail: an arch
of t/R = 0.2 at 0.995-0.998 of its critical kh, with 5 spring points, is
reported unstable (at 0.98 it was too, until a run keeping the plastic
slip, which settles there, gave Newton its start: it stands) with proof
"dynamic-relaxation" although a statically admissible field exists (this
limit analysis, and rockdem's own equilibrium LP, which says the forces
could carry twice the loads); with 2 and 3 points the same arch stands at
0.99 / 0.985 of it, and with friction 85 degrees instead of 60 the verdict
is the same, so the friction is not the cause.
Newton finds no start ("no start after 559 iterations") and the relaxation
calls the slow creep toward the far equilibrium of a nearly-hinged arch a
mechanism ("motion over the last quarter 0.067 x the elastic
displacement").
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.optimize import linprog

import rockdem as rd
from rockdem.modes import failure_modes


def _tan(deg: float) -> float:
    return math.tan(math.radians(deg))


def _area_centroid(poly) -> tuple[float, np.ndarray]:
    x, y = np.asarray(poly, dtype=float).T
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = cross.sum() / 2
    return abs(area), np.array([((x + xn) * cross).sum(), ((y + yn) * cross).sum()]) / (6 * area)


def _limit_load(polys, contacts, mu, dead, live) -> float | None:
    """Livesley's (1978) rigid-block limit analysis: the largest lambda for
    which forces at the ends of every contact, N >= 0 along its normal n
    (from block a into block b; -1 is the fixed ground) and |S| <= mu N
    along it, hold every block in equilibrium under dead + lambda live (per
    block (fx, fy, moment about its centroid)).  None: unbounded (no
    mechanism at all); -inf: infeasible (the dead load alone fails)."""
    cents = [_area_centroid(p)[1] for p in polys]
    n_pts = 2 * len(contacts)
    nv = 2 * n_pts + 1
    A = np.zeros((3 * len(polys), nv))
    A_ub = []
    k = 0
    for a, b, P0, P1, n in contacts:
        P0, P1, n = (np.asarray(v, dtype=float) for v in (P0, P1, n))
        t = (P1 - P0) / np.linalg.norm(P1 - P0)
        for p in (P0, P1):
            for blk, sign in ((b, 1.0), (a, -1.0)):
                if blk < 0:
                    continue
                r = p - cents[blk]
                for j, v in enumerate((n, t)):
                    f = sign * v
                    A[3 * blk : 3 * blk + 3, 2 * k + j] += [f[0], f[1], r[0] * f[1] - r[1] * f[0]]
            for s in (1.0, -1.0):
                row = np.zeros(nv)
                row[2 * k], row[2 * k + 1] = -mu, s
                A_ub.append(row)
            k += 1
    A[:, -1] = np.concatenate(live)
    c = np.zeros(nv)
    c[-1] = -1.0
    r = linprog(
        c,
        A_ub=np.array(A_ub),
        b_ub=np.zeros(len(A_ub)),
        A_eq=A,
        b_eq=-np.concatenate(dead),
        bounds=[(0, None), (None, None)] * n_pts + [(None, None)],
        method="highs",
    )
    if r.status == 3:
        return None
    if r.status == 2:
        return -math.inf  # not even the dead load alone
    assert r.status == 0, r.message
    return float(r.x[-1])


# ------------------------------------- Jennings: joints and bridges in line
J_PSI, J_GAMMA = 35.0, 25.0


def _jennings_model(cuts, length, height, joint, bridge, *, shape, brittle=False, points=3):
    """A block on a plane dipping J_PSI toward +x whose base (length along
    the plane) is joint on the stretches ``cuts`` [(s0, s1), ...] (s down
    the dip from the upper end) and rock bridge elsewhere; ``shape``
    "rect": sides normal to the plane; "parallelogram": vertical sides and
    a top parallel to the base, the weight through the base's middle.
    (c, phi) pairs; ductile unless ``brittle`` (the bridges' cohesion lost
    where a point yields)."""
    p = math.radians(J_PSI)
    e, nrm = np.array([math.cos(p), -math.sin(p)]), np.array([math.sin(p), math.cos(p)])
    A, B = np.zeros(2), length * e
    ends = sorted({0.0, length, *(s for seg in cuts for s in seg)})
    up = nrm * height if shape == "rect" else np.array([0.0, height])
    block = [A + s * e for s in ends] + [B + up, A + up]
    far = A - 30 * e, B + 30 * e
    ground = [far[0], A, B, far[1], (far[1][0], -40.0), (far[0][0], -40.0)]
    blocks = rd.Blocks.from_polygons(
        [[tuple(q) for q in ground], [tuple(q) for q in block]],
        fixed=[True, False],
        unit_weight=J_GAMMA,
    )
    (cj, pj), (cr, pr) = joint, bridge
    joints = [
        rd.Joint(
            normal_stiffness=1e6,
            friction_angle=pr,
            cohesion=cr,
            residual_cohesion=0.0 if brittle else cr,
            name="bridge",
        ),
        rd.Joint(
            normal_stiffness=1e6, friction_angle=pj, cohesion=cj, residual_cohesion=cj, name="joint"
        ),
    ]
    return rd.Model(
        blocks,
        joints,  # the bridges take the default joint, the first
        joint_lines=np.array([[A + s0 * e, A + s1 * e] for s0, s1 in cuts]),
        line_joint=["joint"] * len(cuts),
        settings=rd.Settings(points_per_interface=points, load_steps=1),
    )


def _jennings_fos(k, length, weight, joint, bridge) -> float:
    """Jennings' coplanar step path: FS = (c_eq L + W cos psi tan phi_eq) /
    (W sin psi), strengths weighted by the persistence k."""
    (cj, pj), (cr, pr) = joint, bridge
    p = math.radians(J_PSI)
    c_eq = k * cj + (1 - k) * cr
    tan_eq = k * _tan(pj) + (1 - k) * _tan(pr)
    return (c_eq * length + weight * math.cos(p) * tan_eq) / (weight * math.sin(p))


def _segment_statics_fos(cuts, length, height, joint, bridge) -> float:
    """A rectangular block (sides normal to the plane): its weight meets the
    base h/2 tan(psi) down the dip of the base's middle, so the normal stress
    (linear, all of the base in compression: the shear on the base has no
    moment about it) is N / L + 12 N e (s - L / 2) / L^3; each segment
    carries its c l + N_seg tan(phi) at the limit."""
    p = math.radians(J_PSI)
    W = J_GAMMA * length * height
    N, ecc = W * math.cos(p), height / 2 * math.tan(p)
    assert ecc < length / 6  # no part of the base opens

    def sigma(s):
        return N / length + 12 * N * ecc * (s - length / 2) / length**3

    ends = sorted({0.0, length, *(s for seg in cuts for s in seg)})
    resist = 0.0
    for a, b in itertools.pairwise(ends):
        c, phi = joint if any(math.isclose(a, s0) for s0, _ in cuts) else bridge
        resist += c * (b - a) + (b - a) * (sigma(a) + sigma(b)) / 2 * _tan(phi)
    return resist / (W * math.sin(p))


JENNINGS_STRENGTHS = [((0.0, 25.0), (20.0, 50.0)), ((5.0, 30.0), (30.0, 40.0))]


@pytest.mark.parametrize("brittle", [False, True])
@pytest.mark.parametrize(
    "cuts", [[(0.0, 3.0), (5.0, 8.0)], [(1.0, 2.0), (4.0, 5.0), (7.0, 8.0)], [(0.0, 9.0)]]
)
@pytest.mark.parametrize(("joint", "bridge"), JENNINGS_STRENGTHS)
def test_jennings_coplanar_bridges_under_a_uniform_normal_stress(joint, bridge, cuts, brittle):
    """A parallelogram block 10 m along a 35 degree plane, 4 m tall
    (vertical sides): the normal stress is uniform, so Jennings' strengths
    weighted by the persistence (k = 0.6, 0.3, 0.9) are exact.  The DEM's
    factor (0.81-1.69) within 0.5% (measured 0.02%), with ductile bridges and
    with brittle ones (the uniform shear displacement brings every bridge point to its
    peak at once, so losing it after changes nothing)."""
    length, height = 10.0, 4.0
    k = sum(b - a for a, b in cuts) / length
    weight = J_GAMMA * length * math.cos(math.radians(J_PSI)) * height
    exact = _jennings_fos(k, length, weight, joint, bridge)
    model = _jennings_model(
        cuts, length, height, joint, bridge, shape="parallelogram", brittle=brittle
    )
    fos = rd.factor_of_safety(model, width=0.002)
    assert fos.mode == "strength"
    assert fos.value == pytest.approx(exact, rel=0.005)


RECT_CUTS = {
    "joints at the top": [(0.0, 3.0), (5.0, 8.0)],
    "bridges at the top": [(2.0, 5.0), (7.0, 10.0)],
}


@pytest.mark.parametrize("points", [3, 5])
@pytest.mark.parametrize("where", list(RECT_CUTS))
@pytest.mark.parametrize(("joint", "bridge"), JENNINGS_STRENGTHS)
def test_bridges_under_a_rectangular_block_carry_their_share_of_the_linear_stress(
    joint, bridge, where, points
):
    """A 10 x 3 m rectangular block on the 35 degree plane, persistence 0.6:
    the normal stress rises down the dip (the weight acts 1.05 m below the
    base's middle), so where the bridges lie matters - 1.345 / 1.188 (and
    1.351 / 1.295) with the joints / the bridges at the upper end, against
    Jennings' 1.266 (1.323) for either: the length-weighted strengths are off
    by 2-7% here.  The DEM with ductile bridges reads the segment statics
    within 0.5% (measured 0.02%) with 3 and 5 spring points."""
    cuts = RECT_CUTS[where]
    length, height = 10.0, 3.0
    exact = _segment_statics_fos(cuts, length, height, joint, bridge)
    jennings = _jennings_fos(0.6, length, J_GAMMA * length * height, joint, bridge)
    assert abs(exact / jennings - 1) > 0.02  # the stress distribution matters here
    fos = rd.factor_of_safety(
        _jennings_model(cuts, length, height, joint, bridge, shape="rect", points=points),
        width=0.002,
    )
    assert fos.value == pytest.approx(exact, rel=0.005)


@pytest.mark.parametrize("where", list(RECT_CUTS))
@pytest.mark.parametrize(("joint", "bridge"), JENNINGS_STRENGTHS)
def test_brittle_bridges_under_a_rectangular_block_fail_progressively(joint, bridge, where):
    """The same blocks with brittle bridges: the elastic shear stress is
    uniform along the base (a rigid block's base points share their shear
    displacement) while the normal stress is not, so the bridge points of
    least normal stress yield first and lose their cohesion.  The DEM then
    reads below the ductile statics (measured 9-13%) and above the factor
    with the bridges' cohesion gone altogether (friction only on them)."""
    cuts = RECT_CUTS[where]
    length, height = 10.0, 3.0
    ductile = _segment_statics_fos(cuts, length, height, joint, bridge)
    no_bonds = _segment_statics_fos(cuts, length, height, joint, (0.0, bridge[1]))
    fos = rd.factor_of_safety(
        _jennings_model(cuts, length, height, joint, bridge, shape="rect", brittle=True),
        width=0.002,
    )
    assert no_bonds < fos.value < 0.95 * ductile


# ------------------------------------------------------ a block in a V notch
def _notch(beta_l, beta_r, depth, height):
    """A V notch with its vertex O at the origin, walls rising at beta_l (to
    the lip L) and beta_r (to the lip R) to a ground surface at y = depth,
    and a block filling it and standing ``height`` above the lips (vertical
    sides from the lips up)."""
    O = np.zeros(2)
    R = np.array([depth / _tan(beta_r), depth])
    L = np.array([-depth / _tan(beta_l), depth])
    up = np.array([0.0, height])
    block = [O, R, R + up, L + up, L]
    ground = [(-20.0, -10.0), (20.0, -10.0), (20.0, depth), tuple(R), tuple(O), tuple(L)]
    ground.append((-20.0, depth))
    return ground, block, (O, L, R)


def _notch_kc(beta_l, beta_r, phi, depth, height) -> float | None:
    _, block, (O, L, R) = _notch(beta_l, beta_r, depth, height)
    area, _ = _area_centroid(block)
    b_l, b_r = math.radians(beta_l), math.radians(beta_r)
    contacts = [
        (-1, 0, O, R, (-math.sin(b_r), math.cos(b_r))),
        (-1, 0, O, L, (math.sin(b_l), math.cos(b_l))),
    ]
    return _limit_load(
        [block], contacts, _tan(phi), [np.array([0.0, -area, 0.0])], [np.array([area, 0.0, 0.0])]
    )


def _notch_model(beta_l, beta_r, phi, depth, height, kh, points=3) -> rd.Model:
    ground, block, _ = _notch(beta_l, beta_r, depth, height)
    blocks = rd.Blocks.from_polygons(
        [ground, [tuple(q) for q in block]], fixed=[True, False], unit_weight=25.0
    )
    return rd.Model(
        blocks,
        rd.Joint(normal_stiffness=1e6, friction_angle=phi),
        loads=rd.Loads(seismic_h=kh),
        settings=rd.Settings(points_per_interface=points),
    )


# (beta_l, beta_r, phi, depth, height, the mechanism)
NOTCHES = [
    (25.0, 25.0, 15.0, 1.0, 1.0, "slides"),  # up the right wall: tan 40 = 0.839
    (30.0, 15.0, 20.0, 1.0, 1.0, "slides"),  # tan 35 = 0.700
    (30.0, 30.0, 10.0, 0.5, 3.0, "topples"),  # about the right lip: 0.631
    (30.0, 35.0, 5.0, 0.5, 4.0, "slides and topples"),  # 0.393 < 0.421, 0.839
    (40.0, 35.0, 5.0, 0.5, 4.0, "slides and topples"),  # 0.333 < 0.350, 0.839
]


@pytest.mark.parametrize(("bl", "br", "phi", "depth", "height", "mode"), NOTCHES)
def test_the_limit_analysis_of_a_notch_gives_its_closed_forms(bl, br, phi, depth, height, mode):
    """The linear program against its two closed forms: the block slides
    up the right wall with the left one lifting off at kh = tan(beta_r +
    phi) (a block pushed up a plane), or overturns about the right lip at
    Housner's kh = (x_R - x_G) / (y_G - y_R), whichever is less; where the
    block both slides and turns, its kh lies below both (by 4-7% here)."""
    kc = _notch_kc(bl, br, phi, depth, height)
    _, block, (_, _, R) = _notch(bl, br, depth, height)
    _, G = _area_centroid(block)
    slide = _tan(br + phi)
    housner = (R[0] - G[0]) / (G[1] - R[1]) if G[1] > R[1] else math.inf
    expected = {"slides": slide, "topples": housner}.get(mode)
    if expected is None:
        assert kc < 0.97 * min(slide, housner)
    else:
        assert kc == pytest.approx(expected, rel=1e-9)
        assert kc < 0.99 * max(slide, housner)


@pytest.mark.parametrize("points", [2, 3])
@pytest.mark.parametrize(("bl", "br", "phi", "depth", "height", "mode"), NOTCHES)
def test_a_block_in_a_v_notch_is_pushed_out_at_the_limit_analysis_kh(
    bl, br, phi, depth, height, mode, points
):
    """The DEM stands at 0.998 kh_c and fails at 1.002 kh_c, proven (the
    equilibrium LP), in the limit analysis' mode: sliding up the right
    wall along it (no rotation), overturning about the right lip (the
    point R not moving), or both at once."""
    kc = _notch_kc(bl, br, phi, depth, height)
    assert rd.analyse(_notch_model(bl, br, phi, depth, height, 0.998 * kc, points)).stable
    a = rd.analyse(_notch_model(bl, br, phi, depth, height, 1.002 * kc, points))
    assert a.verdict == "unstable" and a.evidence.proof == "lp-certificate"
    assert list(failure_modes(a).blocks(mode)) == [1]
    ux, uy, w = a.mechanism[1]
    R = _notch(bl, br, depth, height)[2][2]
    if mode == "slides":
        assert abs(w) * 10 < 1e-6 * math.hypot(ux, uy)
        assert math.degrees(math.atan2(uy, ux)) == pytest.approx(br, abs=0.01)
    elif mode == "topples":
        G = a.system.blocks.centroid[1]
        v_R = np.array([ux - w * (R[1] - G[1]), uy + w * (R[0] - G[0])])
        assert np.linalg.norm(v_R) < 1e-4 * abs(w)  # R / 1 m from G: a pivot at R
        assert w < 0  # clockwise, toward +x


def test_a_block_locked_in_a_steep_notch_stands_whatever_the_push():
    """Where beta + phi >= 90 on both walls (60 degree walls, phi 30) no
    mechanism exists (the program is unbounded: sliding up a wall would
    need kh = tan 90, turning about a lip drives the block into the other
    wall); the DEM stands at kh = +-0.95, and without friction under its
    own weight in an asymmetric notch (the two normal forces and the weight
    meet in a point)."""
    assert _notch_kc(60.0, 60.0, 30.0, 2.0, 1.0) is None
    for kh in (0.95, -0.95):
        assert rd.analyse(_notch_model(60.0, 60.0, 30.0, 2.0, 1.0, kh)).stable
    for bl, br, depth, height in [(70.0, 20.0, 1.0, 1.0), (60.0, 15.0, 1.0, 3.0)]:
        assert rd.analyse(_notch_model(bl, br, 0.0, depth, height, 0.0)).stable


# --------------------------------------------- an arch under a horizontal kh
ARCH_R, ARCH_N = 5.0, 16


def _voussoirs(t_over_r: float, n: int = ARCH_N, R: float = 1.0):
    """As round 5: n voussoirs between radial joints at th_k = k pi / n."""
    t = t_over_r * R
    th = np.linspace(0.0, math.pi, n + 1)
    inner = np.c_[(R - t / 2) * np.cos(th), (R - t / 2) * np.sin(th)]
    outer = np.c_[(R + t / 2) * np.cos(th), (R + t / 2) * np.sin(th)]
    polys = [np.array([inner[k], outer[k], outer[k + 1], inner[k + 1]]) for k in range(n)]
    return polys, th, inner, outer


def _arch_kc(t_over_r: float, mu: float, n: int = ARCH_N) -> float | None:
    """Least kh (toward +x) that the arch cannot carry, by the limit
    analysis: contacts at every radial joint (the springings on the ground),
    their forces at the intrados and the extrados."""
    polys, th, inner, outer = _voussoirs(t_over_r, n)
    contacts = []
    for k in range(n + 1):
        nrm = np.array([-math.sin(th[k]), math.cos(th[k])])
        a, b = (-1, 0) if k == 0 else ((-1, n - 1) if k == n else (k - 1, k))
        contacts.append((a, b, inner[k], outer[k], -nrm if k == n else nrm))
    areas = [_area_centroid(p)[0] for p in polys]
    return _limit_load(
        polys,
        contacts,
        mu,
        [np.array([0.0, -a, 0.0]) for a in areas],
        [np.array([a, 0.0, 0.0]) for a in areas],
    )


def _arch(t_over_r: float, kh: float, points: int = 3, phi: float = 60.0) -> rd.Model:
    polys, *_ = _voussoirs(t_over_r, R=ARCH_R)
    w = ARCH_R * (1 + t_over_r)
    ground = [(-w, -1.0), (w, -1.0), (w, 0.0), (-w, 0.0)]
    blocks = rd.Blocks.from_polygons(
        [ground, *polys], fixed=[True] + [False] * ARCH_N, unit_weight=25.0
    )
    return rd.Model(
        blocks,
        rd.Joint(normal_stiffness=1e7, friction_angle=phi),
        loads=rd.Loads(seismic_h=kh),
        settings=rd.Settings(points_per_interface=points, load_steps=1),
    )


def test_the_arch_s_critical_kh_vanishes_at_its_least_thickness():
    """Checked where the answer is known: at kh = 0 the program's least
    thickness for 16 voussoirs is round 5's thrust-line value 0.1071 R
    (0.1075 for the continuous arch, Milankovitch / Heyman); kh_c rises
    with the thickness (0.051, 0.150, 0.287 at t/R = 0.12, 0.15, 0.2) and
    does not depend on the friction once it is high (tan 60 or 10: hinges
    only)."""
    lo, hi = 0.09, 0.12
    while hi - lo > 1e-7:
        mid = 0.5 * (lo + hi)
        kc = _arch_kc(mid, 10.0)
        lo, hi = (lo, mid) if kc is None or kc >= 0 else (mid, hi)
    assert hi == pytest.approx(0.1071, abs=1e-4)
    values = [_arch_kc(t, _tan(60.0)) for t in (0.12, 0.15, 0.2)]
    assert values == pytest.approx([0.0508, 0.1500, 0.2875], abs=1e-4)
    assert _arch_kc(0.2, 10.0) == pytest.approx(values[2], rel=1e-9)


@pytest.mark.parametrize("t_over_r", [0.12, 0.15])
def test_the_dem_arch_collapses_at_the_limit_analysis_kh(t_over_r):
    """16 voussoirs, friction 60 degrees, 3 spring points: the DEM arch
    stands at 0.995 kh_c and collapses at 1.005 kh_c, proven; the moving
    voussoirs are one run through the crown (a four-hinge mechanism: the
    hinge nearest a springing may lie a joint or two above it)."""
    kc = _arch_kc(t_over_r, _tan(60.0))
    assert rd.analyse(_arch(t_over_r, 0.995 * kc)).stable
    a = rd.analyse(_arch(t_over_r, 1.005 * kc))
    assert a.verdict == "unstable" and a.evidence.proof == "lp-certificate"
    moving = sorted(int(b) for b in a.unstable_blocks)
    assert moving == list(range(moving[0], moving[-1] + 1))
    assert moving[0] <= 3 and moving[-1] >= ARCH_N - 2


@pytest.mark.parametrize(
    "fraction",
    [
        # a run keeping the plastic slip settles at 0.98 kh_c (52,531 steps)
        # and Newton from its equilibrium finds the solve's in 3 iterations
        0.98,
        pytest.param(
            0.995,
            marks=pytest.mark.xfail(
                # not strict: the explicit dynamics is chaotic, and with
                # OpenBLAS's Sandybridge kernels the arch reads undecided (passes)
                strict=False,
                reason="an arch of t/R = 0.2 at 0.995 kh_c with 5 spring points: no Newton "
                "start, and dynamic relaxation under the solve's law reads its creep (0.22 x "
                "the elastic displacement over the last quarter, never slowing) as a "
                "mechanism although the equilibrium LP says the forces exist; a run keeping "
                "the plastic slip does not settle either (2 and 3 points: stands at 0.99 / "
                "0.985 kh_c)",
            ),
        ),
    ],
)
def test_a_thick_arch_below_its_critical_kh_is_not_reported_unstable(fraction):
    """Below kh_c a statically admissible field exists (the limit analysis
    here; rockdem's own LP agrees, 'could carry 2 times the loads'), with
    hinges only (the friction does not enter).  A verdict 'unstable' there
    is wrong; 'undecided' would be honest."""
    kc = _arch_kc(0.2, _tan(60.0))
    a = rd.analyse(_arch(0.2, fraction * kc, points=5))
    assert a.verdict != "unstable"
