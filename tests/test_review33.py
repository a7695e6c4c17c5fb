"""Review 33: each test failed before its fix."""

from __future__ import annotations

from test_hostile_round5 import invoke, sliding_wedge  # the same small models


def test_stabilise_overwrite_keeps_a_users_file_named_like_a_picture(tmp_path):
    """--overwrite removes the earlier stabilisation's stale files by glob
    'trial-[0-9][0-9]*.png': a user's marked-up copy 'trial-00-marked.png'
    in the folder was deleted with them."""
    model = sliding_wedge(tmp_path, stabilisation={"target_fos": 0.5})
    out = tmp_path / "o"
    r = invoke("stabilise", model, "--out", out)
    assert r.exit_code == 0, r.output
    (out / "trial-00-marked.png").write_bytes(b"mine")
    (out / "stage-01 copy.png").write_bytes(b"mine")
    r = invoke("stabilise", model, "--out", out, "--overwrite")
    assert r.exit_code == 0, r.output
    assert (out / "trial-00-marked.png").read_bytes() == b"mine"
    assert (out / "stage-01 copy.png").read_bytes() == b"mine"


def test_an_unnamed_bolt_left_by_a_stage_keeps_its_yield_history():
    """bolts_left_in_rock names an unnamed bolt that stays (``bolt 2``) with
    dataclasses.replace, a new object; the stage's carry matched bolts by
    identity, so the unnamed bolt lost its history: first yield at the
    excavation stage, not in load step 1 (as a named one keeps it)."""
    from dataclasses import replace

    import numpy as np
    import pytest

    import rockdem as rd
    from rockdem.stabilisation import Stage, excavate_in_stages
    from test_stabilisation import _two_blocks_and_a_yielding_bolt

    named = _two_blocks_and_a_yielding_bolt()
    model = named.replace(bolts=tuple(replace(b, name="") for b in named.bolts))
    with pytest.warns(rd.ModelWarning, match=r"bolt 2 removed with its rock"):
        ex = excavate_in_stages(model, [Stage("cut", blocks=(2,))])
    before, after = ex.stages[0].analysis, ex.stages[1].analysis
    assert before.bolts.first_yield.tolist() == [1, -1]
    assert [b.name for b in ex.stages[1].model.bolts] == ["bolt 1"]
    assert after.stable and np.asarray(after.bolts.first_yield).tolist() == [1]


def test_a_removal_leaving_only_rock_lighter_than_water_is_not_said_to_dig_below_it():
    """_back wrapped every error of check_water_table as the water table
    'once this rock is removed (it digs below the water table)', also the
    unit-weight check it runs first: removing the only heavy block read as
    digging below the water table, with the fix 'remove less, or lower the
    water table'."""
    import pytest

    import rockdem as rd
    from rockdem.errors import InputError
    from rockdem.stabilisation import _edit

    g = [(-5, -2), (10, -2), (10, 0), (-5, 0)]
    b1 = [(0, 0), (2, 0), (2, 1), (0, 1)]
    b2 = [(3, 0), (5, 0), (5, 1), (3, 1)]
    blocks = rd.Blocks.from_polygons(
        [g, b1, b2], fixed=[True, False, False], unit_weight=[20, 25, 5]
    )
    loads = rd.Loads(water_table=((-5, -0.5), (10, -0.5)), water_unit_weight=9.81)
    model = rd.Model(blocks, rd.Joint(normal_stiffness=1e6, friction_angle=35), loads=loads)
    with pytest.raises(InputError) as info:
        _edit.remove_ids(model, [1])
    assert "water_unit_weight" in info.value.where
    assert "below the water table" not in str(info.value)


def test_a_bolt_through_a_reflex_corner_of_one_block_crosses_no_joint_there():
    """A bolt through the inner corner of an L-shaped block, where the joints
    to the block in its notch end, has that block on both sides: it was
    refused as passing 'from block 1 to block 1 through the corner' (and
    before the corner rule tied the block to its neighbour there); it
    crosses only the joint into the ground."""
    import numpy as np

    import rockdem as rd
    from rockdem.bolts import Bolt
    from rockdem.solver import build_system

    g = [(-5, -2), (10, -2), (10, 0), (-5, 0)]
    a = [(0, 0), (4, 0), (4, 1), (2, 1), (2, 3), (0, 3)]
    b = [(2, 1), (4, 1), (4, 3), (2, 3)]
    blocks = rd.Blocks.from_polygons([g, a, b], fixed=[True, False, False], unit_weight=25)
    angle = float(np.degrees(np.arctan2(-2, 1.5)))  # through (2, 1) into the ground
    bolt = Bolt(head=(0.5, 3.0), angle=angle, length=4.5, capacity=100, axial_stiffness=1e4)
    model = rd.Model(blocks, rd.Joint(normal_stiffness=1e6, friction_angle=35), bolts=(bolt,))
    system = build_system(model)
    faces, c = system.interfaces, system.bolts
    pairs = {(int(faces.block_a[i]), int(faces.block_b[i])) for i in c.interface}
    assert pairs == {(0, 1)}
    np.testing.assert_allclose(c.point, [[2.75, 0.0]], atol=1e-9)


def test_stable_at_puts_after_loads_bolts_into_the_standing_slope():
    """stable_at (the trials of the bolt-pattern and support searches) ran
    the staged analysis at the target factor: a slope that stands at F = 1
    but not at the target unbolted never received its after_loads bolts, so
    a pattern rated FS 2.42 by factor_of_safety read 'not stable at 1.5'
    and stabilisation.bolts with installed: after_loads never found one."""
    import warnings
    from dataclasses import replace

    import numpy as np

    import rockdem as rd
    from rockdem import verification as V
    from rockdem.bolts import Bolt
    from rockdem.stabilisation.removal import stable_at

    R = V._rot(-25)
    ground = np.array([(-8, -2), (12, -2), (12, 0), (-8, 0)]) @ R.T
    block = np.array([(0, 0), (4, 0), (4, 1.5), (0, 1.5)]) @ R.T
    blocks = rd.Blocks.from_polygons([ground, block], fixed=[True, False], unit_weight=25)
    head = tuple(R @ np.array([2.0, 1.5]))
    bolt = Bolt(head=head, angle=205.0, length=4.0, capacity=50, axial_stiffness=1e4,
                spacing=2.0, installed="after_loads")  # fmt: skip
    model = rd.Model(blocks, rd.Joint(normal_stiffness=1e6, friction_angle=30), bolts=(bolt,))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fos = rd.factor_of_safety(model, width=0.01)
        assert fos.value is not None and fos.bracket[0] > 1.5  # unbolted: 1.24
        assert stable_at(model, 1.5)
        unbolted = model.replace(bolts=(replace(bolt, capacity=1e-6),))
        assert not stable_at(unbolted, 1.5)


def test_a_bolt_pattern_whose_4_rows_all_miss_tries_8(monkeypatch):
    """The pattern search raised at once when none of its 4 rows crossed a
    joint into rock beyond the mechanism, although 8 or 16 rows, at other
    points of the face, might anchor (review 33).  Here the 4-row search is
    made to find no anchored row: the 8-row one designs the pattern."""
    from rockdem.config import load_model
    from rockdem.errors import InputError
    from rockdem.examples import example_path
    from rockdem.stabilisation import bolting

    model, _ = load_model(example_path("perpendicular-joints"))
    search, tried = bolting._search, []

    def first_misses(model, target, rows, *args):
        tried.append(len(rows))
        if len(tried) == 1:
            raise InputError("stabilisation.bolts", "no bolt crosses a joint", "(test)")
        return search(model, target, rows, *args)

    monkeypatch.setattr(bolting, "_search", first_misses)
    p = bolting.bolt_pattern(model, 1.1, capacity=2.0, axial_stiffness=1e4)
    assert tried[0] == 4 and tried[1] == 8
    assert p.spacing is not None and p.fos.value >= 1.1
