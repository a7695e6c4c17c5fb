"""Models with closed-form answers (docs/method.md, section 5), and generated test slopes.

These builders are used by the verification tests, the benchmarks and the
examples.  Each returns a :class:`~rockdem.model.Model` built from explicit
polygons; the closed forms are plain functions beside them.
"""

from __future__ import annotations

import numpy as np
import shapely

from .blocks import Blocks
from .joints import Joint
from .model import Loads, Model, Settings


def _rot(deg: float) -> np.ndarray:
    d = np.radians(deg)
    return np.array([[np.cos(d), -np.sin(d)], [np.sin(d), np.cos(d)]])


# ------------------------------------------------------------- single block
def block_on_plane(
    dip: float,
    joint: Joint,
    *,
    width: float = 2.0,
    height: float = 1.0,
    unit_weight: float = 25.0,
    loads: Loads | None = None,
    settings: Settings | None = None,
) -> Model:
    """A ``width x height`` block on a fixed plane dipping ``dip`` degrees toward +x."""
    R = _rot(-dip)
    ground = np.array(
        [(-4 * width, -height), (4 * width, -height), (4 * width, 0), (-4 * width, 0)]
    )
    block = np.array([(0, 0), (width, 0), (width, height), (0, height)])
    blocks = Blocks.from_polygons(
        [ground @ R.T, block @ R.T], fixed=[True, False], unit_weight=unit_weight
    )
    return Model(blocks, joint, loads=loads or Loads(), settings=settings or Settings())


def sliding_fos(dip, phi, *, cohesion=0.0, length=1.0, weight=1.0, k=0.0) -> float:
    """Factor of safety of a block on a plane (limit equilibrium).

    ``(c L + W (cos d - k sin d) tan phi) / (W (sin d + k cos d))`` with a
    horizontal pseudo-static coefficient ``k`` acting down the dip.
    """
    d, p = np.radians(dip), np.radians(phi)
    return (cohesion * length + weight * (np.cos(d) - k * np.sin(d)) * np.tan(p)) / (
        weight * (np.sin(d) + k * np.cos(d))
    )


# ------------------------------------------------------------------ toppling
def toppling_block(
    dip: float, width: float, height: float, friction_angle: float = 80.0, kn: float = 1e6
) -> Model:
    """A ``width x height`` block on a base dipping ``dip``; it topples iff
    ``width / height < tan(dip)`` (friction high enough not to slide)."""
    return block_on_plane(
        dip, Joint(normal_stiffness=kn, friction_angle=friction_angle), width=width, height=height
    )


def toppling_staircase(
    heights,
    *,
    width: float,
    step: float,
    base_dip: float,
    joint: Joint,
    unit_weight: float,
    loads: Loads | None = None,
    settings: Settings | None = None,
) -> Model:
    """Goodman & Bray's (1976) blocks on a stepped base, as rigid DEM blocks.

    Block ``k`` (ids 1 = toe ... n; the ground is id 0) stands on the tread
    ``[(k - 1) width, k width]`` up the dip of the treads (``base_dip``
    degrees toward +x), ``(k - 1) step`` above the toe's tread, and is
    ``heights[k - 1]`` tall (:func:`rockdem.limit_equilibrium.closed_forms.stepped_heights`
    for a regular slope).  The fixed ground follows the steps and reaches
    two widths beyond the blocks on either side and below the lowest step,
    so :func:`~rockdem.limit_equilibrium.closed_forms.toppling_fos` on the
    same arguments is the limit-equilibrium answer for this model.
    """
    y = np.asarray(heights, dtype=float)
    n = len(y)
    p = np.radians(base_dip)
    up = np.array([-np.cos(p), np.sin(p)])  # up the dip of the treads
    normal = np.array([np.sin(p), np.cos(p)])

    def at(s, t):
        return s * up + t * normal

    blocks = [
        [
            at(k * width, k * step),
            at((k + 1) * width, k * step),
            at((k + 1) * width, k * step + y[k]),
            at(k * width, k * step + y[k]),
        ]
        for k in range(n)
    ]
    line = [at(-2 * width, 0.0)]
    for k in range(n):
        line += [at(k * width, k * step), at((k + 1) * width, k * step)]
    line.append(at((n + 2) * width, (n - 1) * step))
    bottom = min(q[1] for q in line) - 2 * width
    ground = [*line, np.array([line[-1][0], bottom]), np.array([line[0][0], bottom])]
    return Model(
        Blocks.from_polygons(
            [ground, *blocks], fixed=[True] + [False] * n, unit_weight=unit_weight, ids=range(n + 1)
        ),
        joint,
        loads=loads or Loads(),
        settings=settings or Settings(),
    )


# ---------------------------------------------------------- two-block wedge
def wedge_thrust(w1, w2, d1, d2, p1, p2, p3) -> float:
    """Thrust the passive block needs (seed paper Eq. 7; > 0 means unstable)."""
    d1, d2, p1, p2, p3 = np.radians([d1, d2, p1, p2, p3])
    num = w1 * np.sin(d1 - p1) * np.cos(d2 - p2 - p3) + w2 * np.sin(d2 - p2) * np.cos(d1 - p1 - p3)
    return num / (np.cos(d2 - p2) * np.cos(d1 - p1 - p3))


def wedge_fos(w1, w2, d1, d2, p1, p2, p3) -> float:
    """Strength-reduction factor of safety of the two-block wedge.

    The factor ``f`` dividing all three ``tan(phi)`` that makes the thrust
    zero; where the interface force at that root is tensile the blocks
    separate and the weaker single block governs (docs/method.md, section 5).
    """

    def reduced(f):
        return [np.degrees(np.arctan(np.tan(np.radians(p)) / f)) for p in (p1, p2, p3)]

    def thrust(f):
        return wedge_thrust(w1, w2, d1, d2, *reduced(f))

    with np.errstate(divide="ignore"):  # a flat plane (d2 = 5e-324): the block holds
        single = min(
            np.tan(np.radians(p1)) / np.tan(np.radians(d1)),
            np.tan(np.radians(p2)) / np.tan(np.radians(d2)),
        )
    from scipy.optimize import brentq  # 0.13 s to import: not at start-up

    f = brentq(thrust, 0.2, 5.0, xtol=1e-12)
    q1, _, q3 = np.radians(reduced(f))
    d = np.radians(d1)
    # force the active block passes to the passive one (compression > 0)
    push = w1 * np.sin(d - q1) / np.cos(d - q1 - q3)
    return f if push >= 0 else single


def two_block_wedge(
    p1: float,
    p2: float,
    p3: float = 35.0,
    *,
    w1: float = 200.0,
    w2: float = 75.0,
    d1: float = 37.0,
    d2: float = 27.0,
    kn: float = 1e5,
    settings: Settings | None = None,
) -> Model:
    """The seed paper's verification wedge (section 5), units t and m.

    An active block (weight ``w1``) on a plane dipping ``d1``, a passive block
    (``w2``) on a plane dipping ``d2``, a vertical joint between them;
    friction ``p1``, ``p2``, ``p3`` on the upper, lower and vertical joint.
    Both blocks are parallelograms 10 m along the dip with vertical sides,
    so their weights come from the unit weights.
    """
    t1, t2 = np.tan(np.radians(d1)), np.tan(np.radians(d2))
    L, h1, h2 = 10.0, 4.0, 3.0
    active = [(-L, L * t1), (0, 0), (0, h1), (-L, L * t1 + h1)]
    passive = [(0, 0), (L, -L * t2), (L, -L * t2 + h2), (0, h2)]
    ground = [
        (-1.5 * L, 1.5 * L * t1),
        (0, 0),
        (1.5 * L, -1.5 * L * t2),
        (1.5 * L, -1.5 * L * t2 - 5),
        (-1.5 * L, -1.5 * L * t2 - 5),
    ]
    blocks = Blocks.from_polygons(
        [ground, active, passive],
        fixed=[True, False, False],
        unit_weight=[1.0, w1 / (L * h1), w2 / (L * h2)],
    )
    joints = tuple(
        Joint(normal_stiffness=kn, friction_angle=p, name=name)
        for p, name in ((p1, "upper"), (p2, "lower"), (p3, "vertical"))
    )
    lines = [[(-2 * L, 2 * L * t1), (0, 0)], [(0, 0), (2 * L, -2 * L * t2)], [(0, 0), (0, 10)]]
    return Model(
        blocks,
        joints,
        joint_lines=np.array(lines),
        line_joint=["upper", "lower", "vertical"],
        settings=settings or Settings(load_steps=1),
        name="two-block wedge",
    )


# --------------------------------------------------------- jointed slopes
def _cut_convex(section: shapely.Polygon, cells: np.ndarray) -> list[np.ndarray]:
    """Clip cell polygons (array of shapely Polygons) by a convex section."""
    pieces = shapely.intersection(cells, section)
    area = shapely.area(pieces)
    pieces = pieces[area > 1e-6 * section.area]
    keep = shapely.get_type_id(pieces) == 3  # Polygon
    out = shapely.get_coordinates(shapely.get_exterior_ring(pieces[keep]), return_index=True)
    xy, idx = out
    splits = np.flatnonzero(np.diff(idx)) + 1
    rings = np.split(xy, splits)
    return [r[:-1] for r in rings]


def bedding_slope(
    *,
    height: float = 20.0,
    face_angle: float = 60.0,
    bedding_dip: float = 30.0,
    bedding_spacing: float = 1.0,
    cross_dip: float = 90.0,
    cross_spacing: float = 1.5,
    behind: float = 30.0,
    friction_angle: float = 40.0,
    kn: float = 1e6,
    unit_weight: float = 26.0,
    stagger: bool = False,
    settings: Settings | None = None,
) -> Model:
    """A slope cut by bedding dipping out of the face and a set of cross joints.

    The section is the convex quadrilateral above the toe level (crest at
    x = 0, face dipping ``face_angle`` toward +x); everything below the toe
    and behind the back (x = -behind) is fixed ground.  Dips follow the
    geometry convention (``(cos dip, -sin dip)`` along the trace).  Spacings
    are measured normal to the joints.  ``stagger`` offsets the cross joints
    by half a cell in every other layer (a brick pattern).

    With vertical cross joints (the default) the only mechanism is sliding
    of the layers that daylight in the face, at ``tan(phi) / tan(bedding_dip)``.
    Cross joints perpendicular to the bedding (120 degrees here) admit a
    block-toppling-and-sliding mechanism near the crest with a lower factor
    (about 1.36 by the equilibrium LP for 3 m x 4.5 m blocks).
    """
    toe_x = height / np.tan(np.radians(face_angle))
    section = shapely.Polygon([(-behind, 0), (toe_x, 0), (0, height), (-behind, height)])
    d1 = np.array([np.cos(np.radians(bedding_dip)), -np.sin(np.radians(bedding_dip))])
    d2 = np.array([np.cos(np.radians(cross_dip)), -np.sin(np.radians(cross_dip))])
    sin = abs(d1[0] * d2[1] - d1[1] * d2[0])
    u = d1 * cross_spacing / sin  # one cell along the bedding
    v = d2 * bedding_spacing / sin  # one cell along the cross joints
    # lattice coordinates of the section's corners give the index range
    corners_xy = np.asarray(section.exterior.coords)
    ij = np.linalg.solve(np.column_stack([u, v]), corners_xy.T).T
    lo, hi = np.floor(ij.min(axis=0)) - 2, np.ceil(ij.max(axis=0)) + 2
    I, J = np.meshgrid(np.arange(lo[0], hi[0]), np.arange(lo[1], hi[1]))
    I = I + (0.5 * (J % 2) if stagger else 0.0)
    origin = I[..., None] * u + J[..., None] * v
    corners = np.stack([origin, origin + u, origin + u + v, origin + v], axis=-2).reshape(-1, 4, 2)
    polys = _cut_convex(section, shapely.polygons(corners))
    # fixed ground: below the toe level and behind the back of the section
    ground = [
        (-behind - 5, -5),
        (toe_x + 20, -5),
        (toe_x + 20, 0),
        (-behind, 0),
        (-behind, height + 5),
        (-behind - 5, height + 5),
    ]
    blocks = Blocks.from_polygons(
        [ground, *polys],
        fixed=[True] + [False] * len(polys),
        unit_weight=unit_weight,
        check_overlap=False,
    )
    joint = Joint(normal_stiffness=kn, friction_angle=friction_angle, name="joint")
    return Model(blocks, joint, settings=settings or Settings(load_steps=1), name="bedding slope")


def brick_slope(
    n_blocks: int,
    *,
    friction_angle: float = 35.0,
    bedding_dip: float = 20.0,
    face_angle: float = 70.0,
    kn: float = 1e6,
    settings: Settings | None = None,
) -> Model:
    """A brick-pattern slope with about ``n_blocks`` blocks, for benchmarks.

    Bedding dipping ``bedding_dip`` out of the face, vertical cross joints
    staggered by half a brick from layer to layer (bricks twice as long as
    high).  The layers that daylight slide at ``tan(phi) / tan(bedding_dip)``
    (1.92 by default), so the benchmark is also a check at scale.

    ``kn`` is the joints' stiffness at 1,000 blocks; smaller blocks get
    stiffer joints (x sqrt(n_blocks / 1000), 1 / the spacing), so that the
    rock mass is as stiff at every size (with ``kn`` at every size, the
    94,533-block slope's back column settled past the fixed boundary by 0.57
    block sizes under gravity, beyond small displacements).
    """
    height = 20.0
    behind = 2 * height
    area = height * behind + 0.5 * height * height / np.tan(np.radians(face_angle))
    size = np.sqrt(area / n_blocks / 2.0)
    kn = kn * np.sqrt(n_blocks / 1000.0)
    return bedding_slope(
        height=height,
        face_angle=face_angle,
        bedding_dip=bedding_dip,
        bedding_spacing=size,
        cross_spacing=2 * size,
        behind=behind,
        friction_angle=friction_angle,
        kn=kn,
        stagger=True,
        settings=settings,
    )
