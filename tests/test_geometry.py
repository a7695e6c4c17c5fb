"""Geometry generator: known counts, rock bridges, ground, slivers, editing, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

import rockdem as rd
from rockdem.errors import InputError
from rockdem.geometry import (
    JointSet,
    Profile,
    add_blocks,
    cut_to_profile,
    excavate,
    generate_slope,
    remove_blocks,
)

J = rd.Joint(normal_stiffness=1e6, friction_angle=35)
BRIDGE = rd.Joint(normal_stiffness=1e7, friction_angle=45, cohesion=1000, tensile_strength=500)
GROUND = rd.Joint(normal_stiffness=1e6, friction_angle=40, name="whatever")


def box(width=10.0, height=10.0):
    """Flat profile at y = height; with depth = height the section is [0, w] x [0, h]."""
    return Profile([(0, height), (width, height)])


def free_area(g):
    return float(g.blocks.area[~g.blocks.fixed].sum())


# ------------------------------------------------------------------ profile
def test_simple_profile_geometry():
    p = Profile.simple(30, 60, crest_length=10, toe_length=5, bench_width=4, bench_height=10)
    x, y = p.points.T
    run = 10 / math.tan(math.radians(60))
    # 3 lifts of 10 and 2 benches of 4: horizontal distance crest to toe
    assert x[-2] - x[1] == pytest.approx(3 * run + 2 * 4)
    assert y.max() - y.min() == pytest.approx(30)
    assert np.all(np.diff(x) >= 0)
    assert p.y_at(x[-1]) == pytest.approx(0.0)


def test_profile_crossing_itself():
    with pytest.raises(InputError) as e:
        Profile([(0, 0), (4, 4), (4, 0), (2, 3), (6, 3)])
    assert e.value.where == "profile"
    assert "crosses itself" in e.value.problem
    assert e.value.fix


def test_profile_right_to_left():
    with pytest.raises(InputError) as e:
        Profile([(10, 0), (5, 0), (0, 10)])
    assert "left to right" in e.value.fix


# -------------------------------------------------------------- known counts
@pytest.mark.parametrize("spacing", [1.0, 2.0, 2.5, 5.0])
@pytest.mark.parametrize("origin", [(0.0, 0.0), (0.3, 0.7)])
def test_perpendicular_sets_count(spacing, origin):
    w, h = 10.0, 10.0
    sets = [
        JointSet("h", 0, spacing, J, origin=origin),
        JointSet("v", 90, spacing, J, origin=origin),
    ]
    g = generate_slope(box(w, h), sets, depth=h, min_block_fraction=0)
    lines_x = [k for k in range(-50, 50) if 0 < origin[0] + k * spacing < w]
    lines_y = [k for k in range(-50, 50) if 0 < origin[1] + k * spacing < h]
    n_free = int((~g.blocks.fixed).sum())
    assert n_free == (len(lines_x) + 1) * (len(lines_y) + 1)
    assert free_area(g) == pytest.approx(w * h, rel=1e-12)


def test_inclined_perpendicular_sets_block_area():
    # 30 / 120 degrees: interior blocks are s1 x s2 rectangles
    s1, s2 = 1.0, 1.5
    sets = [JointSet("a", 30, s1, J), JointSet("b", 120, s2, J, origin=(0.1, 0.2))]
    g = generate_slope(box(40, 40), sets, depth=40, min_block_fraction=0)
    a = g.blocks.area[~g.blocks.fixed]
    assert np.median(a) == pytest.approx(s1 * s2, rel=1e-9)
    assert a.max() <= s1 * s2 * (1 + 1e-9)


# ----------------------------------------------------------------- bridges
@pytest.mark.parametrize("stagger", [0.0, 0.5])
def test_half_persistent_joint_bridge_lengths(stagger):
    w = 12.0  # a multiple of the period 4
    s = JointSet("bed", 0, 4.0, J, origin=(0, 2), trace_length=2, gap=2, stagger=stagger)
    g = generate_slope(box(w, 8), [s], depth=8, bridge_joint=BRIDGE, ground_joint=GROUND,
                       min_block_fraction=0)
    n_lines = 2  # y = 2 and 6
    lengths = g.length_by_type()
    assert lengths["bed"] == pytest.approx(n_lines * w * s.persistence, rel=1e-9)
    assert lengths["bridge"] == pytest.approx(n_lines * w * (1 - s.persistence), rel=1e-9)
    # ground contacts: base + both sides (the back and front strips)
    assert lengths["ground"] == pytest.approx(w + 2 * 8, rel=1e-9)
    # no interface straddles a trace end: every interface lies wholly on one kind
    faces = g.interfaces()
    on_joint = g.interface_types() != "ground"
    assert faces.length[on_joint].max() == pytest.approx(2.0, rel=1e-9)


def test_bridges_need_properties():
    s = JointSet("bed", 10, 2.0, J, trace_length=3, gap=1)
    with pytest.raises(InputError) as e:
        generate_slope(box(), [s], depth=5)
    assert "bridge" in e.value.problem and "bridge_joint" in e.value.fix


def test_interface_types_and_engine_table():
    sets = [
        JointSet("bedding", 30, 1.5, J, trace_length=4, gap=1, stagger=0.5),
        JointSet("cross", 120, 2.0, J),
        JointSet("topple", 100, 3.0, J, origin=(0.4, 0)),
        JointSet("sub", 60, 4.0, J, origin=(1.1, 0.3)),
    ]
    g = generate_slope(Profile.simple(15, 65), sets, depth=5, bridge_joint=BRIDGE,
                       ground_joint=GROUND)
    names = [j.name for j in g.joints]
    assert names == ["bedding", "cross", "topple", "sub", "bridge", "ground"]
    assert set(g.interface_types()) == set(names)
    # traces listed before bridges
    kinds = g.line_names
    first_bridge = int(np.argmax(kinds == "bridge"))
    assert (kinds[:first_bridge] != "bridge").all() and (kinds[first_bridge:] == "bridge").all()
    m = g.model()
    assert m.ground == names.index("ground")


# ------------------------------------------------------------------ ground
def test_boundary_strips_share_edges():
    g = generate_slope(box(10, 6), [JointSet("v", 80, 1.3, J)], depth=4, ground_joint=GROUND,
                       min_block_fraction=0)
    fixed = g.blocks.fixed
    assert fixed.sum() == 3
    polys = g.polygons()
    assert shapely.is_valid(polys).all()
    assert (shapely.get_num_interior_rings(polys) == 0).all()
    # every free-block edge on the base / back / front is a ground contact
    lengths = g.length_by_type()
    assert lengths["ground"] == pytest.approx(10 + 4 + 4, rel=1e-9)


def test_fixed_region_merges_blocks_into_ground():
    sets = [JointSet("h", 0, 1.0, J, origin=(0, 0.5)), JointSet("v", 90, 1.0, J, origin=(0.5, 0))]
    region = shapely.box(-1, -1, 11, 3.2)  # rows below y = 2.5 entirely inside
    g = generate_slope(box(10, 10), sets, depth=10, fixed_region=region, boundary=(),
                       min_block_fraction=0)
    b = g.blocks
    # free blocks: everything above y = 2.5
    assert free_area(g) == pytest.approx(10 * 7.5, rel=1e-12)
    assert b.fixed.sum() == 1
    ground = g.polygons()[b.fixed][0]
    assert ground.area == pytest.approx(10 * 2.5, rel=1e-12)
    assert shapely.is_valid(ground)
    # the ground outline has a vertex at every vertical joint meeting it (x = 0.5 ... 9.5)
    gx = np.asarray(ground.exterior.coords)
    top = gx[np.isclose(gx[:, 1], 2.5)]
    assert set(np.round(top[:, 0], 9)) >= {0.5 + k for k in range(10)}
    # each column block sitting on the ground has an interface with it
    faces = g.interfaces()
    on_ground = b.fixed[faces.block_a] | b.fixed[faces.block_b]
    assert faces.length[on_ground].sum() == pytest.approx(10.0, rel=1e-9)


def test_fixed_region_outside_is_an_error():
    with pytest.raises(InputError) as e:
        generate_slope(box(), [JointSet("v", 90, 1, J)], depth=5,
                       fixed_region=shapely.box(50, 50, 60, 60))
    assert e.value.where == "generate_slope fixed_region"


# ----------------------------------------------------------------- slivers
def test_sliver_merged_into_longest_neighbour():
    # a vertical joint 0.1 from the back cuts strips of area 0.1 x 10 against 1 x 10
    sets = [JointSet("v", 90, 1.0, J, origin=(0.1, 0))]
    g = generate_slope(box(10.2, 10), sets, depth=10, min_block_fraction=0.5)
    a = g.blocks.area[~g.blocks.fixed]
    assert a.min() >= 0.5 * g.typical_area
    assert free_area(g) == pytest.approx(10.2 * 10, rel=1e-12)
    merged = [s for s in g.slivers if s.action == "merged"]
    assert len(merged) == 2  # x in [0, 0.1] and [10.1, 10.2]
    # each went into its only neighbour, the column next to it: 1.1 wide
    for s in merged:
        k = g.blocks.index_of([s.block])[0]
        assert g.blocks.area[k] == pytest.approx(1.1 * 10, rel=1e-9)


def test_sliver_report_only():
    sets = [JointSet("v", 90, 1.0, J, origin=(0.1, 0))]
    g = generate_slope(box(10.2, 10), sets, depth=10, min_block_fraction=0.5, slivers="report")
    kept = [s for s in g.slivers if s.action == "kept"]
    assert len(kept) == 2
    assert {round(s.area, 9) for s in kept} == {round(0.1 * 10, 9)}


# ----------------------------------------------------------------- editing
def _slope():
    sets = [JointSet("a", 25, 1.5, J, origin=(0.2, 0.1)),
            JointSet("b", 115, 2.0, J, origin=(0.7, 0.3))]
    return generate_slope(Profile.simple(12, 60, bench_width=3, bench_height=6), sets, depth=4,
                          ground_joint=GROUND)


def test_remove_blocks_keeps_ids():
    g = _slope()
    face = g.blocks.ids[~g.blocks.fixed][-1]  # right-most block (at the toe)
    h = remove_blocks(g, [int(face)])
    assert int(face) not in h.blocks.ids
    assert set(h.blocks.ids) == set(g.blocks.ids) - {int(face)}
    for i in h.blocks.ids[:5]:
        a, b = g.blocks.index_of([i])[0], h.blocks.index_of([i])[0]
        assert np.array_equal(g.blocks.outline(a), h.blocks.outline(b))


def test_remove_fixed_or_unknown_block():
    g = _slope()
    with pytest.raises(InputError):
        remove_blocks(g, [int(g.blocks.ids[g.blocks.fixed][0])])
    with pytest.raises(InputError) as e:
        remove_blocks(g, [10**6])
    assert "no block" in e.value.problem


def test_excavate_trims_and_keeps_ids():
    g = _slope()
    region = shapely.Polygon([(-8, 12.5), (-2, 3), (20, 3), (20, 20), (-8, 20)])
    h = excavate(g, region)
    removed_small = sum(s.area for s in h.slivers if s.action == "removed")
    cut = shapely.area(shapely.intersection(region, g.section))
    assert free_area(h) == pytest.approx(free_area(g) - cut - removed_small, rel=1e-9)
    # untouched blocks keep id and outline
    polys = g.polygons()
    untouched = ~shapely.intersects(polys, region) & ~g.blocks.fixed
    for k in np.flatnonzero(untouched)[:20]:
        j = h.blocks.index_of([g.blocks.ids[k]])[0]
        assert np.array_equal(h.blocks.outline(j), g.blocks.outline(k))
    # nothing left inside the region
    inside = shapely.area(shapely.intersection(h.polygons()[~h.blocks.fixed], region))
    assert inside.max() < 1e-9
    rd.Blocks.from_polygons(h.polygons(), fixed=h.blocks.fixed)  # valid, no overlap
    h.model()  # builds


def test_cut_to_profile_berm():
    g = _slope()
    new = Profile.simple(12, 60, bench_width=6, bench_height=6,
                         crest_length=g.profile.points[1, 0] - g.profile.points[0, 0])
    h = cut_to_profile(g, new)
    v = h.blocks.vertices
    free_v = np.repeat(~h.blocks.fixed, np.diff(h.blocks.offsets))
    assert (v[free_v, 1] <= new.y_at(v[free_v, 0]) + 1e-9).all()
    assert free_area(h) < free_area(g)


def test_excavation_outside_the_model():
    g = _slope()
    with pytest.raises(InputError) as e:
        excavate(g, shapely.box(100, 100, 110, 110))
    assert e.value.where == "excavation region"
    assert "does not overlap" in e.value.problem
    with pytest.raises(InputError) as e:
        cut_to_profile(g, [(-100, 50), (100, 50)])
    assert e.value.where == "the new profile"


def test_add_explicit_block_after_excavation():
    g = generate_slope(box(10, 10), [JointSet("v", 90, 2.0, J, origin=(1, 0))], depth=10,
                       ground_joint=GROUND)
    h = excavate(g, shapely.box(8.5, 5, 12, 12))
    wall = rd.Joint(1e6, 20, name="wall")
    k = add_blocks(h, [[(8.5, 5), (10, 5), (10, 7), (8.5, 7)]], unit_weight=24, joint=wall)
    assert k.blocks.n_blocks == h.blocks.n_blocks + 1
    new_id = int(k.blocks.ids.max())
    faces = k.interfaces()
    idx = k.blocks.index_of([new_id])[0]
    mine = (faces.block_a == idx) | (faces.block_b == idx)
    assert mine.any()
    other = faces.block_b[mine] + faces.block_a[mine] - idx
    names = np.array([k.joints[j].name for j in faces.joint[mine]])
    # ground contacts take the ground joint; contacts with free blocks the wall joint
    assert set(names[~k.blocks.fixed[other]]) == {"wall"}
    assert set(names[k.blocks.fixed[other]]) == {"ground"}
    with pytest.raises(InputError):
        add_blocks(h, [[(1, 1), (3, 1), (3, 3), (1, 3)]])


# --------------------------------------------------------------- bad input
@pytest.mark.parametrize("spacing", [0, -1.5])
def test_spacing_not_positive(spacing):
    with pytest.raises(InputError) as e:
        JointSet("bedding", 30, spacing, J)
    assert e.value.where == "joint set 'bedding' spacing"
    assert "> 0" in e.value.fix


@pytest.mark.parametrize(
    ("kwargs", "where"),
    [
        ({"dip": 180}, "joint set 'x' dip"),
        ({"dip": -5}, "joint set 'x' dip"),
        ({"gap": 2}, "joint set 'x' gap"),
        ({"trace_length": 0}, "joint set 'x' trace_length"),
        ({"spacing_sd": -1}, "joint set 'x' spacing_sd"),
        # 1e9 x the spacing ran `check` for 87 s into a singular matrix
        ({"spacing_sd": 2.5}, "joint set 'x' spacing_sd"),
        ({"joint": "rock"}, "joint set 'x' joint"),
    ],
)
def test_joint_set_bad_values(kwargs, where):
    args = {"name": "x", "dip": 30, "spacing": 1.0, "joint": J} | kwargs
    with pytest.raises(InputError) as e:
        JointSet(**args)
    assert e.value.where == where


def test_joint_set_missing_the_section():
    far = JointSet("fault", 0, 1000.0, J, origin=(0, 500))
    with pytest.raises(InputError) as e:
        generate_slope(box(), [far], depth=5)
    assert e.value.where == "joint set 'fault'"
    assert "misses the section" in e.value.problem
    assert "origin" in e.value.fix


def test_duplicate_set_names_and_bad_depth():
    with pytest.raises(InputError):
        generate_slope(box(), [JointSet("a", 0, 1, J), JointSet("a", 90, 1, J)], depth=5)
    with pytest.raises(InputError) as e:
        generate_slope(box(), [JointSet("a", 0, 1, J)], depth=0)
    assert e.value.where == "generate_slope depth"


# ------------------------------------------------------------------ engine
def test_generated_slope_runs_in_the_engine():
    sets = [
        JointSet("bedding", 30, 2.0, J, origin=(0.3, 0.1), trace_length=5, gap=2, stagger=0.5),
        JointSet("cross", 120, 3.0, J),
    ]
    g = generate_slope(Profile.simple(12, 60), sets, depth=5, bridge_joint=BRIDGE,
                       ground_joint=GROUND, unit_weight=25)
    n_free = int((~g.blocks.fixed).sum())
    assert 30 <= n_free <= 200
    m = g.model()
    a = rd.analyse(m)
    assert a.stable
    f = rd.factor_of_safety(m)
    assert f.value is not None and f.value > 1


def test_excavation_removes_whole_blocks_and_small_pieces():
    g = generate_slope(box(10, 10), [JointSet("v", 90, 1.0, J, origin=(0.5, 0))], depth=10,
                       boundary=("base", "back"), min_block_fraction=0.1)
    # cuts 0.05 off ... leaves a 0.05 x 10 strip of the column [7.5, 8.5]: removed, reported
    h = excavate(g, shapely.box(7.55, -1, 20, 20))
    assert free_area(h) == pytest.approx(7.5 * 10, rel=1e-12)
    removed = [s for s in h.slivers if s.action == "removed"]
    assert len(removed) == 1
    assert removed[0].area == pytest.approx(0.05 * 10, rel=1e-9)
    assert h.blocks.n_blocks == g.blocks.n_blocks - 3  # columns [7.5, 8.5], [8.5, 9.5], [9.5, 10]
    # a partly cut block keeps its id
    k = excavate(g, shapely.box(8.2, -1, 20, 20))
    j = g.blocks.index_of([int(g.blocks.ids[np.argmax(g.blocks.centroid[:, 0] == 8.0)])])[0]
    assert g.blocks.centroid[j, 0] == pytest.approx(8.0)  # the column [7.5, 8.5]
    i = k.blocks.index_of([g.blocks.ids[j]])[0]
    assert k.blocks.area[i] == pytest.approx(0.7 * 10, rel=1e-12)


@pytest.mark.parametrize(
    "dip, shift", [(35.0, (0.0, 0.0)), (0.0, (5e5, 7e6)), (179.99, (0.0, 0.0))]
)
def test_edge_pairs_by_direction_give_the_interfaces_of_one_r_tree(dip, shift, monkeypatch):
    """The interface search groups edges by direction and turns each group
    level (rockdem.interfaces._edge_pairs); on thin inclined layers (and near
    the 0 = 180 degree wrap, and at site coordinates) it finds exactly the
    interfaces that one R-tree query over all edges gives."""
    from rockdem import interfaces

    profile = Profile.simple(height=6, face_angle=60)
    sets = [JointSet("bedding", dip, 0.05, J), JointSet("cross", 90.0, 1.5, J, origin=(0.3, 0))]
    g = generate_slope(profile, sets, depth=3)
    blocks = rd.Blocks.from_polygons(
        [g.blocks.outline(k) + shift for k in range(g.blocks.n_blocks)], fixed=g.blocks.fixed
    )
    lines = g.joint_lines + shift

    def search(blocks):  # the interfaces, and the joint trace each lies on
        faces = interfaces.find_interfaces(blocks)
        return interfaces.assign_joints(faces, blocks, default=-1, lines=lines,
                                        line_joint=g.line_joint)

    grouped = search(blocks)

    def one_tree(p, q, tol):
        lines = shapely.linestrings(np.stack([p, q], axis=1))
        return shapely.STRtree(lines).query(lines, predicate="dwithin", distance=tol)

    def one_tree_on_lines(faces, lines, tol):
        tree = shapely.STRtree(shapely.linestrings(lines))
        return tree.query(shapely.points(faces.midpoint), predicate="dwithin", distance=tol)

    monkeypatch.setattr(interfaces, "_edge_pairs", one_tree)
    monkeypatch.setattr(interfaces, "_on_lines", one_tree_on_lines)
    ref = search(blocks)
    assert grouped.n_interfaces == ref.n_interfaces > blocks.n_blocks
    assert (ref.joint >= 0).sum() > blocks.n_blocks
    for name in ("block_a", "block_b", "start", "end", "joint"):
        assert np.array_equal(getattr(grouped, name), getattr(ref, name)), name
