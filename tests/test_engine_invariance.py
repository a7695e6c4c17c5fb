"""Results must not depend on block order, on where the origin is, on the unit
system, or on the absolute spring stiffness (c = 0)."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import rockdem as rd
from rockdem import verification as V


def _model(kn=1e6, shift=(0.0, 0.0), scale=1.0, order=None, c=0.0, mirror=False):
    """The 66-block bedded slope, transformed; lengths x scale, forces consistently;
    ``mirror``: reflected left to right (the slope faces the other way)."""
    base = V.bedding_slope(bedding_spacing=3.0, cross_spacing=4.5)
    b = base.blocks
    flip = np.array([-1.0 if mirror else 1.0, 1.0])
    polys = [b.outline(i) * flip * scale + np.asarray(shift) for i in range(b.n_blocks)]
    ids = np.arange(b.n_blocks)
    order = np.arange(b.n_blocks) if order is None else order
    blocks = rd.Blocks.from_polygons(
        [polys[i] for i in order],
        fixed=b.fixed[order],
        unit_weight=26.0,  # weight per area: forces scale as length^2, stresses as length
        ids=ids[order],
    )
    # stiffness is stress per length: keeps displacement / length unchanged
    joint = rd.Joint(normal_stiffness=kn, friction_angle=40, cohesion=c * scale)
    return rd.Model(blocks, joint, settings=base.settings)


def _summary(model):
    fos = rd.factor_of_safety(model)
    failed = fos.failed_analysis
    faces = failed.interfaces
    pairs = {
        tuple(sorted((int(a), int(b))))
        for a, b, s in zip(faces.block_a, faces.block_b, faces.state, strict=True)
        if s > 0
    }
    return fos, set(failed.unstable_blocks.tolist()), pairs


@pytest.fixture(scope="module")
def reference():
    return _summary(_model())


def test_renumbering_blocks(reference):
    order = np.random.default_rng(3).permutation(66)
    fos, unstable, failed = _summary(_model(order=order))
    assert fos.value == pytest.approx(reference[0].value, rel=1e-6)
    assert unstable == reference[1] and failed == reference[2]


def test_translating_coordinates(reference):
    fos, unstable, failed = _summary(_model(shift=(1e4, -1e4)))
    assert fos.value == pytest.approx(reference[0].value, rel=1e-6)
    assert unstable == reference[1] and failed == reference[2]


@pytest.mark.parametrize("shift", [(1e5, -3e4), (5e5, 7e6)])  # mine grid, UTM northing
def test_site_coordinates_keep_every_interface(reference, shift):
    """A closing vertex is dropped only within a tolerance relative to the
    model's size: far from the origin no vertex may merge, no interface vanish."""
    fos, unstable, failed = _summary(_model(shift=shift))
    assert fos.failed_analysis.interfaces.n_interfaces == (
        reference[0].failed_analysis.interfaces.n_interfaces
    )
    assert fos.value == pytest.approx(reference[0].value, rel=1e-6)
    assert unstable == reference[1] and failed == reference[2]


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    dx=st.floats(-1e7, 1e7, allow_nan=False),
    dy=st.floats(-1e7, 1e7, allow_nan=False),
    mirror=st.booleans(),
)
def test_any_translation_up_to_1e7_and_mirroring(reference, dx, dy, mirror):
    """Site coordinates (UTM, mine grids) and a section drawn the other way
    round: the same interfaces, failed joints, unstable blocks and factor."""
    fos, unstable, failed = _summary(_model(shift=(dx, dy), mirror=mirror))
    assert fos.failed_analysis.interfaces.n_interfaces == (
        reference[0].failed_analysis.interfaces.n_interfaces
    )
    assert fos.value == pytest.approx(reference[0].value, rel=1e-6)
    assert unstable == reference[1] and failed == reference[2]


def test_small_blocks_far_from_the_origin_keep_their_vertices():
    """Two 0.5 x 0.25 blocks at (1e5, -3e4): four vertices and full area each."""
    square = np.array([(0, 0), (0.5, 0), (0.5, 0.25), (0, 0.25)]) + np.array([1e5, -3e4])
    b = rd.Blocks.from_polygons([square, square + np.array([0.5, 0.0])])
    assert np.diff(b.offsets).tolist() == [4, 4]
    assert b.area == pytest.approx([0.125, 0.125], rel=1e-9)


def test_scaling_lengths_by_ten(reference):
    fos, unstable, failed = _summary(_model(scale=10.0, kn=1e6 / 10.0))
    assert fos.value == pytest.approx(reference[0].value, rel=1e-6)
    assert unstable == reference[1] and failed == reference[2]


@pytest.mark.parametrize("kn", [1e3, 1e9])
def test_absolute_stiffness_does_not_matter_without_cohesion(reference, kn):
    """The same bracket for joints 1,000 times softer or stiffer.  The soft
    ones move the blocks half their size, beyond small displacements: the
    analysis says so (the small-displacement equations, linear in the
    stiffness, still give the same factor)."""
    if kn < 1e4:
        with pytest.warns(rd.ModelWarning, match="beyond the small displacements"):
            fos, unstable, failed = _summary(_model(kn=kn))
    else:
        fos, unstable, failed = _summary(_model(kn=kn))
    assert fos.bracket == pytest.approx(reference[0].bracket, rel=1e-9)
    assert unstable == reference[1] and failed == reference[2]


def test_displacements_scale_with_one_over_stiffness():
    a1 = rd.analyse(_model(kn=1e6))
    a2 = rd.analyse(_model(kn=1e8))
    assert np.allclose(a1.displacement, 100 * a2.displacement, rtol=1e-6, atol=0)


_ONE_RUN = """
import hashlib, os, sys
import numpy as np
import rockdem as rd
from rockdem import verification as V
system = rd.build_system(V.brick_slope(1000))
a = rd.analyse(system)
print(hashlib.sha1(system.u_elastic.tobytes() + a.displacement.tobytes()).hexdigest())
"""


def test_the_same_model_gives_the_same_bits_in_every_run():
    """Threaded PARDISO summed in an order that changed from run to run and
    with the number of threads: six runs of the 1,021-block brick slope gave
    two different elastic solutions, one thread a third, and relaxation's
    chaos can turn those bits into another verdict.  With MKL's reproducible mode
    (rockdem.linalg), fresh processes on 1 and 2 threads agree to the bit on
    the elastic solution and the staged analysis (without it, 1 and 2
    threads differ)."""
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k not in ("MKL_CBWR", "MKL_NUM_THREADS")}
    digests = set()
    for threads in ("1", "2", "2", None):
        run_env = env if threads is None else {**env, "MKL_NUM_THREADS": threads}
        out = subprocess.run(
            [sys.executable, "-c", _ONE_RUN],
            capture_output=True,
            text=True,
            env=run_env,
            timeout=300,
            check=True,
        )
        digests.add(out.stdout.strip())
    assert len(digests) == 1, digests


_BEDDED_N_MM = """
name: bedded slope in N and mm
units: N, mm, MPa
materials:
  sandstone: {unit_weight: 2.5e-5}
joints:
  bedding: {normal_stiffness: 1.0, friction_angle: 35, cohesion: 0.01, residual_cohesion: 0}
  cross: {normal_stiffness: 1.0, friction_angle: 35}
  ground: {normal_stiffness: 1.0, friction_angle: 40, cohesion: 0.05}
ground_joint: ground
slope:
  material: sandstone
  profile: {height: 10000, face_angle: 60, crest_length: 10000, toe_length: 10000}
  depth: 6000
  joint_sets:
    bedding: {dip: 30, spacing: 2500}
    cross: {dip: 120, spacing: 3000, origin: [500, 0]}
analysis: {load_steps: 5}
"""


def _verdict(path):
    from rockdem.config import load_model

    model, _ = load_model(path)
    fos = rd.factor_of_safety(model)
    return fos, sorted(fos.failed_analysis.unstable_blocks.tolist())


def test_the_bundled_bedded_slope_in_newtons_and_millimetres(tmp_path):
    """The same slope in kN, m, kPa and in N, mm, MPa (lengths x 1000, forces
    x 1000).  Dynamic relaxation, which confirms the failure, gave each
    unknown the raw row sum of |K0| as its mass, adding force/length to
    force/radian: the millimetre model's run 2% beyond the bracket did not
    move, the search took another path, and FS 1.2257 came out for 1.1958."""
    from rockdem.examples import example_path

    path = tmp_path / "n-mm.yaml"
    path.write_text(_BEDDED_N_MM)
    fos_m, blocks_m = _verdict(example_path("bedded-slope"))
    fos_mm, blocks_mm = _verdict(path)
    assert fos_mm.value == pytest.approx(fos_m.value, rel=1e-6)
    assert fos_mm.proof == fos_m.proof == "dynamic-relaxation"
    assert blocks_mm == blocks_m


def test_the_bundled_perpendicular_joints_in_tonnes_and_kilonewtons(tmp_path):
    """The paper's slope (seed paper 6.1) in t, m (its units) and in kN, m:
    only the forces scale (x 9.81), yet rounding takes the chaotic
    relaxation to another verdict 2% beyond the bracket.  In kN the search
    then confirmed the failure only 5% beyond, and the midpoint of the wide
    bracket, 0.925, was given for 0.9024.  A bracket the search could not
    narrow now gives its stable end, the largest factor found stable, which
    Newton's path fixes in any units."""
    from rockdem.examples import example_path

    text = example_path("perpendicular-joints").read_text()
    kn = (
        text.replace("unit_weight: 2.6,", "unit_weight: 25.506,")
        .replace("normal_stiffness: 1.0e+5", "normal_stiffness: 9.81e+5")
        .replace("units: t, m, t/m^2", "units: kN, m, kPa")
    )
    assert kn.count("9.81e+5") == 3 and "25.506" in kn and "kN, m" in kn
    path = tmp_path / "kn.yaml"
    path.write_text(kn)
    fos_t, blocks_t = _verdict(example_path("perpendicular-joints"))
    fos_kn, blocks_kn = _verdict(path)
    # the same stable end; a value within the search's half-width (0.005 / 2)
    assert fos_kn.bracket[0] == pytest.approx(fos_t.bracket[0], rel=1e-6)
    assert abs(fos_kn.value - fos_t.value) <= 0.0025
    assert blocks_kn == blocks_t
    # the report's trust statement says which the value is
    from dataclasses import replace

    from rockdem.trust import trust_statements

    lo = fos_t.bracket[0]
    wide = replace(fos_t, value=lo, bracket=(lo, lo * 1.05))
    for fos in (fos_t, fos_kn, wide):
        first = trust_statements(fos.failed_analysis, fos)[0]
        widened = fos.value == fos.bracket[0] < fos.bracket[1]
        assert ("its stable end" in first) == widened, first
        assert ("the middle of that bracket" in first) == (not widened), first


@pytest.mark.parametrize("shift", [(1e5, -3e4), (1e7, 0.0), (1e7, 1e6)])
def test_a_line_load_in_site_coordinates(shift):
    """A surcharge across two blocks resting on an inclined plane, at the
    origin and in site coordinates.  At (1e7, 0) the check that a line load
    lies on block boundaries united bands 2 tol wide around them, and the
    union collapsed to nothing: a valid model was refused ("lies inside a
    block")."""
    d = np.radians(25.0)
    turn = np.array([[np.cos(d), -np.sin(d)], [np.sin(d), np.cos(d)]])
    ground = np.array([(-5, -1), (5, -1), (5, 0), (-5, 0)], float) @ turn.T
    left = np.array([(0, 0), (1, 0), (1, 1), (0, 1)], float) @ turn.T
    right = left + turn @ np.array([1.0, 0.0])

    def fos(offset):
        o = np.asarray(offset)
        blocks = rd.Blocks.from_polygons([ground + o, left + o, right + o], fixed=[1, 0, 0])
        top = rd.LineLoad(start=tuple(left[3] + o), end=tuple(right[2] + o), qx=0.0, qy=-20.0)
        joint = rd.Joint(normal_stiffness=1e6, friction_angle=35)
        return rd.factor_of_safety(rd.Model(blocks, joint, loads=rd.Loads(lines=(top,))))

    exact = np.tan(np.radians(35.0)) / np.tan(d)  # the surcharge is vertical, like the weight
    here, there = fos((0.0, 0.0)), fos(shift)
    assert here.value == pytest.approx(exact, rel=0.005)
    assert there.value == pytest.approx(here.value, rel=1e-6)
