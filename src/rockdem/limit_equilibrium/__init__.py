"""Limit equilibrium beside the DEM (issue 14).

Closed forms where the geometry matches a classic case
(:mod:`~rockdem.limit_equilibrium.closed_forms`): Hoek & Bray's plane
failure with a tension crack and water, Goodman & Bray's toppling on a
stepped base, the seed paper's two-block wedge (Eq. 7).  For any model,
:func:`sarma` rates the DEM's own failure mechanism by Sarma's method and
sets its factor beside the DEM's (:mod:`~rockdem.limit_equilibrium.sarma`).
"""

from .closed_forms import (
    PlaneFailure,
    Toppling,
    TwoBlockWedge,
    plane_failure,
    plane_failure_fos,
    stepped_heights,
    toppling,
    toppling_fos,
    two_block_wedge,
)
from .sarma import SarmaFace, SarmaResult, sarma

__all__ = [
    "PlaneFailure",
    "SarmaFace",
    "SarmaResult",
    "Toppling",
    "TwoBlockWedge",
    "plane_failure",
    "plane_failure_fos",
    "sarma",
    "stepped_heights",
    "toppling",
    "toppling_fos",
    "two_block_wedge",
]
