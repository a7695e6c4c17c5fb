"""Small explicit-polygon models for the picture and report tests (no geometry generator)."""

from __future__ import annotations

import numpy as np

import rockdem as rd


def wedge(phi_active=35.0, phi_vertical=30.0, phi_passive=35.0, *, loads=False, bridge=False):
    """Two-block wedge on a 37 deg (active) and a 27 deg (passive) plane, slope facing +x.

    With ``bridge`` the passive block is split by a rock bridge; with
    ``loads`` a line load sits on the crest and an anchor holds the face.
    """
    a1, a2 = np.radians(27.0), np.radians(37.0)
    p0 = np.array([0.0, 0.0])
    p1 = p0 + 4.0 * np.array([-np.cos(a1), np.sin(a1)])
    p2 = p1 + 6.0 * np.array([-np.cos(a2), np.sin(a2)])
    h = 6.5
    crest = np.array([-h / np.tan(np.radians(70.0)), h])
    top = np.array([p1[0], h])
    back = np.array([p2[0], h])
    ground = [(3.0, -3.0), (3.0, 0.0), p0, p1, p2, back, (-12.0, h), (-12.0, -3.0)]
    active = [p1, top, back, p2]
    lines = [(p1, p2), (p0, p1), (p2, back)]
    names = ["active plane", "passive plane", "crack"]
    if bridge:
        # split the passive block by a horizontal rock bridge at y = 3
        y = 3.0
        x_face = crest[0] * y / h
        s = (y - p0[1]) / (p1[1] - p0[1])
        x_base = p0[0] + s * (p1[0] - p0[0])
        if y < p1[1]:
            raise ValueError("bridge below the passive plane")
        lower = [p0, (x_face, y), (p1[0], y), p1]
        upper = [(x_face, y), crest, top, (p1[0], y)]
        polys = [ground, lower, upper, active]
        lines.append(((p1[0], y), (x_face, y)))
        names.append("bridge")
        del x_base
    else:
        polys = [ground, [p0, crest, top, p1], active]
    blocks = rd.Blocks.from_polygons(
        polys, fixed=[True] + [False] * (len(polys) - 1), unit_weight=25.0
    )
    joints = [
        rd.Joint(1e6, phi_vertical, name="vertical"),
        rd.Joint(1e6, phi_active, name="active plane"),
        rd.Joint(1e6, phi_passive, name="passive plane"),
        rd.Joint(1e6, 30.0, name="crack"),
    ]
    if bridge:
        joints.append(rd.Joint(1e6, 45.0, cohesion=50.0, tensile_strength=20.0, name="bridge"))
    load = rd.Loads()
    if loads:
        anchor = rd.PointLoad.anchor(crest[0] * 0.4, 0.4 * h, 60.0, 180.0 - 15.0, name="anchor")
        surcharge = rd.LineLoad((back[0] + 0.5, h), (top[0] - 0.5, h), 0.0, -20.0, name="q")
        load = rd.Loads(points=(anchor,), lines=(surcharge,))
    return rd.Model(
        blocks, tuple(joints), joint_lines=lines, line_joint=names, loads=load, name="wedge"
    )
