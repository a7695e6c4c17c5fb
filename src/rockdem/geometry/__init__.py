"""Geometry generator: cut a slope section into blocks with joint sets.

Conventions
-----------
* x to the right, y up; the slope **faces +x** (crest on the left, toe on
  the right); profiles are listed left to right.
* Joint ``dip`` is the apparent dip in the section, degrees in [0, 180):
  trace direction ``(cos dip, -sin dip)``; < 90 dips out of the face, > 90
  dips into the slope at ``180 - dip`` (bedding 30 out of the face = 30,
  its perpendicular = 120, steep toppling joints = 100).
* The model is the section below the profile down to
  ``min(profile y) - depth``, with vertical sides at the profile's ends,
  plus fixed strips (base, back, front) outside it.

Example
-------
>>> from rockdem import Joint
>>> from rockdem.geometry import JointSet, Profile, generate_slope
>>> j = Joint(normal_stiffness=1e6, friction_angle=35)
>>> geom = generate_slope(Profile.simple(10, 60), [JointSet("bedding", 20, 2.0, j)], depth=5)
>>> geom.blocks.fixed.sum() > 0 and len(geom.joints) == 1
True
"""

from .cut import generate_slope, section_polygon
from .edit import add_blocks, cut_to_profile, excavate, remove_blocks
from .joint_sets import JointSet
from .profile import Profile
from .size import MAX_BLOCKS, SizeEstimate, estimate_size
from .slope import Sliver, SlopeGeometry

__all__ = [
    "MAX_BLOCKS",
    "JointSet",
    "Profile",
    "SizeEstimate",
    "Sliver",
    "SlopeGeometry",
    "add_blocks",
    "cut_to_profile",
    "estimate_size",
    "excavate",
    "generate_slope",
    "remove_blocks",
    "section_polygon",
]
