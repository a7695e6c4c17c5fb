"""``rockdem check``: validate a model file and summarise it, without analysis."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rich.markup import escape
from rich.table import Table

from ..linalg import backend
from ..units import parse_units
from .common import (
    _ROOT,
    DebugOpt,
    ExampleOpt,
    JsonOpt,
    ModelArg,
    _echo_json,
    _guard,
    _header,
    _load,
    _plural,
    out,
)


def check(
    model: ModelArg = None,
    example: ExampleOpt = None,
    json_: JsonOpt = False,
    debug: DebugOpt = False,
) -> None:
    """Validate a model file and print a summary (blocks, interfaces, weights); no analysis."""
    with _guard(debug):
        from ..solver import build_system

        path, m, cfg = _load(model, example)
        if cfg.study is not None:
            # the study's key paths and its model at the medians, as `rockdem study`
            # checks them (hostile round 7: a misspelt input path passed check)
            from ..studies.plan import prepare

            prepare(path, max_blocks=_ROOT["max_blocks"])
        system = build_system(m)
        summary = _check_summary(path, m, cfg, system)
        if json_:
            _echo_json(summary)
            return
        _print_check(summary)


def _check_summary(path: Path, m, cfg, system) -> dict[str, Any]:
    import numpy as np

    b = system.blocks
    faces = system.interfaces
    names = [j.name for j in m.joints]
    kinds: dict[str, dict[str, float]] = {}
    for k, length in zip(faces.joint, faces.length, strict=True):
        row = kinds.setdefault(names[k], {"count": 0, "length": 0.0})
        row["count"] += 1
        row["length"] += float(length)
    free = ~b.fixed
    loads = m.loads
    return {
        **_header(path, m, cfg),
        "valid": True,
        "blocks": {
            "total": b.n_blocks,
            "free": int(free.sum()),
            "fixed": int(b.fixed.sum()),
            "free_weight": float(b.weight[free].sum()),
            "free_area": float(b.area[free].sum()),
            "weights": {int(i): float(w) for i, w in zip(b.ids[free], b.weight[free], strict=True)},
        },
        "interfaces": {"total": faces.n_interfaces, "by_kind": kinds},
        "springs": system.springs.n_springs,
        "degrees_of_freedom": system.assembly.n_dof,
        "linear_solver": backend(system.assembly.n_dof),
        "loads": {
            "gravity": loads.gravity,
            "seismic_h": loads.seismic_h,
            "seismic_v": loads.seismic_v,
            "point_loads": sum(not p.support for p in loads.points),
            "supports": sum(p.support for p in loads.points),
            "line_loads": len(loads.lines),
            "resultant": [float(v) for v in np.sum(system.f_block[free, :2], axis=0)],
        },
        "analysis": cfg.analysis.model_dump(mode="json"),
    }


def _print_check(s: dict[str, Any]) -> None:
    b = s["blocks"]
    out.print(f"[bold]{escape(s['model_name'])}[/bold]  ({escape(s['model_file'])}): valid")
    units = parse_units(s["units"])
    per = f" per {units.length} of slope" if units.known else " per unit length of slope"
    out.print(
        f"units: {escape(s['units']) or '(not stated: add a `units:` note)'}; "
        f"2-D section: forces and weights{per}"
    )
    force, area = units.suffix("force", " {}"), units.suffix("area", " {}")
    out.print(
        f"blocks: {b['total']} ({b['free']} free, {b['fixed']} fixed); "
        f"free weight {b['free_weight']:.6g}{force} (area {b['free_area']:.6g}{area})"
    )
    weights = sorted(b["weights"].items())
    if weights and len(weights) <= 20:
        out.print("weights: " + ", ".join(f"{i}: {w:.6g}" for i, w in weights))
    elif weights:
        ws = [w for _, w in weights]
        out.print(f"weights: min {min(ws):.6g}, max {max(ws):.6g}, mean {sum(ws) / len(ws):.6g}")
    table = Table("interface kind", "count", "total length", box=None, pad_edge=False)
    for kind, row in s["interfaces"]["by_kind"].items():
        table.add_row(escape(kind), str(row["count"]), f"{row['length']:.6g}")
    out.print(
        f"interfaces: {s['interfaces']['total']} ({s['springs']} spring points); "
        f"{s['degrees_of_freedom']} unknowns, factorised with {s['linear_solver']}"
    )
    out.print(table)
    ld = s["loads"]
    out.print(
        f"loads: gravity {'on' if ld['gravity'] else 'off'}, kh {ld['seismic_h']:g}, "
        f"kv {ld['seismic_v']:g}, {ld['point_loads']} point, {ld['line_loads']} line, "
        f"{ld['supports']} supports; resultant on free blocks ({ld['resultant'][0]:.6g}, "
        f"{ld['resultant'][1]:.6g})"
    )
    a = s["analysis"]
    out.print(
        f"analysis: {a['quadrature']} x {a['points_per_interface']}, "
        f"{_plural(a['load_steps'], 'load step')}, tolerance {a['tolerance']:g}"
    )
