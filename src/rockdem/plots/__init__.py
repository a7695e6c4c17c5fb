"""Pictures of models and results (matplotlib, no pyplot global state).

Every drawing function takes a model or a result and an optional ``ax`` and
returns the Axes (or a Figure for multi-panel pictures); save with
``ax.figure.savefig("file.svg")`` or use :func:`plot_figure`.

Colours are the Okabe-Ito colour-blind-safe palette; shear failure is red
(vermillion), tension failure blue, elastic interfaces grey.

>>> from rockdem.plots import plot_failure  # doctest: +SKIP
>>> plot_failure(rockdem.analyse(model)).figure.savefig("failure.png")  # doctest: +SKIP
"""

from ._common import JOINT_COLORS, OKABE_ITO, STATE_COLORS, STATE_LABELS, oriented_mechanism
from .figure import WHAT, make_figure, plot_figure
from .fos import max_displacement, plot_fos, trial_displacements
from .model import plot_model
from .motion import auto_magnification, plot_deformed
from .state import Frame, animate_progressive, frames, plot_failure, plot_progressive
from .stress import JointPath, joint_path, plot_joint_stress, select_interfaces

__all__ = [
    "JOINT_COLORS",
    "OKABE_ITO",
    "STATE_COLORS",
    "STATE_LABELS",
    "WHAT",
    "Frame",
    "JointPath",
    "animate_progressive",
    "auto_magnification",
    "frames",
    "joint_path",
    "make_figure",
    "max_displacement",
    "oriented_mechanism",
    "plot_deformed",
    "plot_failure",
    "plot_figure",
    "plot_fos",
    "plot_joint_stress",
    "plot_model",
    "plot_progressive",
    "select_interfaces",
    "trial_displacements",
]
