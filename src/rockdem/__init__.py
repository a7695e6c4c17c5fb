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

from importlib import import_module

__version__ = "0.1.0"

#: public names and the module that defines each: imported on first use, so
#: that ``rockdem --version`` and light scripts do not load SciPy and PARDISO
_PUBLIC = {
    "analyse": ".analysis",
    "factor_of_safety": ".strength_reduction",
    "Blocks": ".blocks",
    "Bolt": ".bolts",
    "InputError": ".errors",
    "ModelWarning": ".errors",
    "RockdemError": ".errors",
    "Joint": ".joints",
    "LineLoad": ".model",
    "Loads": ".model",
    "Model": ".model",
    "PointLoad": ".model",
    "Settings": ".model",
    "Analysis": ".results",
    "FactorOfSafety": ".results",
    "build_system": ".solver",
    "study": ".studies.run",
}


#: public subpackages, also imported on first use (``rd.limit_equilibrium.sarma``)
_MODULES = ("limit_equilibrium",)


def __getattr__(name: str):
    if name in _MODULES:
        return import_module(f".{name}", __name__)
    if name in _PUBLIC:
        value = getattr(import_module(_PUBLIC[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'rockdem' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC) | set(_MODULES))


__all__ = [
    "Analysis",
    "Blocks",
    "Bolt",
    "FactorOfSafety",
    "InputError",
    "Joint",
    "LineLoad",
    "Loads",
    "Model",
    "ModelWarning",
    "PointLoad",
    "RockdemError",
    "Settings",
    "__version__",
    "analyse",
    "build_system",
    "factor_of_safety",
    "study",
]
