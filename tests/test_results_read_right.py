"""Outputs that read right: every label carries the factor of the state it shows.

Issue 10: the failed state of a search was captioned "just above the factor of
safety" at a trial factor far above it; stress plots drew the strength at
F = 1 beside stresses at another factor; the stress path named its joints in
alphabetical, not drawn, order; an unstable report drew the same mechanism
twice, once titled "deformed shape".
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import dataclasses
import re

import numpy as np
import pytest

import rockdem as rd
from rockdem import plots
from rockdem.config import load_model
from rockdem.examples import example_path
from rockdem.report import write_report
from rockdem.results import format_factor
from test_plots_models import wedge

pytestmark = pytest.mark.filterwarnings(
    "ignore:positional argument `normalized`:DeprecationWarning"
)


def example(name):
    return load_model(example_path(name))[0]


@pytest.fixture(scope="module")
def layers():
    """Inclined layers (c = 0): unstable at F = 1, factor of safety about 0.825."""
    m = example("inclined-layers")
    return m, rd.analyse(m), rd.factor_of_safety(m, width=0.005)


def _lines(fig):
    return {ln.get_gid(): ln for ax in fig.axes for ln in ax.lines if ln.get_gid()}


def _finite(y):
    y = np.asarray(y, dtype=float)
    return y[np.isfinite(y)]


# ----------------------------------------------------------------- stress plots
@pytest.mark.parametrize("which", ["run", "stable end", "failed end", "search"])
def test_stress_plot_never_shows_shear_above_the_strength_drawn(layers, which):
    _, run, fos = layers
    shown = {
        "run": run,
        "stable end": fos.stable_analysis,
        "failed end": fos.failed_analysis,
        "search": fos,
    }[which]
    fig = plots.plot_joint_stress(shown)
    lines = _lines(fig)
    tau = _finite(lines["tau"].get_ydata())
    strength = _finite(lines["strength"].get_ydata())
    assert len(tau) == len(strength) > 0
    assert np.all(tau <= strength * (1 + 1e-9) + 1e-12)
    # the strength line and the title name the factor of the stresses shown
    a = fos.stable_analysis if which == "search" else shown
    F = f"F = {format_factor(a.stress_factor)}"
    assert F in lines["strength"].get_label()
    assert F in fig._suptitle.get_text()


def test_stress_factor_is_that_of_the_stresses(layers):
    """The F = 1 run of a slope with FS 0.825 finds no equilibrium: its stresses
    are the solver's last iterate at the factor where equilibrium was lost."""
    _, run, _ = layers
    assert not run.stable
    sp = run.springs
    intact = (sp.state == 0) & (sp.capacity > 0)
    assert intact.any()
    # full strength over strength at the stresses' factor = that factor
    assert np.allclose(sp.capacity[intact] / sp.strength[intact], run.stress_factor)
    assert run.stress_factor < 0.9


def test_stress_path_title_lists_the_joints_in_the_order_drawn():
    m = example("wedge-verification")
    a = rd.analyse(m)
    fig = plots.plot_joint_stress(a)
    chosen = plots.select_interfaces(a)
    path = plots.joint_path(a, chosen)
    drawn = plots.stress.path_kinds(a, path)
    assert len(set(drawn)) >= 3
    title = fig._suptitle.get_text()
    assert " → ".join(drawn) in title
    # the start (distance 0) is the first interface drawn
    assert np.isclose(path.position.min(), 0.0)


# ------------------------------------------------------------------ titles
def test_failure_title_names_the_factor_of_the_state_and_the_fos_apart(layers):
    _, _, fos = layers
    ax = plots.plot_failure(fos)
    title = ax.get_title()
    assert f"F = {format_factor(fos.failed_analysis.strength_factor)}" in title
    assert f"factor of safety {fos.value:.3f}" in title
    assert "just above" not in title


def _captions(text):
    return re.findall(r"<figcaption>(.*?)</figcaption>", text, re.S)


def test_report_says_just_above_only_when_it_is(tmp_path, layers):
    m, run, fos = layers
    failed = fos.failed_analysis
    # a search whose failed trial lies well above the bracket (a trial target)
    far = dataclasses.replace(fos, bracket=(fos.bracket[0], failed.strength_factor * 0.9))
    near = dataclasses.replace(fos, bracket=(fos.bracket[0], failed.strength_factor))
    for case, f in (("far", far), ("near", near)):
        path = write_report(
            m, tmp_path / case, analysis=run, fos=f, animation=False, image_format="svg"
        )
        caps = " ".join(_captions(path.read_text(encoding="utf-8")))
        assert f"F = {format_factor(failed.strength_factor)}" in caps
        assert ("just above the factor of safety" in caps) == (case == "near")


def test_unstable_report_draws_no_deformed_shape_and_no_mechanism_twice(tmp_path):
    m = wedge(30.0, 25.0, 30.0)
    a = rd.analyse(m)
    assert not a.stable
    fos = rd.factor_of_safety(m, width=0.05)
    # a search whose failed end is the F = 1 state itself: one mechanism picture
    same = dataclasses.replace(fos, failed_analysis=dataclasses.replace(a))
    path = write_report(m, tmp_path, analysis=a, fos=same, animation=False, image_format="svg")
    text = path.read_text(encoding="utf-8")
    assert 'alt="deformed shape"' not in text
    assert text.count('alt="failure mechanism"') == 1
    caps = _captions(text)
    assert not any(c.lower().startswith("deformed shape") for c in caps)


def test_deformed_and_mechanism_titles_carry_their_factor(layers):
    m = wedge(loads=True, bridge=True)
    a = rd.analyse(m)
    assert a.stable
    t = plots.plot_deformed(a).get_title()
    assert t.startswith("Deformed shape at F = 1")
    _, _, fos = layers
    t = plots.plot_deformed(fos.failed_analysis, use="mechanism").get_title()
    assert f"Failure mechanism at F = {format_factor(fos.failed_analysis.strength_factor)}" in t


# ------------------------------------------------- current state vs history
@pytest.fixture(scope="module")
def bedded():
    """The bedded slope stands (FS about 1.2) although many joints failed on the way."""
    m = example("bedded-slope")
    a = rd.analyse(m)
    assert a.stable
    return m, a


def test_current_state_follows_the_stresses_now(bedded):
    _, a = bedded
    sp = a.springs
    now = sp.current
    assert set(np.unique(now)) == {0, 1, 2, 3}
    assert np.all(sp.sigma[now == 3] <= 1e-9)  # open: no compression
    closed = (now == 0) | (now == 1)
    assert np.all(np.abs(sp.tau[closed]) < sp.strength[closed] + 1e-12)
    assert np.allclose(np.abs(sp.tau[now == 2]), sp.strength[now == 2], rtol=1e-5)
    # history and current state are different things: failed earlier, holding now
    failed = a.state.yielded | a.state.broken
    assert np.all(failed[now == 1]) and not np.any(failed[now == 0])


def test_joints_failed_in_tension_and_closed_again_are_history_not_open(bedded):
    _, a = bedded
    ir = a.interfaces
    healed = (ir.state == 2) & (ir.current == 1)
    assert healed.any()
    assert np.all(ir.normal_stress[healed] > 0)  # closed, in compression now
    assert not np.any(ir.current_name[healed] == "open")
    # in the picture: their points are drawn as history (dashed), never as open (blue)
    ax = plots.plot_failure(a)
    coll = {c.get_gid(): c for c in ax.collections}
    sp_now = a.springs.current
    assert len(coll["interfaces-open"].get_segments()) == int((sp_now == 3).sum())
    assert len(coll["interfaces-closed-failed-earlier"].get_segments()) == int(
        (sp_now == 1).sum()
    )
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(t.startswith("failed earlier, now closed (") for t in labels)
    assert ax.get_legend().get_title().get_text().startswith("joints now")


def test_tables_and_csv_keep_the_current_state_apart_from_the_history(bedded, tmp_path):
    import csv

    from rockdem.output import analysis_summary, analysis_tables, write_results

    _, a = bedded
    summary = analysis_summary(a)
    states = summary["interface_states"]
    ir = a.interfaces
    assert states["now"]["open"] == int((ir.current == 3).sum())
    assert states["now"]["sliding"] == int((ir.current == 2).sum())
    assert sum(states["history"].values()) == sum(states["now"].values()) == ir.n_interfaces
    assert sum(v for k, v in states["history"].items() if k != "elastic") == len(
        summary["failed_interfaces"]
    )
    write_results(tmp_path / "r", analysis_tables(a), {"summary": summary})
    with (tmp_path / "r" / "interfaces.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    healed = [r for r in rows if r["current_state"] == "closed-failed-earlier"]
    assert healed and all(r["state"] in ("shear", "tension") for r in healed)
    assert {"open_fraction", "sliding_fraction"} <= set(rows[0])
    with (tmp_path / "r" / "springs.csv").open() as fh:
        spr = list(csv.DictReader(fh))
    assert {"current_state", "strength_at_factor"} <= set(spr[0])


def test_run_prints_the_state_now_apart_from_the_history():
    from typer.testing import CliRunner

    from rockdem.cli import app

    r = CliRunner().invoke(app, ["run", "--example", "bedded-slope"])
    assert r.exit_code == 0, r.output
    text = r.stdout
    assert "STABLE" in text
    assert "joints now (" in text and "failure history: " in text
    assert "failed joints (" not in text
    now_line = next(ln for ln in text.splitlines() if ln.startswith("joints now"))
    assert "failed earlier and now closed" in now_line
