"""What Sarma's rating of the DEM's mechanism (:mod:`.sarma`) leaves out
or treats otherwise than the DEM, said as notes beside its factor."""

from __future__ import annotations

import numpy as np


def ids_text(values, limit=12) -> str:
    """At most ``limit`` ids, then how many more."""
    text = ", ".join(str(v) for v in values[:limit])
    return text + (f", ... ({len(values) - limit} more)" if len(values) > limit else "")


def differences(result, failed, group, joints) -> list[str]:
    """Where the limit equilibrium (a :class:`~.sarma.SarmaResult`) and the
    DEM's failed analysis differ, in words."""
    out = []
    faces = failed.system.interfaces
    if failed.system.bolts is not None:
        out.append(
            "the bolts act on the LE's bodies with the forces the DEM found in them at its "
            "last equilibrium below the limit (a bolt not yet at its capacity there may carry "
            "more as the blocks move)"
        )
    current = failed.interfaces.current_name if failed.interfaces.current is not None else None
    if current is not None:
        holding = [
            k
            for f in result.faces
            if f.state == "sliding"
            for k in f.interfaces
            if current[k] in ("elastic", "closed-failed-earlier")
        ]
        if holding:
            out.append(
                f"{len(holding)} interface(s) the LE assumes at limit the DEM found holding "
                f"below their strength at its limit: {ids_text(holding)}"
            )
        inside = [
            int(k)
            for k in np.flatnonzero(
                (group[faces.block_a] >= 0) & (group[faces.block_a] == group[faces.block_b])
            )
            if current[k] in ("sliding", "open")
        ]
        if inside:
            out.append(
                f"{len(inside)} interface(s) inside a rigid body of the LE slide or open in "
                f"the DEM (the LE treats them as rigid): {ids_text(inside)}"
            )
    opened = failed.interfaces.open_fraction
    if opened is not None:
        part = [
            (k, opened[k])
            for f in result.faces
            if f.state == "sliding"
            for k in f.interfaces
            if opened[k] > 0.01
        ]
        if part:
            where = ", ".join(f"{k} ({100 * share:.0f}%)" for k, share in part[:12])
            out.append(
                "the LE assumes the whole of each sliding face in contact; in the DEM part of "
                f"interface(s) {where} is open and carries no cohesion or friction there "
                "(opened on the way to the limit: the blocks' rotation lifted it, and an opened "
                "point keeps no bond), so its factor can be lower"
            )
    brittle = sorted(
        {
            joints[faces.joint[k]].name
            for f in result.faces
            if f.state == "sliding"
            for k in f.interfaces
            if joints[faces.joint[k]].residual_cohesion < joints[faces.joint[k]].cohesion
            or joints[faces.joint[k]].residual_friction_angle
            < joints[faces.joint[k]].friction_angle
        }
    )
    if brittle:
        out.append(
            "the LE uses peak strengths; the DEM loses strength where these brittle joints "
            f"yield ({', '.join(brittle)}), so its factor can be lower"
        )
    if any(joints[faces.joint[k]].tensile_strength > 0 for f in result.faces for k in f.interfaces):
        out.append("the LE ignores tensile strength, the DEM does not")
    out.append(
        "the LE satisfies force equilibrium of each body only (Sarma's factor); the DEM "
        "also moment equilibrium and compatible deformation"
    )
    return out
