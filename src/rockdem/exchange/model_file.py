"""The model file of a section read from a drawing (``rockdem import``): explicit
blocks and joint lines, every coordinate written so that it reads back to the same
float."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..units import water_unit_weight
from .dxf_cut import cut_section
from .dxf_in import DxfError, Section, SectionBlocks, read_section

__all__ = ["PLACEHOLDER_JOINT", "model_document", "model_text"]

#: Joint properties written when no template gives them (to be edited).
PLACEHOLDER_JOINT = {"normal_stiffness": 1.0e6, "friction_angle": 35.0, "cohesion": 0.0}


def _fail(source: str, problem: str, fix: str, key: str = "") -> DxfError:
    return DxfError(source, problem, fix, key)


class _Flow(dict):
    """A mapping written on one line (``{joint: bedding, start: [x, y], ...}``)."""


class _FlowList(list):
    """A list written on one line (``[[x, y], [x, y]]``)."""


def _dumper():
    import yaml

    from ..config.yaml_read import add_core_resolvers

    class Dumper(yaml.SafeDumper):
        pass

    add_core_resolvers(Dumper)  # a name like 1e3 or 0o17 is written in quotes

    def flow_map(dumper, data):
        return dumper.represent_mapping("tag:yaml.org,2002:map", data.items(), flow_style=True)

    def flow_list(dumper, data):
        return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=True)

    Dumper.add_representer(_Flow, flow_map)
    Dumper.add_representer(_FlowList, flow_list)
    return Dumper


def _floats(xy) -> list[list[float]]:
    return [[float(x), float(y)] for x, y in np.asarray(xy, dtype=float)]


def model_document(
    section: Section,
    blocks: SectionBlocks,
    *,
    template: Mapping[str, Any] | None = None,
    name: str | None = None,
    bolt_force: float | None = None,
    bolt: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """The model file (as data) of a cut section: explicit ``blocks`` and
    ``joint_lines``, the water table as a load, the bolts drawn as passive
    ``bolts`` with the properties ``bolt`` (capacity, axial_stiffness, ...) or
    as active anchors (``supports``) of force ``bolt_force``.

    ``template`` (a model file's data) gives the units, materials, joints,
    loads, analysis settings; without it the joints get placeholder
    properties (:data:`PLACEHOLDER_JOINT`) to be edited.
    """
    base = dict(template or {})
    for key in ("blocks", "slope", "geometry", "remove"):
        base.pop(key, None)
    if isinstance(base.get("stabilisation"), Mapping):
        # trials and stages name the template's blocks, which are not these
        # (found by fuzzing: they were carried into the imported model)
        stabilisation = dict(base["stabilisation"])
        for key in ("trials", "stages"):
            stabilisation.pop(key, None)
        base["stabilisation"] = stabilisation
    doc: dict[str, Any] = {}
    doc["name"] = base.pop("name", None) or name or Path(section.source).stem
    doc["description"] = base.pop(
        "description", f"Section imported from {Path(section.source).name} (rockdem import)."
    )
    doc["units"] = base.pop("units", "kN, m, kPa")
    doc["materials"] = base.pop("materials", {"rock": {"unit_weight": 26.0}})
    joints = dict(base.pop("joints", {}))
    for joint in section.joints or ["joint"]:
        if joint not in joints:
            if template is not None:
                raise _fail(
                    section.source,
                    f"the template has no joint {joint!r} for the traces "
                    f"on layer {_layer_of(section, joint)}",
                    "add it to the template's `joints`",
                )
            joints[joint] = dict(PLACEHOLDER_JOINT)
    doc["joints"] = joints
    for key in ("default_joint", "ground_joint"):
        if key in base:
            doc[key] = base.pop(key)
    doc["joint_lines"] = list(base.pop("joint_lines", [])) + [
        _Flow(joint=joint, start=_floats([a])[0], end=_floats([b])[0])
        for joint, a, b in blocks.lines
    ]
    if not doc["joint_lines"]:
        del doc["joint_lines"]
    doc["blocks"] = [
        _Flow(id=i, **({"fixed": True} if f else {}), vertices=_floats(p))
        for i, (p, f) in enumerate(zip(blocks.polygons, blocks.fixed, strict=True))
    ]
    loads = dict(base.pop("loads", {}))
    if section.water_table is not None:
        loads["water_table"] = _FlowList(_floats(section.water_table))
        if "water_unit_weight" not in loads:
            # in the file's units (found by fuzzing: 9.81 was written beside lbf and ft)
            gamma_w = water_unit_weight(str(doc["units"]))
            if gamma_w is None:
                raise _fail(
                    section.source,
                    f"the drawing has a water table, and the units {doc['units']!r} name no "
                    "force and length to give the unit weight of water in",
                    "give loads.water_unit_weight in the template (9.81 for kN and m)",
                )
            loads["water_unit_weight"] = gamma_w
    if loads:
        doc["loads"] = loads
    supports = list(base.pop("supports", []))
    passive = list(base.pop("bolts", []))
    if section.bolts:
        if (bolt is None) == (bolt_force is None):
            raise _fail(
                section.source,
                f"layer {section.layers['bolts']} holds {len(section.bolts)} bolts "
                + (
                    "and both bolt properties and a bolt force were given"
                    if bolt
                    else "but neither bolt properties nor a bolt force were given"
                ),
                "give --bolt-capacity C and --bolt-stiffness K (passive bolts) or "
                "--bolt-force F (active anchors)",
                "bolt",
            )
        for k, b in enumerate(section.bolts):
            name = f"drawn bolt {k + 1}"
            head = _floats([b.head])[0]
            if bolt is not None:
                passive.append(
                    _Flow(head=head, angle=b.angle, length=b.length, **dict(bolt), name=name)
                )
            else:
                supports.append(_Flow(at=head, force=float(bolt_force), angle=b.angle, name=name))
    if supports:
        doc["supports"] = supports
    if passive:
        doc["bolts"] = passive
    doc.update(base)  # analysis, stabilisation, format, ... as the template has them
    return doc


def _layer_of(section: Section, joint: str) -> str:
    return next((la for la, j in section.joint_layers.items() if j == joint), joint)


def model_text(
    path: str | Path,
    *,
    layers: Mapping[str, Any] | None = None,
    template: str | Path | None = None,
    name: str | None = None,
    bolt_force: float | None = None,
    bolt: Mapping[str, Any] | None = None,
    max_blocks: int | None = None,
) -> tuple[str, Section, SectionBlocks]:
    """The text of a model file (YAML) for the section drawn in ``path``.

    Returns
    -------
    text : str
        Explicit ``blocks`` and ``joint_lines`` (every coordinate written so
        that it reads back to the same float), headed by comments saying where
        it came from and what to edit.
    section, blocks
        What was read and cut.
    """
    import yaml

    tpl = None
    joints = None
    length_unit = None
    if template is not None:
        from ..config import read_document
        from ..units import length_of

        tpl, _ = read_document(template)
        joints = list(tpl.get("joints") or {}) or None
        length_unit = length_of(str(tpl.get("units", "")))
    section = read_section(path, layers=layers, joints=joints, length_unit=length_unit)
    blocks = cut_section(section, max_blocks=max_blocks)
    doc = model_document(section, blocks, template=tpl, name=name, bolt_force=bolt_force, bolt=bolt)
    unit = f"$INSUNITS {section.insunits}" if section.insunits else "unitless (model units)"
    head = [
        f"# rockdem model imported from {Path(path).name} by `rockdem import`",
        f"# drawing units: {unit}; scale to model units: {section.scale:g}",
        f"# {blocks.n_free} free blocks, {len(blocks.polygons) - blocks.n_free} fixed, "
        f"{len(blocks.lines)} joint trace segments on layers "
        + (", ".join(section.joint_layers) or "none"),
    ]
    if template is None:
        head.append(
            "# EDIT the joint properties and the unit weight: they are placeholders "
            "(phi 35, c 0, kn 1e6; 26 kN/m^3)"
        )
    if "ground_joint" not in doc and "default_joint" not in doc:
        # (found by fuzzing: which joint the ground contacts took was not said)
        first = next(iter(doc["joints"]))
        head.append(
            f"# contacts with the fixed ground and untraced contacts take joint {first!r} "
            "(the first); set ground_joint: or default_joint: to choose"
        )
    body = yaml.dump(
        doc,
        Dumper=_dumper(),
        sort_keys=False,
        default_flow_style=None,
        width=100,
        allow_unicode=True,
    )
    return "\n".join(head) + "\n" + body, section, blocks
