"""Editing a generated slope for stabilisation design.

Every editor returns a **new** :class:`SlopeGeometry`; untouched blocks keep
their ids and outlines, a block partly inside the removed region is trimmed
and keeps its id (extra pieces, if the cut splits it, get new ids).  The
fixed ground is never cut.  Pieces smaller than ``min_block_fraction`` x the
typical block left by a cut are removed with the excavation and reported in
``slivers`` (action ``"removed"``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import shapely

from ..blocks import GEOMETRY_RTOL, Blocks
from ..errors import InputError
from ..interfaces import find_interfaces
from ..joints import Joint
from . import _topology as topo
from ._topology import as_region
from .profile import Profile
from .slope import Sliver, SlopeGeometry

__all__ = ["add_blocks", "cut_to_profile", "excavate", "remove_blocks"]


def remove_blocks(geom: SlopeGeometry, ids: Sequence[int] | int) -> SlopeGeometry:
    """The geometry without the blocks of the given ids.

    Raises
    ------
    InputError
        An unknown id, a fixed ground block, or a block that would be left
        touching nothing.

    Examples
    --------
    >>> from rockdem import Joint
    >>> from rockdem.geometry import JointSet, Profile, generate_slope
    >>> j = Joint(1e6, 35)
    >>> g = generate_slope(Profile([(0, 4), (4, 4)]), [JointSet("v", 90, 1, j, origin=(0.5, 0))],
    ...                    depth=1)
    >>> h = remove_blocks(g, [3])
    >>> g.blocks.n_blocks - h.blocks.n_blocks, 3 in h.blocks.ids
    (1, False)
    """
    idx = geom.blocks.index_of(np.atleast_1d(ids))
    fixed = idx[geom.blocks.fixed[idx]]
    if fixed.size:
        raise InputError(f"block {int(geom.blocks.ids[fixed[0]])}", "is fixed ground",
                         "remove free blocks only (the ground is not excavated)")
    keep = np.ones(geom.blocks.n_blocks, dtype=bool)
    keep[idx] = False
    blocks = geom.blocks.subset(keep)
    _check_touching(blocks, "after removing blocks")
    section = shapely.union_all(
        shapely.intersection(blocks.polygons()[~blocks.fixed], geom.section))
    return geom.replace(blocks=blocks, section=section)


def excavate(geom: SlopeGeometry, region, *, where: str = "excavation region") -> SlopeGeometry:
    """The geometry with everything inside ``region`` removed (blocks trimmed).

    Parameters
    ----------
    geom : SlopeGeometry
    region : shapely Polygon or sequence of (x, y)
        The excavation.

    Raises
    ------
    InputError
        A region that overlaps no free block, that would leave a hole in a
        block, or that would leave a block touching nothing.
    """
    poly = as_region(region, where)
    blocks = geom.blocks
    polys = blocks.polygons()
    tol = blocks.tolerance
    extent = blocks.extent
    tree = shapely.STRtree(polys)
    cand = tree.query(poly, predicate="intersects")
    cand = cand[~blocks.fixed[cand]]
    if cand.size:
        common = shapely.area(shapely.intersection(polys[cand], poly))
        cand = cand[common > tol * extent]
    if cand.size == 0:
        x0, y0, x1, y1 = shapely.bounds(shapely.union_all(polys[~blocks.fixed]))
        raise InputError(
            where,
            f"does not overlap the model's free blocks (they span x {x0:g} to {x1:g}, "
            f"y {y0:g} to {y1:g})",
            "give a region that overlaps the blocks to remove",
        )
    rest = shapely.difference(polys[cand], poly)
    holes = shapely.get_num_interior_rings(shapely.get_parts(rest))
    if (holes > 0).any():
        parts, owner = shapely.get_parts(rest, return_index=True)
        k = cand[owner[np.flatnonzero(holes > 0)[0]]]
        raise InputError(where, f"would leave a hole in block {int(blocks.ids[k])}",
                         "extend the region to a free surface, or remove the block")
    parts, owner = shapely.get_parts(rest, return_index=True)
    is_piece = (shapely.get_type_id(parts) == 3) & ~shapely.is_empty(parts)
    parts, owner = parts[is_piece], owner[is_piece]
    area = shapely.area(parts)
    small = geom.min_block_fraction * geom.typical_area if math.isfinite(
        geom.typical_area) else 0.0
    # the largest piece of each block keeps its id
    order = np.lexsort((-area, owner))
    first = np.ones(len(order), dtype=bool)
    first[1:] = owner[order][1:] != owner[order][:-1]
    is_main = np.zeros(len(parts), dtype=bool)
    is_main[order[first]] = True
    gone = (area < small) | (area <= tol * extent)
    cent = shapely.get_coordinates(shapely.centroid(parts)) if len(parts) else np.zeros((0, 2))
    report = [Sliver(float(area[i]), (float(cent[i, 0]), float(cent[i, 1])), "removed", None)
              for i in np.flatnonzero(gone & (area > tol * extent))]
    keep_part = ~gone
    new_ids = blocks.ids[cand[owner]].copy()
    extra = keep_part & ~is_main
    next_id = int(blocks.ids.max()) + 1
    new_ids[extra] = next_id + np.arange(int(extra.sum()))
    untouched = np.ones(blocks.n_blocks, dtype=bool)
    untouched[cand] = False
    base = blocks.subset(untouched)
    pieces = parts[keep_part]
    xy, offsets = topo.to_arrays(pieces, tol)
    out = Blocks(
        np.concatenate([base.vertices, xy]),
        np.concatenate([base.offsets, base.offsets[-1] + offsets[1:]]),
        np.concatenate([base.fixed, np.zeros(len(pieces), dtype=bool)]),
        np.concatenate([base.unit_weight, blocks.unit_weight[cand[owner[keep_part]]]]),
        np.concatenate([base.ids, new_ids[keep_part]]),
    )
    _check_touching(out, f"after the {where}")
    section = shapely.difference(geom.section, poly)
    return geom.replace(blocks=out, section=section, slivers=geom.slivers + tuple(report))


def cut_to_profile(geom: SlopeGeometry, profile: Profile | Sequence) -> SlopeGeometry:
    """The geometry cut down to a new ground profile (e.g. a new berm).

    Everything above ``profile`` is excavated; the profile is extended
    horizontally at its ends to the sides of the model.

    Examples
    --------
    >>> from rockdem import Joint
    >>> from rockdem.geometry import JointSet, Profile, generate_slope
    >>> j = Joint(1e6, 35)
    >>> g = generate_slope(Profile([(0, 4), (4, 4)]), [JointSet("h", 0, 1, j, origin=(0, 0.5))],
    ...                    depth=2, boundary=("base",))
    >>> h = cut_to_profile(g, [(0, 3), (4, 3)])
    >>> float(h.blocks.area[~h.blocks.fixed].sum())  # 4 wide, from the base (y = 2) to 3
    4.0
    """
    if not isinstance(profile, Profile):
        profile = Profile(profile)
    x0, y0, x1, y1 = shapely.bounds(shapely.union_all(geom.blocks.polygons()))
    span = math.hypot(x1 - x0, y1 - y0)
    pts = profile.points
    left, right = x0 - 0.1 * span, x1 + 0.1 * span
    if pts[0, 0] > left:
        pts = np.vstack([[left, pts[0, 1]], pts])
    if pts[-1, 0] < right:
        pts = np.vstack([pts, [right, pts[-1, 1]]])
    top = max(y1, float(pts[:, 1].max())) + span
    region = shapely.Polygon(np.vstack([pts, [[pts[-1, 0], top], [pts[0, 0], top]]]))
    return excavate(geom, region, where="the new profile")


def add_blocks(
    geom: SlopeGeometry,
    polygons: Sequence,
    *,
    fixed: bool | Sequence[bool] = False,
    unit_weight: float | Sequence[float] | None = None,
    joint: Joint | None = None,
) -> SlopeGeometry:
    """Explicit block polygons added to a generated geometry (new ids).

    Parameters
    ----------
    polygons : sequence
        Vertex lists or shapely Polygons; they must not overlap existing blocks.
    fixed : bool or sequence of bool
    unit_weight : float or sequence, optional
        Default: the unit weight of the first block.
    joint : Joint, optional
        Properties of the contacts along the new blocks' outlines (added to
        the joint table; their edges are listed first among the joint lines).
    """
    gamma = float(geom.blocks.unit_weight[0]) if unit_weight is None else unit_weight
    new = Blocks.from_polygons(list(polygons), fixed=fixed, unit_weight=gamma)
    old = geom.blocks
    tol = max(old.tolerance, GEOMETRY_RTOL * new.extent)
    tree = shapely.STRtree(old.polygons())
    a, b = tree.query(new.polygons(), predicate="intersects")
    if a.size:
        common = shapely.area(shapely.intersection(new.polygons()[a], old.polygons()[b]))
        bad = np.flatnonzero(common > tol * old.extent * 10)
        if bad.size:
            k = bad[0]
            raise InputError(f"added block {int(a[k])}",
                             f"overlaps block {int(old.ids[b[k]])} (area {common[k]:.3g})",
                             "excavate the space first (excavate / remove_blocks)")
    ids = int(old.ids.max()) + 1 + np.arange(new.n_blocks)
    blocks = Blocks(
        np.concatenate([old.vertices, new.vertices]),
        np.concatenate([old.offsets, old.offsets[-1] + new.offsets[1:]]),
        np.concatenate([old.fixed, new.fixed]),
        np.concatenate([old.unit_weight, new.unit_weight]),
        np.concatenate([old.ids, ids]),
    )
    joints, lines, line_joint = geom.joints, geom.joint_lines, geom.line_joint
    if joint is not None:
        joints = (*joints, joint)
        p, q, _ = new.edges()
        lines = np.concatenate([np.stack([p, q], axis=1), lines])
        line_joint = np.concatenate([np.full(len(p), len(joints) - 1), line_joint])
    _check_touching(blocks, "after adding blocks")
    return geom.replace(blocks=blocks, joints=joints, joint_lines=lines, line_joint=line_joint)


def _check_touching(blocks: Blocks, when: str) -> None:
    try:
        find_interfaces(blocks)
    except InputError as exc:
        raise InputError(exc.where, f"{exc.problem} {when}",
                         "remove it too, or keep a neighbour that holds it") from exc
