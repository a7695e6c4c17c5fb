"""Rigid polygonal blocks, stored as one struct of arrays.

A block is a simple polygon (convex or not) with a unit weight; fixed blocks
are the stable ground and carry no degrees of freedom.  Outlines are ragged,
so they are kept as ``vertices (n_vertices, 2)`` plus ``offsets``: block *i*
owns ``vertices[offsets[i]:offsets[i + 1]]``, counter-clockwise.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import shapely

from .errors import InputError

#: Relative tolerance of geometric tests, as a fraction of the model's extent.
GEOMETRY_RTOL = 1e-8
#: Largest unit weight (beyond it forces overflow in the squares of the solver).
MAX_UNIT_WEIGHT = 1e9
#: smallest non-zero unit weight (1e-200 underflowed: "no failure" where 1e-150
#: gave the factor of safety; rock is 0.026 MN/m^3, 165 lbf/ft^3, 26,000 N/m^3,
#: 2.6e-8 kN/mm^3 and 2.6e-11 MN/mm^3: 1e-6 refused kN and mm, found by fuzzing)
MIN_UNIT_WEIGHT = 1e-12
#: A block farther than this many typical block sizes from the others makes every
#: block degenerate under the model-relative tolerance: it is refused by name.
MAX_SPREAD = 1e7


@dataclass(frozen=True, eq=False, repr=False)
class Blocks:
    """Block outlines, fixity and unit weights (immutable).

    Build with :meth:`Blocks.from_polygons`; the constructor assumes its
    arrays are already clean (counter-clockwise, no repeated vertices).

    Attributes
    ----------
    vertices : ndarray, shape (n_vertices, 2)
        All outline vertices, block after block, counter-clockwise.
    offsets : ndarray, shape (n_blocks + 1,)
        Block *i* owns ``vertices[offsets[i]:offsets[i + 1]]``.
    fixed : ndarray of bool, shape (n_blocks,)
        True for immobile ground blocks.
    unit_weight : ndarray, shape (n_blocks,)
        Weight per unit area (for example kN/m^3 x 1 m thickness).
    ids : ndarray of int, shape (n_blocks,)
        User labels, reported in results (default ``0 .. n_blocks - 1``).
    """

    vertices: np.ndarray
    offsets: np.ndarray
    fixed: np.ndarray
    unit_weight: np.ndarray
    ids: np.ndarray
    area: np.ndarray = field(init=False)
    centroid: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        area, centroid = _area_centroid(self.vertices, self.offsets)
        object.__setattr__(self, "area", area)
        object.__setattr__(self, "centroid", centroid)
        for name in ("vertices", "offsets", "fixed", "unit_weight", "ids", "area", "centroid"):
            getattr(self, name).setflags(write=False)

    # ------------------------------------------------------------------ build
    @classmethod
    def from_polygons(
        cls,
        polygons: Sequence,
        *,
        fixed: Sequence[bool] | np.ndarray | bool = False,
        unit_weight: Sequence[float] | np.ndarray | float = 1.0,
        ids: Sequence[int] | np.ndarray | None = None,
        check_overlap: bool = True,
    ) -> Blocks:
        """Blocks from polygons given as vertex lists or shapely Polygons.

        Parameters
        ----------
        polygons : sequence
            Each item is an ``(m, 2)`` sequence of vertices (either
            orientation, not closed) or a :class:`shapely.Polygon`.
        fixed : bool or sequence of bool
            Which blocks are immobile ground.
        unit_weight : float or sequence of float
            Weight per unit area of each block (>= 0).
        ids : sequence of int, optional
            User labels of the blocks (unique).
        check_overlap : bool
            Reject blocks that overlap (costs one spatial query).

        Raises
        ------
        InputError
            A block with fewer than 3 vertices, non-finite coordinates, zero
            area, a self-intersecting outline, or two blocks that overlap.

        Examples
        --------
        >>> b = Blocks.from_polygons([[(0, 0), (2, 0), (2, 1), (0, 1)]], unit_weight=26.0)
        >>> b.n_blocks, float(b.area[0]), float(b.weight[0])
        (1, 2.0, 52.0)
        """
        if isinstance(polygons, str | bytes) or not hasattr(polygons, "__len__"):
            raise InputError(
                "blocks", f"{type(polygons).__name__} is not a list of polygons", "give a list"
            )
        n = len(polygons)
        if n == 0:
            raise InputError("blocks", "no blocks were given", "give at least one polygon")
        ids_arr = np.arange(n) if ids is None else _as_ids(ids)
        if ids_arr.shape != (n,) or len(np.unique(ids_arr)) != n:
            raise InputError("block ids", "must be one unique integer per block", "renumber")
        label = {i: int(ids_arr[i]) for i in range(n)}
        # each block named by its id (hostile round 7: the position was taken
        # for the id, "block 1" for the block of id 20)
        rings = [_as_vertices(poly, label[i]) for i, poly in enumerate(polygons)]
        _check_spread(rings, label)
        extent = _extent(np.concatenate(rings))
        _check_resolution(np.concatenate(rings), extent)
        tol = GEOMETRY_RTOL * extent
        clean = []
        for i, xy in enumerate(rings):
            clean.append(_clean_ring(xy, tol, f"block {label[i]}"))
        counts = np.array([len(r) for r in clean])
        offsets = np.concatenate([[0], np.cumsum(counts)])
        vertices = np.concatenate(clean)
        fixed_arr = _per_block(fixed, n, "fixed", bool)
        gamma = _per_block(unit_weight, n, "unit_weight", float)
        tiny = (gamma > 0) & (gamma < MIN_UNIT_WEIGHT)  # underflows in the forces
        bad = np.flatnonzero(~np.isfinite(gamma) | (gamma < 0) | (gamma > MAX_UNIT_WEIGHT) | tiny)
        if bad.size:
            raise InputError(
                f"block {label[int(bad[0])]}",
                f"unit weight {gamma[bad[0]]:g} is out of range",
                f"give 0 (weightless) or a unit weight from {MIN_UNIT_WEIGHT:g} to "
                f"{MAX_UNIT_WEIGHT:g}",
            )
        _check_rings(vertices, offsets, label)
        area, _ = _area_centroid(vertices, offsets)
        signed = area.copy()
        # make counter-clockwise
        cw = signed < 0
        if cw.any():
            for i in np.flatnonzero(cw):
                s, e = offsets[i], offsets[i + 1]
                vertices[s:e] = vertices[s:e][::-1]
        small = np.flatnonzero(np.abs(signed) <= (GEOMETRY_RTOL * extent) ** 2 * 1e2)
        if small.size:
            raise InputError(
                f"block {label[int(small[0])]}",
                "has zero area",
                "give at least three vertices that are not collinear",
            )
        blocks = cls(vertices, offsets, fixed_arr, gamma, ids_arr)
        _check_simple(blocks, label)
        if check_overlap and n > 1:
            _check_overlap(blocks, label, tol)
        return blocks

    # -------------------------------------------------------------- derived
    @property
    def n_blocks(self) -> int:
        """Number of blocks."""
        return len(self.offsets) - 1

    @property
    def weight(self) -> np.ndarray:
        """Self-weight of each block (unit weight x area)."""
        return self.unit_weight * self.area

    @property
    def extent(self) -> float:
        """Diagonal of the bounding box: the length scale of tolerances."""
        return _extent(self.vertices)

    @property
    def tolerance(self) -> float:
        """Absolute geometric tolerance (relative to the model's extent)."""
        return GEOMETRY_RTOL * self.extent

    def outline(self, i: int) -> np.ndarray:
        """Vertices of block *i* (counter-clockwise)."""
        return self.vertices[self.offsets[i] : self.offsets[i + 1]]

    def polygons(self) -> np.ndarray:
        """The blocks as an array of shapely Polygons."""
        block = np.repeat(np.arange(self.n_blocks), np.diff(self.offsets))
        return shapely.polygons(shapely.linearrings(self.vertices, indices=block))

    def edges(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """All outline edges: ``(start (m, 2), end (m, 2), block (m,))``."""
        counts = np.diff(self.offsets)
        block = np.repeat(np.arange(self.n_blocks), counts)
        nxt = np.arange(len(self.vertices)) + 1
        last = self.offsets[1:] - 1
        nxt[last] = self.offsets[:-1]
        return self.vertices, self.vertices[nxt], block

    def subset(self, keep: np.ndarray) -> Blocks:
        """A new Blocks with only the blocks where ``keep`` is True (ids kept)."""
        keep = np.asarray(keep, dtype=bool)
        counts = np.diff(self.offsets)
        vmask = np.repeat(keep, counts)
        offsets = np.concatenate([[0], np.cumsum(counts[keep])])
        return Blocks(
            self.vertices[vmask].copy(),
            offsets,
            self.fixed[keep].copy(),
            self.unit_weight[keep].copy(),
            self.ids[keep].copy(),
        )

    def index_of(self, ids: Sequence[int] | np.ndarray) -> np.ndarray:
        """Positions of the blocks with the given user ids."""
        ids = np.atleast_1d(np.asarray(ids, dtype=np.int64))
        order = np.argsort(self.ids)
        pos = np.searchsorted(self.ids, ids, sorter=order)
        pos = np.clip(pos, 0, self.n_blocks - 1)
        found = self.ids[order[pos]] == ids
        if not found.all():
            raise InputError(
                f"block {int(ids[~found][0])}", "no block has this id", "use an id of the model"
            )
        return order[pos]

    def __repr__(self) -> str:
        return (
            f"<Blocks: {self.n_blocks:,} blocks ({int(self.fixed.sum()):,} fixed), "
            f"{len(self.vertices):,} vertices>"
        )


# ---------------------------------------------------------------- helpers
def _as_ids(ids) -> np.ndarray:
    """Block ids as 64-bit integers: whole numbers, not flags or fractions
    (hostile round 7: ``ids=[0.7, 1.2]`` were truncated to 0 and 1, silently)."""
    try:
        raw = np.asarray(ids)
        if raw.dtype.kind == "f":
            whole = np.isfinite(raw) & (raw == np.round(raw)) & (np.abs(raw) < 2.0**63)
            if not whole.all():
                raise TypeError
        elif raw.dtype.kind not in "iu" or (raw.dtype.kind == "u" and (raw >= 2**63).any()):
            raise TypeError
        return raw.astype(np.int64)
    except (OverflowError, TypeError, ValueError):
        raise InputError(
            "block ids", "must be whole numbers within 64 bits", "renumber the blocks"
        ) from None


def _as_vertices(poly, i: int) -> np.ndarray:
    if isinstance(poly, shapely.Polygon):
        if len(poly.interiors):
            raise InputError(f"block {i}", "has holes", "split it into blocks without holes")
        xy = np.asarray(poly.exterior.coords)[:-1]
    else:
        try:
            raw = np.asarray(poly)
            if raw.dtype.kind in "USb":  # (hostile round 7: "0" was taken as 0.0, as
                raise TypeError  # a Joint's friction_angle="30" is not)
            xy = np.asarray(poly, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InputError(f"block {i}", "vertices are not numbers", "give (x, y) pairs") from exc
    if xy.ndim != 2 or xy.shape[1] != 2 or len(xy) < 3:
        raise InputError(f"block {i}", "needs at least 3 (x, y) vertices", "give a polygon")
    if not np.isfinite(xy).all():
        raise InputError(f"block {i}", "has a coordinate that is not finite", "fix the vertex")
    # a closing vertex equal to the first is dropped by _clean_ring, with a
    # tolerance relative to the model's size (never to the coordinates' size)
    return xy.astype(float)


#: fewest steps of floating-point resolution across a model: a model this
#: few steps wide at its coordinates cannot be cut, matched and analysed
#: (found by fuzzing: the two-block wedge shrunk to 10 um at x = 1e9, 45
#: steps, read FS 1.0388 instead of 0.9786; 10 m there, 4.5e7 steps, is right)
MIN_RESOLUTION_STEPS = 1e6


def _check_resolution(xy: np.ndarray, extent: float) -> None:
    """Refuse a model so small for the size of its coordinates that floating
    point cannot resolve it."""
    far = float(np.max(np.abs(xy))) if xy.size else 0.0
    steps = extent / (np.finfo(float).eps * far) if far > 0 else np.inf
    if steps < MIN_RESOLUTION_STEPS:
        raise InputError(
            "blocks",
            f"span {extent:.3g} at coordinates up to {far:.3g}: floating point resolves only "
            f"{steps:.3g} steps across the model (at least {MIN_RESOLUTION_STEPS:.0e} are needed)",
            "move the model near the origin (subtract a reference point from every "
            "coordinate), or check the units",
        )


def _check_spread(rings: list[np.ndarray], label) -> None:
    """Refuse a block lying so far from the others that the model-relative tolerance
    would make every block degenerate; name that block (not the first one)."""
    if len(rings) < 2:
        return
    lo = np.array([r.min(axis=0) for r in rings])
    hi = np.array([r.max(axis=0) for r in rings])
    centre = lo + 0.5 * (hi - lo)
    size = np.hypot(*(hi - lo).T)
    typical = float(np.median(size))
    if not typical > 0:
        return
    middle = np.median(centre, axis=0)
    dist = np.hypot(*(centre - middle).T)
    far = int(np.argmax(dist))
    if dist[far] > MAX_SPREAD * typical:
        x, y = centre[far]
        raise InputError(
            f"block {label[far]}",
            f"lies {dist[far]:.3g} from the other blocks (at ({x:.6g}, {y:.6g}); typical block "
            f"size {typical:.3g})",
            "check its coordinates (all blocks in one coordinate system)",
        )


def _clean_ring(xy: np.ndarray, tol: float, where: str) -> np.ndarray:
    """Drop repeated consecutive vertices (zero-length edges)."""
    nxt = np.roll(xy, -1, axis=0)
    keep = np.hypot(*(nxt - xy).T) > tol
    if keep.sum() < 3:
        if len(np.unique(xy, axis=0)) >= 3 and _extent(xy) > 0:  # small, not degenerate
            raise InputError(
                where,
                f"is smaller than the model's geometric tolerance ({tol:.3g}: "
                f"{GEOMETRY_RTOL:g} of the extent of all blocks), so its vertices merge",
                "make it larger, or leave out the blocks far larger than it",
            )
        raise InputError(where, "has zero area", "give at least three distinct vertices")
    return xy[keep]


def _extent(xy: np.ndarray) -> float:
    span = xy.max(axis=0) - xy.min(axis=0)
    return float(np.hypot(*span)) or 1.0


def _area_centroid(vertices: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed area and centroid of every polygon, vectorised (shoelace).

    Coordinates are taken relative to each block's first vertex so that the
    result does not lose digits far from the origin.
    """
    counts = np.diff(offsets)
    block = np.repeat(np.arange(len(counts)), counts)
    origin = vertices[offsets[:-1]]
    p = vertices - origin[block]
    nxt = np.arange(len(vertices)) + 1
    nxt[offsets[1:] - 1] = offsets[:-1]
    q = p[nxt]
    cross = p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]
    area2 = np.bincount(block, cross, minlength=len(counts))
    cx = np.bincount(block, (p[:, 0] + q[:, 0]) * cross, minlength=len(counts))
    cy = np.bincount(block, (p[:, 1] + q[:, 1]) * cross, minlength=len(counts))
    with np.errstate(divide="ignore", invalid="ignore"):
        centroid = np.column_stack([cx, cy]) / (3.0 * area2)[:, None]
    return 0.5 * area2, centroid + origin


def _check_rings(vertices: np.ndarray, offsets: np.ndarray, label) -> None:
    """Reject outlines that cross themselves (before their area means anything)."""
    block = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
    hull = shapely.area(shapely.convex_hull(shapely.multipoints(vertices, indices=block)))
    flat = hull <= (GEOMETRY_RTOL * _extent(vertices)) ** 2 * 1e2
    if flat.any():
        raise InputError(
            f"block {label[int(np.flatnonzero(flat)[0])]}",
            "has zero area",
            "give at least three vertices that are not collinear",
        )
    simple = shapely.is_simple(shapely.linearrings(vertices, indices=block))
    if not simple.all():
        i = int(np.flatnonzero(~simple)[0])
        raise InputError(
            f"block {label[i]}",
            "outline crosses itself",
            "list the vertices in order around the block",
        )


def _check_simple(blocks: Blocks, label) -> None:
    polys = blocks.polygons()
    ok = shapely.is_valid(polys)
    if not ok.all():
        i = int(np.flatnonzero(~ok)[0])
        raise InputError(
            f"block {label[i]}",
            "outline crosses itself",
            "list the vertices in order around the block",
        )


def _check_overlap(blocks: Blocks, label, tol: float) -> None:
    polys = blocks.polygons()
    tree = shapely.STRtree(polys)
    a, b = tree.query(polys, predicate="intersects")
    m = a < b
    a, b = a[m], b[m]
    if a.size == 0:
        return
    common = shapely.area(shapely.intersection(polys[a], polys[b]))
    limit = tol * blocks.extent * 10.0
    bad = np.flatnonzero(common > limit)
    if bad.size:
        i, j = int(a[bad[0]]), int(b[bad[0]])
        raise InputError(
            f"blocks {label[i]} and {label[j]}",
            f"overlap (common area {common[bad[0]]:.3g})",
            "blocks may touch along edges but not overlap",
        )


def _per_block(value, n: int, key: str, kind: type) -> np.ndarray:
    """``value`` (one for all, or one per block) as an array of ``n`` ``kind``:
    a list of another length, text, or (for flags) numbers other than 0 and 1
    are refused (``fixed=[True]`` for two blocks made both fixed; ``fixed="no"``
    both fixed too)."""
    arr = np.asarray(value)
    if arr.dtype.kind not in ("b", "i", "u", "f") or arr.ndim > 1:
        raise InputError(
            f"blocks {key}", f"{value!r} is not one value per block", "give one value per block"
        )
    if arr.ndim == 1 and arr.shape != (n,):
        raise InputError(
            f"blocks {key}",
            f"has {arr.shape[0]} values for {n} blocks",
            "give one value per block, or a single value for all",
        )
    if kind is bool and arr.dtype.kind != "b" and not np.isin(arr, (0, 1)).all():
        raise InputError(f"blocks {key}", f"{value!r} is not true or false", "give True or False")
    return np.broadcast_to(arr.astype(kind), (n,)).copy()
