"""Property-based checks of the generator over random profiles and joint sets."""

from __future__ import annotations

import numpy as np
import shapely
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import rockdem as rd
from rockdem.geometry import JointSet, Profile, generate_slope

J = rd.Joint(normal_stiffness=1e6, friction_angle=35)
BRIDGE = rd.Joint(normal_stiffness=1e7, friction_angle=45, cohesion=1000, tensile_strength=500)
GROUND = rd.Joint(normal_stiffness=1e6, friction_angle=40)

SETTINGS = settings(max_examples=25, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])


@st.composite
def profiles(draw):
    n = draw(st.integers(2, 7))
    # millimetre resolution: features far above the engine's tolerance (1e-8 x extent)
    dx = draw(st.lists(st.integers(500, 10_000), min_size=n - 1, max_size=n - 1))
    ys = draw(st.lists(st.integers(0, 20_000), min_size=n, max_size=n))
    dx, ys = np.asarray(dx) / 1000, np.asarray(ys) / 1000
    x = np.concatenate([[0.0], np.cumsum(dx)]) + draw(st.integers(-100_000, 100_000)) / 1000
    return Profile(np.column_stack([x, ys + draw(st.integers(-50_000, 50_000)) / 1000]))


@st.composite
def joint_sets(draw, size):
    n = draw(st.integers(1, 4))
    out = []
    for k in range(n):
        spacing = size * draw(st.floats(0.08, 0.5))
        persistent = draw(st.booleans())
        trace = None if persistent else spacing * draw(st.floats(0.5, 4))
        gap = 0.0 if persistent else spacing * draw(st.floats(0.2, 2))
        out.append(JointSet(
            f"set{k}", draw(st.integers(0, 359)) / 2, spacing, J,  # 0.5 degree steps
            origin=(draw(st.integers(-20_000, 20_000)) / 1000,
                    draw(st.integers(-20_000, 20_000)) / 1000),
            trace_length=trace, gap=gap, stagger=draw(st.floats(0, 1)),
            spacing_sd=draw(st.sampled_from([0.0, 0.3 * spacing])),
            dip_sd=draw(st.sampled_from([0.0, 5.0])),
        ))
    return out


@st.composite
def slopes(draw):
    p = draw(profiles())
    size = max(np.ptp(p.points[:, 0]), np.ptp(p.points[:, 1]), 1.0)
    sets = draw(joint_sets(size))
    depth = draw(st.floats(1, 10))
    frac = draw(st.sampled_from([0.0, 0.05]))
    seed = draw(st.integers(0, 10))
    return p, sets, depth, frac, seed


def build(p, sets, depth, frac, seed):
    try:
        return generate_slope(p, sets, depth=depth, bridge_joint=BRIDGE, ground_joint=GROUND,
                              min_block_fraction=frac, seed=seed)
    except rd.InputError as exc:
        # a wide set may legitimately miss a small section (or only graze its outline)
        assert exc.where.startswith("joint set") and (
            "misses the section" in exc.problem or "no trace" in exc.problem)
        assume(False)


@SETTINGS
@given(slopes())
def test_partition_of_the_section(case):
    g = build(*case)
    b = g.blocks
    free = ~b.fixed
    polys = g.polygons()
    # areas sum to the section area
    assert abs(b.area[free].sum() - g.section.area) <= 1e-9 * g.section.area
    assert (b.area > 0).all()
    # valid simple polygons, no two overlap
    assert shapely.is_valid(polys).all()
    tree = shapely.STRtree(polys)
    i, j = tree.query(polys, predicate="intersects")
    m = i < j
    common = shapely.area(shapely.intersection(polys[i[m]], polys[j[m]]))
    assert common.max(initial=0) <= 1e-9 * g.section.area
    # the engine accepts them as they are
    rd.Blocks.from_polygons(polys, fixed=b.fixed)


@SETTINGS
@given(slopes())
def test_interfaces_have_two_sides_and_blocks_touch(case):
    g = build(*case)
    b = g.blocks
    faces = g.interfaces()
    assert (faces.block_a != faces.block_b).all()
    # every stretch of a free block's outline is either the ground surface or
    # exactly one interface with one other block
    per_block = np.bincount(faces.block_a, faces.length, minlength=b.n_blocks)
    per_block += np.bincount(faces.block_b, faces.length, minlength=b.n_blocks)
    polys = g.polygons()
    # edges on the ground surface: both ends and the midpoint on the profile
    p, q, owner = b.edges()
    line, tol = g.profile.line, 1e-9 * b.extent
    on = np.ones(len(p), dtype=bool)
    for pt in (p, q, 0.5 * (p + q)):
        on &= shapely.distance(shapely.points(pt), line) <= tol
    surface = np.bincount(owner[on], np.hypot(*(q - p)[on].T), minlength=b.n_blocks)
    perimeter = shapely.length(polys)
    free = ~b.fixed
    scale = perimeter[free]
    np.testing.assert_allclose(per_block[free] + surface[free], perimeter[free],
                               rtol=0, atol=1e-5 * scale.max())
    # every block touches something
    touched = np.zeros(b.n_blocks, dtype=bool)
    touched[faces.block_a] = True
    touched[faces.block_b] = True
    assert touched[free].all()
    # no interface straddles a trace end: lengths by kind match the joint lines
    assert set(g.interface_types()) <= {j.name for j in g.joints}


@SETTINGS
@given(slopes())
def test_deterministic_for_a_seed(case):
    a = build(*case)
    b = build(*case)
    assert np.array_equal(a.blocks.vertices, b.blocks.vertices)
    assert np.array_equal(a.blocks.offsets, b.blocks.offsets)
    assert np.array_equal(a.joint_lines, b.joint_lines)
    assert np.array_equal(a.line_joint, b.line_joint)


@SETTINGS
@given(slopes())
def test_no_slivers_left_unreported(case):
    p, sets, depth, _, seed = case
    g = build(p, sets, depth, 0.05, seed)
    free = ~g.blocks.fixed
    small = g.blocks.area[free] < 0.05 * g.typical_area
    kept = [s for s in g.slivers if s.action == "kept"]
    assert small.sum() <= len(kept)
