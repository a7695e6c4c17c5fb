"""Make the bundled example section, src/rockdem/exchange/data/section.dxf.

A 20 m high rock slope with a 60 degree face, drawn in site coordinates
(chainage 1000 m, elevation 400 m at the toe), in the layer convention of
`rockdem import` (docs/file-format.md, "Sections from CAD"):

* OUTLINE: the section, one closed polyline;
* FIXED: the ground below elevation 390 and strips along the back and the
  front (three closed polylines that touch: one ground block);
* JOINT_bedding: persistent bedding dipping 35 degrees out of the face, as LINEs;
* JOINT_cross: a steep cross set (dip 110: 70 degrees into the slope), as
  two-point polylines, every other one stopping short (it does not cut);
* WATER: the water table, left to right, below the face;
* BOLTS: two bolts from the face into the slope, 15 degrees below horizontal.

Run:  python examples/make_dxf.py [OUT.dxf]
Then: rockdem import --example --out model.yaml --bolt-force 150  (bolts as anchors)
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

X0, Y0 = 1000.0, 400.0  # chainage and elevation of the toe's foot of the section
HEIGHT, FACE = 20.0, 60.0
TOE = 20.0 + HEIGHT / math.tan(math.radians(FACE))  # x of the toe (from the back)


def face_y(x: float) -> float:
    return Y0 + HEIGHT - (x - X0 - 20.0) * math.tan(math.radians(FACE))


def section() -> dict:
    """The parts of the example section (for write_section_dxf)."""
    outline = [(0, -15), (60, -15), (60, 0), (TOE, 0), (20, HEIGHT), (0, HEIGHT)]
    outline = [(X0 + x, Y0 + y) for x, y in outline]
    fixed = [
        [(X0, Y0 - 15), (X0 + 60, Y0 - 15), (X0 + 60, Y0 - 10), (X0, Y0 - 10)],
        [(X0, Y0 - 10), (X0 + 3, Y0 - 10), (X0 + 3, Y0 + HEIGHT), (X0, Y0 + HEIGHT)],
        [(X0 + 57, Y0 - 10), (X0 + 60, Y0 - 10), (X0 + 60, Y0), (X0 + 57, Y0)],
    ]

    def family(dip: float, spacing: float, through: tuple[float, float], n: int, reach: float):
        d = np.array([math.cos(math.radians(dip)), -math.sin(math.radians(dip))])
        normal = np.array([-d[1], d[0]])
        out = []
        for k in range(-n, n + 1):
            p = np.array(through) + k * spacing * normal
            out.append([tuple(p - reach * d), tuple(p + reach * d)])
        return out

    centre = (X0 + 30.0, Y0)
    bedding = family(35.0, 3.0, centre, 12, 45.0)
    cross = family(110.0, 4.0, centre, 9, 30.0)
    for k in range(0, len(cross), 2):  # every other cross joint stops inside the rock
        a, b = (np.array(p) for p in cross[k])
        cross[k] = [tuple(a), tuple(a + 0.45 * (b - a))]
    water = [(X0, Y0 + 10), (X0 + 20, Y0 + 4), (X0 + 32, Y0 - 1.5), (X0 + 60, Y0 - 3)]
    pull = (math.cos(math.radians(195)), math.sin(math.radians(195)))
    bolts = []
    for x in (X0 + 23.0, X0 + 27.0):
        head = (x, face_y(x))
        bolts.append((head, (head[0] + 8 * pull[0], head[1] + 8 * pull[1])))
    return {
        "outline": outline,
        "fixed": fixed,
        "traces": {"bedding": bedding, "cross": cross},
        "water": water,
        "bolts": bolts,
    }


def main(out: str | None = None) -> Path:
    from rockdem.exchange.dxf_out import write_section_dxf

    target = (
        Path(out)
        if out
        else (
            Path(__file__).resolve().parents[1]
            / "src"
            / "rockdem"
            / "exchange"
            / "data"
            / "section.dxf"
        )
    )
    # bedding as LINEs, cross joints as polylines: both kinds are read
    return write_section_dxf(target, insunits=6, as_lines=("bedding",), **section())


if __name__ == "__main__":
    print(main(sys.argv[1] if len(sys.argv) > 1 else None))
