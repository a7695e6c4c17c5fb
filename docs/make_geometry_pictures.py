"""Draw three generated slopes to docs/geometry-*.png.

Run: ``python docs/make_geometry_pictures.py``.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import shapely

import rockdem as rd
from rockdem.geometry import JointSet, Profile, cut_to_profile, generate_slope
from rockdem.geometry.plot import plot_geometry

HERE = Path(__file__).parent
ROCK = rd.Joint(normal_stiffness=1e6, friction_angle=35)
BRIDGE = rd.Joint(normal_stiffness=1e7, friction_angle=45, cohesion=2000, tensile_strength=1000)
GROUND = rd.Joint(normal_stiffness=1e6, friction_angle=40)


def perpendicular():
    profile = Profile.simple(20, 70, crest_length=15, toe_length=10)
    sets = [
        JointSet("J1 (dip 30)", 30, 2.0, ROCK, origin=(0.3, 0.2)),
        JointSet("J2 (dip 120)", 120, 2.5, ROCK),
    ]
    return generate_slope(profile, sets, depth=8, ground_joint=GROUND, unit_weight=26)


def inclined_layers():
    profile = Profile.simple(24, 60, bench_width=4, bench_height=8, crest_length=12,
                             toe_length=10)
    sets = [
        JointSet("bedding (dip 20 out)", 20, 1.6, ROCK, origin=(0, 0.4)),
        JointSet("cross (dip 110)", 110, 3.0, ROCK, trace_length=2.5, gap=1.5, stagger=0.5,
                 spacing_sd=0.6, seed=3),
    ]
    return generate_slope(profile, sets, depth=8, ground_joint=GROUND,
                          bridge_joint=BRIDGE, unit_weight=26)


def toppling_with_berm():
    profile = Profile.simple(24, 80, crest_length=14, toe_length=10)
    sets = [
        JointSet("toppling (dip 100)", 100, 1.8, ROCK, origin=(0.5, 0), dip_sd=2.0, seed=7),
        JointSet("cross (dip 10)", 10, 2.5, ROCK, trace_length=3.0, gap=1.0, stagger=0.5),
    ]
    deep = shapely.Polygon([(-30, -12), (-30, -2), (12, -7), (12, -12)])
    g = generate_slope(profile, sets, depth=10, ground_joint=GROUND, bridge_joint=BRIDGE,
                       fixed_region=deep, boundary=("back", "base", "front"), unit_weight=26)
    # stabilisation design: flatten the upper half into a 4.6 m wide berm at y = 12
    berm = Profile([(-40, 24), (-9.0, 24), (-6.8, 12), (-2.116, 12), (0, 0), (20, 0)])
    return cut_to_profile(g, berm)


def main() -> None:
    cases = {
        "geometry-perpendicular.png": (perpendicular, "Two perpendicular persistent sets"),
        "geometry-inclined-layers.png": (inclined_layers,
                                         "Inclined layers, benched slope, rock bridges"),
        "geometry-toppling-berm.png": (toppling_with_berm,
                                       "Toppling set, berm cut, fixed deep region"),
    }
    for name, (make, title) in cases.items():
        geom = make()
        fig, ax = plt.subplots(figsize=(11, 6.5))
        plot_geometry(geom, ax, title=f"{title}: {int((~geom.blocks.fixed).sum())} blocks")
        fig.tight_layout()
        fig.savefig(HERE / name, dpi=110)
        plt.close(fig)
        print(f"wrote {HERE / name}")


if __name__ == "__main__":
    main()
