"""Regenerate the pictures in docs/img (run: python docs/img/make_pictures.py).

A jointed slope from the geometry generator (bedding dipping out of the face,
cross joints with rock bridges, an anchor and a crest surcharge), analysed
at F = 1 and by strength reduction; every figure of rockdem.plots, the
report, and a screenshot of the report in headless chromium.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import rockdem as rd
from rockdem import plots
from rockdem.geometry import JointSet, Profile, generate_slope
from rockdem.report import write_report

HERE = Path(__file__).resolve().parent


def slope_model() -> rd.Model:
    bedding = rd.Joint(1e6, 30.0, cohesion=15.0, name="bedding")
    cross = rd.Joint(1e6, 30.0, cohesion=0.0, name="cross joints")
    bridge = rd.Joint(1e6, 40.0, cohesion=60.0, tensile_strength=20.0, name="bridge")
    ground = rd.Joint(1e6, 35.0, cohesion=10.0, name="ground")
    geom = generate_slope(
        Profile.simple(16.0, 65.0, crest_length=14.0, toe_length=6.0),
        [
            JointSet("bedding", 32.0, 3.0, bedding, origin=(0.0, 0.0)),
            JointSet(
                "cross joints",
                115.0,
                4.5,
                cross,
                origin=(-3.0, 0.0),
                trace_length=7.0,
                gap=1.5,
                stagger=0.5,
            ),
        ],
        depth=4.0,
        unit_weight=26.0,
        ground_joint=ground,
        bridge_joint=bridge,
    )
    loads = rd.Loads(
        points=(
            rd.PointLoad.anchor(-3.0, 6.4, 150.0, 180.0 - 15.0, name="anchor A"),
            rd.PointLoad.anchor(-0.933, 2.0, 100.0, 180.0 - 15.0, name="anchor B"),
        ),
        lines=(rd.LineLoad((-12.0, 16.0), (-9.0, 16.0), 0.0, -30.0, name="surcharge"),),
    )
    return geom.model(loads=loads, name="jointed slope")


def main() -> None:
    warnings.simplefilter("ignore", DeprecationWarning)
    model = slope_model()
    a = rd.analyse(model)
    fos = rd.factor_of_safety(model, width=0.01)
    print(a, fos, file=sys.stderr)
    dpi = 110
    plots.plot_model(model, block_ids=True).figure.savefig(HERE / "model.png", dpi=dpi)
    plots.plot_model(model).figure.savefig(HERE / "model.svg")
    plots.plot_failure(a).figure.savefig(HERE / "failure-state.png", dpi=dpi)
    plots.plot_failure(fos).figure.savefig(HERE / "failure-at-fos.png", dpi=dpi)
    plots.plot_deformed(fos.stable_analysis).figure.savefig(HERE / "deformed.png", dpi=dpi)
    plots.plot_deformed(fos, use="mechanism").figure.savefig(HERE / "mechanism.png", dpi=dpi)
    bed = model.joint_index("bedding")
    traces = [k for k, j in enumerate(model.line_joint) if j == bed]
    longest = max(traces, key=lambda k: len(plots.select_interfaces(a, k)))
    stress = plots.plot_joint_stress(fos.stable_analysis, longest)
    stress.savefig(HERE / "stress-bedding.png", dpi=dpi)
    plots.plot_joint_stress(fos.failed_analysis).savefig(HERE / "stress-slip-surface.png", dpi=dpi)
    plots.plot_fos(fos).figure.savefig(HERE / "fos-search.png", dpi=dpi)
    plots.plot_progressive(fos).savefig(HERE / "progressive.png", dpi=90)
    plots.animate_progressive(fos, HERE / "progressive.gif", dpi=70)
    out = Path(tempfile.mkdtemp(prefix="rockdem-report-"))
    report = write_report(model, out, analysis=a, fos=fos, units="kN, m, kPa")
    chromium = shutil.which("chromium") or shutil.which("google-chrome")
    if chromium:
        subprocess.run(
            [
                chromium,
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                f"--user-data-dir={tempfile.mkdtemp()}",
                "--hide-scrollbars",
                "--window-size=1200,2200",
                f"--screenshot={HERE / 'report-screenshot.png'}",
                report.as_uri(),
            ],
            capture_output=True,
            timeout=120,
            check=True,
        )
    print(report, file=sys.stderr)


if __name__ == "__main__":
    main()
