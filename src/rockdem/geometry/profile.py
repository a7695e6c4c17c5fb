"""Slope profiles: the ground surface of the section, as a polyline.

The slope **faces +x**: the crest and the upper slope are on the left, the
toe on the right.  A profile lists its points left to right (x never
decreasing; a vertical step is allowed, an overhang is not).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from ..errors import InputError

#: a benched profile has at most this many benches (each is two profile points)
MAX_BENCHES = 10_000

__all__ = ["Profile"]


@dataclass(frozen=True, eq=False)
class Profile:
    """The ground surface of a slope section, listed left to right.

    Parameters
    ----------
    points : sequence of (x, y)
        At least two points; x must not decrease and the polyline must not
        cross or touch itself.

    Raises
    ------
    InputError
        Fewer than two points, coordinates that are not finite, a polyline
        that crosses itself, or x decreasing.

    Examples
    --------
    >>> p = Profile([(0, 10), (5, 10), (10, 0), (15, 0)])
    >>> p.n_points, p.x_range, p.height
    (4, (0.0, 15.0), 10.0)
    >>> round(p.y_at(7.5), 9)
    5.0
    """

    points: np.ndarray

    def __post_init__(self) -> None:
        try:
            xy = np.array(self.points, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InputError("profile", "points are not numbers", "give (x, y) pairs") from exc
        if xy.ndim != 2 or xy.shape[1] != 2 or len(xy) < 2:
            raise InputError("profile", "needs at least 2 (x, y) points", "give a polyline")
        if not np.isfinite(xy).all():
            raise InputError("profile", "has a coordinate that is not finite", "fix the point")
        span = float(np.hypot(*(xy.max(axis=0) - xy.min(axis=0)))) or 1.0
        # coordinates near underflow (1e-308) break GEOS's robust predicates: snap them to 0
        xy[np.abs(xy) < 1e-100 * span] = 0.0
        step = np.hypot(*np.diff(xy, axis=0).T)
        keep = np.concatenate([[True], step > 1e-12 * span])
        xy = xy[keep]
        if len(xy) < 2:
            raise InputError("profile", "all points coincide", "give distinct points")
        line = shapely.LineString(xy)
        if not shapely.is_simple(line):
            # locate a crossing for the message
            segs = shapely.linestrings(np.stack([xy[:-1], xy[1:]], axis=1))
            tree = shapely.STRtree(segs)
            a, b = tree.query(segs, predicate="intersects")
            m = b > a + 1
            where = ""
            if m.any():
                pt = shapely.intersection(segs[a[m][0]], segs[b[m][0]])
                c = shapely.get_coordinates(pt)[0]
                where = f" near ({c[0]:.6g}, {c[1]:.6g})"
            elif np.any(np.isclose(xy[1:-1], xy[0]).all(axis=1)):
                where = ""
            raise InputError(
                "profile",
                f"crosses itself{where}",
                "list the ground surface once, left to right (x increasing)",
            )
        dx = np.diff(xy[:, 0])
        back = np.flatnonzero(dx < 0)
        if back.size:
            k = int(back[0])
            raise InputError(
                f"profile point {k + 1}",
                f"x decreases from {xy[k, 0]:g} to {xy[k + 1, 0]:g} (an overhang or points "
                "listed right to left)",
                "list the points left to right (the slope faces +x); overhangs are not supported",
            )
        if xy[-1, 0] <= xy[0, 0]:
            raise InputError("profile", "has no horizontal extent", "give points with x increasing")
        xy.setflags(write=False)
        object.__setattr__(self, "points", xy)

    # ----------------------------------------------------------- shortcuts
    @classmethod
    def simple(
        cls,
        height: float,
        face_angle: float,
        *,
        crest_length: float | None = None,
        toe_length: float | None = None,
        bench_width: float = 0.0,
        bench_height: float | None = None,
        toe: tuple[float, float] = (0.0, 0.0),
    ) -> Profile:
        """A slope of given height and face angle, optionally benched.

        Parameters
        ----------
        height : float
            Crest elevation above the toe (> 0).
        face_angle : float
            Angle of the face (of each bench face) from horizontal, degrees, 0 < a <= 90.
        crest_length : float, optional
            Horizontal length of ground behind the crest (default ``height``).
        toe_length : float, optional
            Horizontal length of ground in front of the toe (default ``height / 2``).
        bench_width : float
            Width of each bench (berm); 0 for a single face.
        bench_height : float, optional
            Vertical distance between benches, counted up from the toe (the
            top lift takes what is left).  Needed when ``bench_width > 0``.
        toe : (x, y)
            Position of the toe.

        Examples
        --------
        >>> Profile.simple(10, 45, crest_length=5, toe_length=5).points.round(9).tolist()
        [[-15.0, 10.0], [-10.0, 10.0], [0.0, 0.0], [5.0, 0.0]]
        >>> p = Profile.simple(20, 90, bench_width=2, bench_height=10, crest_length=4, toe_length=4)
        >>> p.points.tolist()
        [[-6.0, 20.0], [-2.0, 20.0], [-2.0, 10.0], [0.0, 10.0], [0.0, 0.0], [4.0, 0.0]]
        """
        where = "Profile.simple"
        h = _positive(where, "height", height)
        a = float(face_angle)
        if not (math.isfinite(a) and 0.0 < a <= 90.0):
            raise InputError(
                f"{where} face_angle",
                f"{face_angle} is out of range",
                "give an angle in (0, 90] degrees",
            )
        crest = h if crest_length is None else _positive(where, "crest_length", crest_length, True)
        toe_len = (
            0.5 * h if toe_length is None else _positive(where, "toe_length", toe_length, True)
        )
        bw = float(bench_width)
        if not (math.isfinite(bw) and bw >= 0.0):
            raise InputError(
                f"{where} bench_width", f"{bench_width} is negative", "give a width >= 0"
            )
        run = 0.0 if a == 90.0 else 1.0 / math.tan(math.radians(a))
        if bw > 0:
            if bench_height is None:
                raise InputError(
                    f"{where} bench_height",
                    "is missing for a benched slope",
                    "give the vertical distance between benches",
                )
            bh = _positive(where, "bench_height", bench_height)
            if bh >= h * (1 - 1e-9):  # found by fuzzing: no bench was cut, silently
                raise InputError(
                    f"{where} bench_height",
                    f"{bench_height} is not less than the slope's height {height}, "
                    "so no bench would be cut",
                    "give a bench height below the height, or bench_width 0 for no benches",
                )
            n_lifts = max(1, math.ceil(h / bh - 1e-9))
            if n_lifts > MAX_BENCHES:  # found by fuzzing: 1e8 benches filled the memory
                raise InputError(
                    f"{where} bench_height",
                    f"{bench_height} cuts the {height} high slope into {n_lifts:,} benches, "
                    f"more than {MAX_BENCHES:,}",
                    f"give a bench height of at least {h / MAX_BENCHES:.4g}",
                )
            lifts = np.full(n_lifts, bh)
            lifts[-1] = h - bh * (n_lifts - 1)
        else:
            lifts = np.array([h])
        x0, y0 = float(toe[0]), float(toe[1])
        pts = [(x0 + toe_len, y0), (x0, y0)]
        x, y = x0, y0
        for k, lift in enumerate(lifts):
            x, y = x - lift * run, y + lift
            pts.append((x, y))
            if k < len(lifts) - 1:
                x -= bw
                pts.append((x, y))
        pts.append((x - crest, y))
        return cls(pts[::-1])

    # -------------------------------------------------------------- derived
    @property
    def n_points(self) -> int:
        return len(self.points)

    @property
    def x_range(self) -> tuple[float, float]:
        return float(self.points[0, 0]), float(self.points[-1, 0])

    @property
    def height(self) -> float:
        """Difference between the highest and the lowest point."""
        return float(np.ptp(self.points[:, 1]))

    @property
    def line(self) -> shapely.LineString:
        return shapely.LineString(self.points)

    def y_at(self, x: float | np.ndarray) -> float | np.ndarray:
        """Ground elevation at ``x`` (the lower side at a vertical step)."""
        xs, ys = self.points[:, 0], self.points[:, 1]
        out = np.interp(x, xs, ys)
        return float(out) if np.ndim(out) == 0 else out

    def extended(self, left: float = 0.0, right: float = 0.0) -> Profile:
        """The profile with horizontal ground added at its ends."""
        pts = self.points
        if left > 0:
            pts = np.vstack([[pts[0, 0] - left, pts[0, 1]], pts])
        if right > 0:
            pts = np.vstack([pts, [pts[-1, 0] + right, pts[-1, 1]]])
        return Profile(pts)

    def __repr__(self) -> str:
        return f"<Profile: {self.n_points} points, x {self.x_range}, height {self.height:g}>"


def _positive(where: str, key: str, value, allow_zero: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{where} {key}", f"{value!r} is not a number", "give a number") from exc
    ok = math.isfinite(v) and (v >= 0 if allow_zero else v > 0)
    if not ok:
        rel = ">= 0" if allow_zero else "> 0"
        raise InputError(f"{where} {key}", f"{value} is out of range", f"give a value {rel}")
    return v
