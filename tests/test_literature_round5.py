"""Literature cross-check, round 5: the DEM against rigid-block benchmarks
rounds 1-4 did not cover.  Each test names its source; the reference values
are computed here, from the source's statics, not by rockdem.

* the minimum thickness of a semicircular masonry arch under its own weight
  (Milankovitch 1907; Heyman 1969, "The safety of masonry arches", Int. J.
  Mech. Sci. 11; Heyman 1995, The Stone Skeleton; Ochsendorf's and
  Gilbert et al.'s (2006) rigid-block limit analyses): t/R = 0.1075, hinges
  at the extrados of the crown and springings and at the intrados about
  54.5 degrees from the crown.  The reference is the static (safe) theorem
  written out here - a crown thrust whose line of thrust stays within every
  joint - checked against the published continuous values at 1000
  voussoirs, and applied to the DEM's own polygonal voussoirs (16 and 36);
  with Coulomb friction at the joints the same statics gives the least
  friction coefficient an arch of a given thickness needs, so the factor of
  safety tan(phi) / mu_min;
* the pseudo-static overturning of a stack of two rigid blocks (Housner
  1963's condition applied to each rigid group of the assembly, the static
  onset of rocking of Psycharis 1990's two-block columns): kh_c =
  sum W (x_P - x_G) / sum W (y_G - y_P) about the pivot P of the top block
  alone and of the two together, the smaller governs;
* the two-wedge (active-passive) slide with an inclined joint between the
  wedges carrying cohesion: Sarma's (1979) non-vertical slices / Hoek &
  Bray's (1981, ch. 8-9) active and passive blocks, the factor of safety
  (c and tan(phi) on all three joints divided by F) and the critical
  acceleration Kc (F = 1), each block in force equilibrium with the shear
  on the inclined joint opposing the relative slip that the kinematics of
  the two translating blocks give.

Equation numbers are not quoted: the books were not at hand to check them.

Tolerances: the arch and the stack are decided within 0.2% of the critical
thickness and acceleration (the spring points include the joints' corners,
so the DEM pivots where the rigid-block analysis does; stiff springs, so
the small-displacement geometry is the drawn one): a check as sharp as the
run allows, measured to hold at 0.2% on both sides.  Factors of safety:
0.5% (the search's bracket is 0.002 wide; rigid-block limit equilibrium and
the DEM share their assumptions).  Critical accelerations: 2% either side,
as round 4.

Finding (marked xfail, strict): with cohesion on an inclined joint between
the wedges that rises into the slope, the DEM reads 4-5% below Sarma's
factor and depends on the spring points (1.605 / 1.595 / 1.581 at 2 / 3 / 5
for 1.672), although a statically admissible field with the whole joint
closed and carrying its cohesion exists up to 1.672 (the rigid-block LP
with moments, worked out here).  The joint opens at an end in the elastic
state under gravity, and a point that opens loses its cohesion for good
(docs/method.md, section 3).  Without cohesion on that joint, and with the
joint leaning the other way, the DEM reads Sarma's factor within 0.01%.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq, linprog

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


# ------------------------------------------------------ semicircular arch
ARCH_R, ARCH_GAMMA = 5.0, 25.0


def _voussoirs(R: float, t: float, n: int):
    """``n`` voussoirs of a semicircular arch of mean radius R and thickness
    t (straight chords between radial joints at th_k = k pi / n from the
    right springing); voussoir k is [intrados k, extrados k, extrados k+1,
    intrados k+1]."""
    th = np.linspace(0.0, math.pi, n + 1)
    ri, ro = R - t / 2, R + t / 2
    inner = np.c_[ri * np.cos(th), ri * np.sin(th)]
    outer = np.c_[ro * np.cos(th), ro * np.sin(th)]
    return [np.array([inner[k], outer[k], outer[k + 1], inner[k + 1]]) for k in range(n)], th


def _thrust_line(R: float, t: float, n: int, mu: float | None = None):
    """The static theorem on the right half of a symmetric arch (n even: a
    joint at the crown; a symmetric admissible thrust exists if any does,
    the constraints being convex).  Unknowns: the crown thrust H and its
    moment m = H y0 about the springing line's centre.  The portion between
    the crown and joint k (angle th) weighs W and has the first moment S
    (sum of W x); its resultant (H, -W) crosses the joint at the radius
    s = (m + S) / (W cos th + H sin th), which must lie between the intrados
    and the extrados; the normal force N = W cos th + H sin th > 0 and, with
    friction, |H cos th - W sin th| <= mu N.  Returns the LP result (None if
    no such thrust exists) and the per-joint data."""
    polys, th = _voussoirs(R, t, n)
    ri, ro = R - t / 2, R + t / 2
    rows, rhs, joints = [[ri, -1.0], [-ro, 1.0]], [0.0, 0.0], []  # y0 within the crown joint
    W = S = 0.0
    for k in range(n // 2 - 1, -1, -1):
        a, c = _area_centroid(polys[k])
        W, S = W + a, S + a * c[0]
        ct, st = math.cos(th[k]), math.sin(th[k])
        joints.append((k, W, S, ct, st))
        rows += [[ri * st, -1.0], [-ro * st, 1.0], [-st, 0.0]]
        rhs += [S - ri * W * ct, ro * W * ct - S, W * ct]
        if mu is not None:
            rows += [[ct - mu * st, 0.0], [-(ct + mu * st), 0.0]]
            rhs += [W * (st + mu * ct), W * (mu * ct - st)]
    r = linprog(
        [0.0, 0.0],
        A_ub=np.array(rows),
        b_ub=np.array(rhs),
        bounds=[(0, None), (None, None)],
        method="highs",
    )
    return (r.x if r.status == 0 else None), joints


def _t_min(n: int, mu: float | None = None) -> float:
    """Least t / R for which a thrust line exists (bisection to 1e-12)."""
    lo, hi = 0.05, 0.3
    while hi - lo > 1e-12:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if _thrust_line(1.0, mid, n, mu)[0] is not None else (mid, hi)
    return hi


def _mu_min(t_over_r: float, n: int) -> float:
    """Least friction coefficient for which a thrust line exists."""
    lo, hi = 0.0, 2.0
    while hi - lo > 1e-10:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if _thrust_line(1.0, t_over_r, n, mid)[0] is not None else (mid, hi)
    return hi


def _touching(t_over_r: float, n: int, tol: float = 1e-6):
    """At the least thickness: the crown's y0 (in t from the intrados) and
    the joints of the right half where the thrust line touches the intrados
    (-1) or the extrados (+1), as {joint k: side}."""
    x, joints = _thrust_line(1.0, t_over_r, n)
    H, m = x
    ri = 1.0 - t_over_r / 2
    out = {n // 2: round(((m / H) - ri) / t_over_r) * 2 - 1}  # the crown joint
    for k, W, S, ct, st in joints:
        s = ((m + S) / (W * ct + H * st) - ri) / t_over_r
        if s < tol:
            out[k] = -1
        elif s > 1 - tol:
            out[k] = +1
    return out


def _arch(t: float, n: int, phi: float = 45.0, points: int = 3) -> rd.Model:
    """The voussoirs (ids 1..n from the right springing) on a fixed ground
    block (id 0) whose top y = 0 carries both springings."""
    polys, _ = _voussoirs(ARCH_R, t, n)
    w = ARCH_R + t
    ground = [(-w, -1.0), (w, -1.0), (w, 0.0), (-w, 0.0)]
    blocks = rd.Blocks.from_polygons(
        [ground, *polys], fixed=[True] + [False] * n, unit_weight=ARCH_GAMMA
    )
    return rd.Model(
        blocks,
        rd.Joint(normal_stiffness=1e7, friction_angle=phi),
        settings=rd.Settings(points_per_interface=points, load_steps=1),
    )


def test_the_thrust_line_gives_milankovitch_s_minimum_thickness():
    """Milankovitch (1907) / Heyman (1969): a semicircular arch with enough
    friction needs t/R >= 0.1075, the line of thrust touching the intrados
    54.5 degrees from the crown and the extrados at the crown and the
    springings.  The statics above with 1000 voussoirs (a 0.18 degree grid)
    gives 0.10748 and the intrados at 54.54 degrees; the least friction for
    it, 0.395, is the classic result that a semicircular arch at its least
    thickness needs mu of about 0.4 (measured here, not quoted)."""
    n = 1000
    t = _t_min(n)
    assert t == pytest.approx(0.1075, abs=1e-4)
    touch = _touching(t * (1 + 1e-9), n, tol=1e-5)
    assert touch[n // 2] == +1 and touch[0] == +1  # crown and springing: extrados
    intrados = [k for k, side in touch.items() if side == -1]
    assert intrados
    angles = [90.0 - k * 180.0 / n for k in intrados]
    assert all(abs(a - 54.5) < 0.2 for a in angles), angles
    assert 0.39 < _mu_min(t * (1 + 1e-6), n) < 0.40


def _hinges(a: rd.Analysis, t: float, n: int) -> dict[int, int]:
    """The DEM mechanism's hinges: {joint k (0: right springing ... n: left
    springing): the side (-1 intrados, +1 extrados) whose corner does not
    move relatively}, for the joints with a relative rotation."""
    polys, _ = _voussoirs(ARCH_R, t, n)
    mech = a.mechanism
    cent = a.system.blocks.centroid
    scale = np.max(np.abs(mech[:, 2]))

    def velocity(i, p):
        ux, uy, w = mech[i]
        return np.array([ux - w * (p[1] - cent[i][1]), uy + w * (p[0] - cent[i][0])])

    out = {}
    for k in range(n + 1):
        below, above = (k, k + 1) if k < n else (n, 0)  # block positions (0: ground)
        poly = polys[min(k, n - 1)]
        inner, outer = (poly[0], poly[1]) if k < n else (poly[3], poly[2])
        if abs(mech[above][2] - mech[below][2]) < 0.05 * scale:
            continue
        vi = np.linalg.norm(velocity(above, inner) - velocity(below, inner))
        vo = np.linalg.norm(velocity(above, outer) - velocity(below, outer))
        out[k] = -1 if vi < 0.01 * vo else (+1 if vo < 0.01 * vi else 0)
    return out


@pytest.mark.parametrize("n", [16, 36])
def test_the_dem_arch_stands_at_its_least_thickness_and_hinges_where_the_thrust_touches(n):
    """The DEM's polygonal arch of n voussoirs (R = 5 m; 0.1071 and 0.1074 R
    by the statics above for 16 and 36, against 0.1075 for the continuous
    arch) stands at 1.002 t_min and fails at 0.998 t_min, proven (the
    equilibrium LP), friction 45 degrees (more than the 0.4 it needs).  Its
    mechanism hinges at exactly the joints where the limit thrust line
    touches - the springings' and the crown's extrados, the intrados at the
    joint nearest 54.5 degrees from the crown on each side (56.25 and 55) -
    the symmetric five-hinge mechanism, the two four-hinge ones at once."""
    t = _t_min(n)
    touch = _touching(t * (1 + 1e-9), n)
    stands = rd.analyse(_arch(1.002 * t * ARCH_R, n))
    assert stands.stable
    fails = rd.analyse(_arch(0.998 * t * ARCH_R, n))
    assert not fails.stable and fails.evidence.proof == "lp-certificate"
    expected = {k: s for k, s in touch.items()} | {n - k: s for k, s in touch.items()}
    assert len(expected) == 5
    assert _hinges(fails, 0.998 * t * ARCH_R, n) == expected


@pytest.mark.parametrize(("thickness", "phi"), [(1.2, 30.0), (1.5, 30.0), (2.0, 25.0)])
def test_the_factor_of_safety_of_a_thick_arch_is_the_least_friction_it_needs(thickness, phi):
    """An arch thicker than its least (1.2, 1.5 and 2 t_min, 16 voussoirs)
    fails by sliding and hinging when the friction falls below mu_min (the
    thrust-line statics with |T| <= mu N at every joint: 0.375, 0.343,
    0.306); strength reduction gives tan(phi) / mu_min (1.54, 1.68, 1.52)
    within 0.5%."""
    n = 16
    t = thickness * _t_min(n)
    exact = _tan(phi) / _mu_min(t, n)
    fos = rd.factor_of_safety(_arch(t * ARCH_R, n, phi=phi), width=0.002)
    assert fos.mode == "strength"
    assert fos.value == pytest.approx(exact, rel=0.005)


# ------------------------------------------------- a stack of two blocks
def _tipping_k(polys, pivot) -> float:
    """Housner (1963) for a rigid group of uniform blocks overturning toward
    +x about ``pivot``: the moment of W (kh, -1) about it vanishes at
    kh = sum W (x_P - x_G) / sum W (y_G - y_P)."""
    num = den = 0.0
    for p in polys:
        a, c = _area_centroid(p)
        num += a * (pivot[0] - c[0])
        den += a * (c[1] - pivot[1])
    return num / den


STACKS = {
    # bottom 2 x 2, a slender 1 x 2.5 top centred on it: the top rocks first
    "slender top": ([(0, 0), (2, 0), (2, 2), (0, 2)], [(0.5, 2), (1.5, 2), (1.5, 4.5), (0.5, 4.5)]),
    # a squat top flush with the bottom's right side: the pair rocks as one
    "offset top": ([(0, 0), (2, 0), (2, 2), (0, 2)], [(0.75, 2), (2, 2), (2, 3), (0.75, 3)]),
    # a 1 x 3 column capped by a 1 x 1 block: as one column, b / h = 1 / 4
    "column": ([(0, 0), (1, 0), (1, 3), (0, 3)], [(0, 3), (1, 3), (1, 4), (0, 4)]),
}


def _stack(bottom, top, kh, points) -> rd.Model:
    ground = [(-10, -2), (10, -2), (10, 0), (-10, 0)]
    blocks = rd.Blocks.from_polygons(
        [ground, bottom, top], fixed=[True, False, False], unit_weight=25.0
    )
    return rd.Model(
        blocks,
        rd.Joint(normal_stiffness=1e6, friction_angle=60.0),
        loads=rd.Loads(seismic_h=kh),
        settings=rd.Settings(points_per_interface=points),
    )


@pytest.mark.parametrize("points", [2, 3])
@pytest.mark.parametrize("name", list(STACKS))
def test_a_two_block_stack_overturns_at_the_smaller_housner_acceleration(name, points):
    """Two rigid blocks on a level base, friction 60 degrees (they do not
    slide), kh toward +x.  Either the top block rocks alone about its right
    base corner on the bottom block (kh_A = b_top / h_top) or the two rock
    together about the bottom's right corner (kh_B from the pair's centre
    of gravity): 0.40 / 0.536, 1.25 / 0.671, 1.0 / 0.25.  A mechanism with
    both hinges open at once is no weaker (its multiplier is a ratio of two
    forms linear in the hinge rotations, least at one of them alone).  The
    DEM stands at 0.998 kh_c and topples at 1.002 kh_c, the block(s) of the
    governing mechanism and no other, turning as one."""
    bottom, top = STACKS[name]
    k_top = _tipping_k([top], (max(x for x, _ in top), top[0][1]))
    k_both = _tipping_k([bottom, top], (max(x for x, _ in bottom), 0.0))
    kc = min(k_top, k_both)
    assert abs(k_top - k_both) > 0.1 * kc  # one mechanism clearly governs
    assert rd.analyse(_stack(bottom, top, 0.998 * kc, points)).stable
    a = rd.analyse(_stack(bottom, top, 1.002 * kc, points))
    assert a.verdict == "unstable"
    moving = [2] if k_top < k_both else [1, 2]
    assert list(a.unstable_blocks) == moving
    assert list(failure_modes(a).blocks("topples")) == moving
    if moving == [1, 2]:
        assert a.mechanism[1, 2] == pytest.approx(a.mechanism[2, 2], rel=1e-3)


# -------------------------------- two wedges with an inclined joint (Sarma)
# The slope faces +x: the upper plane (dip 50) from U on the crest to the
# kink K at the origin, the lower plane (dip 20) from K to the toe T, a 70
# degree face from T to the crest at y = 10; the joint between the wedges
# runs from K to J on the crest at 70 degrees, rising into the slope
# (lean -1) or toward the face (lean +1).
W_D1, W_D2, W_DELTA, W_TOP, W_TOE, W_FACE, W_GAMMA = 50.0, 20.0, 70.0, 10.0, -4.0, 70.0, 26.0


def _wedge_geometry(lean: int):
    K = np.array([0.0, 0.0])
    U = np.array([-W_TOP / _tan(W_D1), W_TOP])
    T = np.array([-W_TOE / _tan(W_D2), W_TOE])
    C = T + np.array([-(W_TOP - W_TOE) / _tan(W_FACE), W_TOP - W_TOE])
    J = np.array([lean * W_TOP / _tan(W_DELTA), W_TOP])
    ground = [(-40.0, W_TOP), U, K, T, (40.0, W_TOE), (40.0, -30.0), (-40.0, -30.0)]
    return ground, [U, K, J], [K, T, C, J], (U, K, T, J)


def _sarma(upper, lower, between, lean, F=1.0, kh=0.0):
    """Sarma (1979) / Hoek & Bray's active and passive blocks: each block in
    force equilibrium under W (kh, -1), its base reaction and the force of
    the other block, every joint at its limit |S| = (c L + N tan phi) / F
    against the relative slip.  The kinematics: block 1 slides along U->K
    at unit speed, block 2 along K->T at v2, and e1 - v2 e2 = s t3 gives the
    slip s along the joint between them (t3 = K->J).  Unknowns N1, N2, N3
    and the horizontal force P (toward -x) that block 2 would need: the
    limit is P = 0.  (c, phi) pairs.  Returns (N1, N2, N3, P)."""
    _, b1, b2, (U, K, T, J) = _wedge_geometry(lean)
    W1, W2 = W_GAMMA * _area_centroid(b1)[0], W_GAMMA * _area_centroid(b2)[0]
    L1, L2, L3 = np.linalg.norm(K - U), np.linalg.norm(T - K), np.linalg.norm(J - K)
    e1, e2, t3 = (K - U) / L1, (T - K) / L2, (J - K) / L3
    v2, s = np.linalg.solve(np.c_[e2, t3], e1)
    assert v2 > 0  # both blocks move down their planes
    n1, n2 = np.array([-e1[1], e1[0]]), np.array([-e2[1], e2[0]])  # up, into the blocks
    n3 = np.array([t3[1], -t3[0]])
    n3 = n3 if n3 @ (U - K) > 0 else -n3  # from block 2 into block 1
    d3 = np.sign(s) * t3  # block 1's slip relative to block 2
    (c1, p1), (c2, p2), (c3, p3) = upper, lower, between
    load1, load2 = W1 * np.array([kh, -1.0]), W2 * np.array([kh, -1.0])
    A, b = np.zeros((4, 4)), np.zeros(4)
    A[0:2, 0] = n1 - _tan(p1) / F * e1
    A[0:2, 2] = n3 - _tan(p3) / F * d3
    b[0:2] = -(load1 - c1 * L1 / F * e1 - c3 * L3 / F * d3)
    A[2:4, 1] = n2 - _tan(p2) / F * e2
    A[2:4, 2] = -(n3 - _tan(p3) / F * d3)
    A[2:4, 3] = [-1.0, 0.0]
    b[2:4] = -(load2 - c2 * L2 / F * e2 + c3 * L3 / F * d3)
    return np.linalg.solve(A, b)


def _sarma_fos(upper, lower, between, lean) -> float:
    F = brentq(lambda f: _sarma(upper, lower, between, lean, F=f)[3], 0.2, 5.0, xtol=1e-12)
    assert min(_sarma(upper, lower, between, lean, F=F)[:3]) > 0  # all joints in compression
    return F


def _sarma_kc(upper, lower, between, lean) -> float:
    kc = brentq(lambda k: _sarma(upper, lower, between, lean, kh=k)[3], -0.5, 0.9, xtol=1e-12)
    assert min(_sarma(upper, lower, between, lean, kh=kc)[:3]) > 0
    return kc


def _wedges(upper, lower, between, lean, kh=0.0, points=3) -> rd.Model:
    """Ductile joints (limit equilibrium keeps the cohesion at the limit)."""
    ground, b1, b2, (U, K, T, _) = _wedge_geometry(lean)
    blocks = rd.Blocks.from_polygons(
        [ground, b1, b2], fixed=[True, False, False], unit_weight=W_GAMMA
    )

    def joint(cp, name):
        c, phi = cp
        return rd.Joint(
            normal_stiffness=1e6, friction_angle=phi, cohesion=c, residual_cohesion=c, name=name
        )

    return rd.Model(
        blocks,
        [joint(between, "between"), joint(upper, "upper"), joint(lower, "lower")],
        joint_lines=np.array([[U, K], [K, T]]),
        line_joint=[1, 2],
        loads=rd.Loads(seismic_h=kh),
        settings=rd.Settings(points_per_interface=points, load_steps=1),
    )


WEDGE_CASES = [
    ((0.0, 35.0), (0.0, 35.0), (20.0, 30.0), 1),  # 1.293
    ((10.0, 30.0), (5.0, 35.0), (30.0, 25.0), 1),  # 1.345
    ((10.0, 30.0), (5.0, 35.0), (0.0, 25.0), -1),  # 1.539
]


@pytest.mark.parametrize("points", [2, 3])
@pytest.mark.parametrize(("upper", "lower", "between", "lean"), WEDGE_CASES)
def test_two_wedges_with_an_inclined_joint_between_them_at_sarma_s_factor(
    upper, lower, between, lean, points
):
    """Sarma's factor of the two translating wedges (c and tan(phi) on all
    three joints divided by F; 1.293, 1.345 and 1.539): the DEM's within
    0.5%, with 2 and 3 spring points (measured 0.01%); both wedges slide."""
    exact = _sarma_fos(upper, lower, between, lean)
    fos = rd.factor_of_safety(_wedges(upper, lower, between, lean, points=points), width=0.002)
    assert fos.value == pytest.approx(exact, rel=0.005)
    assert list(failure_modes(fos.failed_analysis).blocks("slides")) == [1, 2]


@pytest.mark.parametrize(("upper", "lower", "between", "lean"), WEDGE_CASES[:2])
def test_two_wedges_fail_at_sarma_s_critical_acceleration(upper, lower, between, lean):
    """Sarma's (1979) critical acceleration Kc of the same wedges at their
    full strengths (0.157 and 0.189): the DEM stands at 0.98 Kc and both
    wedges slide at 1.02 Kc."""
    kc = _sarma_kc(upper, lower, between, lean)
    assert kc > 0.05
    assert rd.analyse(_wedges(upper, lower, between, lean, kh=0.98 * kc)).stable
    a = rd.analyse(_wedges(upper, lower, between, lean, kh=1.02 * kc))
    assert a.verdict == "unstable"
    assert list(a.unstable_blocks) == [1, 2]


COHESIVE_BETWEEN = ((10.0, 30.0), (5.0, 35.0), (30.0, 25.0), -1)  # Sarma: 1.672


def _admissible_with_moments(F, upper, lower, between, lean) -> bool:
    """The rigid-block static theorem with moments: on each joint two normal
    forces at its ends (>= 0: any non-negative linear normal stress) and a
    shear |S| <= (c L + N tan phi) / F anywhere on it; force and moment
    equilibrium of both wedges.  Is there such a field?"""
    _, b1, b2, (U, K, T, J) = _wedge_geometry(lean)
    polys = [np.array(b1), np.array(b2)]
    faces = [(U, K, 0, -1, upper), (K, T, 1, -1, lower), (K, J, 0, 1, between)]
    A_eq, b_eq = np.zeros((6, 9)), np.zeros(6)
    for i, p in enumerate(polys):
        a, c = _area_centroid(p)
        f = W_GAMMA * a * np.array([0.0, -1.0])
        b_eq[3 * i : 3 * i + 3] = -np.array([f[0], f[1], c[0] * f[1] - c[1] * f[0]])
    A_ub, b_ub = [], []
    for j, (p, q, a, b, (c, phi)) in enumerate(faces):
        p, q = np.asarray(p, float), np.asarray(q, float)
        L = np.linalg.norm(q - p)
        e = (q - p) / L
        n = np.array([-e[1], e[0]])
        n = n if n @ (polys[a].mean(axis=0) - p) > 0 else -n  # into block a
        for blk, sign in ((a, 1.0), (b, -1.0)):
            if blk < 0:
                continue
            for col, at, d in ((3 * j, p, n), (3 * j + 1, q, n), (3 * j + 2, p, e)):
                f = sign * d
                A_eq[3 * blk : 3 * blk + 3, col] += [f[0], f[1], at[0] * f[1] - at[1] * f[0]]
        for side in (1.0, -1.0):
            row = np.zeros(9)
            row[[3 * j, 3 * j + 1, 3 * j + 2]] = [-_tan(phi) / F, -_tan(phi) / F, side]
            A_ub.append(row)
            b_ub.append(c * L / F)
    r = linprog(
        np.zeros(9),
        A_ub=np.array(A_ub),
        b_ub=np.array(b_ub),
        A_eq=A_eq,
        b_eq=b_eq,
        bounds=[(0, None), (0, None), (None, None)] * 3,
        method="highs",
    )
    return r.status == 0


def test_the_cohesive_inclined_joint_can_carry_sarma_s_factor_with_moments():
    """The case the DEM reads low (below): Sarma's factor 1.672 is not an
    artefact of leaving out moment equilibrium - a statically admissible
    field with every joint closed (normal stress >= 0) and at most at its
    strength carries both wedges at 0.999 x 1.672 and none at 1.001 x.
    Cohesion on the joint between the wedges adds 0.133 to the 1.539 it has
    without."""
    exact = _sarma_fos(*COHESIVE_BETWEEN)
    assert _admissible_with_moments(0.999 * exact, *COHESIVE_BETWEEN)
    assert not _admissible_with_moments(1.001 * exact, *COHESIVE_BETWEEN)
    upper, lower, _, lean = COHESIVE_BETWEEN
    assert exact - _sarma_fos(upper, lower, (0.0, 25.0), lean) > 0.1


@pytest.mark.xfail(
    strict=True,
    reason="DEM 1.605/1.595/1.581 at 2/3/5 spring points for Sarma's 1.672: the joint "
    "between the wedges opens at an end under gravity and an opened point loses its "
    "cohesion for good, though an admissible field keeping it closed exists",
)
def test_cohesion_on_a_joint_rising_into_the_slope_is_read_at_sarma_s_factor():
    """The joint between the wedges rising into the slope (lean -1) with
    c = 30 kPa on it: Sarma's factor 1.672 (the same with moments, above).
    The DEM reads 4.6% low at 3 points, between Sarma's factor without that
    cohesion (1.539) and with it."""
    exact = _sarma_fos(*COHESIVE_BETWEEN)
    fos = rd.factor_of_safety(_wedges(*COHESIVE_BETWEEN), width=0.002)
    assert fos.value == pytest.approx(exact, rel=0.005)


def test_the_dem_s_shortfall_on_the_cohesive_joint_is_its_opening():
    """What the xfail above measures, held as it stands so that a change
    shows: at the failed end of the search the joint between the wedges is
    partly open (a sixth of it, its end point, at 3 spring points) and the
    factor lies between Sarma's without and with that joint's cohesion."""
    upper, lower, _, lean = COHESIVE_BETWEEN
    fos = rd.factor_of_safety(_wedges(*COHESIVE_BETWEEN), width=0.002)
    assert _sarma_fos(upper, lower, (0.0, 25.0), lean) < fos.value < _sarma_fos(*COHESIVE_BETWEEN)
    limit = fos.failed_analysis.limit_interfaces
    between = list(limit.kind).index("between")
    assert limit.open_fraction[between] > 0
