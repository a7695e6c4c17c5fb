"""Pore-pressure ratio r_u: u = r_u gamma d, d the depth of rock above the point.

Closed form (limit equilibrium of a block on a plane with a base uplift U,
Hoek & Bray 1981 ch. 7): FS = (W cos psi - U) tan phi / (W sin psi).  For a
rectangular block (length L along the plane, thickness H) the vertical
depth of rock above a base point s from the block's upslope end is
min(s / sin psi, H / cos psi), so

    U = r_u gamma [ (H tan psi)^2 / (2 sin psi) + (L - H tan psi) H / cos psi ].
"""

from __future__ import annotations

import numpy as np
import pytest

import rockdem as rd
from rockdem import verification as V
from rockdem.errors import InputError
from rockdem.loads import joint_water, pore_pressure

PSI, PHI, L, H, GAMMA = 25.0, 40.0, 4.0, 1.0, 25.0


def block(ru: float) -> rd.Model:
    joint = rd.Joint(normal_stiffness=1e6, friction_angle=PHI)
    loads = rd.Loads(pore_pressure_ratio=ru)
    return V.block_on_plane(PSI, joint, width=L, height=H, unit_weight=GAMMA, loads=loads)


def closed_form(ru: float) -> float:
    s, p = np.radians(PSI), np.radians(PHI)
    W = GAMMA * L * H
    U = ru * GAMMA * ((H * np.tan(s)) ** 2 / (2 * np.sin(s)) + (L - H * np.tan(s)) * H / np.cos(s))
    return (W * np.cos(s) - U) * np.tan(p) / (W * np.sin(s))


@pytest.mark.parametrize("ru", [0.0, 0.2, 0.4])
def test_block_on_a_plane_with_a_pore_pressure_ratio(ru):
    fos = rd.factor_of_safety(block(ru), width=0.002)
    assert fos.value == pytest.approx(closed_form(ru), rel=0.005)


def test_pressure_is_ru_times_the_overburden():
    model = block(0.3)
    water = joint_water(model.blocks, model.loads)
    # a point mid-base: the block's full thickness above it, vertically
    R = V._rot(-PSI)
    mid = R @ np.array([L / 2, 0.0])
    u = pore_pressure(water, mid[None, :])[0]
    assert u == pytest.approx(0.3 * GAMMA * H / np.cos(np.radians(PSI)), rel=1e-9)


@pytest.mark.parametrize(
    ("loads", "words"),
    [
        (dict(pore_pressure_ratio=1.2), "out of range"),
        (dict(pore_pressure_ratio=0.2, water_table=[(0, 0), (1, 0)], water_unit_weight=9.81),
         "either a water table or"),
    ],
)  # fmt: skip
def test_bad_ratio_is_refused(loads, words):
    with pytest.raises(InputError, match=words):
        rd.Loads(**loads)


def test_ratio_in_a_model_file():
    from rockdem.config import parse_model

    text = """
units: kN, m, kPa
joints:
  rock: {normal_stiffness: 1.0e+6, friction_angle: 40}
blocks:
  - {vertices: [[-5, -1], [5, -1], [5, 0], [-5, 0]], fixed: true}
  - {vertices: [[0, 0], [1, 0], [1, 2], [0, 2]], unit_weight: 25}
loads: {pore_pressure_ratio: 0.25}
"""
    model, _ = parse_model(text)
    assert model.loads.pore_pressure_ratio == 0.25
    system = rd.build_system(model)
    # the uplift on the base: r_u gamma h over the width, straight up
    assert system.f_block[1, 1] == pytest.approx(-25 * 2 + 0.25 * 25 * 2 * 1, rel=1e-9)
