"""Seeded random slopes of the verdict audit (benchmarks/verdict_audit.py,
tests/test_verdict_audit.py): case ``seed`` is drawn by ``draw(seed)`` and
built by ``build``; ``transformed`` moves it, changes its force unit, lists
its blocks in reverse or sets its load steps."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

import rockdem as rd
from rockdem.geometry import JointSet, Profile, generate_slope

KINDS = ("planar", "toppling", "perpendicular", "face-parallel")
G_T = 9.80665  # kN per tonne-force: the kN -> t conversion


# ------------------------------------------------------------------ cases
def draw(seed: int) -> dict:
    """Parameters of case ``seed`` (kind by seed, everything else drawn)."""
    rng = np.random.default_rng(seed)
    kind = KINDS[seed % len(KINDS)]
    p: dict = dict(seed=seed, kind=kind)
    p["height"] = round(float(rng.uniform(8, 14)), 3)
    p["phi"] = None
    if kind == "planar":
        dip = float(rng.uniform(20, 35))
        p.update(
            face=float(rng.uniform(dip + 15, 75)),
            dips=[dip, 90.0],
            phi=float(dip + rng.uniform(3, 15)),
        )
        t = float(rng.uniform(0.5, 0.9))
        p["spacings"] = [t, t * float(rng.uniform(1.5, 2.5))]
    elif kind == "toppling":
        steep = float(rng.uniform(60, 80))  # dip into the slope
        p.update(
            face=float(rng.uniform(60, 80)),
            dips=[180.0 - steep, 90.0 - steep + rng.uniform(-5, 5)],
            phi=float(rng.uniform(25, 40)),
        )
        t = float(rng.uniform(0.5, 0.9))
        p["spacings"] = [t, t * float(rng.uniform(1.5, 3.0))]
    elif kind == "perpendicular":
        dip = float(rng.uniform(20, 40))
        p.update(
            face=float(rng.uniform(dip + 15, 80)),
            dips=[dip, dip + 90.0],
            phi=float(dip + rng.uniform(3, 15)),
        )
        t = float(rng.uniform(0.6, 1.0))
        p["spacings"] = [t, t * float(rng.uniform(1.0, 2.0))]
    else:  # a set near the face angle, vertical cross joints
        face = float(rng.uniform(50, 70))
        dip = face + float(rng.uniform(-8, 5))
        p.update(
            face=face,
            dips=[dip, 90.0 if dip < 80 else 0.0],
            phi=float(rng.uniform(max(30, dip - 15), dip + 10)),
        )
        t = float(rng.uniform(0.45, 0.7))
        p["spacings"] = [t, t * float(rng.uniform(2.0, 3.0))]
    p["phi"] = float(min(p["phi"], 60.0))
    p["cohesion"] = float(rng.uniform(5, 30)) if rng.random() < 0.3 else 0.0
    w = rng.random()
    p["water"] = (
        ("ru", float(rng.uniform(0.1, 0.3)))
        if w < 0.2
        else (("table", float(rng.uniform(0.3, 0.7))) if w < 0.35 else None)
    )
    p["kh"] = float(rng.uniform(0.05, 0.15)) if rng.random() < 0.3 else 0.0
    p["unit_weight"] = 26.0
    p["kn"] = 1e6
    return p


def build(p: dict, cohesion: float | None = None) -> rd.Model:
    c = p["cohesion"] if cohesion is None else cohesion
    H = p["height"]
    joint = rd.Joint(
        normal_stiffness=p["kn"],
        friction_angle=p["phi"],
        cohesion=c,
        tensile_strength=0.0,
        name="set1",
    )
    sets = [
        JointSet("set1", p["dips"][0] % 180.0, p["spacings"][0], joint, origin=(0.0, 0.0)),
        JointSet(
            "set2",
            p["dips"][1] % 180.0,
            p["spacings"][1],
            replace(joint, name="set2"),
            origin=(0.0, 0.0),
        ),
    ]
    prof = Profile.simple(H, p["face"], crest_length=1.2 * H, toe_length=0.4 * H)
    geom = generate_slope(prof, sets, depth=0.25 * H, unit_weight=p["unit_weight"])
    loads = rd.Loads(seismic_h=p["kh"])
    if p["water"] is not None:
        kind, v = p["water"]
        if kind == "ru":
            loads = replace(loads, pore_pressure_ratio=v)
        else:  # a straight table from a fraction of the height at the back to the toe
            pts = prof.points
            x0, x1 = float(pts[0][0]), float(pts[-1][0])
            loads = replace(
                loads, water_table=((x0, v * H), (0.0, 0.0), (x1, 0.0)), water_unit_weight=9.81
            )
    return geom.model(loads=loads, settings=rd.Settings(load_steps=5), name=f"audit{p['seed']}")


# --------------------------------------------------------------- variants
def transformed(
    model: rd.Model, shift=(0.0, 0.0), force=1.0, reverse=False, steps=None
) -> rd.Model:
    """The same slope moved by ``shift``, with forces x ``force`` (lengths
    kept), or its blocks listed in reverse order, or in ``steps`` load steps."""
    b = model.blocks
    n = b.n_blocks
    order = np.arange(n)[::-1] if reverse else np.arange(n)
    s = np.asarray(shift, float)
    polys = [b.outline(i) + s for i in order]
    blocks = rd.Blocks.from_polygons(
        polys,
        fixed=b.fixed[order],
        unit_weight=b.unit_weight[order] * force,
        ids=b.ids[order],
        check_overlap=False,
    )

    def joint(j):
        return replace(
            j,
            normal_stiffness=j.normal_stiffness * force,
            shear_stiffness=None if j.shear_stiffness is None else j.shear_stiffness * force,
            cohesion=j.cohesion * force,
            tensile_strength=j.tensile_strength * force,
            residual_cohesion=None if j.residual_cohesion is None else j.residual_cohesion * force,
            residual_tensile_strength=None
            if j.residual_tensile_strength is None
            else j.residual_tensile_strength * force,
        )

    joints = model.joints if isinstance(model.joints, (list, tuple)) else [model.joints]
    lines = None if model.joint_lines is None else np.asarray(model.joint_lines) + s
    L = model.loads
    loads = replace(
        L,
        water_table=tuple((x + s[0], y + s[1]) for x, y in L.water_table),
        water_unit_weight=L.water_unit_weight * force,
    )
    settings = model.settings if steps is None else replace(model.settings, load_steps=steps)
    return rd.Model(
        blocks,
        [joint(j) for j in joints],
        joint_lines=lines,
        line_joint=model.line_joint,
        ground=model.ground,
        loads=loads,
        settings=settings,
        name=model.name,
    )


def closed_form(p: dict) -> float | None:
    """tan(phi) / tan(dip + atan kh) where planar sliding on persistent set 1
    is the only mechanism: c = 0, dry, set 1 daylights, vertical cross
    joints whose blocks cannot topple (b / t > tan of the resultant's dip)."""
    if p["cohesion"] or p["water"] is not None or p["kind"] not in ("planar", "face-parallel"):
        return None
    dip = p["dips"][0]
    if not (0 < dip < p["face"]) or p["dips"][1] != 90.0:
        return None
    eff = np.radians(dip) + np.arctan(p["kh"])
    b_over_t = p["spacings"][1] / np.cos(np.radians(dip)) / p["spacings"][0]
    if b_over_t <= np.tan(eff) * 1.2:
        return None
    return float(np.tan(np.radians(p["phi"])) / np.tan(eff))
