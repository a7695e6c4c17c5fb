"""The report's section "Limit equilibrium beside the DEM" (Sarma on the mechanism)."""

from __future__ import annotations

from ..results import FactorOfSafety
from .sarma import sarma


def html_section(fos: FactorOfSafety, units=None) -> list[str]:
    """HTML fragments: Sarma's factor of the DEM's mechanism beside the DEM's,
    its faces, and where the two differ (or, plainly, why there is no factor).
    ``units`` (a :class:`rockdem.units.Units`) labels the lengths and forces."""
    from ..report_html import esc, html_table, num
    from ..units import UNKNOWN

    u = units or UNKNOWN

    head = '<h2 id="limit-equilibrium">Limit equilibrium beside the DEM</h2>'
    try:
        r = sarma(fos)
    except Exception as exc:  # the report must not fail for its cross-check
        return [head, f"<p>Not available: {esc(type(exc).__name__)}: {esc(exc)}.</p>"]
    intro = (
        "<p>The DEM's failure mechanism (the moving blocks at the upper end of the "
        "bracket, and their contacts) rated by Sarma's method (1979, non-vertical "
        "slices) generalised to blocks: blocks moving together are one body, every "
        "contact a body slides on is at its limit with c and tan(phi) divided by F, and "
        "F is the factor at which no horizontal acceleration is needed for failure "
        "(force equilibrium of each body).</p>"
    )
    if r.fos is None:
        return [head, intro, f"<p><b>No limit-equilibrium factor:</b> {esc(r.reason)}.</p>"]
    diff = "" if r.difference is None else f" ({signed_percent(r.difference)} against the DEM)"
    rows = [
        [
            str(i),
            f"{'rock' if f.body_a < 0 else f.body_a}-{f.body_b}",
            f.kind,
            f.state,
            ", ".join(f.joints),
            num(f.length),
            num(f.normal_force),
            num(f.shear_force),
            esc(", ".join(sorted(set(f.dem_state)))),
        ]
        for i, f in enumerate(r.faces)
    ]
    table = html_table(
        [
            "face",
            "bodies",
            "kind",
            "LE state",
            "joints",
            "length" + u.suffix("length"),
            "N" + u.suffix("force"),
            "S" + u.suffix("force"),
            "DEM now",
        ],
        rows,
        left=5,
    )
    bodies = "; ".join(
        f"{i}: blocks {', '.join(map(str, b[:30]))}{' ...' if len(b) > 30 else ''}"
        for i, b in enumerate(r.bodies)
    )
    return [
        head,
        intro,
        f"<p>DEM (strength reduction): <b>{num(r.dem_fos, '.4f')}</b>; "
        f"Sarma on the same blocks and slip surface: <b>{num(r.fos, '.4f')}</b>{diff}; "
        f"critical acceleration at full strength Kc = {num(r.critical_acceleration, '.4f')} g"
        + (
            " (negative: the blocks slide at full strength even without one)."
            if r.critical_acceleration is not None and r.critical_acceleration < 0
            else "."
        )
        + f"</p><p>Rigid bodies: {esc(bodies)}.</p>",
        table,
        "<p>Where the two differ:</p><ul>"
        + "".join(f"<li>{esc(n)}</li>" for n in r.notes)
        + "</ul>",
    ]


def signed_percent(x: float) -> str:
    """``x`` as a signed percentage to 0.1, never "-0.0%"."""
    return f"{round(100 * x, 1) + 0.0:+.1f}%"
