"""``rockdem import``: a slope section drawn in CAD (DXF) to a model file."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from .common import _ROOT, DebugOpt, OverwriteOpt, _guard, _plural, err

LayerOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--layer",
        "-l",
        help="Layer of a part of the section, PART=LAYER (PART: outline, fixed, water, "
        "bolts; defaults OUTLINE, FIXED, WATER, BOLTS).  Repeat for several.",
        metavar="PART=LAYER",
        show_default=False,
    ),
]
JointLayerOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--joint-layer",
        "-j",
        help="A layer of joint traces and its joint, LAYER=JOINT (default: every layer "
        "JOINT_<name> takes the joint <name>).  Repeat for several.",
        metavar="LAYER=JOINT",
        show_default=False,
    ),
]


def _pairs(values: list[str] | None, option: str) -> dict[str, str]:
    from ..errors import InputError

    out: dict[str, str] = {}
    for value in values or []:
        key, sep, name = value.partition("=")
        if not sep or not key.strip() or not name.strip():
            raise InputError(f"{option} {value}", "is not NAME=VALUE", f"write {option} A=B")
        out[key.strip()] = name.strip()
    return out


def _in_template(exc, template: Path | None, drawing: Path):
    """An error of the imported model at a key the template gave, named in the
    template at that key's line; any other, named at the drawing (the model
    written, or not written, is not where the user can fix it: found by
    fuzzing, "<import>:13: loads water_table ..." for the drawing's WATER
    layer)."""
    import re

    from ..config import read_document
    from ..config.errors import ModelFileError, _line

    at_drawing = ModelFileError(str(drawing), exc.key, exc.problem, exc.fix, None)
    if template is None or not exc.key:
        return at_drawing
    loc = tuple(int(part) if part.isdigit() else part for part in re.findall(r"[^.\[\]]+", exc.key))
    data, nodes = read_document(template)
    node = data
    for part in loc:  # the whole key path must be the template's
        if isinstance(node, dict) and part in node:
            node = node[part]
        elif isinstance(node, list) and isinstance(part, int) and part < len(node):
            node = node[part]
        else:
            return at_drawing
    return ModelFileError(str(template), exc.key, exc.problem, exc.fix, _line(nodes, loc))


def import_dxf(
    dxf: Annotated[
        Path | None,
        typer.Argument(help="DXF drawing of the section.", show_default=False),
    ] = None,
    out_file: Annotated[
        Path | None,
        typer.Option(
            "--out",
            "-o",
            help="Write the model file (.yaml) here (default: print it).",
            metavar="FILE",
        ),
    ] = None,
    example: Annotated[
        bool, typer.Option("--example", help="Import the bundled example section.")
    ] = False,
    template: Annotated[
        Path | None,
        typer.Option(
            "--template",
            "-t",
            help="Take units, materials, joints, loads, supports, bolts, analysis and "
            "stabilisation settings (not its trials or stages, which name its own blocks) "
            "from this model file (otherwise the joints get placeholder properties to edit).",
            metavar="MODEL",
        ),
    ] = None,
    layer: LayerOpt = None,
    joint_layer: JointLayerOpt = None,
    bolt_capacity: Annotated[
        float | None,
        typer.Option(
            "--bolt-capacity",
            help="The bolts drawn are passive bolts of this axial capacity (one bolt; "
            "with --bolt-stiffness; edit the other properties in the file).",
            metavar="C",
        ),
    ] = None,
    bolt_stiffness: Annotated[
        float | None,
        typer.Option(
            "--bolt-stiffness",
            help="Axial stiffness of the passive bolts (force per unit joint opening).",
            metavar="K",
        ),
    ] = None,
    bolt_force: Annotated[
        float | None,
        typer.Option(
            "--bolt-force",
            help="Instead: the bolts drawn are active anchors of this force.",
            metavar="F",
        ),
    ] = None,
    name: Annotated[str | None, typer.Option("--name", help="Name of the model.")] = None,
    overwrite: OverwriteOpt = False,
    debug: DebugOpt = False,
) -> None:
    """A model file from a slope section drawn in CAD (DXF).

    The outline (one closed polyline on layer OUTLINE), the fixed ground
    (closed polylines on FIXED) and the joint traces (layers JOINT_<name>) are
    cut into explicit blocks; a water table (WATER) becomes a load, and bolts
    (lines on BOLTS) passive bolts (--bolt-capacity, --bolt-stiffness) or
    anchors (--bolt-force).  Coordinates keep the drawing's (site
    coordinates stay), converted from its $INSUNITS to metres (or the
    template's length unit).  The file written loads with every command.
    """
    with _guard(debug):
        from ..config import parse_model
        from ..config.errors import ModelFileError
        from ..errors import InputError
        from ..exchange.dxf_in import example_dxf
        from ..exchange.model_file import model_text
        from .files import _check_new_file, _check_out_file, _save_file

        if (dxf is None) == (not example):
            raise InputError(
                "DXF",
                "give either a DXF file or --example" + (", not both" if dxf else ""),
                "for example: rockdem import section.dxf --out model.yaml",
            )
        path = example_dxf() if example else dxf
        assert path is not None
        for option, value in (
            ("--bolt-force", bolt_force),
            ("--bolt-capacity", bolt_capacity),
            ("--bolt-stiffness", bolt_stiffness),
        ):
            if value is not None and not (value > 0 and value < 1e15):
                raise InputError(option, f"{value:g} is out of range", "give a value > 0")
        bolt = None
        if (bolt_capacity is None) != (bolt_stiffness is None):
            raise InputError(
                "--bolt-capacity" if bolt_capacity is None else "--bolt-stiffness",
                "is missing",
                "passive bolts need both --bolt-capacity and --bolt-stiffness",
            )
        if bolt_capacity is not None:
            bolt = {"capacity": bolt_capacity, "axial_stiffness": bolt_stiffness}
        layers: dict = _pairs(layer, "--layer")
        joints = _pairs(joint_layer, "--joint-layer")
        if joints:
            layers["joints"] = joints
        if template is not None and template.suffix.lower() == ".dxf":
            raise InputError(
                f"--template {template}",
                "is a DXF drawing, not a model file",
                "give a model file (.yaml or .toml) to take the units, materials and joints from",
            )
        if out_file is not None:
            if out_file.exists() and out_file.resolve() == Path(path).resolve():
                raise InputError(
                    f"--out {out_file}", "is the DXF drawing itself", "give a .yaml file name"
                )
            if out_file.suffix.lower() not in (".yaml", ".yml"):
                # (found by hostile testing: --out model.toml wrote YAML that
                # then read "not valid TOML"; --out other.dxf replaced a drawing)
                raise InputError(
                    f"--out {out_file}",
                    "is not a .yaml name, and import writes a YAML model file",
                    "give a .yaml file name",
                )
            inputs = [path] + ([template] if template is not None else [])
            _check_out_file(out_file, inputs=inputs)
            _check_new_file(out_file, "--out", overwrite)
        text, section, blocks = model_text(
            path,
            layers=layers,
            template=template,
            name=name,
            bolt_force=bolt_force,
            bolt=bolt,
            max_blocks=_ROOT["max_blocks"],
        )
        source = str(out_file) if out_file is not None else "<import>"
        try:
            parse_model(text, source=source, max_blocks=None)  # what is written loads
        except ModelFileError as exc:
            raise _in_template(exc, template, path) from None
        if out_file is None:
            typer.echo(text, nl=False)
        else:
            _save_file(out_file, overwrite, lambda tmp: tmp.write_text(text, encoding="utf-8"))
        read = ", ".join(f"{part} {n}" for part, n in section.layers.items() if n)
        joints_read = ", ".join(f"{la} -> {j}" for la, j in section.joint_layers.items())
        skipped = ", ".join(f"{la} ({n})" for la, n in sorted(section.skipped.items()))
        where = escape(str(out_file)) if out_file is not None else "stdout"
        err.print(
            f"{escape(str(path))} -> {where}: {_plural(blocks.n_free, 'free block')}, "
            f"{_plural(len(blocks.polygons) - blocks.n_free, 'fixed block')}, "
            f"{_plural(len(blocks.lines), 'joint trace segment')}"
            + (", a water table" if section.water_table is not None else "")
            + (f", {_plural(len(section.bolts), 'bolt')}" if section.bolts else "")
        )
        err.print(f"  layers read: {escape(read)}; joints: {escape(joints_read or 'none')}")
        if skipped:
            err.print(f"  not read (other layers, annotation): {escape(skipped)}")
        if template is None:
            err.print(
                "  [yellow]edit the joint properties and the unit weight[/yellow]: "
                "they are placeholders (or give --template MODEL)"
            )
