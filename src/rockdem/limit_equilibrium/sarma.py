"""The DEM's failure mechanism rated by Sarma's method (1979), generalised to blocks.

Sarma's method for non-vertical slices finds the horizontal acceleration
``Kc`` (as a share of gravity) that brings a chain of slices with inclined
interfaces to limiting equilibrium, and the factor of safety as the factor
``F`` dividing ``c`` and ``tan(phi)`` on the base and on every interface
together that makes ``Kc = 0``.  Here the slices are the DEM's moving
blocks:

* blocks that move together (no relative motion at their contacts, as
  :func:`rockdem.modes.failure_modes` groups them) form one rigid **body**;
* every contact of a body with the still rock or with another body is a
  **face**, classified from the DEM's mechanism: opening (the body leaves
  it: no force) or sliding (at limit, the shear opposing the relative
  slip).  Collinear or parallel interfaces of the same pair of bodies are one
  face with a uniform normal stress, so its shear strength is
  ``(sum c_k L_k + N sum L_k tan phi_k / sum L_k) / F``;
* each body is in force equilibrium under its loads (weight, water,
  surcharges, anchors: the DEM's own load vector; passive bolts with their
  forces at the DEM's last equilibrium below the limit), the face forces and
  ``Kc W`` horizontally in the direction of its motion.

A chain of ``n`` bodies with ``n`` base faces and ``n - 1`` faces between
them has ``2n`` equations and ``2n`` unknowns (the face normal forces and
``Kc``): Sarma's case.  Anything else - a mechanism that rotates (toppling),
falls free, or has more or fewer sliding faces than equations - is not
rated: the result says why and gives no number.  Moments are not used (as
in Sarma's factor; the points of action of the face forces are free), and
the tensile strength is not either: a face in tension at the solution means
the blocks would separate, and no number is given.  Strengths are the peak
values.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components

from ..modes import MODES, failure_modes, oriented_mechanism
from ..results import Analysis, FactorOfSafety
from .sarma_notes import differences, ids_text

__all__ = ["SarmaFace", "SarmaResult", "sarma"]

#: A face opens when its opening speed exceeds this share of its relative speed.
OPEN_SHARE = 0.2
#: Parallel faces of the same pair of bodies are one face within this angle (degrees).
PARALLEL_DEG = 2.0
#: The factor of safety is searched between these factors.
F_RANGE = (0.02, 100.0)
#: A face normal force below -this share of the bodies' weight is tension.
TENSION_SHARE = 1e-6


@dataclass(frozen=True)
class SarmaFace:
    """One face of the limit-equilibrium mechanism.

    ``body_a`` (-1: the still rock) and ``body_b`` are the two sides; the
    normal ``normal`` points from a into b.  ``normal_force`` (effective,
    compression > 0) and ``shear_force`` are the forces on b at the factor
    of safety of its group of bodies (None for an open face or when no
    factor was found).  ``dem_state`` is the DEM's current
    state of each interface at its failed state.
    """

    interfaces: tuple[int, ...]
    body_a: int
    body_b: int
    kind: str  # "base" (against the still rock) or "between bodies"
    state: str  # "sliding" (at limit in the LE) or "open"
    length: float
    joints: tuple[str, ...]
    normal: tuple[float, float]
    normal_force: float | None = None
    shear_force: float | None = None
    dem_state: tuple[str, ...] = ()


@dataclass(frozen=True)
class SarmaResult:
    """Sarma's factor of safety of the DEM's mechanism, beside the DEM's.

    Attributes
    ----------
    fos : float or None
        The factor dividing ``c`` and ``tan(phi)`` on every sliding face
        that brings the mechanism to limiting equilibrium; None with
        ``reason`` when the mechanism is not one Sarma's method can rate.
    reason : str
        Why there is no number ("" when there is one).
    critical_acceleration : float or None
        ``Kc`` at full strength (F = 1), as a share of gravity, horizontal in
        the direction of motion (< 0: unstable without any acceleration).
    dem_fos : float or None
        The DEM's strength-reduction factor of safety, when known.
    bodies : list of list of int
        Block ids of each rigid body.
    faces : tuple of SarmaFace
    notes : list of str
        Where the two methods differ, and why the factors may.
    """

    fos: float | None
    reason: str
    critical_acceleration: float | None
    dem_fos: float | None
    bodies: list[list[int]]
    faces: tuple[SarmaFace, ...]
    notes: list[str] = field(default_factory=list)

    @property
    def difference(self) -> float | None:
        """Relative difference (Sarma - DEM) / DEM, when both exist."""
        if self.fos is None or self.dem_fos is None or not np.isfinite(self.fos):
            return None
        return (self.fos - self.dem_fos) / self.dem_fos

    def as_dict(self) -> dict:
        """A JSON-ready summary."""
        return {
            "method": "Sarma (1979), non-vertical slices, generalised to blocks",
            "fos": self.fos,
            "reason": self.reason or None,
            "critical_acceleration": self.critical_acceleration,
            "dem_fos": self.dem_fos,
            "difference": self.difference,
            "bodies": self.bodies,
            "faces": [
                {
                    "interfaces": list(f.interfaces),
                    "between": [f.body_a, f.body_b],
                    "kind": f.kind,
                    "state": f.state,
                    "length": f.length,
                    "joints": list(f.joints),
                    "normal_force": f.normal_force,
                    "shear_force": f.shear_force,
                    "dem_state": list(f.dem_state),
                }
                for f in self.faces
            ],
            "notes": list(self.notes),
        }


def _velocity(blocks, motion, i, p):
    ux, uy, th = motion[i].T
    c = blocks.centroid[i]
    return np.column_stack([ux - th * (p[:, 1] - c[:, 1]), uy + th * (p[:, 0] - c[:, 0])])


def sarma(source: FactorOfSafety | Analysis) -> SarmaResult:
    """Rate the DEM's failure mechanism by Sarma's method.

    Parameters
    ----------
    source : FactorOfSafety or Analysis
        A strength-reduction result (its ``failed_analysis`` is the
        mechanism at the limit, its ``value`` the DEM's factor), or a failed
        analysis.

    Returns
    -------
    SarmaResult
    """
    dem_fos, stable = None, None
    if isinstance(source, FactorOfSafety):
        dem_fos, stable = source.value, source.stable_analysis
        failed = source.failed_analysis
        if failed is None:
            why = "the DEM found no failure up to the largest factor it tried: no mechanism"
            return SarmaResult(None, why, None, dem_fos, [], ())
    else:
        failed = source
    if failed.stable or not np.any(failed.unstable):
        return SarmaResult(None, "the analysis found no mechanism to rate", None, dem_fos, [], ())
    system = failed.system
    blocks, faces, joints = system.blocks, system.interfaces, system.model.joints
    modes = failure_modes(failed)
    moving = np.asarray(failed.unstable, dtype=bool) & ~blocks.fixed
    group = np.where(moving, modes.group, -1)
    n_bodies = int(group.max()) + 1
    bodies = [blocks.ids[group == g].tolist() for g in range(n_bodies)]
    bad = {
        m: modes.ids[moving & (modes.code == MODES.index(m))].tolist()
        for m in ("topples", "slides and topples", "falls")
    }
    if bad["topples"] or bad["slides and topples"]:
        # bolted-slope: block 45 "slides and topples" in the DEM's tables was
        # said here to "topple"
        said = [
            f"block(s) {ids_text(bad[m])} {m[:-1] if m == 'topples' else 'slide and topple'}"
            for m in ("topples", "slides and topples")
            if bad[m]
        ]
        why = (
            f"the mechanism rotates: {' and '.join(said)}; Sarma's method rates "
            "sliding of a chain of blocks, not rotation (for toppling on a stepped base "
            "use the Goodman & Bray closed form)"
        )
        return SarmaResult(None, why, None, dem_fos, bodies, ())
    if bad["falls"]:
        why = (
            f"block(s) {ids_text(bad['falls'])} fall free of every contact: there is no "
            "sliding surface to rate"
        )
        return SarmaResult(None, why, None, dem_fos, bodies, ())

    motion = oriented_mechanism(failed).copy()
    motion[~moving] = 0.0
    A, B = faces.block_a, faces.block_b
    ga, gb = group[A], group[B]
    touching = (ga >= 0) | (gb >= 0)
    between = touching & (ga != gb)
    mid = faces.midpoint
    rel = _velocity(blocks, motion, B, mid) - _velocity(blocks, motion, A, mid)
    n_vec, t_vec = faces.normal, faces.tangent
    opening = np.einsum("ij,ij->i", rel, n_vec)
    slip = np.einsum("ij,ij->i", rel, t_vec)
    speed = np.hypot(opening, slip)
    is_open = opening > OPEN_SHARE * speed
    names = [j.name for j in joints]
    current = failed.interfaces.current_name if failed.interfaces.current is not None else None

    # faces: interfaces of one pair of bodies (a < b, -1 the still rock), parallel
    groups: dict[tuple, list[int]] = {}
    flip = np.zeros(faces.n_interfaces, dtype=bool)
    for k in np.flatnonzero(between):
        a, b = int(ga[k]), int(gb[k])
        if a > b:
            a, b = b, a
            flip[k] = True
        nk = -n_vec[k] if flip[k] else n_vec[k]
        angle = np.degrees(np.arctan2(nk[1], nk[0]))
        key = None
        for (pa, pb, open_, ang), _ in groups.items():
            if (pa, pb, open_) == (a, b, bool(is_open[k])):
                d = abs((angle - ang + 180.0) % 360.0 - 180.0)
                if d <= PARALLEL_DEG:
                    key = (pa, pb, open_, ang)
                    break
        groups.setdefault(key or (a, b, bool(is_open[k]), angle), []).append(int(k))

    face_list = []
    sliding = []  # (a, b, normal, tangent, C, tan_phi, slip sign, interfaces)
    for (a, b, open_, _), ks in groups.items():
        ks_arr = np.asarray(ks)
        sign = np.where(flip[ks_arr], -1.0, 1.0)
        L = faces.length[ks_arr]
        normal = (n_vec[ks_arr] * sign[:, None] * L[:, None]).sum(0)
        normal /= np.hypot(*normal)
        tangent = np.array([-normal[1], normal[0]])  # as for interfaces: n = (t_y, -t_x)
        js = faces.joint[ks_arr]
        coh = np.array([joints[j].cohesion for j in js])
        tan_phi = np.tan(np.radians([joints[j].friction_angle for j in js]))
        # slip of b relative to a along the face tangent (flip-invariant)
        s = float(np.sum(rel[ks_arr] @ tangent * sign * L))
        face = SarmaFace(
            interfaces=tuple(ks),
            body_a=a,
            body_b=b,
            kind="base" if a < 0 else "between bodies",
            state="open" if open_ else "sliding",
            length=float(L.sum()),
            joints=tuple(sorted({names[j] for j in js})),
            normal=(float(normal[0]), float(normal[1])),
            dem_state=tuple(str(current[k]) for k in ks) if current is not None else (),
        )
        face_list.append(face)
        if not open_:
            sliding.append(
                (
                    a,
                    b,
                    normal,
                    tangent,
                    float(np.sum(coh * L)),
                    float(np.sum(tan_phi * L) / L.sum()),
                    np.sign(s) or 1.0,
                    len(face_list) - 1,
                )
            )

    # bodies joined by sliding faces are solved together
    links = [(a, b) for a, b, *_ in sliding if a >= 0]
    graph = coo_array(
        (np.ones(len(links)), ([a for a, _ in links], [b for _, b in links])),
        shape=(n_bodies, n_bodies),
    )
    _, comp = connected_components(graph, directed=False)
    f_body = np.zeros((n_bodies, 2))
    weight = np.zeros(n_bodies)
    vx = np.zeros(n_bodies)
    on_blocks = system.f_block[:, :2] + _bolt_forces(system, stable or failed)
    for g in range(n_bodies):
        members = group == g
        f_body[g] = on_blocks[members].sum(0)
        weight[g] = blocks.weight[members].sum()
        vx[g] = float(np.sum(blocks.weight[members] * motion[members, 0]))

    results = []
    for c in np.unique(comp):
        members = np.flatnonzero(comp == c)
        own = [s for s in sliding if s[1] in members]
        out = _solve_component(members, own, f_body, weight, vx)
        results.append(out)
        if out[0] is None:
            return SarmaResult(None, out[2], None, dem_fos, bodies, tuple(face_list))
    # the mechanism fails at the lowest factor of its parts
    best = min(results, key=lambda r: r[0])
    fos, kc = best[0], best[1]
    forces = {i: nf for r in results for i, nf in r[3].items()}  # each at its own factor
    faces_out = tuple(
        replace(f, normal_force=forces[i][0], shear_force=forces[i][1]) if i in forces else f
        for i, f in enumerate(face_list)
    )
    result = SarmaResult(fos, "", kc, dem_fos, bodies, faces_out)
    return replace(result, notes=differences(result, failed, group, joints))


def _bolt_forces(system, analysis) -> np.ndarray:
    """The forces the bolts put on each block, ``(n_blocks, 2)``, as the
    DEM has them in ``analysis`` (the last equilibrium below the limit):
    passive bolts are elements of the DEM, not loads, so Sarma's bodies take
    them as loads (a crossing inside a body cancels).  (Not counted, a
    bolted block read its unbolted factor: 0.82 for the DEM's 1.78.)"""
    out = np.zeros((system.blocks.n_blocks, 2))
    if system.bolts is None:
        return out
    asm, free = system.assembly, ~system.blocks.fixed
    q = np.zeros(asm.n_dof)
    q[asm.dof[free].ravel()] = analysis.displacement[free].ravel()
    # on the blocks (the springs' resistance), from where each was installed
    pull = -system.bolts.internal_force(q, analysis.state.bolt_reference)
    out[free] = pull[asm.dof[free][:, :2]]
    return out


def _solve_component(members, own, f_body, weight, vx):
    """Factor of safety of one group of bodies joined by sliding faces.

    Returns ``(fos, Kc at F = 1, reason, {face index: (N, S)})``.
    """
    index = {int(g): i for i, g in enumerate(members)}
    n_eq = 2 * len(members)
    n_unknown = len(own) + 1
    if n_unknown != n_eq:
        what = "more" if n_unknown > n_eq else "fewer"
        return (
            None,
            None,
            f"the mechanism has {len(members)} rigid bodies and {len(own)} sliding faces: "
            f"{what} unknowns than Sarma's {n_eq} equations (a chain of n bodies has n base "
            "faces and n - 1 faces between them); no single limit-equilibrium factor",
            {},
        )
    direction = np.sign(vx[members].sum()) or 1.0

    def system_at(F):
        M = np.zeros((n_eq, n_unknown))
        rhs = np.zeros(n_eq)
        for col, (a, b, n, t, C, tp, s, _) in enumerate(own):
            # force on b: N n + S t, S = -s (C + N tan phi) / F
            per_N = n - s * tp / F * t
            const = -s * C / F * t
            for body, sgn in ((b, 1.0), (a, -1.0)):
                if body < 0:
                    continue
                r = 2 * index[body]
                M[r : r + 2, col] += sgn * per_N
                rhs[r : r + 2] -= sgn * const
        for g, i in index.items():
            M[2 * i, -1] = direction * weight[g]
            rhs[2 * i : 2 * i + 2] -= f_body[g]
        return M, rhs

    def solve(F):
        M, rhs = system_at(F)
        try:
            x = np.linalg.solve(M, rhs)
        except np.linalg.LinAlgError:
            return None
        if not np.all(np.isfinite(x)) or np.linalg.cond(M) > 1e12:
            return None
        return x

    def kc(F):
        x = solve(F)
        return np.nan if x is None else x[-1]

    x1 = solve(1.0)
    if x1 is None:
        return (None, None, "the faces of the mechanism give a singular system", {})
    grid = np.geomspace(*F_RANGE, 161)
    values = np.array([kc(F) for F in grid])
    ok = np.isfinite(values)
    if not ok.any():
        return (None, None, "the faces of the mechanism give a singular system", {})
    if values[ok][0] <= 0:
        return (
            None,
            float(x1[-1]),
            f"no limit equilibrium even with the strengths x {1 / F_RANGE[0]:g}: "
            "the loads drive the mechanism whatever the strength",
            {},
        )
    if values[ok][-1] > 0:
        fos = float("inf")
        x = x1
    else:
        fos = _largest_root(kc, grid, values)
        if fos is None:
            return (None, float(x1[-1]), "the faces of the mechanism give a singular system", {})
        x = solve(fos)
    total = float(weight[members].sum())
    forces = {}
    for col, (_, _, _, _, C, tp, s, i) in enumerate(own):
        N = float(x[col])
        F = fos if np.isfinite(fos) else 1.0
        forces[i] = (N, float(-s * (C + N * tp) / F))
    tension = [i for i, (N, _) in forces.items() if N < -TENSION_SHARE * total]
    if tension:
        return (
            None,
            float(x1[-1]),
            f"at the limit {len(tension)} sliding face(s) would carry tension: those "
            "blocks would separate, the mechanism Sarma assumes is not admissible",
            {},
        )
    return fos, float(x1[-1]), "", forces


def _largest_root(kc, grid, values) -> float | None:
    """The largest factor at which ``kc`` falls through zero (+ to -): the
    limit the full-strength state is connected to.  Sign changes through a
    pole (where tan(phi) / F makes a chain's system singular, at F ~ 0.2-0.5
    for wedge chains) are skipped: there ``kc`` does not vanish.  (The first
    change from F = 0.02 up was taken: on three-wedge chains it was beside
    such a pole, with tensile faces, and every mechanism was refused.)"""
    from scipy.optimize import brentq  # 0.13 s to import: not at start-up

    ok = np.isfinite(values)
    change = np.flatnonzero(ok[:-1] & ok[1:] & (values[:-1] > 0) & (values[1:] <= 0))
    scale = float(np.median(np.abs(values[ok]))) or 1.0
    for k in change[::-1]:
        root = float(brentq(kc, grid[k], grid[k + 1], xtol=1e-12))
        if abs(kc(root)) <= 1e-6 * scale:
            return root
    return None
