"""Generated slopes must not depend on where the model lies: the same blocks
(up to the shift), the same ids, the same slivers and the same factor of
safety when the profile and the joint sets are moved together."""

import copy

import numpy as np
import pytest
import shapely
import yaml

import rockdem as rd
from rockdem import geometry
from rockdem.config import parse_model
from rockdem.examples import example_path, list_examples

SHIFTS = [(10.0, 0.0), (1e3, 0.0), (1e5, 0.0), (-7.3, 2.1), (12345.678, -987.65)]

#: the bundled examples generated from a profile and joint sets
SLOPES = [n for n in list_examples() if "slope" in yaml.safe_load(example_path(n).read_text())]


def _moved(name: str, dx: float, dy: float) -> str:
    """The slope of example ``name`` moved by (dx, dy) (stabilisation, bolts and
    removals dropped: they name points of the unmoved model)."""
    doc = copy.deepcopy(yaml.safe_load(example_path(name).read_text()))
    slope = doc["slope"]
    prof = slope["profile"]
    if "points" in prof:
        prof["points"] = [[x + dx, y + dy] for x, y in prof["points"]]
    else:
        tx, ty = prof.get("toe", (0.0, 0.0))
        prof["toe"] = [tx + dx, ty + dy]
    for js in slope["joint_sets"].values():
        ox, oy = js.get("origin", (0.0, 0.0))
        js["origin"] = [ox + dx, oy + dy]
    if "fixed_region" in slope:
        slope["fixed_region"] = [[x + dx, y + dy] for x, y in slope["fixed_region"]]
    for key in ("stabilisation", "bolts", "remove"):
        doc.pop(key, None)
    assert not doc.get("loads", {}).get("points") and not doc.get("loads", {}).get("lines")
    return yaml.safe_dump(doc)


def _generate(name: str, dx: float = 0.0, dy: float = 0.0, monkeypatch=None):
    """(model, SlopeGeometry) of example ``name`` moved by (dx, dy)."""
    made = []
    real = geometry.generate_slope

    def keep(*args, **kw):
        made.append(real(*args, **kw))
        return made[-1]

    monkeypatch.setattr(geometry, "generate_slope", keep)
    model, _ = parse_model(_moved(name, dx, dy), source=f"{name}.yaml")
    monkeypatch.setattr(geometry, "generate_slope", real)
    assert len(made) == 1
    return model, made[0]


def _same_geometry(g0, g, dx, dy):
    """Assert ``g`` is ``g0`` moved by (dx, dy): outlines id by id, slivers."""
    b0, b = g0.blocks, g.blocks
    assert b.n_blocks == b0.n_blocks
    assert b.ids.tolist() == b0.ids.tolist()
    assert b.fixed.tolist() == b0.fixed.tolist()
    size = b0.extent
    for i in range(b0.n_blocks):
        a, c = b0.outline(i), b.outline(i) - [dx, dy]
        assert a.shape == c.shape, f"block {i}: {len(a)} corners, moved {len(c)}"
        assert np.abs(a - c).max() <= 1e-9 * size, f"block {i} differs when moved"
    s0 = [(s.action, s.block) for s in g0.slivers]
    s1 = [(s.action, s.block) for s in g.slivers]
    assert s1 == s0
    for p, q in zip(g0.slivers, g.slivers, strict=True):
        assert q.area == pytest.approx(p.area, rel=1e-9)
        assert np.allclose(np.subtract(q.centroid, (dx, dy)), p.centroid, rtol=0, atol=1e-9 * size)


def test_the_bundled_slopes_are_found():
    assert {"bedded-slope", "inclined-layers", "perpendicular-joints"} <= set(SLOPES)


@pytest.mark.parametrize("name", SLOPES)
def test_generated_examples_are_the_same_wherever_they_lie(name, monkeypatch):
    _, g0 = _generate(name, monkeypatch=monkeypatch)
    for dx, dy in SHIFTS:
        _, g = _generate(name, dx, dy, monkeypatch=monkeypatch)
        assert g.blocks.n_blocks == g0.blocks.n_blocks, (name, dx, dy)
        _same_geometry(g0, g, dx, dy)  # ids, fixed, outlines, slivers (asserts)


@pytest.mark.parametrize("dx, dy", [(0.0, 0.0), *SHIFTS, (3e6, 5e6)])
def test_stacked_blocks_are_numbered_column_by_column_bottom_to_top(dx, dy):
    """Layers between vertical joints have the same centroid x up to round-off:
    ids go left to right by column and bottom to top in each, wherever the
    slope lies (sorted by x then y, the last bits of x decided)."""
    j = rd.Joint(normal_stiffness=1e6, friction_angle=35)
    prof = geometry.Profile([(dx, 10 + dy), (dx + 9, 10 + dy)])
    sets = [
        geometry.JointSet("bed", 0, 0.7, j, origin=(dx, dy + 0.35)),
        geometry.JointSet("cross", 90, 1.5, j, origin=(dx + 0.3, dy)),
    ]
    g = geometry.generate_slope(prof, sets, depth=10, boundary=(), min_block_fraction=0)
    c = g.blocks.centroid - [dx, dy]
    assert g.blocks.ids.tolist() == list(range(len(c)))
    column = np.round(c[:, 0] / 0.75).astype(int)  # columns 1.5 m wide, centred 0.75 apart
    assert (np.diff(column) >= 0).all()
    same = np.diff(column) == 0
    assert same.sum() >= len(c) - 8
    assert (np.diff(c[:, 1])[same] > 0).all()


def test_bedded_slope_has_the_same_factor_of_safety_wherever_it_lies(monkeypatch):
    """Moved by 10 m it gave FS 1.2124 instead of 1.1958: its bedding joint through
    the toe passed 1e-15 m inside it and was not split there, so a 0.054 m2
    sliver and the 1.90 m2 block above the toe were one bow-tie block."""
    m0, g0 = _generate("bedded-slope", monkeypatch=monkeypatch)
    assert [s.action for s in g0.slivers] == ["merged", "merged"]
    fos0 = rd.factor_of_safety(m0).value
    assert fos0 == pytest.approx(1.1958, abs=5e-4)
    for dx, dy in [(10.0, 0.0), (1e3, 0.0), (1e5, 0.0)]:
        m, g = _generate("bedded-slope", dx, dy, monkeypatch=monkeypatch)
        assert len(g.slivers) == 2
        assert rd.factor_of_safety(m).value == pytest.approx(fos0, rel=1e-6)


@pytest.mark.parametrize("dx", [0.0, 0.1, 3.0, 10.0, 1e3, 1e5, 7e6])
def test_a_joint_through_a_profile_corner_is_split_there(dx):
    """Toe at (dx, 0), face 60 degrees, a joint dipping 30 through the toe: the
    toe is a reflex corner of the section, so the joint runs through rock on
    both sides of it: with a cross joint through (dx + 0.5, 0) it cuts 5 blocks,
    one of them the 0.054 m2 triangle below the toe, wherever the slope lies
    (unsplit at the toe, that triangle was part of the block above the joint)."""
    j = rd.Joint(normal_stiffness=1e6, friction_angle=35)
    prof = geometry.Profile.simple(10, 60, crest_length=10, toe_length=10, toe=(dx, 0.0))
    sets = [
        geometry.JointSet("bed", 30, 100.0, j, origin=(dx, 0.0)),
        geometry.JointSet("cross", 120, 100.0, j, origin=(dx + 0.5, 0.0)),
    ]
    g = geometry.generate_slope(prof, sets, depth=6, boundary=(), min_block_fraction=0)
    areas = sorted(shapely.area(g.polygons()).round(4).tolist())
    assert len(areas) == 5, areas
    assert areas[0] == pytest.approx(0.0541, abs=1e-4)  # the triangle below the toe


ROCK = rd.Joint(normal_stiffness=1e6, friction_angle=35, cohesion=10)
BRIDGE = rd.Joint(normal_stiffness=1e6, friction_angle=40, cohesion=500, tensile_strength=100)


def _crossing_at_the_toe(at, s):
    """Two persistent sets crossing at the toe of a 70-degree face."""
    prof = geometry.Profile.simple(20 * s, 70, crest_length=12 * s, toe_length=8 * s, toe=at(0, 0))
    sets = [
        geometry.JointSet("J1", 30, 2.0 * s, ROCK, origin=at(0, 0)),
        geometry.JointSet("J2", 120, 2.5 * s, ROCK, origin=at(0, 0)),
    ]
    return geometry.generate_slope(prof, sets, depth=8 * s, ground_joint=ROCK), None


def _benched_with_bridges(at, s):
    """A benched slope, random spacing, rock bridges."""
    prof = geometry.Profile.simple(
        24 * s,
        60,
        bench_width=4 * s,
        bench_height=8 * s,
        crest_length=12 * s,
        toe_length=10 * s,
        toe=at(0, 0),
    )
    sets = [
        geometry.JointSet("bed", 20, 1.6 * s, ROCK, origin=at(0, 0.4)),
        geometry.JointSet(
            "cross",
            110,
            3.0 * s,
            ROCK,
            origin=at(0, 0),
            trace_length=2.5 * s,
            gap=1.5 * s,
            stagger=0.5,
            spacing_sd=0.6 * s,
            seed=3,
        ),
    ]
    g = geometry.generate_slope(prof, sets, depth=8 * s, ground_joint=ROCK, bridge_joint=BRIDGE)
    return g, None


def _fixed_region_and_berm(at, s):
    """Random dips, rock bridges, a fixed region, then cut to a berm."""
    prof = geometry.Profile.simple(24 * s, 80, crest_length=14 * s, toe_length=10 * s, toe=at(0, 0))
    sets = [
        geometry.JointSet("top", 100, 1.8 * s, ROCK, origin=at(0.5, 0), dip_sd=2.0, seed=7),
        geometry.JointSet(
            "cross",
            10,
            2.5 * s,
            ROCK,
            origin=at(0, 0),
            trace_length=3.0 * s,
            gap=1.0 * s,
            stagger=0.5,
        ),
    ]
    deep = [at(-30, -12), at(-30, -2), at(12, -7), at(12, -12)]
    g = geometry.generate_slope(
        prof, sets, depth=10 * s, ground_joint=ROCK, bridge_joint=BRIDGE, fixed_region=deep
    )
    berm = [at(-40, 24), at(-9.0, 24), at(-6.8, 12), at(-2.116, 12), at(0, 0), at(20, 0)]
    return g, geometry.cut_to_profile(g, berm)


@pytest.mark.parametrize(
    "make", [_crossing_at_the_toe, _benched_with_bridges, _fixed_region_and_berm]
)
def test_generated_slopes_are_the_same_moved_or_in_other_units(make):
    """The same blocks, ids and slivers moved (up to 7e6 m) or in mm or km.
    (Before, the two sets crossing at the toe moved by 10 m changed block 111.)"""
    base = make(lambda x, y: (float(x), float(y)), 1.0)
    for (dx, dy), s in [
        ((10.0, 0.0), 1.0),
        ((1e5, 3e3), 1.0),
        ((5e5, 7e6), 1.0),
        ((0.0, 0.0), 1e3),
        ((-3.7, 1.1), 1e-3),
    ]:
        moved = make(lambda x, y, dx=dx, dy=dy, s=s: (x * s + dx, y * s + dy), s)
        for g0, g in zip(base, moved, strict=True):
            if g0 is None:
                continue
            b0, b = g0.blocks, g.blocks
            assert b.ids.tolist() == b0.ids.tolist() and b.fixed.tolist() == b0.fixed.tolist()
            for i in range(b0.n_blocks):
                a, c = b0.outline(i), (b.outline(i) - [dx, dy]) / s
                assert a.shape == c.shape and np.abs(a - c).max() <= 1e-9 * b0.extent, (dx, s, i)
            assert [(x.action, x.block) for x in g.slivers] == [
                (x.action, x.block) for x in g0.slivers
            ]


def test_a_sliver_with_two_equal_neighbours_goes_to_the_same_one_wherever_it_lies():
    """An isosceles sliver (0.00012 m2 at the right side) shares edges of the same
    length (0.0156 m) with two blocks: equal to the bit unmoved, it went to the
    first one listed; moved by (8374.15, -7327.9) m the round-off made the other
    edge 6e-16 m longer and it went there.  Lengths within the tolerance are equal."""

    def make(dx, dy):
        prof = geometry.Profile([(dx, 10 + dy), (dx + 20, 10 + dy)])
        sets = [
            geometry.JointSet("a", 45, 2.0, ROCK, origin=(dx, dy)),
            geometry.JointSet("b", 45, 2.0, ROCK, origin=(dx, dy + 0.08)),
            geometry.JointSet("c", 135, 3.0, ROCK, origin=(dx + 0.3, dy)),
        ]
        return geometry.generate_slope(prof, sets, depth=10, boundary=())

    g0 = make(0.0, 0.0)
    assert len(g0.slivers) == 3
    rng = np.random.default_rng(5)
    for dx, dy in [(8374.15, -7327.9), (10.0, 0.0), *rng.uniform(-1e4, 1e4, (6, 2))]:
        g = make(dx, dy)
        assert [(s.action, s.block) for s in g.slivers] == [(s.action, s.block) for s in g0.slivers]
        assert g.blocks.n_blocks == g0.blocks.n_blocks
        for i in range(g0.blocks.n_blocks):
            a, c = g0.blocks.outline(i), g.blocks.outline(i) - [dx, dy]
            assert a.shape == c.shape and np.abs(a - c).max() <= 1e-9 * g0.blocks.extent, (dx, i)
