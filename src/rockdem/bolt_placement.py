"""Where bolts cross the joints: the crossings of a model's bolts with its
interfaces (:class:`rockdem.bolts.Crossings`), the checks that each bolt
starts on the rock's face and ties a free block to other rock, and which
bolts a removal of rock leaves in place.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp
import shapely

from .bolts import Crossings
from .errors import InputError

#: the rock must start within this share of the bolt's length from its head
HEAD_REACH = 0.01


#: smallest out-of-plane bolt spacing, as a share of the blocks' mean size
MIN_SPACING = 1e-2


#: largest ratio of a bolt's stiffness per unit width (axial or shear, over
#: its spacing) to the normal stiffness of the interface it crosses (the
#: joint's normal stiffness x the interface's length, or the blocks' mean
#: size where that is longer).  Real bolts are softer
#: than the joints they cross (a 25 mm bar 1 m long, ~1e5 kN/m, against
#: 1e6 kPa/m over 1 m).  Far stiffer ones make the equations ill-conditioned
#: and the verdicts wrong: a bolted block on a plane (closed form 1.7833)
#: read 1.7831 up to 2.5e4 x, 1.771 at 2.5e5 x and 1.50 "undecided" at
#: 2.5e6 x; a flat two-block stack that cannot fail read "strength-
#: independent failure" at 5e6 x.
BOLT_STIFFNESS_CONTRAST_MAX = 1e4


def check_bolt_stiffness(bolts, crossings, faces, joints, length_scale: float) -> None:
    """An InputError for a bolt far stiffer than the interface it crosses
    (see BOLT_STIFFNESS_CONTRAST_MAX), naming the bolt and its key.

    The interface counts at least the blocks' mean size (``length_scale``):
    a bolt through the tip of a sliver interface is held by the blocks'
    contacts, not by that sliver alone."""
    if crossings is None:
        return
    kn = np.array([j.normal_stiffness for j in joints], dtype=float)[faces.joint]
    length = np.maximum(faces.length[crossings.interface], length_scale)
    iface_k = kn[crossings.interface] * length
    for key, k in (("axial_stiffness", crossings.k_axial), ("shear_stiffness", crossings.k_shear)):
        ratio = k / iface_k
        worst = int(np.argmax(ratio))
        if ratio[worst] <= BOLT_STIFFNESS_CONTRAST_MAX:
            continue
        i = int(crossings.bolt[worst])
        bolt = bolts[i]
        where = f"bolts {bolt.name}" if bolt.name else "bolts"
        limit = BOLT_STIFFNESS_CONTRAST_MAX * iface_k[worst] * crossings.spacing[worst]
        raise InputError(
            f"{where} {key}",
            f"{getattr(bolt, key):g} makes the bolt {ratio[worst]:.3g} times as stiff as the "
            f"joint it crosses at ({crossings.point[worst][0]:.4g}, "
            f"{crossings.point[worst][1]:.4g}) (normal stiffness x length, at least the blocks' "
            "mean size, per unit width): "
            f"beyond {BOLT_STIFFNESS_CONTRAST_MAX:g} times the equations are ill-conditioned "
            "and the verdicts are not reliable",
            f"give {key}: {limit:.3g} or less (a bolt's E A / L; its capacity, not its "
            "stiffness, limits what it carries)",
        )


def _crossed(bolt, where: str, blocks, faces, tree):
    """The interfaces ``bolt`` crosses with rock on both sides and a free
    block on one (indices, by depth) and every interface's parameter along
    the bolt; InputError where its head is not on the rock's face or it
    crosses no such interface."""
    tol = blocks.tolerance
    P0, P1 = faces.start, faces.end
    e = bolt.direction
    head = np.asarray(bolt.head)
    # the head may sit a little off the face (rounded coordinates): 1% of the
    # length, and of the model's size for a bolt longer than the model
    reach = HEAD_REACH * min(bolt.length, blocks.extent)
    probe = shapely.points(head + max(10 * tol, reach) * e)
    if not len(tree.query(probe, predicate="intersects")):
        raise InputError(
            where,
            f"the head ({head[0]:g}, {head[1]:g}) is not on the rock in the bolt's direction",
            "put the head on the face and point the bolt into the rock",
        )
    behind = shapely.points(head - max(10 * tol, reach) * e)
    if len(tree.query(behind, predicate="within")):  # (found by fuzzing: 2 m in)
        raise InputError(
            where,
            f"the head ({head[0]:g}, {head[1]:g}) is inside the rock, not on its face",
            "put the head on the face (the bolt is drilled from the free surface)",
        )
    r = bolt.length * e
    s = P1 - P0
    qp = P0 - head
    denom = r[0] * s[:, 1] - r[1] * s[:, 0]
    ok = np.abs(denom) > 1e-12 * bolt.length * np.hypot(*s.T)
    _check_not_along_a_joint(bolt, where, e, head, P0, P1, ~ok, tol, faces, blocks)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (qp[:, 0] * s[:, 1] - qp[:, 1] * s[:, 0]) / denom
        u = (qp[:, 0] * r[1] - qp[:, 1] * r[0]) / denom
    eps_t, eps_u = tol / bolt.length, tol / np.maximum(np.hypot(*s.T), tol)
    hit = ok & (t > eps_t) & (t < 1 - eps_t) & (u >= -eps_u) & (u <= 1 + eps_u)
    hit = np.flatnonzero(hit)
    hit = hit[np.argsort(t[hit], kind="stable")]
    step = max(10 * tol, 1e-6 * min(bolt.length, blocks.extent))
    hit = _one_per_depth(hit, t, bolt, where, blocks, faces, tree, step)
    free = ~(blocks.fixed[faces.block_a[hit]] & blocks.fixed[faces.block_b[hit]])
    hit = hit[free]
    # rock on both sides: a bolt that leaves the rock through a corner of
    # an interface, or runs along a free face, crosses nothing there
    # (found by fuzzing: one out through a corner into the air held the
    # block above as if anchored, FS 2.797 for 1.213)
    sides = [
        shapely.points(head + (t[hit, None] * bolt.length + sign * step) * e)
        for sign in (-1.0, 1.0)
    ]
    in_rock = [np.isin(np.arange(len(hit)), tree.query(pt, predicate="within")[0]) for pt in sides]
    hit = hit[in_rock[0] & in_rock[1]]
    if not len(hit):
        raise InputError(
            where,
            "crosses no joint between a free block and another block",
            "lengthen it or change its angle so that it ties the moving rock to stable rock",
        )
    return hit, t


def _check_not_along_a_joint(bolt, where, e, head, P0, P1, parallel, tol, faces, blocks):
    """InputError where the bolt runs along an interface (on its line, over
    more than the tolerance): which side it is on is round-off's choice
    (found by hostile testing, round 5)."""
    k = np.flatnonzero(parallel)
    if not k.size:
        return
    off = np.abs(e[0] * (P0[k, 1] - head[1]) - e[1] * (P0[k, 0] - head[0]))
    a = (P0[k] - head) @ e
    b = (P1[k] - head) @ e
    lo, hi = np.maximum(np.minimum(a, b), 0.0), np.minimum(np.maximum(a, b), bolt.length)
    along = k[(off <= tol) & (hi - lo > 10 * tol)]
    if along.size:
        i = int(along[0])
        ids = blocks.ids
        raise InputError(
            where,
            f"runs along the joint between blocks {int(ids[faces.block_a[i]])} and "
            f"{int(ids[faces.block_b[i]])}, so it ties neither side to the other",
            "turn it a little, or move its head off the joint's line",
        )


def _one_per_depth(hit, t, bolt, where, blocks, faces, tree, step):
    """The interfaces ``hit`` (sorted by depth) with one per depth: where the
    bolt crosses through a corner it touches several, and the one it crosses
    joins the block before the corner to the block after it (the first found
    was kept: one through the ground's corner tied two free blocks instead,
    found by hostile testing).  InputError where no interface joins them (the
    blocks touch only at that corner)."""
    if not len(hit):
        return hit
    group = np.concatenate([[0], np.cumsum(np.diff(t[hit]) * bolt.length > blocks.tolerance)])
    kept = []
    for g in range(group[-1] + 1):
        mine = hit[group == g]
        at = np.asarray(bolt.head) + t[mine[0]] * bolt.length * bolt.direction
        sides = [
            tree.query(shapely.points(at + sign * step * bolt.direction), predicate="within")
            for sign in (-1.0, 1.0)
        ]
        if not all(len(side) == 1 for side in sides):
            kept.append(mine[0])  # air or a face on one side: crosses nothing here
            continue
        pair = {int(sides[0][0]), int(sides[1][0])}
        if len(pair) == 1:
            # the same block on both sides: through a reflex corner of it, where
            # joints end, the bolt crosses none (it was refused as passing "from
            # block 1 to block 1", and before that tied the block to its
            # neighbour at that corner; review 33)
            continue
        if len(mine) == 1:
            kept.append(mine[0])
            continue
        join = [k for k in mine if {int(faces.block_a[k]), int(faces.block_b[k])} == pair]
        if not join:
            a, b = (int(blocks.ids[side[0]]) for side in sides)
            raise InputError(
                where,
                f"passes from block {a} to block {b} through the corner at "
                f"({at[0]:.6g}, {at[1]:.6g}), where they touch at that point only",
                "move or turn the bolt a little so that it crosses the joints away from their ends",
            )
        kept.append(join[0])
    return np.array(kept, dtype=hit.dtype)


def place_bolts(bolts, blocks, faces, asm):
    """The crossings of every bolt with the interfaces (None without bolts).

    Raises InputError for a bolt whose head is not on the rock or that ties
    no free block across any joint: it would hold nothing.
    """
    if not bolts:
        return None
    dof, scatter, n_nnz, n_dof = asm.dof, asm.scatter, asm.nnz, asm.n_dof
    tree = shapely.STRtree(blocks.polygons())
    rows: list[tuple] = []
    names = []
    for i, bolt in enumerate(bolts):
        name = bolt.name or f"bolt {i + 1}"
        names.append(name)
        where = f"bolts {bolt.name}" if bolt.name else "bolts"
        if bolt.spacing < MIN_SPACING * asm.length_scale:
            # forces per unit width = per bolt / spacing: a spacing far below the
            # blocks' size makes the bolt rows 1e9 x stiffer than the joints
            # (measured: 1e-8 gave FS 1.19, 1e-9 "no failure at any factor"
            # where 1e-7 and above give 1.2378)
            raise InputError(
                f"{where} spacing",
                f"{bolt.spacing:g} is far below the size of the blocks ({asm.length_scale:.3g})",
                f"give the out-of-plane spacing of the bolts, at least "
                f"{MIN_SPACING * asm.length_scale:.3g}",
            )
        e = bolt.direction
        head = np.asarray(bolt.head)
        hit, t = _crossed(bolt, where, blocks, faces, tree)
        for k in hit:
            depth = float(t[k] * bolt.length)
            bond = bolt.bond_strength * (bolt.length - depth)
            t_max = min(bolt.capacity, bond) / bolt.spacing
            rows.append(
                (
                    i,
                    int(k),
                    head + depth * e,
                    depth,
                    bolt.axial_stiffness / bolt.spacing,
                    0.0 if bolt.kind == "cable" else bolt.shear_stiffness / bolt.spacing,
                    t_max,
                    0.0 if bolt.kind == "cable" else -t_max,
                    0.0 if bolt.kind == "cable" else bolt.shear_capacity / bolt.spacing,
                    min(bolt.pretension / bolt.spacing, t_max),
                    bolt.spacing,
                )
            )
    cols = list(zip(*rows, strict=True))
    bolt_idx = np.array(cols[0], dtype=np.int64)
    iface = np.array(cols[1], dtype=np.int64)
    point = np.array(cols[2], dtype=float).reshape(-1, 2)
    axis = np.array([bolts[b].direction for b in bolt_idx]).reshape(-1, 2)
    # kinematics in the interface's a -> b orientation: the axial row measures
    # extension when the head lies on a's side (axis . normal > 0)
    normal = faces.normal[iface]
    v_axial = axis * np.sign(np.einsum("ij,ij->i", axis, normal))[:, None]
    v_shear = np.column_stack([-v_axial[:, 1], v_axial[:, 0]])
    a, b = faces.block_a[iface], faces.block_b[iface]
    ra, rb = point - blocks.centroid[a], point - blocks.centroid[b]

    def cross(r_, v):
        return r_[:, 0] * v[:, 1] - r_[:, 1] * v[:, 0]

    B = np.empty((len(iface), 2, 6))
    for row, v in enumerate((v_axial, v_shear)):
        B[:, row, 0:2] = -v
        B[:, row, 2] = -cross(ra, v)
        B[:, row, 3:5] = v
        B[:, row, 5] = cross(rb, v)
    columns = np.concatenate([dof[a], dof[b]], axis=1)
    B[np.repeat(columns[:, None, :] < 0, 2, axis=1)] = 0.0
    m = len(iface)
    r_idx = np.repeat(np.arange(2 * m), 6)
    c_idx = np.repeat(columns, 2, axis=0).ravel()
    vals = B.reshape(-1)
    valid = c_idx >= 0
    operator = sp.csr_array((vals[valid], (r_idx[valid], c_idx[valid])), shape=(2 * m, n_dof))
    places = scatter.reshape(-1, 36)[iface].ravel()
    ok = places >= 0
    gather = sp.csr_array(
        (np.ones(int(ok.sum())), (places[ok], np.flatnonzero(ok))), shape=(n_nnz, 36 * m)
    )
    return Crossings(
        bolt_idx,
        iface,
        point,
        axis,
        np.array(cols[3], dtype=float),
        *(np.array(c, dtype=float) for c in cols[4:11]),
        names=tuple(names),
        operator=operator,
        gather=gather,
        B=B,
        late=np.array([bolts[b].installed == "after_loads" for b in bolt_idx], dtype=bool),
    )


def bolts_left_in_rock(bolts, blocks, faces) -> tuple[tuple, tuple[str, ...]]:
    """The bolts that still hold after rock was removed (an excavation stage,
    a removal trial), and the names of those that went with it: a bolt whose
    head block was removed, or every joint it tied, holds nothing.  (The
    removal once dropped every bolt of the model, silently: a bolted slope's
    excavation stages and removal trials were analysed unbolted.)  An unnamed
    bolt that stays keeps the name of its place in the model it came from
    (``bolt 3`` stays ``bolt 3`` when bolt 1 went with its rock)."""
    if not bolts:
        return (), ()
    tree = shapely.STRtree(blocks.polygons())
    kept, gone = [], []
    for i, bolt in enumerate(bolts):
        name = bolt.name or f"bolt {i + 1}"
        try:
            _crossed(bolt, "bolts", blocks, faces, tree)
        except InputError:
            gone.append(name)
        else:
            kept.append(bolt if bolt.name else replace(bolt, name=name))
    return tuple(kept), tuple(gone)
