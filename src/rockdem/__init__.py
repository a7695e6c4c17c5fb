"""rockdem: stability of jointed rock slopes by the discrete element method.

Rigid blocks joined by elasto-plastic Winkler springs (normal springs with a
tension cut-off, Mohr-Coulomb shear springs), gravity in load steps,
progressive failure, and the factor of safety by strength reduction.

>>> import rockdem as rd
>>> ground = [(-5, -1), (5, -1), (5, 0), (-5, 0)]
>>> block = [(0, 0), (1, 0), (1, 1), (0, 1)]
>>> model = rd.Model(rd.Blocks.from_polygons([ground, block], fixed=[True, False]),
...                  rd.Joint(normal_stiffness=1e6, friction_angle=30))
>>> rd.analyse(model).stable
True
"""

from .analysis import analyse, factor_of_safety
from .blocks import Blocks
from .errors import InputError, RockdemError
from .joints import Joint
from .model import LineLoad, Loads, Model, PointLoad, Settings
from .results import Analysis, FactorOfSafety
from .solver import build_system

__version__ = "0.1.0"

__all__ = [
    "Analysis",
    "Blocks",
    "FactorOfSafety",
    "InputError",
    "Joint",
    "LineLoad",
    "Loads",
    "Model",
    "PointLoad",
    "RockdemError",
    "Settings",
    "__version__",
    "analyse",
    "build_system",
    "factor_of_safety",
]
