"""The model: blocks, joint properties, loads and analysis settings.

Immutable; analyses take a model and return results, never write into it,
so strength-reduction and stabilisation trials can reuse it safely.
Units are the user's, consistent throughout (for example kN, m, kPa, or
t, m, t/m^2); angles in degrees.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from .blocks import Blocks
from .bolts import Bolt
from .errors import InputError
from .joints import Joint
from .springs import POINTS_RANGE


@dataclass(frozen=True)
class PointLoad:
    """A force ``(fx, fy)`` at ``(x, y)`` on the block it pushes into.

    ``support=True`` marks a bolt or anchor force (reported apart, and the
    quantity the stabilisation search scales).
    """

    x: float
    y: float
    fx: float
    fy: float
    support: bool = False
    name: str = ""

    def __post_init__(self) -> None:
        where = f"point load {self.name}".rstrip()
        for key in ("x", "y", "fx", "fy"):
            object.__setattr__(self, key, _finite(f"{where} {key}", getattr(self, key)))
        for key in ("fx", "fy"):  # (found by fuzzing: 1e300 gave 228,106 RuntimeWarnings)
            if abs(getattr(self, key)) > MAX_FORCE:
                raise InputError(
                    f"{where} {key}", f"{getattr(self, key):g} is out of range", "give <= 1e15"
                )

    @classmethod
    def anchor(cls, x: float, y: float, force: float, angle: float, name: str = "") -> PointLoad:
        """A support force of magnitude ``force`` acting at ``angle`` degrees
        counter-clockwise from +x (for example 195 = 180 + 15 pulls a face
        that looks toward +x back into the slope, 15 degrees below the
        horizontal, as an anchor drilled downward does)."""
        where = f"point load {name}".rstrip()
        force, angle = _finite(f"{where} force", force), _finite(f"{where} angle", angle)
        if force < 0:  # (found by fuzzing: it reversed the direction without a word)
            raise InputError(
                f"{where} force", f"{force:g} is negative", "give its size; the angle gives the way"
            )
        a = np.radians(angle)
        return cls(x, y, force * np.cos(a), force * np.sin(a), support=True, name=name)


@dataclass(frozen=True)
class LineLoad:
    """A traction ``(qx, qy)`` (force per unit length) on the block boundary
    along the segment ``start -> end`` (for example a foundation).

    ``q_end``: the traction at ``end`` for a linearly varying load (a
    trapezoid from ``(qx, qy)`` at ``start``: water on a face, a fill);
    None: uniform.
    """

    start: tuple[float, float]
    end: tuple[float, float]
    qx: float
    qy: float
    name: str = ""
    q_end: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        where = f"line load {self.name}".rstrip()
        for key in ("start", "end"):  # (found by fuzzing: NaN was a GEOSException)
            point = getattr(self, key)
            if isinstance(point, str | bytes) or np.size(point) != 2:
                raise InputError(f"{where} {key}", f"{point!r} is not a point", "give (x, y)")
            xy = tuple(_finite(f"{where} {key}", v) for v in np.ravel(point))
            object.__setattr__(self, key, xy)
        for key in ("qx", "qy"):
            value = _finite(f"{where} {key}", getattr(self, key))
            if abs(value) > MAX_FORCE:
                raise InputError(f"{where} {key}", f"{value:g} is out of range", "give <= 1e15")
            object.__setattr__(self, key, value)
        if self.q_end is not None:
            q = tuple(_finite(f"{where} q_end", v) for v in np.ravel(self.q_end))
            if len(q) != 2 or max(map(abs, q)) > MAX_FORCE:
                raise InputError(
                    f"{where} q_end", f"{self.q_end!r} is not a traction", "give (qx, qy)"
                )
            object.__setattr__(self, "q_end", q)

    def traction(self, t: np.ndarray) -> np.ndarray:
        """The traction at fractions ``t`` of the way from start to end, (n, 2)."""
        q0 = np.array([self.qx, self.qy], dtype=float)
        q1 = q0 if self.q_end is None else np.asarray(self.q_end, dtype=float)
        t = np.asarray(t, dtype=float)[:, None]
        return (1.0 - t) * q0 + t * q1


@dataclass(frozen=True)
class Loads:
    """External loads besides self-weight.

    Parameters
    ----------
    gravity : bool
        Self-weight at each block's centroid (unit weight x area).
    seismic_h : float
        Pseudo-static horizontal coefficient: a force ``kh W`` toward +x.
    seismic_v : float
        Pseudo-static vertical coefficient: a force ``kv W`` downward.
    points, lines : sequences of PointLoad, LineLoad
    water_table : sequence of (x, y), optional
        Phreatic line, left to right (level beyond its ends).  Every joint
        below it carries the hydrostatic pressure ``u = gamma_w (h(x) - y)``
        on both its faces; the springs carry the effective stress.
    water_unit_weight : float
        ``gamma_w`` in the model's units (9.81 kN/m^3, 1.0 t/m^3); required
        with a water table.
    pore_pressure_ratio : float
        ``r_u`` for a quick check instead of a water table: every joint
        carries ``u = r_u gamma (s(x) - y)``, ``s`` the top of the rock above
        the point and ``gamma`` the free rock's mean unit weight
        (:func:`rockdem.loads.joint_water`).
    """

    gravity: bool = True
    seismic_h: float = 0.0
    seismic_v: float = 0.0
    points: tuple[PointLoad, ...] = ()
    lines: tuple[LineLoad, ...] = ()
    water_table: tuple[tuple[float, float], ...] = ()
    water_unit_weight: float = 0.0
    pore_pressure_ratio: float = 0.0

    def __post_init__(self) -> None:
        # (found by fuzzing: gravity="no" was truthy, gravity on; "0.1" for a
        # coefficient was a numpy TypeError)
        if not isinstance(self.gravity, bool | np.bool_):
            raise InputError(
                "loads gravity", f"{self.gravity!r} is not True or False", "give a bool"
            )
        for key in ("seismic_h", "seismic_v", "water_unit_weight", "pore_pressure_ratio"):
            object.__setattr__(self, key, _number(f"loads {key}", getattr(self, key)))
        for key, kind in (("points", PointLoad), ("lines", LineLoad)):
            items = getattr(self, key)
            if isinstance(items, str | bytes | dict) or not hasattr(items, "__iter__"):
                raise InputError(
                    f"loads {key}", f"{items!r} is not a list", f"give {kind.__name__}s"
                )
            odd = [i for i, item in enumerate(items) if not isinstance(item, kind)]
            if odd:
                raise InputError(
                    f"loads {key}[{odd[0]}]",
                    f"{items[odd[0]]!r} is not a {kind.__name__}",
                    f"make it with rockdem.{kind.__name__}",
                )
        if isinstance(self.water_table, str | bytes):
            raise InputError("loads water_table", "is text", "give a list of (x, y) points")
        for key in ("seismic_h", "seismic_v"):
            v = getattr(self, key)
            if not np.isfinite(v) or abs(v) >= 1.0:
                raise InputError(f"loads {key}", f"{v} is out of range", "use |k| < 1")
        object.__setattr__(self, "points", tuple(self.points))
        object.__setattr__(self, "lines", tuple(self.lines))
        ru = self.pore_pressure_ratio
        if not (np.isfinite(ru) and 0.0 <= ru < 1.0):
            raise InputError(
                "loads pore_pressure_ratio", f"{ru} is out of range", "use 0 <= r_u < 1"
            )
        if ru and self.water_table:
            raise InputError(
                "loads pore_pressure_ratio",
                "is given with a water table",
                "give either a water table or a pore-pressure ratio",
            )
        table = tuple((float(x), float(y)) for x, y in self.water_table)
        object.__setattr__(self, "water_table", table)
        if table:
            xy = np.asarray(table)
            if len(xy) < 2 or not np.isfinite(xy).all() or np.any(np.diff(xy[:, 0]) <= 0):
                raise InputError(
                    "loads water_table",
                    "needs two or more finite points with x increasing",
                    "give the phreatic line left to right",
                )
            gw = self.water_unit_weight
            if not (np.isfinite(gw) and gw > 0):
                raise InputError(
                    "loads water_unit_weight",
                    "is 0 or missing: a water table needs it"
                    if gw == 0
                    else f"{gw} is not a positive unit weight",
                    "give the unit weight of water in the model's units (9.81 kN/m^3, 1 t/m^3)",
                )


#: largest force or traction (the model file's range)
MAX_FORCE = 1e15


def _finite(where: str, value) -> float:
    """``value`` as a finite float (see :func:`_number`)."""
    v = _number(where, value)
    if not np.isfinite(v):
        raise InputError(where, f"{v} is not finite", "give a finite number")
    return v


def _number(where: str, value) -> float:
    """``value`` as a float; an InputError naming ``where`` for text, None, a bool."""
    if isinstance(value, str | bytes | bool | np.bool_) or value is None:
        raise InputError(where, f"{value!r} is not a number", "give a number")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise InputError(where, f"{value!r} is not a number", "give a number") from None


#: Most load steps and Newton iterations per solve (every count of work is bounded).
MAX_LOAD_STEPS = 1000
MAX_ITERATIONS = 1000
#: Range of the equilibrium tolerance: below 1e-12 round-off decides, not equilibrium.
TOLERANCE_RANGE = (1e-12, 1e-2)


def check_count(where: str, value, top: int) -> int:
    """``value`` as a whole number from 1 to ``top`` (InputError naming ``where``)."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise InputError(where, f"{value!r} is not a whole number", f"use 1 to {top}")
    if not 1 <= value <= top:
        raise InputError(where, f"{value} is out of range", f"use 1 to {top}")
    return int(value)


@dataclass(frozen=True)
class Settings:
    """How the equations are integrated and solved.

    Parameters
    ----------
    quadrature : {"lobatto", "gauss"}
        Spring point rule; Lobatto includes the interface ends (exact pivoting).
    points_per_interface : int
        3 with Lobatto is Simpson's rule (the default).
    load_steps : int
        Increments of the loads (gravity applied in steps, as in the paper).
        With c = 0 and no tensile strength the answer does not depend on it.
    tolerance : float
        Equilibrium when the scaled out-of-balance force is below
        ``tolerance`` x the scaled external force.
    max_iterations : int
        Newton iterations per solve before the step is declared failed.
    reduce_tensile : bool
        Divide the tensile strength by the trial factor in strength reduction
        (as cohesion and tan(phi) are).
    """

    quadrature: str = "lobatto"
    points_per_interface: int = 3
    load_steps: int = 5
    tolerance: float = 1e-8
    max_iterations: int = 100
    reduce_tensile: bool = True

    def __post_init__(self) -> None:
        check_count("settings load_steps", self.load_steps, MAX_LOAD_STEPS)
        check_count("settings max_iterations", self.max_iterations, MAX_ITERATIONS)
        if self.quadrature not in POINTS_RANGE:
            raise InputError(
                "settings quadrature",
                f"unknown rule {self.quadrature!r}",
                f"use one of {', '.join(POINTS_RANGE)}",
            )
        n, (fewest, most) = self.points_per_interface, POINTS_RANGE[self.quadrature]
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or not fewest <= n <= most:
            raise InputError(
                "settings points_per_interface",
                f"{n!r} is not offered by the {self.quadrature} rule",
                f"use {fewest} to {most}",
            )
        if not isinstance(self.reduce_tensile, bool | np.bool_):
            raise InputError(
                "settings reduce_tensile",
                f"{self.reduce_tensile!r} is not true or false",
                "use True or False",
            )
        lo, hi = TOLERANCE_RANGE
        if not isinstance(self.tolerance, int | float | np.floating) or isinstance(
            self.tolerance, bool
        ):
            raise InputError(
                "settings tolerance",
                f"{self.tolerance!r} is not a number",
                f"use {lo:g} to < {hi:g}",
            )
        if not lo <= self.tolerance < hi:
            raise InputError(
                "settings tolerance", f"{self.tolerance} is out of range", f"use {lo:g} to < {hi:g}"
            )


@dataclass(frozen=True)
class Model:
    """A slope section ready to analyse.

    Parameters
    ----------
    blocks : Blocks
    joints : Joint or sequence of Joint
        Joint property table.  The first entry is the default of every
        interface not on a listed line and not touching the ground.
    joint_lines : array (m, 2, 2), optional
        Segments (joint traces); an interface lying on segment ``i`` takes
        joint ``line_joint[i]`` (an index or a joint name).
    line_joint : sequence of int or str, optional
    ground : int or str, optional
        Joint used on every contact with a fixed block.
    loads : Loads
    settings : Settings
    name : str
    bolts : sequence of Bolt
        Passive bolts and cables (:mod:`rockdem.bolts`).

    Examples
    --------
    >>> from rockdem import Blocks, Joint, Model
    >>> ground = [(-5, -1), (5, -1), (5, 0), (-5, 0)]
    >>> block = [(0, 0), (1, 0), (1, 1), (0, 1)]
    >>> m = Model(Blocks.from_polygons([ground, block], fixed=[True, False], unit_weight=25),
    ...           Joint(normal_stiffness=1e6, friction_angle=30))
    >>> m
    <Model: 2 blocks, 1 joint types>
    """

    blocks: Blocks
    joints: Joint | Sequence[Joint]
    joint_lines: np.ndarray | None = None
    line_joint: Sequence[int | str] | None = None
    ground: int | str | None = None
    loads: Loads = field(default_factory=Loads)
    settings: Settings = field(default_factory=Settings)
    name: str = "model"
    bolts: Sequence[Bolt] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.blocks, Blocks):
            raise InputError(
                "model blocks",
                f"{type(self.blocks).__name__} is not rockdem Blocks",
                "make them with rockdem.Blocks.from_polygons",
            )
        if not isinstance(self.loads, Loads):  # (found by fuzzing: a dict, then AttributeError)
            raise InputError(
                "model loads",
                f"{self.loads!r} is not rockdem Loads",
                "make them with rockdem.Loads",
            )
        bolts = self.bolts
        if isinstance(bolts, str | bytes | dict) or not hasattr(bolts, "__iter__"):
            raise InputError("model bolts", f"{bolts!r} is not a list", "give rockdem.Bolt objects")
        object.__setattr__(self, "bolts", tuple(bolts))
        odd = [i for i, b in enumerate(self.bolts) if not isinstance(b, Bolt)]
        if odd:
            raise InputError(
                f"model bolts[{odd[0]}]",
                f"{self.bolts[odd[0]]!r} is not a Bolt",
                "give rockdem.Bolt",
            )
        given = self.joints
        if isinstance(given, Joint):
            joints = (given,)
        elif isinstance(given, str | bytes | dict) or not hasattr(given, "__iter__"):
            raise InputError(
                "model joints", f"{given!r} is not a Joint", "give a Joint or a list of Joints"
            )
        else:
            joints = tuple(given)
        if not joints:
            raise InputError("model joints", "no joint properties", "give at least one Joint")
        odd = [i for i, j in enumerate(joints) if not isinstance(j, Joint)]
        if odd:
            raise InputError(
                f"model joints[{odd[0]}]",
                f"{joints[odd[0]]!r} is not a Joint",
                "give rockdem.Joint objects",
            )
        object.__setattr__(self, "joints", joints)
        if self.ground is not None:
            object.__setattr__(self, "ground", self.joint_index(self.ground))
        if self.joint_lines is None and self.line_joint is not None:
            raise InputError(  # (hostile round 7: ignored, silently)
                "model line_joint",
                "is given without joint_lines: it names the joint of each line",
                "give joint_lines too, or leave line_joint out",
            )
        if self.joint_lines is not None:
            try:
                lines = np.asarray(self.joint_lines, dtype=float).reshape(-1, 2, 2)
            except (TypeError, ValueError):
                lines = np.full((1, 2, 2), np.nan)
            if not np.isfinite(lines).all():  # (found by fuzzing: NaN was a GEOSException)
                raise InputError(
                    "model joint_lines",
                    "are not pairs of finite points",
                    "give [((x0, y0), (x1, y1)), ...]",
                )
            if self.line_joint is None or len(self.line_joint) != len(lines):
                raise InputError("model line_joint", "needs one joint per line", "list them")
            idx = tuple(self.joint_index(j) for j in self.line_joint)
            object.__setattr__(self, "joint_lines", lines)
            object.__setattr__(self, "line_joint", idx)

    def joint_index(self, key: int | str) -> int:
        """Position of a joint in the table, by index or by name."""
        if isinstance(key, str):
            names = [j.name for j in self.joints]
            if key not in names:
                raise InputError(f"joint {key!r}", "is not defined", f"use one of {names}")
            if names.count(key) > 1:  # (hostile round 7: the first was taken, silently)
                at = [i for i, n in enumerate(names) if n == key]
                raise InputError(
                    f"joint {key!r}",
                    f"names joints {at[0]} and {at[1]} of the table",
                    "give the joint by its index, or give the joints names of their own",
                )
            return names.index(key)
        # (hostile round 7: ground=1.5 and ground=True were joint 1)
        if isinstance(key, bool) or not isinstance(key, numbers.Integral):
            raise InputError(
                f"joint {key!r}", "is no index or name", "give the joint's index or its name"
            )
        if not 0 <= int(key) < len(self.joints):
            raise InputError(f"joint {key}", "index out of range", "use a defined joint")
        return int(key)

    def replace(self, **changes) -> Model:
        """A copy with some fields changed."""
        return replace(self, **changes)

    def __repr__(self) -> str:
        return f"<Model: {self.blocks.n_blocks:,} blocks, {len(self.joints)} joint types>"
