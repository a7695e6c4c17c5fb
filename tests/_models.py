"""Small model files shared by the tests (YAML text)."""

#: two blocks stacked on fixed ground
BOX = """units: kN, m, kPa
materials: {rock: {unit_weight: 25}}
joints:
  bedding: {normal_stiffness: 1.0e+6, friction_angle: 30}
blocks:
  - {fixed: true, vertices: [[-5, -1], [5, -1], [5, 0], [-5, 0]]}
  - {material: rock, vertices: [[0, 0], [2, 0], [2, 1], [0, 1]]}
  - {material: rock, vertices: [[0, 1], [2, 1], [2, 2], [0, 2]]}
"""

#: a generated 6 m slope: horizontal bedding and vertical cross joints
SLOPE = """units: kN, m, kPa
materials: {rock: {unit_weight: 25}}
joints:
  bedding: {normal_stiffness: 1.0e+6, friction_angle: 35}
  cross: {normal_stiffness: 1.0e+6, friction_angle: 35}
  base: {normal_stiffness: 1.0e+6, friction_angle: 45}
ground_joint: base
slope:
  profile: {height: 6, face_angle: 60}
  depth: 3
  joint_sets:
    bedding: {dip: 0, spacing: 2, origin: [0, 1]}
    cross: {dip: 90, spacing: 3, origin: [0.5, 0]}
"""

#: a free block overhanging its base (a support placed on it pulls out of the rock)
OVERHANG = """units: kN, m, kPa
materials: {r: {unit_weight: 25}}
joints:
  j: {normal_stiffness: 1.0e+6, friction_angle: 30}
blocks:
  - {fixed: true, vertices: [[-5, -1], [9, -1], [9, 0], [-5, 0]]}
  - {material: r, vertices: [[0, 0], [1, 0], [1, 1], [5, 1], [5, 2], [0, 2]]}
"""
