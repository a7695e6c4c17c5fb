"""The pictures contain what they should: inspect the matplotlib artists."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
import shapely
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.colors import to_rgba
from matplotlib.patches import FancyArrowPatch
from matplotlib.quiver import Quiver
from PIL import Image

import rockdem as rd
from rockdem import plots
from rockdem.plots import OKABE_ITO, STATE_COLORS
from test_plots_models import wedge

# rockdem.loads calls shapely.line_interpolate_point(g, 0.5, True): deprecated in
# shapely 2.1 (reported; remove when loads.py passes normalized=True by keyword)
pytestmark = pytest.mark.filterwarnings(
    "ignore:positional argument `normalized`:DeprecationWarning"
)

RED = to_rgba(OKABE_ITO["vermillion"])
BLUE = to_rgba(OKABE_ITO["blue"])


@pytest.fixture(scope="module")
def model():
    return wedge(loads=True, bridge=True)


@pytest.fixture(scope="module")
def analysis(model):
    return rd.analyse(model)


@pytest.fixture(scope="module")
def fos(model):
    return rd.factor_of_safety(model, width=0.02)


@pytest.fixture(scope="module")
def unstable():
    a = rd.analyse(wedge(30.0, 25.0, 30.0))
    assert not a.stable
    return a


def by_gid(ax, gid, kind=LineCollection):
    found = [a for a in ax.get_children() if isinstance(a, kind) and a.get_gid() == gid]
    assert len(found) == 1, f"expected one {kind.__name__} {gid!r}, found {len(found)}"
    return found[0]


def count_colour(ax, rgba) -> int:
    """Segments of all LineCollections drawn in the colour ``rgba``."""
    n = 0
    for coll in ax.collections:
        if not isinstance(coll, LineCollection):
            continue
        colors = coll.get_colors()
        segs = coll.get_segments()
        if len(segs) == 0:
            continue
        colors = np.broadcast_to(colors, (len(segs), 4)) if len(colors) == 1 else colors
        n += int(np.all(np.isclose(colors, rgba), axis=1).sum())
    return n


def test_palette_red_means_shear():
    assert STATE_COLORS[1] == OKABE_ITO["vermillion"]
    assert STATE_COLORS[2] == OKABE_ITO["blue"]
    assert OKABE_ITO["vermillion"] not in plots.JOINT_COLORS


def test_model_figure(model, analysis):
    ax = plots.plot_model(model, block_ids=True)
    system = analysis.system
    joints = by_gid(ax, "joints")
    bridges = by_gid(ax, "bridges")
    bridge_idx = model.joint_index("bridge")
    n_bridge = int((system.interfaces.joint == bridge_idx).sum())
    assert n_bridge == 1
    assert (
        len(joints.get_segments()) + len(bridges.get_segments()) == system.interfaces.n_interfaces
    )
    assert len(bridges.get_segments()) == n_bridge
    # joints coloured by joint set
    want = [to_rgba(plots.JOINT_COLORS[j]) for j in system.interfaces.joint if j != bridge_idx]
    assert np.allclose(joints.get_colors(), want)
    ground = by_gid(ax, "ground", PolyCollection)
    assert len(ground.get_paths()) == 1 and ground.get_hatch() == "///"
    assert len(by_gid(ax, "blocks", PolyCollection).get_paths()) == 3
    arrows = [p for p in ax.patches if isinstance(p, FancyArrowPatch)]
    assert sum(a.get_gid() == "support" for a in arrows) == 1
    assert sum(a.get_gid() == "line-load" for a in arrows) == 5
    ids = [t.get_text() for t in ax.texts if t.get_gid() == "block-id"]
    assert sorted(ids) == ["1", "2", "3"]
    assert ax.get_aspect() == 1.0
    assert "(m)" in ax.get_xlabel() and "(m)" in ax.get_ylabel()
    assert any(a.get_gid() == "scale-bar" for a in ax.artists)


def test_failure_state_colours(analysis):
    # the history (current=False): one segment per interface, worst flag so far
    ax = plots.plot_failure(analysis, current=False)
    state = analysis.interfaces.state
    assert (state == 1).sum() >= 1 and (state == 2).sum() >= 1
    assert count_colour(ax, RED) == (state == 1).sum()
    assert count_colour(ax, BLUE) == (state == 2).sum()
    assert len(by_gid(ax, "interfaces-elastic").get_segments()) == (state == 0).sum()
    assert not [c for c in ax.collections if c.get_gid() == "unstable"]
    # the default: the current state, one stretch per spring point
    ax = plots.plot_failure(analysis)
    now = analysis.springs.current
    assert count_colour(ax, RED) == (now == 2).sum()
    assert count_colour(ax, BLUE) == (now == 3).sum()
    assert len(by_gid(ax, "interfaces-elastic").get_segments()) == (now == 0).sum()


def test_failure_state_of_mechanism(fos):
    a = fos.failed_analysis
    ax = plots.plot_failure(fos)
    assert len(by_gid(ax, "slip-surface").get_segments()) == len(a.slip_surface) > 0
    shaded = by_gid(ax, "unstable", PolyCollection)
    assert len(shaded.get_paths()) == int(a.unstable.sum()) > 0
    assert count_colour(ax, RED) == (a.springs.current == 2).sum()


def test_deformed_blocks_moved_by_magnified_displacement(analysis):
    mag = 2000.0
    ax = plots.plot_deformed(analysis, magnification=mag)
    blocks = analysis.system.blocks
    free = np.flatnonzero(~blocks.fixed)
    polys = by_gid(ax, "deformed", PolyCollection).get_paths()
    assert len(polys) == len(free)
    for path, i in zip(polys, free, strict=True):
        v = path.vertices
        v = v[:-1] if np.allclose(v[0], v[-1]) and len(v) > len(blocks.outline(i)) else v
        ux, uy, th = analysis.displacement[i]
        moved = shapely.Polygon(v).centroid
        assert np.allclose([moved.x, moved.y], blocks.centroid[i] + mag * np.array([ux, uy]))
        # rigid: edge lengths kept, first edge turned by mag * rotation
        e0 = blocks.outline(i)[1] - blocks.outline(i)[0]
        e1 = v[1] - v[0]
        assert np.isclose(np.hypot(*e0), np.hypot(*e1))
        turn = np.arctan2(e1[1], e1[0]) - np.arctan2(e0[1], e0[0])
        assert np.isclose(turn, mag * th, atol=1e-9)
    q = [c for c in ax.collections if isinstance(c, Quiver)]
    assert len(q) == 1
    assert np.allclose(q[0].U, mag * analysis.displacement[free, 0])
    assert f"x{mag:g}" in ax.get_title()
    # the colour map shows the motion magnitude per block
    assert np.all(np.asarray(by_gid(ax, "deformed", PolyCollection).get_array()) > 0)


def test_mechanism_for_unstable(unstable):
    ax = plots.plot_deformed(unstable)
    assert "mechanism" in ax.get_title().lower()
    q = next(c for c in ax.collections if isinstance(c, Quiver))
    moving = unstable.unstable & ~unstable.system.blocks.fixed
    mag = plots.auto_magnification(unstable.system.blocks, unstable.mechanism)
    mech = plots.oriented_mechanism(unstable)
    assert np.allclose(q.U, mag * mech[moving, 0])
    # the blocks fall: gravity does positive work on the drawn mechanism
    assert np.all(mech[moving, 1] <= 0) and np.sum(unstable.system.f_block * mech) > 0


def test_stress_along_joint(analysis):
    fig = plots.plot_joint_stress(analysis, "active plane")
    sp = analysis.springs
    chosen = np.flatnonzero(analysis.interfaces.kind == "active plane")
    want = np.flatnonzero(np.isin(sp.interface, chosen))
    lines = {ln.get_gid(): ln for ax in fig.axes for ln in ax.lines}
    sigma = np.asarray(lines["sigma"].get_ydata(), dtype=float)
    sigma = sigma[np.isfinite(sigma)]
    assert len(sigma) == len(want)
    assert np.allclose(np.sort(sigma), np.sort(sp.sigma[want]))
    x = np.asarray(lines["sigma"].get_xdata(), dtype=float)
    x = x[np.isfinite(x)]
    assert np.isclose(x.min(), 0.0) and np.isclose(
        x.max(), analysis.interfaces.length[chosen].sum()
    )
    strength = np.asarray(lines["strength"].get_ydata(), dtype=float)
    assert np.allclose(np.sort(strength[np.isfinite(strength)]), np.sort(sp.capacity[want]))
    n_sliding = int((sp.current[want] == 2).sum())
    if n_sliding:
        assert len(lines["now-sliding"].get_xdata()) == n_sliding
    path = next(c for ax in fig.axes for c in ax.collections if c.get_gid() == "path")
    assert len(path.get_segments()) == len(chosen)


def test_stress_along_joint_line_and_default(analysis, unstable):
    by_line = plots.select_interfaces(analysis, 0)  # the first joint line: active plane
    assert np.array_equal(by_line, np.flatnonzero(analysis.interfaces.kind == "active plane"))
    assert np.array_equal(plots.select_interfaces(unstable), unstable.slip_surface)
    p = plots.joint_path(unstable, unstable.slip_surface)
    assert np.all(np.diff(p.position) >= -1e-12)


def test_frames(fos):
    a = fos.failed_analysis
    fr = plots.frames(a)
    assert len(fr) == len(a.steps)
    n_failed = [int((f.spring_state > 0).sum()) for f in fr]
    assert n_failed == sorted(n_failed)
    assert np.array_equal(fr[-1].interface_state, a.interfaces.state)
    assert fr[-1].final and not fr[-1].converged


def test_progressive_grid(fos):
    fig = plots.plot_progressive(fos, max_frames=4, ncols=2)
    shown = [ax for ax in fig.axes if ax.axison]
    assert len(shown) == 4
    assert "no equilibrium" in shown[-1].get_title()


def test_animation(tmp_path, analysis):
    out = plots.animate_progressive(analysis, tmp_path / "a.gif", dpi=40, hold=2)
    with Image.open(out) as im:
        assert im.format == "GIF"
        assert 1 <= im.n_frames <= len(analysis.steps) + 2


def test_fos_plot(fos):
    ax = plots.plot_fos(fos)
    stable = sum(t.stable for t in fos.trials)
    lines = {ln.get_gid(): ln for ln in ax.lines}
    assert len(lines["trials-stable"].get_xdata()) == stable
    assert len(lines["trials-unstable"].get_xdata()) == len(fos.trials) - stable
    assert len(lines["trials-undecided"].get_xdata()) == 0
    assert f"{fos.value:.3f}" in ax.get_title()
    assert "displacement" in ax.get_ylabel()


def test_fos_plot_tells_a_stall_from_a_failure(fos):
    """A trial where Newton found no equilibrium but nothing proved or
    confirmed the failure is drawn apart from the failures (hollow grey), with
    its own legend entry: it is not a verdict."""
    from dataclasses import replace

    from rockdem.results import Evidence

    failed = [k for k, t in enumerate(fos.trials) if not t.stable]
    assert failed and fos.trials[failed[0]].evidence.proof != "undecided"
    stall = Evidence(reason="stalled", iterations=40, residuals=(1e-3,))
    assert stall.proof == "undecided"
    trials = list(fos.trials)
    trials[failed[0]] = replace(trials[failed[0]], evidence=stall)
    ax = plots.plot_fos(replace(fos, trials=tuple(trials)), recompute=False)
    lines = {ln.get_gid(): ln for ln in ax.lines}
    assert list(lines["trials-undecided"].get_xdata()) == [trials[failed[0]].factor]
    assert len(lines["trials-unstable"].get_xdata()) == len(failed) - 1
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "none found, failure not proven" in labels


def test_fos_plot_without_displacements(fos):
    """Trials with no recorded displacement fall back to a verdict-only plot."""
    import dataclasses

    bare = dataclasses.replace(
        fos, trials=tuple(dataclasses.replace(t, max_displacement=None) for t in fos.trials)
    )
    ax = plots.plot_fos(bare, recompute=False)
    assert ax.get_ylabel() == "verdict"


def test_fos_plot_uses_recorded_displacements(fos):
    values, source = plots.trial_displacements(fos, recompute=False)
    assert source == "search"
    stable = np.array([t.stable for t in fos.trials])
    assert np.all(np.isfinite(values[stable])) and np.all(np.isnan(values[~stable]))


@pytest.mark.parametrize("what", sorted(plots.WHAT))
def test_plot_figure(tmp_path, model, fos, what):
    ext = "gif" if what == "animation" else ("svg" if what in ("model", "failure") else "png")
    out = plots.plot_figure(fos if what != "model" else model, what, tmp_path / f"f.{ext}", dpi=50)
    data = out.read_bytes()
    assert len(data) > 1000
    if ext == "svg":
        assert b"<svg" in data[:2000]
    elif ext == "png":
        assert data[:8] == b"\x89PNG\r\n\x1a\n"
    else:
        assert data[:6] in (b"GIF89a", b"GIF87a")


def test_plot_figure_rejects_unknown(tmp_path, analysis):
    with pytest.raises(ValueError, match="unknown figure"):
        plots.plot_figure(analysis, "nonsense", tmp_path / "x.png")


def test_plot_figure_from_model(tmp_path):
    out = plots.plot_figure(wedge(), "failure", tmp_path / "f.pdf")
    assert out.read_bytes()[:4] == b"%PDF"


def test_no_pyplot_state(analysis):
    import sys

    before = sys.modules.get("matplotlib.pyplot")
    plots.plot_failure(analysis)
    if before is not None:
        assert before.get_fignums() == []


def test_failure_picture_draws_the_support_forces():
    """A support force (an anchor) is part of the state shown: drawn as in the
    model picture, with a legend entry."""
    import rockdem as rd
    from rockdem import plots
    from rockdem import verification as V

    anchor = rd.PointLoad.anchor(1.0, 0.5, 5.0, 195.0, name="anchor")
    joint = rd.Joint(normal_stiffness=1e6, friction_angle=20)
    model = V.block_on_plane(30, joint, loads=rd.Loads(points=(anchor,)))
    ax = plots.plot_failure(rd.analyse(model))
    assert any(p.get_gid() == "support" for p in ax.patches)
    from rockdem.plots.state import failure_legend

    legend = failure_legend(ax)
    assert "support" in [t.get_text() for t in legend.get_texts()]


def test_a_search_that_found_no_failure_is_not_titled_a_mechanism():
    """Two blocks stacked on flat ground: the search grows the factor to 86.5
    and finds no failure.  Its motion picture was titled 'Failure mechanism
    at F = 86.4976' (found by fuzzing); it says there is none."""
    ground = [(-5, -1), (5, -1), (5, 0), (-5, 0)]
    low, high = [(0, 0), (2, 0), (2, 1), (0, 1)], [(0, 1), (2, 1), (2, 2), (0, 2)]
    blocks = rd.Blocks.from_polygons([ground, low, high], fixed=[True, False, False])
    fos = rd.factor_of_safety(rd.Model(blocks, rd.Joint(normal_stiffness=1e6, friction_angle=30)))
    assert fos.mode == "no-failure"
    for use in ("auto", "mechanism"):
        title = plots.plot_deformed(fos, use=use).get_title()
        assert "Failure mechanism" not in title
    assert plots.plot_deformed(fos, use="mechanism").get_title().startswith("No failure mechanism")
