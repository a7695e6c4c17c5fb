"""Draw the pictures of docs/examples.md to docs/img/examples-*.png.

Run: ``python docs/make_example_pictures.py`` (about half a minute).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import rockdem as rd
from rockdem.config import load_model
from rockdem.examples import example_path
from rockdem.geometry import JointSet, Profile, generate_slope
from rockdem.plots import plot_failure
from rockdem.results import format_factor
from rockdem.stabilisation import Stage, excavate_in_stages, stabilise, trial_picture

OUT = Path(__file__).parent / "img"


def save(fig, name: str) -> None:
    fig.tight_layout()
    fig.savefig(OUT / name, dpi=100)
    plt.close(fig)
    print(f"wrote {OUT / name}")


def wedge() -> None:
    fig, axes = plt.subplots(2, 2, figsize=(12, 7.5))
    for ax, name in zip(axes.ravel(), ["wedge-verification", "wedge-verification-35-31",
                                       "wedge-verification-36-30", "wedge-verification-35-32"],
                        strict=True):
        model, cfg = load_model(example_path(name))
        fos = rd.factor_of_safety(model, width=0.002)
        a = rd.analyse(model)
        p1, p2 = cfg.joints["upper"].friction_angle, cfg.joints["lower"].friction_angle
        plot_failure(a, ax=ax, legend=False, title=f"phi1 = {p1:g}, phi2 = {p2:g}: "
                     f"{a.verdict} at F = {format_factor(a.strength_factor)}, "
                     f"FS {fos.value:.3f}")
    save(fig, "examples-wedge.png")


def removal(name: str, target: float, file: str, **kw) -> None:
    model, _ = load_model(example_path(name))
    s = stabilise(model, target, **kw)
    shown = [t for t in s.trials if t.accepted]
    size = (max(8.5, 7.5 * len(shown)), 4.8)
    fig, axes = plt.subplots(1, len(shown), figsize=size, squeeze=False)
    for ax, t in zip(axes[0], shown, strict=True):
        trial_picture(t, model, target, ax=ax)
        if ax.get_legend() is not None and t is not shown[0]:
            ax.get_legend().remove()
    save(fig, file)


def toppling() -> None:
    """The toppling example: the mechanism at its limit (a mode per column)
    and the slope held at the file's target by the toe support it names."""
    from rockdem.stabilisation import support_force

    model, cfg = load_model(example_path("toppling"))
    fos = rd.factor_of_safety(model)
    target, sup = cfg.stabilisation.target_fos, cfg.stabilisation.support
    held = support_force(model, target, at=sup.at, angle=sup.angle)
    fig, axes = plt.subplots(1, 2, figsize=(15, 5.2))
    plot_failure(fos.failed_analysis, ax=axes[0],
                 title=f"FS {fos.value:.3f} (Goodman & Bray 0.735): the face columns fail\n"
                       f"(state at F = {format_factor(fos.failed_analysis.strength_factor)}, "
                       "where equilibrium is lost)")
    shown = held.fos.stable_analysis
    plot_failure(shown, ax=axes[1], legend=False,
                 title=f"toe support {held.force:.2f} t at {sup.angle:g} degrees: "
                       f"FS {held.fos.value:.2f}\n(state at F = "
                       f"{format_factor(shown.strength_factor)}, target {target:g})")
    save(fig, "examples-toppling.png")


def inclined_designs() -> None:
    from rockdem.stabilisation import study

    model, cfg = load_model(example_path("inclined-layers"))
    s = study(model, cfg, support=False, stages=False)
    fig, axes = plt.subplots(1, 3, figsize=(19, 4.8))
    for ax, d in zip(axes, s.designs, strict=True):
        f = d.then.final.fos if d.then is not None else d.fos
        shown = d.fos.failed_analysis if not d.reached else d.fos.stable_analysis
        more = (f"\nthen {len(d.then.removed_blocks)} more blocks: total area "
                f"{d.total_removed_area:.2f} m^2, FS {f.value:.2f}") if d.then else ""
        plot_failure(shown, ax=ax, legend=False,
                     title=f"{d.name}: area {d.removed_area:.2f} m^2 removed, "
                           f"{'stable' if d.reached else 'unstable'}\n(FS {d.fos.value:.3f}; "
                           f"state at F = {format_factor(shown.strength_factor)})" + more)
    save(fig, "examples-inclined-layers-designs.png")


def stages() -> None:
    j = rd.Joint(normal_stiffness=1e5, friction_angle=40, name="j")
    sets = [JointSet("bedding", 35, 1.0, j, origin=(0, 0.3)),
            JointSet("cross", 90, 1.5, j, origin=(0.2, 0))]
    g = generate_slope(Profile([(-10, 5), (6, 5)]), sets, depth=6, unit_weight=2.6,
                       ground_joint=j)
    ex = excavate_in_stages(g.model(), [
        Stage("bench 1", profile=((-10, 5), (-3, 5), (-2.3, 2.5), (6, 2.5))),
        Stage("bench 2", profile=((-10, 5), (-3, 5), (-2.3, 2.5), (0, 2.5), (0.7, 0), (6, 0))),
    ])
    fig, axes = plt.subplots(1, len(ex.stages), figsize=(6.5 * len(ex.stages), 4.6))
    for ax, s in zip(axes, ex.stages, strict=True):
        plot_failure(s.analysis, ax=ax, legend=s.number == 0,
                     title=f"stage {s.number}: {s.name}\n{len(s.new_failures)} joints failed "
                           f"in this stage ({'stable' if s.stable else 'unstable'} at "
                           f"F = {format_factor(s.analysis.strength_factor)})")
    save(fig, "examples-stages.png")


def main() -> None:
    OUT.mkdir(exist_ok=True)
    wedge()
    removal("perpendicular-joints", 1.0, "examples-perpendicular-joints.png")
    inclined_designs()
    toppling()
    stages()


if __name__ == "__main__":
    main()
