"""Stabilisation design: block removal, berms, support forces, staged excavation.

>>> from rockdem.stabilisation import stabilise, support_force, compare_measures
... # doctest: +SKIP
"""

from .measures import Measure, MeasureComparison, SupportSearch, compare_measures, support_force
from .plan import DesignTrial, Study, save_pictures, study, trial_picture
from .removal import RemovalTrial, Stabilisation, meets, rate, stabilise
from .stages import Excavation, Stage, StageResult, carry_state, excavate_in_stages

__all__ = [
    "DesignTrial",
    "Excavation",
    "Measure",
    "MeasureComparison",
    "RemovalTrial",
    "Stabilisation",
    "Stage",
    "StageResult",
    "Study",
    "SupportSearch",
    "carry_state",
    "compare_measures",
    "excavate_in_stages",
    "meets",
    "rate",
    "save_pictures",
    "stabilise",
    "study",
    "support_force",
    "trial_picture",
]
