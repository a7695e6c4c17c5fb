"""HTML building blocks of the reports (the analysis report, the limit-
equilibrium and the study sections): the style sheet, escaped text,
numbers, tables and embedded pictures."""

from __future__ import annotations

import base64
import html
import io
from collections.abc import Sequence

import numpy as np

CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,Helvetica,Arial,sans-serif;
 margin:0 auto;max-width:1100px;padding:1em 2em;color:#222;line-height:1.4}
h1{margin-bottom:.2em}h2{border-bottom:2px solid #0072B2;padding-bottom:.15em;margin-top:1.6em}
.meta{color:#555;font-size:.9em}
.verdict{display:inline-block;padding:.6em 1em;border-radius:6px;font-size:1.15em;margin:.4em 0}
.stable{background:#d7f0e6;border:2px solid #009E73}
.unstable{background:#f9e0cc;border:2px solid #D55E00}
.undecided{background:#fbf3d0;border:2px solid #E69F00}
.fos{font-size:1.3em;font-weight:600}
table{border-collapse:collapse;margin:.5em 0 1em;font-size:.88em}
th,td{border:1px solid #ccc;padding:.2em .55em;text-align:right}
th{background:#eef3f8}td.l,th.l{text-align:left}
figure{margin:1em 0}figure img{max-width:100%;height:auto;border:1px solid #ddd}
figcaption{color:#444;font-size:.9em}
.note{color:#555;font-size:.88em}
.warning{background:#fff4cc;border:2px solid #E69F00;border-radius:6px;padding:.5em 1em;
 margin:.5em 0}
nav a{margin-right:1em}
"""


def esc(x) -> str:
    return html.escape(str(x), quote=True)


def num(x, fmt: str = ".4g") -> str:
    if x is None:
        return "-"
    try:
        v = float(x)
    except (TypeError, ValueError):
        return esc(x)
    if np.isinf(v):
        return "∞" if v > 0 else "-∞"
    if np.isnan(v):
        return "-"
    return format(v + 0.0, fmt)  # (+ 0.0: no "-0")


def html_table(
    header: Sequence[str], rows: Sequence[Sequence], left: int = 0, cls: str = ""
) -> str:
    """An HTML table; the first ``left`` columns are left-aligned text."""
    head = "".join(
        f'<th class="l">{esc(h)}</th>' if i < left else f"<th>{esc(h)}</th>"
        for i, h in enumerate(header)
    )
    body = []
    for row in rows:
        cells = "".join(
            f'<td class="l">{esc(v)}</td>' if i < left else f"<td>{v}</td>"
            for i, v in enumerate(row)
        )
        body.append(f"<tr>{cells}</tr>")
    return (
        f'<table class="{cls}"><thead><tr>{head}</tr></thead><tbody>{"".join(body)}</tbody></table>'
    )


def figure_uri(fig, fmt: str, dpi: int) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format=fmt, dpi=dpi)
    mime = "image/svg+xml" if fmt == "svg" else f"image/{fmt}"
    return f"data:{mime};base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def img(uri: str, caption: str, alt: str, ident: str) -> str:
    return (
        f'<figure id="{esc(ident)}"><img src="{uri}" alt="{esc(alt)}">'
        f"<figcaption>{caption}</figcaption></figure>"
    )
