"""The size of a generated slope, estimated from its input before it is built.

A joint spacing of 1e-4 m, a slope 1e6 m high, a face angle of 0.001 degrees
or a trace length of 1e-5 m all describe millions of blocks or joint pieces:
building them exhausts the memory long before any analysis.  The estimate
here costs nothing (the section's area and widths, the sets' spacings and
angles), so :func:`~rockdem.geometry.generate_slope` refuses such input at
once, with the estimate in the message.

Estimate
--------
For joint sets ``i`` with spacing ``s_i`` and dip ``a_i`` across a section
of area ``A``, the faces of the arrangement (the blocks) number about::

    1 + sum_i lines_i + sum_{i<j} A |sin(a_i - a_j)| / (s_i s_j)

(every line adds a face, every crossing one more), with ``lines_i`` the width
of the section normal to set ``i`` over ``s_i``.  Scatter of the dip
(``dip_sd``) makes lines of one set cross too.  Interfaces number about twice
the blocks, plus one for every trace end of a non-persistent set (``2 A /
(s_i (trace_length + gap))``); springs are the interfaces times the spring
points per interface.  The estimate is good to a few tens of percent for
regular sets, which is all a limit needs.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely

from ..errors import InputError
from .joint_sets import JointSet

__all__ = ["MAX_BLOCKS", "SizeEstimate", "check_size", "estimate_size"]

#: Default largest model, in blocks (raise it with ``rockdem --max-blocks N``).
MAX_BLOCKS = 100_000
#: Interfaces allowed per block of the limit (trace ends split interfaces).
INTERFACES_PER_BLOCK = 4
#: Memory of a model, measured on generated slopes (geometry, springs, one
#: factorisation): a base and a share per block (rough: for the message only).
BASE_BYTES = 150e6
BYTES_PER_BLOCK = 25e3


@dataclass(frozen=True)
class SizeEstimate:
    """Estimated size of a generated slope.

    Attributes
    ----------
    blocks, interfaces, springs : float
        Estimated counts.
    memory : float
        Estimated memory in bytes (rough).
    main_set : str or None
        The joint set that contributes most (None without sets).
    by_trace_ends : bool
        True if the interfaces are driven by the trace ends of ``main_set``
        (a short trace length) more than by its spacing.
    """

    blocks: float
    interfaces: float
    springs: float
    memory: float
    main_set: str | None = None
    by_trace_ends: bool = False

    def describe(self) -> str:
        """``about 4.7 million blocks, 9.6 million interfaces (about 120 GB of memory)``."""
        return (
            f"about {_count(self.blocks)} blocks, {_count(self.interfaces)} interfaces "
            f"({_bytes(self.memory)} of memory)"
        )


def memory_for(blocks: float) -> float:
    """Rough memory in bytes of a model of ``blocks`` blocks."""
    return BASE_BYTES + BYTES_PER_BLOCK * blocks


def estimate_size(
    section: shapely.Polygon, joint_sets: Sequence[JointSet], points_per_interface: int = 3
) -> SizeEstimate:
    """Estimate the blocks, interfaces and springs of ``section`` cut by ``joint_sets``."""
    area = float(section.area)
    xy = np.asarray(section.exterior.coords, dtype=float)
    xy = xy - xy.mean(axis=0)  # widths relative to the section, not to the origin
    per_set: dict[str, float] = {}
    ends_per_set: dict[str, float] = {}
    faces = 1.0
    for s in joint_sets:
        n = np.asarray(s.normal)
        proj = xy @ n
        width = float(proj.max() - proj.min())
        lines = width / s.spacing + 1.0
        contrib = lines
        if s.dip_sd > 0:  # lines of one set cross one another
            spread = min(1.0, math.radians(s.dip_sd) * 1.2)
            contrib += 0.5 * area * spread / s.spacing**2
        per_set[s.name] = contrib
        faces += contrib
        if not s.persistent:
            period = float(s.trace_length) + s.gap
            ends_per_set[s.name] = 2.0 * area / (s.spacing * period)
    sets = list(joint_sets)
    for i, a in enumerate(sets):
        for b in sets[i + 1 :]:
            crossings = area * abs(math.sin(math.radians(a.dip - b.dip))) / (a.spacing * b.spacing)
            faces += crossings
            per_set[a.name] += 0.5 * crossings
            per_set[b.name] += 0.5 * crossings
    ends = sum(ends_per_set.values())
    interfaces = 2.0 * faces + ends
    main = max(per_set, key=per_set.__getitem__) if per_set else None
    by_ends = False
    if ends_per_set:
        top = max(ends_per_set, key=ends_per_set.__getitem__)
        if ends_per_set[top] > 2.0 * faces:
            main, by_ends = top, True
    return SizeEstimate(
        blocks=faces,
        interfaces=interfaces,
        springs=interfaces * points_per_interface,
        memory=memory_for(max(faces, 0.5 * interfaces)),
        main_set=main,
        by_trace_ends=by_ends,
    )


def check_size(estimate: SizeEstimate, max_blocks: int | None, section: shapely.Polygon) -> None:
    """Refuse a slope whose estimate exceeds ``max_blocks`` (None: no limit).

    Raises
    ------
    InputError
        Naming the joint set that contributes most, the estimate, the section
        and the limit, and how to raise it.
    """
    if max_blocks is None:
        return
    too_many = estimate.blocks > max_blocks
    too_many |= estimate.interfaces > INTERFACES_PER_BLOCK * max_blocks
    memory = physical_memory()
    beyond_memory = memory is not None and estimate.memory > memory
    if not (too_many or beyond_memory):
        return
    x0, y0, x1, y1 = section.bounds
    if beyond_memory and not too_many:  # found by fuzzing: a limit of 1e12 blocks ran out of memory
        raise InputError(
            "generate_slope",
            f"would cut the section ({x1 - x0:.6g} x {y1 - y0:.6g}) into {estimate.describe()}, "
            f"more than this machine's {_bytes(memory).removeprefix('about ')} of memory",
            "check the spacings, the profile and the depth",
        )
    where = "generate_slope" if estimate.main_set is None else f"joint set {estimate.main_set!r}"
    cause = "trace_length" if estimate.by_trace_ends else "spacing"
    if estimate.by_trace_ends:
        where += " trace_length"
    raise InputError(
        where,
        f"would cut the section ({x1 - x0:.6g} x {y1 - y0:.6g}) into {estimate.describe()}, "
        f"more than the limit of {max_blocks:,} blocks",
        f"check the {cause}, the profile and the depth, or raise the limit "
        "(`rockdem --max-blocks N ...`; max_blocks= in Python)",
    )


def physical_memory() -> float | None:
    """Bytes of physical memory, where the system says (None elsewhere)."""
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):  # not POSIX
        return None


def _count(n: float) -> str:
    if n >= 1e9:
        return f"{n:.3g}"
    if n >= 1e6:
        return f"{n / 1e6:.1f} million"
    return f"{round(n):,}"


def _bytes(n: float) -> str:
    if n >= 1e12:
        return f"about {n / 1e12:.3g} TB"
    if n >= 1e9:
        return f"about {n / 1e9:.1f} GB"
    return f"about {n / 1e6:.0f} MB"
