"""Sizing a pattern of passive bolts to reach a target factor of safety.

The engineer chooses the bolt (capacity, stiffness, kind) and its
inclination; rockdem places rows of them on the face of the critical
mechanism, long enough to pass through the moving rock and anchor beyond
it, and finds by bisection the widest spacing along the slope (the fewest
bolts) with which the staged analysis holds at the target (rock strengths
divided by the target; the steel is not reduced), then rates the pattern by
a full strength-reduction search.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import shapely

from ..bolt_placement import bolts_left_in_rock
from ..bolts import Bolt
from ..errors import InputError
from ..interfaces import find_interfaces
from ..model import Model
from ..results import FactorOfSafety
from . import _progress
from .removal import mechanism_ids, rate, stable_at

__all__ = ["BoltPattern", "bolt_pattern", "face_rows"]

#: outward normals with at least this +x share count as the face (the slope faces +x)
FACE_NORMAL_X = 0.3
#: spacings tried along the slope: from this, doubled or halved
FIRST_SPACING = 2.0
SPACING_RANGE = (0.25, 4.0)
#: relative width of the final spacing bracket
RTOL = 0.05
#: rows tried on the face when none is given (more when fewer do not reach the target)
ROW_COUNTS = (4, 8, 16)


@dataclass(frozen=True, eq=False)
class BoltPattern:
    """Result of :func:`bolt_pattern`.

    Attributes
    ----------
    spacing : float or None
        Widest out-of-plane spacing of the rows that reaches the target
        (None: not reached even at the closest spacing tried).
    bolts : tuple of Bolt
        One per row, at ``spacing`` (empty when not reached).
    bracket : (float, float)
        Closest spacing found short of the target (inf if none), widest found
        enough (0 if none).
    evaluations : int
        Staged analyses made by the search.
    fos : FactorOfSafety or None
        Rating of the model with the pattern.
    model : Model or None
        The model with the pattern.
    """

    spacing: float | None
    bolts: tuple[Bolt, ...]
    bracket: tuple[float, float]
    evaluations: int
    fos: FactorOfSafety | None
    model: Model | None

    @property
    def bolts_per_metre(self) -> float | None:
        """Bolts per unit length of slope (all rows)."""
        return None if self.spacing is None else len(self.bolts) / self.spacing


#: most bolt rows a pattern puts on the face of a mechanism
MAX_ROWS = 100


def face_rows(
    model: Model, ids, *, row_spacing: float | None = None, angle: float = 195.0, n_rows: int = 4
):
    """Heads on the face of the moving blocks ``ids`` and the length each bolt
    needs to cross them: ``[(head, depth through the mass)]``.

    The face is the free surface of the moving mass whose outward normal
    looks toward +x; rows are ``row_spacing`` apart along it (default:
    ``n_rows`` rows; at least one), centred on it.
    """
    b = model.blocks
    polys = b.polygons()
    idx = b.index_of(np.atleast_1d(ids))
    mass = shapely.union_all(polys[idx])
    rock = shapely.union_all(polys)
    outline = rock.exterior
    probe = 1e-6 * b.extent
    exposed = shapely.intersection(outline, mass.boundary)
    pieces = []
    for line in shapely.get_parts(shapely.line_merge(exposed) if exposed.length else exposed):
        xy = np.asarray(line.coords)
        for p, q in itertools.pairwise(xy):
            d = q - p
            length = float(np.hypot(*d))
            if length == 0:
                continue
            normal = np.array([d[1], -d[0]]) / length
            if rock.contains(shapely.Point(0.5 * (p + q) + probe * normal)):
                normal = -normal  # the outward one
            if normal[0] >= FACE_NORMAL_X:
                pieces.append((p, q, length))
    if not pieces:
        raise InputError(
            "bolt pattern",
            "the moving blocks have no face looking toward +x to bolt",
            "bolt the slope by hand (bolts: in the model file)",
        )
    total = sum(length for *_, length in pieces)
    step = total / n_rows if row_spacing is None else float(row_spacing)
    n = max(1, int(np.floor(total / step + 1e-9)))
    if n > MAX_ROWS:  # each row is a bolt the analysis carries: keep it a pattern
        raise InputError(
            "stabilisation.bolts.row_spacing",
            f"{step:g} puts {n:,} rows on the {total:.3g} of face to bolt",
            f"give a row spacing of at least {total / MAX_ROWS:.3g} ({MAX_ROWS} rows)",
        )
    at = (np.arange(n) + 0.5) * total / n
    e = np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle))])
    reach = 2.0 * b.extent
    rows = []
    start = 0.0
    for p, q, length in pieces:
        for s in at[(at >= start) & (at < start + length)]:
            head = p + (s - start) / length * (q - p)
            ray = shapely.LineString([head, head + reach * e])
            inside = shapely.intersection(ray, mass)
            depth = float(inside.length) if not inside.is_empty else 0.0
            rows.append((tuple(float(v) for v in head), depth))
        start += length
    return rows


def bolt_pattern(
    model: Model,
    target_fos: float,
    *,
    capacity: float,
    axial_stiffness: float,
    angle: float = 195.0,
    row_spacing: float | None = None,
    length: float | None = None,
    anchorage: float | None = None,
    bond_strength: float = np.inf,
    kind: str = "bolt",
    installed: str = "before_loads",
    width: float = 0.01,
) -> BoltPattern:
    """Widest spacing of bolt rows on the critical mechanism's face that
    reaches ``target_fos``.

    Parameters
    ----------
    capacity, axial_stiffness, bond_strength, kind, installed :
        The bolt (:class:`rockdem.bolts.Bolt`).
    angle : float
        Direction from the head into the rock (195: 15 degrees below
        horizontal into a face looking toward +x).
    row_spacing : float, optional
        Distance between rows along the face (default: 4 rows, then 8 and
        16 when fewer rows do not reach the target at the closest spacing).
    length : float, optional
        Bolt length (default: through the moving rock plus ``anchorage``).
    anchorage : float, optional
        Length beyond the moving rock (default: half the largest depth
        through it, at least 1/20 of the model's size).
    width : float
        Bracket width of the factor-of-safety ratings.
    """
    base = rate(model, width=width)
    mech = mechanism_ids(base)
    if not mech:
        raise InputError("bolt pattern", "no mechanism to bolt", "the slope has no failure")
    bolt = dict(
        angle=angle,
        capacity=capacity,
        axial_stiffness=axial_stiffness,
        bond_strength=bond_strength,
        kind=kind,
        installed=installed,
    )
    tried = ROW_COUNTS if row_spacing is None else (None,)
    count = 0
    result = None
    unanchored = None
    for n_rows in tried:
        rows = face_rows(model, mech, row_spacing=row_spacing, angle=angle, n_rows=n_rows or 4)
        try:
            result = _search(model, target_fos, rows, count, bolt, length, anchorage)
        except InputError as exc:  # no row of these anchors: more rows may (review 33)
            unanchored = exc
            continue
        count = result.evaluations
        if result.spacing is not None:
            break
    if result is None:
        raise unanchored
    if result.spacing is None:
        return result
    with _progress.stage("rating the bolt pattern"):
        fos = rate(result.model, width=width)
    return BoltPattern(
        result.spacing, result.bolts, result.bracket, result.evaluations, fos, result.model
    )


def _search(model, target_fos, rows, count, bolt: dict, length, anchorage) -> BoltPattern:
    """Bisection on the spacing of the rows (fewest bolts that reach the target)."""
    deepest = max(depth for _, depth in rows)
    if anchorage is None:
        anchorage = max(0.5 * deepest, model.blocks.extent / 20)

    def pattern(spacing: float) -> tuple[Bolt, ...]:
        return tuple(
            Bolt(
                head=head,
                length=float(length) if length is not None else depth + anchorage,
                spacing=spacing,
                name=f"row {k + 1}",
                **bolt,
            )
            for k, (head, depth) in enumerate(rows)
        )

    # a row that leaves the rock before it crosses a joint ties nothing: it is
    # left out (one such row failed the whole pattern, "crosses no joint")
    anchored, _ = bolts_left_in_rock(pattern(1.0), model.blocks, find_interfaces(model.blocks))
    names = {b.name for b in anchored}
    rows = [row for k, row in enumerate(rows) if f"row {k + 1}" in names]
    if not rows:
        raise InputError(
            "stabilisation.bolts",
            "no bolt from the face of the moving blocks crosses a joint into rock beyond "
            "them at this angle and length (each leaves the rock first)",
            "give another angle or length, or bolt the slope by hand (bolts: in the model file)",
        )

    def enough(spacing: float) -> bool:
        nonlocal count
        count += 1
        _progress.note(f"staged analysis {count}: {len(rows)} bolt rows {spacing:.3g} apart")
        return stable_at(model.replace(bolts=(*model.bolts, *pattern(spacing))), target_fos)

    lo_bad, hi_ok = np.inf, 0.0  # closest spacing short of the target, widest enough
    s = FIRST_SPACING
    if enough(s):
        hi_ok = s
        while s < SPACING_RANGE[1]:
            s *= 2
            if not enough(s):
                lo_bad = s
                break
            hi_ok = s
    else:
        lo_bad = s
        while s > SPACING_RANGE[0]:
            s /= 2
            if enough(s):
                hi_ok = s
                break
            lo_bad = s
    if hi_ok == 0.0:
        return BoltPattern(None, (), (lo_bad, 0.0), count, None, None)
    while np.isfinite(lo_bad) and lo_bad - hi_ok > RTOL * hi_ok:
        mid = 0.5 * (lo_bad + hi_ok)
        if enough(mid):
            hi_ok = mid
        else:
            lo_bad = mid
    bolts = pattern(hi_ok)
    return BoltPattern(
        hi_ok, bolts, (lo_bad, hi_ok), count, None, model.replace(bolts=(*model.bolts, *bolts))
    )
