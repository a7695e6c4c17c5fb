"""Line loads: uniform and linearly varying (trapezoidal) tractions on block boundaries.

Closed form: a traction varying linearly from q0 to q1 over a length L has
the resultant L (q0 + q1) / 2 acting at L (q0 + 2 q1) / (3 (q0 + q1)) from
the q0 end (statics of a trapezoid).
"""

from __future__ import annotations

import numpy as np
import pytest

import rockdem as rd
from rockdem.loads import block_loads

B, H = 4.0, 2.0


def two_blocks():
    """Two free blocks side by side on the ground, tops at y = H over 0..B."""
    ground = [(-5, -1), (9, -1), (9, 0), (-5, 0)]
    left = [(0, 0), (B / 2, 0), (B / 2, H), (0, H)]
    right = [(B / 2, 0), (B, 0), (B, H), (B / 2, H)]
    return rd.Blocks.from_polygons([ground, left, right], fixed=[True, False, False])


def trapezoid(q0, q1, a, b):
    """Resultant and its position of a load q0 at a to q1 at b (1-D)."""
    L = b - a
    R = L * (q0 + q1) / 2
    x = a + L * (q0 + 2 * q1) / (3 * (q0 + q1))
    return R, x


@pytest.mark.parametrize(("q0", "q1"), [(0.0, 30.0), (10.0, 30.0), (30.0, 10.0), (20.0, 20.0)])
def test_trapezoid_gives_each_block_its_exact_force_and_moment(q0, q1):
    blocks = two_blocks()
    load = rd.LineLoad((0.0, H), (B, H), 0.0, -q0, q_end=(0.0, -q1))
    f = block_loads(blocks, rd.Loads(gravity=False, lines=(load,)))
    q_mid = q0 + (q1 - q0) / 2  # the traction where the blocks meet
    for k, (a, b, qa, qb) in enumerate([(0.0, B / 2, q0, q_mid), (B / 2, B, q_mid, q1)], 1):
        R, x = trapezoid(qa, qb, a, b)
        cx = blocks.centroid[k, 0]
        assert f[k, 0] == pytest.approx(0.0, abs=1e-12)
        assert f[k, 1] == pytest.approx(-R, rel=1e-12)
        assert f[k, 2] == pytest.approx((x - cx) * -R, rel=1e-9, abs=1e-9)


def test_uniform_load_is_the_trapezoid_with_equal_ends():
    blocks = two_blocks()
    uniform = rd.LineLoad((0.0, H), (B, H), 3.0, -20.0)
    same = rd.LineLoad((0.0, H), (B, H), 3.0, -20.0, q_end=(3.0, -20.0))
    fa = block_loads(blocks, rd.Loads(gravity=False, lines=(uniform,)))
    fb = block_loads(blocks, rd.Loads(gravity=False, lines=(same,)))
    np.testing.assert_allclose(fa, fb, rtol=1e-12, atol=1e-12)


def test_a_line_load_inside_a_block_is_refused():
    """Found by fuzzing: a line load across the middle of a block (y = H / 2)
    was taken, while one across open air was refused; a load acts on the
    rock's surface (or a joint), so both are refused, each saying why."""
    blocks = two_blocks()
    inside = rd.LineLoad((0.2, H / 2), (1.8, H / 2), 0.0, -10.0, name="buried")
    with pytest.raises(rd.InputError, match="buried: lies inside a block, not on its boundary"):
        block_loads(blocks, rd.Loads(gravity=False, lines=(inside,)))
    above = rd.LineLoad((0.0, H + 1), (B, H + 1), 0.0, -10.0, name="in the air")
    with pytest.raises(rd.InputError, match="does not lie on block boundaries"):
        block_loads(blocks, rd.Loads(gravity=False, lines=(above,)))
    # on the surface, and on the joint between the blocks (pushing sideways)
    block_loads(blocks, rd.Loads(gravity=False, lines=(rd.LineLoad((0, H), (B, H), 0, -10),)))
    joint = rd.LineLoad((B / 2, 0.1), (B / 2, H - 0.1), 10.0, 0.0)
    block_loads(blocks, rd.Loads(gravity=False, lines=(joint,)))


def test_a_line_load_pulling_away_from_the_surface_says_so():
    """Found by fuzzing: an uplift on the crest (q = (0, +10)) was "does not
    lie on block boundaries all along", though it lies on the crest."""
    uplift = rd.LineLoad((0.0, H), (B, H), 0.0, 10.0, name="uplift")
    with pytest.raises(rd.InputError, match=r"uplift: pulls away from the rock \(traction"):
        block_loads(two_blocks(), rd.Loads(gravity=False, lines=(uplift,)))


def test_a_trapezoid_turning_from_push_to_pull_is_refused_as_such():
    """Found by fuzzing: q from (0, -10) to (0, 5) was refused as a Gauss
    point 'at (-8.64391, 10)' that 'does not act on any block'."""
    turning = rd.LineLoad((0.0, H), (B, H), 0.0, -10.0, name="turning", q_end=(0.0, 5.0))
    with pytest.raises(rd.InputError, match="turning: has a traction that turns from pushing"):
        block_loads(two_blocks(), rd.Loads(gravity=False, lines=(turning,)))


def test_a_line_load_on_the_fixed_ground_alone_is_refused():
    """Found by fuzzing: a line load on the ground's surface beside the
    blocks pushed only into the fixed block, where it carries nothing, and
    vanished from the loads without a word (a point load there is refused)."""
    blocks = two_blocks()
    beside = rd.LineLoad((-4.0, 0.0), (-1.0, 0.0), 0.0, -10.0, name="on the ground")
    with pytest.raises(rd.InputError, match="on the ground: acts only on fixed blocks"):
        block_loads(blocks, rd.Loads(gravity=False, lines=(beside,)))


def test_a_trapezoid_in_a_model_file(tmp_path):
    from rockdem.config import parse_model

    text = f"""
joints:
  rock: {{normal_stiffness: 1.0e+6, friction_angle: 35}}
blocks:
  - {{vertices: [[-5, -1], [9, -1], [9, 0], [-5, 0]], fixed: true}}
  - {{vertices: [[0, 0], [{B}, 0], [{B}, {H}], [0, {H}]], unit_weight: 25}}
loads:
  lines:
    - {{start: [0, {H}], end: [{B}, {H}], q: [0, 0], q_end: [0, -30], name: fill}}
"""
    model, _ = parse_model(text)
    f = block_loads(model.blocks, model.loads)
    R, x = trapezoid(0.0, 30.0, 0.0, B)
    W = 25 * B * H
    assert f[1, 1] == pytest.approx(-W - R, rel=1e-12)
    assert f[1, 2] == pytest.approx((x - B / 2) * -R, rel=1e-9)
    assert rd.analyse(model).stable
