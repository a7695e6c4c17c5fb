"""The tables of the HTML report: the inputs, and of an analysis the state of
the joints, the failed interfaces, the unstable blocks, the bolts, the warnings."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from . import plots
from .modes import boundary_warnings, failure_modes
from .report_html import esc, html_table, num
from .results import Analysis, format_factor
from .units import UNKNOWN, Units, parse_units


def state_counts(a: Analysis) -> str:
    """Current state and failure history of the interfaces, kept apart."""
    now = np.bincount(a.interfaces.current, minlength=4)
    s = a.interfaces.state
    return (
        f"now {int(now[2])} sliding, {int(now[3])} open, {int(now[1])} failed earlier and "
        f"now closed, {int(now[0])} elastic interfaces (history: {int((s > 0).sum())} have "
        f"failed at some time, {int((s == 1).sum())} in shear, {int((s == 2).sum())} in "
        "tension)"
    )


#: current state of a failed interface, in words (codes of rockdem.results.CURRENT_NAMES)
_NOW = ("closed", "closed", "sliding", "open")


def failed_table(a: Analysis, stress_unit: str, limit: int, u: Units = UNKNOWN) -> str:
    """Every interface that has failed at some time (the history), with its state now."""
    ir = a.interfaces
    faces = a.system.interfaces
    idx = np.flatnonzero(ir.state > 0)
    if not idx.size:
        return '<p class="note">No interface has failed.</p>'
    slip = set(np.asarray(a.slip_surface).tolist())
    rows = []
    for i in idx[:limit]:
        rows.append(
            [
                str(ir.kind[i]),
                str(ir.state_name[i]),
                _NOW[int(ir.current[i])],
                int(i),
                f"{int(ir.block_a[i])} / {int(ir.block_b[i])}",
                f"({num(faces.start[i][0], '.3g')}, {num(faces.start[i][1], '.3g')}) - "
                f"({num(faces.end[i][0], '.3g')}, {num(faces.end[i][1], '.3g')})",
                num(ir.length[i], ".3g"),
                num(100 * ir.failed_fraction[i], ".0f"),
                num(ir.normal_stress[i], ".3g"),
                num(ir.shear_stress[i], ".3g"),
                int(ir.first_failure[i]),
                "yes" if int(i) in slip else "",
            ]
        )
    header = [
        "joint",
        "failed in",
        "now",
        "interface",
        "blocks",
        "from - to",
        "length" + u.suffix("length"),
        "failed %",
        ("σ' mean" if plots.stress.wet(a) else "σ mean") + f" ({stress_unit})",
        f"τ mean ({stress_unit})",
        "first failed (stage)",
        "slip surface",
    ]
    more = f'<p class="note">... and {idx.size - limit} more.</p>' if idx.size > limit else ""
    listing = html_table(header, rows, left=3, cls="failed-joints") + more
    if idx.size <= 15:
        return listing
    return (
        f"<details><summary>{idx.size} interfaces that have failed at some time "
        f"(click to show)</summary>{listing}</details>"
    )


def unstable_table(a: Analysis, limit: int, u: Units = UNKNOWN) -> str:
    """The moving blocks with their failure mode (rockdem.modes) and mechanism motion."""
    blocks = a.system.blocks
    idx = np.flatnonzero(a.unstable)
    if not idx.size:
        return '<p class="note">No block moves (no failure mechanism).</p>'
    rows = []
    mech = plots.oriented_mechanism(a)
    modes = failure_modes(a)
    for i in idx[:limit]:
        ux, uy, rot = mech[i]
        px, py = modes.pivot[i]
        rows.append(
            [
                int(blocks.ids[i]),
                str(modes.name[i]),
                f"({num(px, '.4g')}, {num(py, '.4g')})" if np.isfinite(px) else "",
                num(blocks.area[i], ".4g"),
                num(blocks.weight[i], ".4g"),
                f"({num(blocks.centroid[i][0], '.4g')}, {num(blocks.centroid[i][1], '.4g')})",
                num(ux, ".3f"),
                num(uy, ".3f"),
                num(rot, ".3g"),
            ]
        )
    header = [
        "block",
        "failure mode",
        "pivot",
        "area" + u.suffix("area"),
        "weight" + u.suffix("force"),
        "centroid",
        "mech. ux",
        "mech. uy",
        "mech. rot",
    ]
    more = f'<p class="note">... and {idx.size - limit} more.</p>' if idx.size > limit else ""
    counts = ", ".join(f"{n} {m}" for m, n in modes.counts().items() if n and m != "stable")
    lead = f'<p class="modes">Failure modes: {esc(counts)}.</p>'
    key = (
        '<p class="note">mech. ux, uy, rot: the direction of each block\'s motion in the '
        "failure mechanism (translation of its centroid, and rotation in radians, "
        "counter-clockwise positive), scaled so that the largest block motion is 1: "
        "relative, not a displacement.</p>"
    )
    return lead + html_table(header, rows, left=2, cls="unstable-blocks") + key + more


def bolts_table(a: Analysis, u: Units = UNKNOWN) -> str:
    """Every joint a bolt crosses: force per bolt, capacity there, utilisation."""
    r = a.bolts
    if r is None:
        return ""
    use = r.utilisation
    # an after_loads bolt of a slope that never stood: not a bolt at rest
    gone = np.zeros(r.n, bool) if r.installed is None else ~r.installed
    rows = [
        [
            str(r.name[k]),
            num(r.depth[k], ".3g"),
            f"({num(r.point[k, 0], '.4g')}, {num(r.point[k, 1], '.4g')})",
            num(r.axial_force[k], ".4g"),
            num(r.shear_force[k], ".4g"),
            num(r.capacity[k], ".4g"),
            f"{100 * use[k]:.0f}%",
            "not installed" if gone[k] else "yes" if r.yielded[k] else "",
        ]
        for k in np.argsort(-use, kind="stable")
    ]
    header = [
        "bolt",
        "depth" + u.suffix("length"),
        "at joint",
        "axial force" + u.suffix("force"),
        "shear force" + u.suffix("force"),
        "capacity" + u.suffix("force"),
        "utilisation",
        "yielded",
    ]
    note = (
        '<p class="note">Force per bolt where it crosses each joint (tension positive), '
        "most used first; capacity is the steel's or the grout bond's beyond the joint.</p>"
    )
    return note + html_table(header, rows, left=3, cls="bolts")


def warnings_html(*analyses: Analysis | None, notes: Sequence[str] = ()) -> str:
    """A warning box per side of the model the mechanism reaches (rockdem.modes),
    then one per note (the ModelWarnings issued about the model: a joint line
    that assigns nothing, joints too soft for the verdict to hold)."""
    shown: dict[str, str] = {}  # message -> the factor of the first state that gave it
    for a in analyses:
        for text in boundary_warnings(a) if a is not None else ():
            shown.setdefault(text, format_factor(a.strength_factor))
    boxes = [
        f'<div class="warning">Warning (mechanism at F = {F}): {esc(t)}.</div>'
        for t, F in shown.items()
    ]
    boxes += [f'<div class="warning">Warning: {esc(t)}</div>' for t in dict.fromkeys(notes)]
    return "".join(boxes)


def inputs_section(model, system, units: str | None) -> str:
    """The report's inputs: the model, its materials, joints and loads."""
    blocks = system.blocks
    n_free = int((~blocks.fixed).sum())
    summary = [
        ["name", esc(model.name)],
        ["units", esc(units or "consistent user units (not stated)")],
        [
            "section",
            "2-D: forces and weights are per "
            + esc(parse_units(units).length or "unit length")
            + " of slope perpendicular to the section (an area is a volume per "
            + esc(parse_units(units).length or "unit length")
            + ")",
        ],
        ["blocks", f"{blocks.n_blocks} ({n_free} free, {blocks.n_blocks - n_free} fixed)"],
        ["interfaces", str(system.interfaces.n_interfaces)],
        ["spring points", str(system.springs.n_springs)],
        [
            "weight of free blocks" + parse_units(units).suffix("force"),
            num(blocks.weight[~blocks.fixed].sum(), ".5g"),
        ],
    ]
    s = model.settings
    summary += [
        ["quadrature", f"{esc(s.quadrature)}, {s.points_per_interface} points per interface"],
        ["load steps", str(s.load_steps)],
        ["tolerance", num(s.tolerance, ".1e")],
    ]
    out = [html_table(["quantity", "value"], summary, left=1, cls="summary")]
    used = np.bincount(system.interfaces.joint, minlength=len(model.joints))
    rows = [
        [
            j.name,
            "yes" if model.ground == k else "",
            num(j.normal_stiffness, ".4g"),
            num(j.shear_stiffness, ".4g"),
            num(j.friction_angle, ".4g"),
            num(j.cohesion, ".4g"),
            num(j.tensile_strength, ".4g"),
            num(j.residual_friction_angle, ".4g"),
            num(j.residual_cohesion, ".4g"),
            int(used[k]),
        ]
        for k, j in enumerate(model.joints)
    ]
    out.append("<h3>Joints</h3>")
    u = parse_units(units)
    stiff = ""
    if u.known:  # kPa/m; t/m^3 rather than t/m^2/m
        stiff = f" ({u.force}/{u.length}^3)" if "/" in u.stress else f" ({u.stress}/{u.length})"
    stress = u.suffix("stress")
    out.append(
        html_table(
            [
                "joint",
                "ground",
                "kn" + stiff,
                "ks" + stiff,
                "φ (°)",
                "c" + stress,
                "tensile" + stress,
                "φ res. (°)",
                "c res." + stress,
                "interfaces",
            ],
            rows,
            left=2,
            cls="joints",
        )
    )
    ld = model.loads
    rows = [
        ["self-weight", "on" if ld.gravity else "off"],
        ["seismic kh / kv", f"{num(ld.seismic_h)} / {num(ld.seismic_v)}"],
    ]
    for k, p in enumerate(ld.points):
        kind = "support" if p.support else "point load"
        rows.append(
            [f"{kind} {p.name or k}", f"({num(p.fx)}, {num(p.fy)}) at ({num(p.x)}, {num(p.y)})"]
        )
    for k, line in enumerate(ld.lines):
        rows.append(
            [
                f"line load {line.name or k}",
                f"({num(line.qx)}, {num(line.qy)})"
                + (
                    ""
                    if line.q_end is None
                    else f" to ({num(line.q_end[0])}, {num(line.q_end[1])}) (linear)"
                )
                + " per length from "
                f"({num(line.start[0])}, {num(line.start[1])}) to "
                f"({num(line.end[0])}, {num(line.end[1])})",
            ]
        )
    if ld.water_table:
        rows.append(
            [
                "water table",
                " - ".join(f"({num(x)}, {num(y)})" for x, y in ld.water_table)
                + f", water unit weight {num(ld.water_unit_weight)}"
                + u.suffix("unit_weight", " {}"),
            ]
        )
    if ld.pore_pressure_ratio:
        rows.append(["pore pressure ratio r_u", num(ld.pore_pressure_ratio)])
    out.append("<h3>Loads</h3>")
    out.append(html_table(["load", "value"], rows, left=2, cls="loads"))
    return "\n".join(out)
