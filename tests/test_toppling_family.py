"""A family of seeded random toppling slopes: the DEM against Goodman & Bray.

Source: R. E. Goodman and J. W. Bray (1976), "Toppling of rock slopes";
the regular slope of E. Hoek and J. W. Bray (1981), Rock Slope Engineering,
ch. 10 (Wyllie & Mah 2004, section 9.4): columns of width dx on treads
dipping psi, the overall base at beta (step b = dx tan(beta - psi)), the
face at theta_f (a1 = dx tan(theta_f - psi)), a flat crest (a2 = dx tan psi),
friction phi on bases and faces.  The factor of safety is the one dividing
tan(phi) until the toe needs no force (:func:`toppling_fos`, checked against
the published 38.15 degrees in tests/test_limit_equilibrium.py).

Not tuned to any geometry: the slopes are drawn at random (face 50-80
degrees, treads 10-25, overall base 3-12 degrees steeper, 10-20 columns,
phi 25-45), keeping those whose limit-equilibrium factor lies in 0.3-2.5.

What they showed (measured on 58 slopes): the DEM reads Goodman & Bray's
factor within 0.6% where tan(phi) / F at the limit stays away from 1 (one
slope at 0.81 read 2.5% low).  Near it (0.85-1.15) the two part: the
sliding equation of Goodman & Bray divides by 1 - tan(phi_p) tan(phi_d),
so its toe blocks lock against
sliding as the limit friction nears 45 degrees, with the full friction of
both faces taken in their favour.  The DEM, which finds how much of that
friction the faces carry, read 2.6% above to 13% below there, and its limit
there depends on the spring points of the joints (for one slope 0.632 /
0.624 / 0.685 with 2 / 3 / 5 points; 0.3% elsewhere): the result says so.
"""

from __future__ import annotations

import numpy as np
import pytest

import rockdem as rd
from rockdem import verification as V
from rockdem.limit_equilibrium.closed_forms import stepped_heights, toppling_fos
from rockdem.result_tables import fos_summary

#: tan(phi) / F at the limit in this band: near Goodman & Bray's lock
LOCK_BAND = (0.85, 1.15)


def _slopes(seed: int, count: int, near_lock: bool):
    """``count`` random regular toppling slopes: (model, LE factor, tan(phi)/F)."""
    rng = np.random.default_rng(seed)
    found = []
    while len(found) < count:
        dx, psi, face = rng.uniform(0.5, 2.0), rng.uniform(10, 25), rng.uniform(50, 80)
        beta = psi + rng.uniform(3, 12)
        n = int(rng.integers(10, 21))
        crest = int(rng.integers(n // 3, 2 * n // 3 + 1))
        phi = rng.uniform(25, 45)
        t = np.tan(np.radians([face - psi, psi, beta - psi])) * dx
        y = stepped_heights(n, crest, t[0], t[1], t[2])
        if (y <= 0.3 * dx).any():  # columns running out above the crest
            continue
        args = dict(width=dx, step=t[2], base_dip=psi, unit_weight=2.6)
        le = toppling_fos(y, base_friction=phi, **args)
        if le is None or not 0.3 < le < 2.5:
            continue
        lock = np.tan(np.radians(phi)) / le
        if (LOCK_BAND[0] < lock < LOCK_BAND[1]) != near_lock:
            continue
        joint = rd.Joint(normal_stiffness=1e5, friction_angle=phi)
        found.append((V.toppling_staircase(y, joint=joint, **args), le, lock))
    return found


@pytest.mark.parametrize("k", range(6))
def test_random_toppling_slopes_read_goodman_and_brays_factor(k):
    """Away from the lock, within 1% of Goodman & Bray (these six: <= 0.11%)."""
    model, le, lock = _slopes(seed=5, count=6, near_lock=False)[k]
    fos = rd.factor_of_safety(model)
    assert fos.mode == "strength"
    assert fos.value == pytest.approx(le, rel=0.01), (le, lock)
    assert fos.failed_analysis.evidence.proof in {"lp-certificate", "dynamic-relaxation"}


@pytest.mark.parametrize("k", range(3))
def test_near_goodman_and_brays_lock_the_result_says_the_limit_is_not_unique(k):
    """Near the lock the DEM is never much above Goodman & Bray (their locked
    toes are the strongest a toe can be; measured +2.6% at most), and the
    result says that a toppling limit depends on the spring points."""
    model, le, lock = _slopes(seed=11, count=3, near_lock=True)[k]
    fos = rd.factor_of_safety(model)
    assert fos.value is not None and fos.value <= 1.03 * le, (le, lock)
    warnings = fos_summary(fos)["warnings"]
    assert any("a toppling limit is not unique" in w for w in warnings), warnings
