"""What a study leaves in its folder besides the table: the worst samples'
model files (with their digests, so that an edit is never deleted), the
pictures and summary.json."""

from __future__ import annotations

from pathlib import Path

from ..result_tables import jsonable
from .plan import Plan, sample_document
from .store import _atomic_write, worst_digest


def write_outputs(folder: Path, plan: Plan, table, summary: dict) -> None:
    """Rewrite worst/, the pictures and summary.json from the finished table."""
    import json

    worst_dir = folder / "worst"
    for old in worst_dir.glob("sample-*.yaml"):  # (checked unedited at the start)
        old.unlink()
    written = []
    rows = table.set_index("sample")
    for i in summary["worst"]:
        worst_dir.mkdir(exist_ok=True)
        path = worst_dir / f"sample-{i:06d}.yaml"
        write_sample_model(path, plan, i, rows.loc[i])
        written.append(str(path.relative_to(folder)))
    summary["worst_files"] = written
    # what each held, so that the next run into this folder can tell an edit
    summary["worst_digests"] = {
        path.relative_to(folder).as_posix(): worst_digest(path)
        for path in worst_dir.glob("sample-*.yaml")
    }
    from .plots import write_pictures

    summary["pictures"] = write_pictures(folder, table, summary, plan.names)
    text = json.dumps(jsonable(summary), indent=1, allow_nan=False) + "\n"
    _atomic_write(folder / "summary.json", lambda tmp: tmp.write_text(text, encoding="utf-8"))


def write_sample_model(path: Path, plan: Plan, sample: int, row) -> None:
    """Sample ``sample``'s model file, headed by its inputs and result (replayable)."""
    import yaml

    doc = _drawing_from(sample_document(plan, sample), plan.source, path.parent)
    fs = row["fs"]
    head = [
        f"# rockdem study: sample {sample} of {plan.source}",
        f"# factor of safety {fs:.4f}" if fs == fs else f"# mode {row['mode']}",
        "# inputs:",
        *(f"#   {n} = {float(row[n])!r}" for n in plan.names),
        f"# replay: rockdem fos {path.name}",
        "",
    ]
    from ..config.yaml_read import add_core_resolvers

    class Dumper(yaml.SafeDumper):
        pass

    add_core_resolvers(Dumper)  # a joint named '1e3' stays a name when read back
    body = yaml.dump(doc, Dumper=Dumper, sort_keys=False, allow_unicode=True)
    text = "\n".join(head) + body
    _atomic_write(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def _drawing_from(doc: dict, source: str, folder: Path) -> dict:
    """``doc`` with its drawing (``geometry.dxf``, relative to the model file)
    named from ``folder``, where the sample's file is written (found by
    fuzzing: `rockdem fos worst/sample-....yaml` did not find the drawing)."""
    import os

    geometry = doc.get("geometry")
    if not isinstance(geometry, dict) or not geometry.get("dxf") or source.startswith("<"):
        return doc
    drawing = Path(str(geometry["dxf"])).expanduser()
    if not drawing.is_absolute():
        drawing = Path(source).parent / drawing
    drawing = drawing.resolve()
    try:
        name = os.path.relpath(drawing, folder.resolve())
    except ValueError:  # another drive
        name = str(drawing)
    return {**doc, "geometry": {**geometry, "dxf": name}}
