"""Joint sets in the section plane: parallel traces, persistent or not.

Dip convention
--------------
``dip`` is the apparent dip in the section plane, in degrees in ``[0, 180)``,
measured from the +x axis *downward*: a joint trace has the direction
``(cos dip, -sin dip)``.  The slope faces +x, so

* ``dip < 90`` dips **out of the face** (down toward +x), e.g. bedding
  dipping 30 degrees out of the face is ``dip = 30``;
* ``dip = 90`` is vertical;
* ``dip > 90`` dips **into the slope** at ``180 - dip``, e.g. the set
  perpendicular to that bedding is ``120`` and steep toppling joints dipping
  80 degrees into the slope are ``100``.

Spacing is measured normal to the traces.  One joint of the set passes
through ``origin``; the others follow at ``spacing`` on both sides.

Persistence
-----------
A non-persistent set (``trace_length`` and ``gap > 0``) has, along each
joint line, traces of length ``trace_length`` separated by intact **rock
bridges** of length ``gap`` (persistence ``trace_length / (trace_length +
gap)``).  The pattern along each line starts at the foot of ``origin`` on
that line and is shifted by ``stagger`` x period from one line to the next
(0: bridges aligned across the set, 0.5: staggered).  The whole line still
cuts the rock into blocks; the bridge stretches are given intact-rock
properties so that they can break progressively.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, check_number
from ..joints import Joint

__all__ = ["JointSet"]

RESERVED_NAMES = ("bridge", "ground")
#: largest coefficient of variation of a joint set's spacing (spacing_sd / spacing)
MAX_SPACING_COV = 2.0
#: a set with random spacing draws its joints one by one from its origin:
#: at most this many spacings away from it (a model at real-world
#: coordinates, 4e6 m from an origin at (0, 0) with 2.5 m spacing, takes
#: 1.6e6; 1e7 takes about 1 s and 64 MB)
MAX_WALK = 1e7


@dataclass(frozen=True, eq=False)
class JointSet:
    """A set of parallel joints seen in the section plane.

    Parameters
    ----------
    name : str
        Name of the set, reported with results (unique in a model; not
        ``"bridge"`` or ``"ground"``).
    dip : float
        Apparent dip in the section, degrees in [0, 180) (see the module doc).
    spacing : float
        Mean normal spacing between joints (> 0).
    joint : rockdem.Joint
        Properties of the joints of this set.
    origin : (x, y)
        A point one joint of the set passes through.
    trace_length : float, optional
        Length of each trace; None for persistent joints.
    gap : float
        Length of the rock bridge between traces along a joint (>= 0).
    stagger : float
        Shift of the trace pattern from one joint to the next, as a fraction
        of the period ``trace_length + gap`` (0 to 1).
    spacing_sd : float
        Standard deviation of the spacing (lognormal spacing of the given
        mean, always positive); 0 for regular spacing.
    dip_sd : float
        Standard deviation of each joint's dip (normal, degrees).
    seed : int, optional
        Seed of this set's random variation; default: derived from the
        ``seed`` of :func:`generate_slope` and the set's position.

    Examples
    --------
    >>> from rockdem import Joint
    >>> s = JointSet("bedding", 30, 2.0, Joint(1e6, 35), trace_length=6, gap=2)
    >>> s.persistence, s.persistent
    (0.75, False)
    >>> [round(v, 6) for v in s.direction]
    [0.866025, -0.5]
    """

    name: str
    dip: float
    spacing: float
    joint: Joint
    origin: tuple[float, float] = (0.0, 0.0)
    trace_length: float | None = None
    gap: float = 0.0
    stagger: float = 0.0
    spacing_sd: float = 0.0
    dip_sd: float = 0.0
    seed: int | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise InputError("joint set", f"name {self.name!r} is empty", "give the set a name")
        where = f"joint set {self.name!r}"
        if self.name in RESERVED_NAMES:
            raise InputError(where, "uses a reserved name", f"avoid {RESERVED_NAMES}")
        if not isinstance(self.joint, Joint):
            raise InputError(f"{where} joint", f"{self.joint!r} is not a rockdem.Joint",
                             "give Joint(normal_stiffness=..., friction_angle=...)")
        dip = check_number(where, "dip", self.dip)
        if not 0.0 <= dip < 180.0:
            raise InputError(f"{where} dip", f"{dip:g} is out of range",
                             "give the apparent dip in [0, 180) degrees (> 90 dips into the slope)")
        spacing = check_number(where, "spacing", self.spacing)
        if spacing <= 0:
            raise InputError(f"{where} spacing", f"{spacing:g} is not positive",
                             "give a spacing > 0 (the normal distance between joints)")
        try:
            ox, oy = (float(v) for v in self.origin)
        except (TypeError, ValueError) as exc:
            raise InputError(f"{where} origin", f"{self.origin!r} is not a point",
                             "give (x, y)") from exc
        if not (math.isfinite(ox) and math.isfinite(oy)):
            raise InputError(f"{where} origin", "is not finite", "give finite (x, y)")
        gap = check_number(where, "gap", self.gap)
        if gap < 0:
            raise InputError(f"{where} gap", f"{gap:g} is negative", "give a gap >= 0")
        trace = self.trace_length
        if trace is not None:
            trace = check_number(where, "trace_length", trace)
            if trace <= 0:
                raise InputError(f"{where} trace_length", f"{trace:g} is not positive",
                                 "give a trace length > 0, or None for persistent joints")
        elif gap > 0:
            raise InputError(f"{where} gap", "is given without a trace_length",
                             "give trace_length (or gap=0 for persistent joints)")
        stagger = check_number(where, "stagger", self.stagger)
        if not 0.0 <= stagger <= 1.0:
            raise InputError(f"{where} stagger", f"{stagger:g} is out of range", "give 0 to 1")
        for key in ("spacing_sd", "dip_sd"):
            if check_number(where, key, getattr(self, key)) < 0:
                raise InputError(f"{where} {key}", "is negative", "give a value >= 0")
        if self.spacing_sd > MAX_SPACING_COV * spacing:
            raise InputError(
                f"{where} spacing_sd",
                f"{self.spacing_sd:g} is more than {MAX_SPACING_COV:g} x the spacing "
                f"{spacing:g}: the lognormal spacings would cut slivers without end",
                f"give at most {MAX_SPACING_COV * spacing:g} (field spacings vary by about "
                "0.5 to 1.5 x their mean)",
            )
        object.__setattr__(self, "dip", dip)
        object.__setattr__(self, "spacing", spacing)
        # coordinates near underflow break GEOS's robust predicates: snap them to 0
        ox, oy = (0.0 if abs(v) < 1e-100 else v for v in (ox, oy))
        object.__setattr__(self, "origin", (ox, oy))
        object.__setattr__(self, "gap", gap)
        object.__setattr__(self, "trace_length", trace)
        object.__setattr__(self, "stagger", stagger)
        object.__setattr__(self, "spacing_sd", float(self.spacing_sd))
        object.__setattr__(self, "dip_sd", float(self.dip_sd))

    # -------------------------------------------------------------- derived
    @property
    def persistent(self) -> bool:
        """True if the joints run through (no rock bridges)."""
        return self.trace_length is None or self.gap == 0

    @property
    def persistence(self) -> float:
        """Share of each joint line that is open joint (1 for persistent sets)."""
        if self.persistent:
            return 1.0
        return self.trace_length / (self.trace_length + self.gap)

    @property
    def direction(self) -> tuple[float, float]:
        """Unit vector along the traces, ``(cos dip, -sin dip)``."""
        a = math.radians(self.dip)
        return (math.cos(a), -math.sin(a))

    @property
    def normal(self) -> tuple[float, float]:
        """Unit normal of the traces, ``(sin dip, cos dip)`` (spacing is along it)."""
        a = math.radians(self.dip)
        return (math.sin(a), math.cos(a))

    # ------------------------------------------------------------- traces
    def segments(
        self, bounds: tuple[float, float, float, float], rng: np.random.Generator | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The set's lines across a box, split into traces and rock bridges.

        Parameters
        ----------
        bounds : (xmin, ymin, xmax, ymax)
            Box the lines must cover (they extend a little beyond it).
        rng : numpy Generator, optional
            Source of the random variation (needed if ``spacing_sd`` or
            ``dip_sd`` is not 0; default: ``numpy.random.default_rng(seed)``).

        Returns
        -------
        segments : ndarray, shape (k, 2, 2)
            Consecutive pieces of every line, end to end.
        is_trace : ndarray of bool, shape (k,)
            True for a joint trace, False for a rock bridge.
        line : ndarray of int, shape (k,)
            Which line of the set each piece belongs to (0 passes through origin).

        Examples
        --------
        >>> from rockdem import Joint
        >>> s = JointSet("v", 90, 1.0, Joint(1e6, 30), origin=(0.5, 0))
        >>> seg, trace, line = s.segments((0, 0, 3, 1))
        >>> sorted(set(seg[:, 0, 0].round(9).tolist())), bool(trace.all())
        ([0.5, 1.5, 2.5], True)
        """
        if rng is None:
            rng = np.random.default_rng(self.seed)
        xmin, ymin, xmax, ymax = (float(v) for v in bounds)
        o = np.array(self.origin)
        c = np.array([(xmin + xmax) / 2, (ymin + ymax) / 2])
        radius = 0.5 * math.hypot(xmax - xmin, ymax - ymin)
        margin = 0.02 * radius + 1e-9
        d0 = np.array(self.direction)
        n0 = np.array(self.normal)
        s_c = float(n0 @ (c - o))
        t_c = float(d0 @ (c - o))
        reach = radius + margin
        if self.dip_sd > 0:
            # rotated lines must still cover the box
            reach *= 1.0 + math.radians(min(3 * self.dip_sd, 60.0))
        s_lo, s_hi = s_c - reach, s_c + reach
        offsets, index = self._offsets(s_lo, s_hi, rng)
        if self.dip_sd > 0:
            dips = self.dip + rng.normal(0.0, self.dip_sd, len(offsets))
        else:
            dips = np.full(len(offsets), self.dip)
        a = np.radians(dips)
        dirs = np.column_stack([np.cos(a), -np.sin(a)])
        anchors = o + offsets[:, None] * n0 + t_c * d0  # foot of the box centre on each line
        t_lo, t_hi = t_c - reach, t_c + reach
        # positions along each line are measured from the foot of origin (t = 0)
        pieces, kinds, lines = [], [], []
        for k in range(len(offsets)):
            if self.persistent:
                ts = np.array([t_lo, t_hi])
                kind = np.array([True])
            else:
                # traces only where the line crosses the box (found by fuzzing: a
                # 5 km long, 47 m high section cut traces over the whole circle
                # around it, 57 million pieces; the traces inside are the same)
                box = (xmin - margin, ymin - margin, xmax + margin, ymax + margin)
                span = _clip(anchors[k], dirs[k], t_c, t_lo, t_hi, box)
                if span is None:
                    continue
                lo, hi = span
                period = self.trace_length + self.gap
                shift = (index[k] * self.stagger * period) % period
                k0 = math.floor((lo - shift) / period) - 1
                k1 = math.ceil((hi - shift) / period) + 1
                starts = shift + period * np.arange(k0, k1 + 1)
                ends = starts + self.trace_length
                bp = np.column_stack([starts, ends]).ravel()  # trace, gap, trace, ...
                inside = (bp > lo) & (bp < hi)
                # kind of the piece that begins at lo: trace if an odd number of breaks before
                begins_trace = (np.sum(bp <= lo) % 2) == 1
                ts = np.concatenate([[lo], bp[inside], [hi]])
                n_pieces = len(ts) - 1
                kind = (np.arange(n_pieces) % 2 == 0) == begins_trace
            pts = anchors[k] + (ts - t_c)[:, None] * dirs[k]
            pieces.append(np.stack([pts[:-1], pts[1:]], axis=1))
            kinds.append(kind)
            lines.append(np.full(len(kind), index[k]))
        if not pieces:
            return np.zeros((0, 2, 2)), np.zeros(0, dtype=bool), np.zeros(0, dtype=np.int64)
        return (np.concatenate(pieces), np.concatenate(kinds).astype(bool),
                np.concatenate(lines).astype(np.int64))

    def _offsets(self, s_lo: float, s_hi: float, rng) -> tuple[np.ndarray, np.ndarray]:
        """Normal offsets (from origin) of the lines within [s_lo, s_hi], and their indices."""
        sp = self.spacing
        if self.spacing_sd == 0:
            j0, j1 = math.ceil(s_lo / sp), math.floor(s_hi / sp)
            idx = np.arange(j0, j1 + 1)
            return idx * sp, idx
        walk = max(abs(s_lo), abs(s_hi)) / sp  # about this many joints from the origin
        if walk > MAX_WALK:
            # found by fuzzing: a 20-block slope at x = 3e8 walked 1.2e8 joints
            # from the origin, one at a time, and took 8.5 GB
            raise InputError(
                f"joint set '{self.name}' origin",
                f"lies about {walk:.3g} spacings from the section: random spacings are "
                "drawn joint by joint from the origin",
                f"give the set an origin near the section (within {MAX_WALK:.0e} spacings)",
            )
        sigma2 = math.log1p((self.spacing_sd / sp) ** 2)
        mu = math.log(sp) - sigma2 / 2
        out = []
        for sign, limit in ((1.0, s_hi), (-1.0, s_lo)):
            pos, j, vals = 0.0, 0, []
            while True:
                steps = rng.lognormal(mu, math.sqrt(sigma2), 64)
                for st in steps:
                    pos += sign * st
                    j += 1
                    if (sign > 0 and pos > limit) or (sign < 0 and pos < limit):
                        break
                    if s_lo <= pos <= s_hi:  # (only the section's joints are kept)
                        vals.append((pos, int(sign) * j))
                else:
                    continue
                break
            out.append(vals)
        ups, downs = out
        allv = [*reversed(downs), (0.0, 0), *ups]
        allv = [v for v in allv if s_lo <= v[0] <= s_hi]
        if not allv:
            return np.zeros(0), np.zeros(0, dtype=np.int64)
        s = np.array([v[0] for v in allv])
        i = np.array([v[1] for v in allv], dtype=np.int64)
        return s, i


def _clip(anchor, direction, t_c, t_lo, t_hi, box):
    """The part ``[lo, hi]`` of ``[t_lo, t_hi]`` where the line ``anchor +
    (t - t_c) direction`` lies in ``box`` (xmin, ymin, xmax, ymax); None if
    it misses the box."""
    lo, hi = t_lo, t_hi
    for axis in (0, 1):
        a, d = float(anchor[axis]), float(direction[axis])
        b0, b1 = box[axis], box[axis + 2]
        if abs(d) < 1e-15:
            if not b0 <= a <= b1:
                return None
            continue
        u0, u1 = sorted(((b0 - a) / d + t_c, (b1 - a) / d + t_c))
        lo, hi = max(lo, u0), min(hi, u1)
    return (lo, hi) if lo < hi else None
