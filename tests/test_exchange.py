"""Sections from CAD (DXF in) and results out (VTK, GeoJSON, DXF): issue 14.

The drawings are made here, in the test's folder, with ezdxf (the bundled
example is made by examples/make_dxf.py the same way).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import rockdem as rd
from _cli import assert_refused
from rockdem.cli import app
from rockdem.config import load_model, parse_model
from rockdem.exchange.dxf_cut import cut_section
from rockdem.exchange.dxf_in import example_dxf, read_section
from rockdem.exchange.dxf_out import write_dxf, write_section_dxf
from rockdem.exchange.model_file import model_text
from rockdem.output import RESULT_FILES

ezdxf = pytest.importorskip("ezdxf")
runner = CliRunner()
SITE = (5.0e5, 7.0e6)  # a mine grid / UTM northing


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


# ------------------------------------------------------------------ a section
def _line(p, dip, reach=40.0):
    d = np.array([math.cos(math.radians(dip)), -math.sin(math.radians(dip))])
    p = np.asarray(p, float)
    return [tuple(p - reach * d), tuple(p + reach * d)]


def parts(shift=(0.0, 0.0)):
    """A 10 m slope (face 70 degrees), bedding at 30, two cross joints (one stops
    inside the rock), ground below y = -3 and behind x = 1, a water table."""
    sx, sy = shift

    def move(points):
        return [(x + sx, y + sy) for x, y in points]

    outline = move([(0, -5), (24, -5), (24, 0), (14, 0), (10, 10), (0, 10)])
    fixed = [
        move([(0, -5), (24, -5), (24, -3), (0, -3)]),
        move([(0, -3), (1, -3), (1, 10), (0, 10)]),
        move([(22, -3), (24, -3), (24, 0), (22, 0)]),
    ]
    bedding = [move(_line((12, y), 30)) for y in (-1.0, 1.5, 4.0, 6.5)]
    cross = [move(_line((6, 0), 100)), move([(9.0, 9.9), (9.3, 6.0)])]  # second: stops inside
    water = move([(0, 6), (12, 0.5), (14, -0.5), (24, -1.5)])
    return {
        "outline": outline,
        "fixed": fixed,
        "traces": {"bedding": bedding, "cross": cross},
        "water": water,
    }


def draw(folder: Path, name="section.dxf", shift=(0.0, 0.0), insunits=6, scale=1.0, **change):
    p = parts(shift)
    p.update(change)
    if scale != 1.0:

        def sc(points):
            return [(x * scale, y * scale) for x, y in points]

        p["outline"] = sc(p["outline"])
        p["fixed"] = [sc(f) for f in p["fixed"]]
        p["traces"] = {k: [sc(t) for t in v] for k, v in p["traces"].items()}
        p["water"] = sc(p["water"]) if p.get("water") else None
    return write_section_dxf(folder / name, insunits=insunits, as_lines=("bedding",), **p)


MODEL = """\
units: kN, m, kPa
materials: {rock: {unit_weight: 26}}
joints:
  bedding: {normal_stiffness: 1.0e+6, friction_angle: 32}
  cross: {normal_stiffness: 1.0e+6, friction_angle: 40, cohesion: 10}
geometry: {dxf: section.dxf}
loads: {water_unit_weight: 9.81}
"""


def outlines(model):
    b = model.blocks
    return [b.outline(i) for i in range(b.n_blocks)]


# ------------------------------------------------------------------ DXF in
def test_the_imported_model_file_loads_and_gives_the_blocks_cut(tmp_path):
    dxf = draw(tmp_path)
    (tmp_path / "model.yaml").write_text(MODEL)
    text, section, blocks = model_text(dxf, template=tmp_path / "model.yaml")
    out = tmp_path / "imported.yaml"
    out.write_text(text)
    imported, cfg = load_model(out)  # (a trace ending inside a block: kept, no warning)
    drawn, _ = load_model(tmp_path / "model.yaml")  # geometry: {dxf: ...}
    assert cfg.blocks is not None and cfg.geometry is None
    assert imported.blocks.n_blocks == len(blocks.polygons) == drawn.blocks.n_blocks
    for a, b, c in zip(outlines(imported), blocks.polygons, outlines(drawn), strict=True):
        assert np.array_equal(a, b) and np.array_equal(a, c)  # the very same floats
    assert imported.blocks.fixed.tolist() == blocks.fixed.tolist()
    assert blocks.fixed.sum() == 1  # the three ground regions touch: one ground block
    # the cross trace that stops inside the rock cuts nothing but is a joint line
    assert len(blocks.lines) == 6 and sum(j == "cross" for j, *_ in blocks.lines) == 2
    assert imported.loads.water_table == drawn.loads.water_table
    assert len(imported.loads.water_table) == 4
    # the free blocks tile the section minus the ground
    import shapely

    sec = shapely.Polygon(section.outline)
    ground = shapely.union_all([shapely.Polygon(f) for f in section.fixed])
    free = imported.blocks.area[~imported.blocks.fixed].sum()
    assert free == pytest.approx(shapely.difference(sec, ground).area, rel=1e-12)
    ra, rb = rd.analyse(imported), rd.analyse(drawn)
    assert ra.stable == rb.stable
    assert np.array_equal(ra.displacement, rb.displacement)


def test_site_coordinates_give_the_same_blocks(tmp_path):
    near, far = tmp_path / "near", tmp_path / "far"
    near.mkdir()
    far.mkdir()
    for folder, shift in ((near, (0.0, 0.0)), (far, SITE)):
        draw(folder, shift=shift)
        (folder / "model.yaml").write_text(MODEL)
    a, _ = load_model(near / "model.yaml")
    b, _ = load_model(far / "model.yaml")
    size = a.blocks.extent
    assert b.blocks.n_blocks == a.blocks.n_blocks
    assert b.blocks.fixed.tolist() == a.blocks.fixed.tolist()
    for pa, pb in zip(outlines(a), outlines(b), strict=True):
        assert pa.shape == pb.shape
        assert np.abs(pb - np.asarray(SITE) - pa).max() <= 1e-9 * size
    assert np.max(np.abs(b.blocks.area - a.blocks.area)) <= 1e-9 * size**2
    ra, rb = rd.analyse(a), rd.analyse(b)
    assert ra.system.interfaces.n_interfaces == rb.system.interfaces.n_interfaces
    assert ra.stable == rb.stable
    assert ra.unstable_blocks.tolist() == rb.unstable_blocks.tolist()
    assert np.allclose(rb.displacement, ra.displacement, rtol=1e-6, atol=1e-9 * size)
    # the outline's vertices come back bit for bit at site coordinates
    section = read_section(far / "section.dxf")
    corners = {tuple(p) for p in section.outline.tolist()}
    on_blocks = {tuple(p) for poly in outlines(b) for p in poly.tolist()}
    assert corners <= on_blocks


def test_insunits_millimetres_are_converted_to_metres(tmp_path):
    metres = draw(tmp_path, "m.dxf", shift=SITE)
    mm = draw(tmp_path, "mm.dxf", shift=SITE, insunits=4, scale=1000.0)
    a = cut_section(read_section(metres))
    s = read_section(mm)
    b = cut_section(s)
    assert s.insunits == 4 and s.scale == pytest.approx(1e-3)
    assert len(a.polygons) == len(b.polygons)
    size = read_section(metres).extent
    for pa, pb in zip(a.polygons, b.polygons, strict=True):
        assert np.abs(pa - pb).max() <= 1e-9 * size
    # a unitless drawing is read in model units, as it is
    raw = draw(tmp_path, "raw.dxf", insunits=0)
    assert read_section(raw).scale == 1.0


# (the geometry only: the unit weights stay those of kN and m, which is warned)
@pytest.mark.filterwarnings("ignore::rockdem.errors.ModelWarning")
@pytest.mark.parametrize("note", ["lb, ft, psf", "lbf, ft, psf", "ft", "kips, ft, ksf"])
def test_a_drawing_in_feet_is_read_in_the_length_the_units_name(tmp_path, note):
    """Found by fuzzing: a feet drawing was converted to metres when the
    `units` note named no force unit rockdem knew ("lb, ft, psf", or only
    "ft"): 16.07 instead of 173 ft^2 of rock, FS 2.84 instead of 1.52."""
    draw(tmp_path, "ft.dxf", insunits=2)
    model = MODEL.replace("units: kN, m, kPa", f"units: {note}").replace("section.dxf", "ft.dxf")
    (tmp_path / "ft.yaml").write_text(model)
    loaded, _ = load_model(tmp_path / "ft.yaml")
    draw(tmp_path, "m.dxf")
    (tmp_path / "m.yaml").write_text(MODEL.replace("section.dxf", "m.dxf"))
    metres, _ = load_model(tmp_path / "m.yaml")
    # the same numbers: the drawing is in the file's own length unit
    assert loaded.blocks.area.sum() == pytest.approx(metres.blocks.area.sum(), rel=1e-12)


@pytest.mark.parametrize("name", ["1e3", "0o17", "true", "12"])
def test_an_imported_name_that_looks_like_a_number_stays_a_name(tmp_path, name):
    """Found by fuzzing: `--name 1e3` (or a layer JOINT_1e3) was written bare,
    and the reader took it for 1000.0 ("write a name in quotes")."""
    dxf = draw(tmp_path)
    out = tmp_path / "m.yaml"
    r = invoke("import", dxf, "--name", name, "-o", out)
    assert r.exit_code == 0, r.stderr
    _, cfg = load_model(out)
    assert cfg.name == name


def test_an_empty_joint_layer_left_in_the_drawing_is_ignored(tmp_path):
    """Found by fuzzing: an empty leftover layer JOINT_old refused the
    template ("no joint 'old' in joints"), and without a template an empty
    JOINT_aaa became the joint of every ground contact."""
    import ezdxf

    dxf = draw(tmp_path)
    doc = ezdxf.readfile(dxf)
    doc.layers.add("JOINT_old")
    doc.layers.add("JOINT_aaa")
    doc.saveas(dxf)
    (tmp_path / "model.yaml").write_text(MODEL)
    model, _ = load_model(tmp_path / "model.yaml")
    assert [j.name for j in model.joints] == ["bedding", "cross"]
    section = read_section(dxf)
    assert set(section.joint_layers) == {"JOINT_bedding", "JOINT_cross"}


def test_a_binary_drawing_is_read_as_its_text_twin(tmp_path):
    """Found by fuzzing: binary DXF was refused ("Invalid group code"), though
    the refusal of a DWG asks for DXF "ASCII or binary"; cut short, it is a
    one-line refusal (it was "the analysis failed: error: unpack_from")."""
    import ezdxf

    text = draw(tmp_path)
    binary = tmp_path / "binary.dxf"
    ezdxf.readfile(text).saveas(binary, fmt="bin")
    assert binary.read_bytes().startswith(b"AutoCAD Binary DXF")
    a, b = cut_section(read_section(text)), cut_section(read_section(binary))
    assert len(a.polygons) == len(b.polygons)
    for pa, pb in zip(a.polygons, b.polygons, strict=True):
        assert np.array_equal(pa, pb)
    cut = tmp_path / "cut.dxf"
    cut.write_bytes(binary.read_bytes()[:3000])
    assert_refused(invoke("import", cut), "is not a readable DXF file")


@pytest.mark.parametrize("code", [21, 8, 9])
def test_a_drawing_unit_rockdem_cannot_convert_is_refused(tmp_path, code):
    """Found by fuzzing: $INSUNITS 21 (US survey feet), 8 or 9 stopped with
    "the analysis failed: TypeError: Unsupported conversion" (exit 1)."""
    dxf = draw(tmp_path, insunits=code)
    assert_refused(invoke("import", dxf), f"$INSUNITS = {code} is not a unit of length")


@pytest.mark.parametrize(
    ("note", "rock", "gamma_w"),
    [("kN, m, kPa", 26, 9.81), ("t, m, t/m^2", 2.65, 1.0), ("lbf, ft, psf", 165, 62.4)],
)
def test_an_imported_water_table_gets_the_water_of_the_template_units(
    tmp_path, note, rock, gamma_w
):
    """Found by fuzzing: the import wrote water_unit_weight 9.81 (kN and m)
    beside a template in lbf and ft (FS 1.057 instead of 0.921), and a t/m
    template was then refused for rock and water in different units."""
    dxf = draw(tmp_path)
    template = MODEL.replace("units: kN, m, kPa", f"units: {note}")
    template = template.replace("unit_weight: 26", f"unit_weight: {rock}")
    template = template.replace("loads: {water_unit_weight: 9.81}\n", "")
    (tmp_path / "t.yaml").write_text(template.replace("geometry: {dxf: section.dxf}\n", ""))
    text, _, _ = model_text(dxf, template=tmp_path / "t.yaml")
    model, _ = parse_model(text)
    assert model.loads.water_unit_weight == gamma_w


def test_a_study_of_a_drawn_model_replays_and_sees_its_drawing_change(tmp_path):
    """Found by fuzzing: a study rerun after its drawing was corrected printed
    the old statistics ("all done before"), and a resumed one mixed rows cut
    from the two drawings; only the model file's text was compared."""
    pytest.importorskip("pyarrow")
    draw(tmp_path)
    (tmp_path / "model.yaml").write_text(MODEL)
    spec = {"sweep": {"joints.bedding.friction_angle": {"values": [30, 34]}}}
    out = tmp_path / "out"
    rd.study(tmp_path / "model.yaml", spec, workers=0, out=out)
    rd.study(tmp_path / "model.yaml", spec, workers=0, out=out)  # the same: resumed
    # the worst samples' files replay: they find the drawing from worst/
    # (found by fuzzing: they named it as the model file did, from its folder)
    worst = sorted((out / "worst").glob("sample-*.yaml"))
    assert worst
    replayed, _ = load_model(worst[0])
    assert replayed.blocks.n_blocks == load_model(tmp_path / "model.yaml")[0].blocks.n_blocks
    draw(tmp_path, shift=(0.0, 0.5))  # the drawing corrected
    with pytest.raises(rd.InputError, match="results of another study"):
        rd.study(tmp_path / "model.yaml", spec, workers=0, out=out)


def _traces(path: Path) -> dict[str, list[np.ndarray]]:
    """Segments on the JOINT_ layers of a drawing (LINEs and polyline pieces)."""
    doc = ezdxf.readfile(path)
    out: dict[str, list[np.ndarray]] = {}
    for e in doc.modelspace():
        layer = e.dxf.layer
        if not layer.upper().startswith("JOINT_"):
            continue
        if e.dxftype() == "LINE":
            pts = [e.dxf.start, e.dxf.end]
        else:
            pts = list(e.vertices_in_wcs())
        xy = np.array([(p[0], p[1]) for p in pts])
        out.setdefault(layer[6:], []).extend(np.stack([xy[:-1], xy[1:]], axis=1))
    return out


@pytest.mark.parametrize("shift", [(0.0, 0.0), SITE, (-3.2e5, 4.1e6)])
def test_dxf_model_dxf_round_trip_keeps_every_trace(tmp_path, shift):
    dxf = draw(tmp_path, shift=shift)
    (tmp_path / "model.yaml").write_text(MODEL)
    text, section, _ = model_text(dxf, template=tmp_path / "model.yaml")
    (tmp_path / "imported.yaml").write_text(text)
    model, _ = load_model(tmp_path / "imported.yaml")
    back = write_dxf(tmp_path / "back.dxf", model)
    before, after = _traces(dxf), _traces(back)
    size = section.extent
    assert sorted(before) == sorted(after) == ["bedding", "cross"]
    for joint, segs in before.items():
        got = np.array(after[joint])
        assert len(got) == len(segs)
        for seg in segs:  # every drawn trace is in the drawing written back
            err = np.abs(got - seg).max(axis=(1, 2))
            assert err.min() <= 1e-9 * size, (joint, seg, err.min())
    # and the blocks drawn back are the model's
    doc = ezdxf.readfile(back)
    drawn = [
        np.array([(p[0], p[1]) for p in e.vertices_in_wcs()])
        for e in doc.modelspace().query("LWPOLYLINE")
        if e.dxf.layer in ("BLOCKS", "FIXED")
    ]
    assert len(drawn) == model.blocks.n_blocks
    for poly, outline in zip(drawn, outlines(model), strict=True):
        assert np.abs(poly - outline).max() <= 1e-9 * size


def test_the_bundled_example_imports_and_runs(tmp_path):
    out = tmp_path / "example.yaml"
    r = invoke("import", "--example", "--bolt-force", "150", "--out", out)
    assert r.exit_code == 0, r.stderr
    assert "free blocks" in r.stderr and "2 bolts" in r.stderr and "a water table" in r.stderr
    model, cfg = load_model(out)
    assert len(cfg.supports) == 2 and cfg.loads.water_table
    assert model.blocks.n_blocks > 20 and model.blocks.fixed.sum() == 1
    assert model.blocks.centroid[:, 0].min() > 1000  # site coordinates kept
    # the committed drawing is what examples/make_dxf.py makes
    import runpy

    script = Path(__file__).resolve().parents[1] / "examples" / "make_dxf.py"
    made = runpy.run_path(str(script))["main"](str(tmp_path / "made.dxf"))
    a, b = read_section(example_dxf()), read_section(made)
    assert np.array_equal(a.outline, b.outline)
    assert [t.points.tolist() for t in a.traces] == [t.points.tolist() for t in b.traces]
    # bolts pull into the slope from their heads on the face
    assert all(90 < abs(s.angle) < 270 or s.angle < -90 for s in cfg.supports)


def test_import_prints_the_model_without_out_and_refuses_to_overwrite(tmp_path):
    dxf = draw(tmp_path)
    r = invoke("import", dxf)
    assert r.exit_code == 0, r.stderr
    model, _ = parse_model(r.stdout)
    assert model.blocks.n_blocks >= 5
    assert "placeholders" in r.stderr  # no template: the joint properties must be edited
    out = tmp_path / "m.yaml"
    assert invoke("import", dxf, "-o", out).exit_code == 0
    assert_refused(invoke("import", dxf, "-o", out), "exists already", "--overwrite")
    assert invoke("import", dxf, "-o", out, "--overwrite").exit_code == 0


@pytest.mark.parametrize(
    "bad, fragment",
    [("friction_angle: 40", "friction_angle: abc"), ("cohesion: 10", "cohesion: -10")],
)
def test_a_bad_value_in_the_template_is_named_in_the_template(tmp_path, bad, fragment):
    """The imported model is validated before it is written: an error at a key
    the template gave names the template and the key's line there (it named
    the --out file, not written, or "<import>")."""
    dxf = draw(tmp_path)
    template = tmp_path / "model.yaml"
    template.write_text(MODEL.replace(bad, fragment))
    out = tmp_path / "m.yaml"
    line = assert_refused(invoke("import", dxf, "-t", template, "-o", out), "joints.cross.")
    assert line.startswith(f"error: {template}:5: joints.cross.")
    assert not out.exists()


def test_an_error_from_the_drawing_is_named_at_the_drawing(tmp_path):
    """Found by fuzzing: a water table drawn above the crest was reported at
    "<import>:13" (a line of the model not written) instead of the drawing."""
    dxf = draw(tmp_path, water=[(0, 12), (24, 12)])
    out = tmp_path / "m.yaml"
    line = assert_refused(invoke("import", dxf, "-o", out), "loads.water_table")
    assert line.startswith(f"error: {dxf}: loads.water_table: ")
    assert "<import>" not in line and not out.exists()


def test_layer_names_are_overridden_by_a_mapping(tmp_path):
    dxf = draw(tmp_path)
    doc = ezdxf.readfile(dxf)
    doc.layers.get("FIXED").rename("GROUND")
    doc.layers.get("JOINT_bedding").rename("BEDDING_PLANES")
    doc.saveas(tmp_path / "renamed.dxf")
    (tmp_path / "model.yaml").write_text(
        MODEL.replace(
            "geometry: {dxf: section.dxf}",
            "geometry:\n  dxf: renamed.dxf\n  layers:\n    fixed: ground\n"
            "    joints: {BEDDING_PLANES: bedding, JOINT_cross: cross}",
        )
    )
    renamed, _ = load_model(tmp_path / "model.yaml")
    (tmp_path / "plain.yaml").write_text(MODEL)
    plain, _ = load_model(tmp_path / "plain.yaml")
    assert [o.tolist() for o in outlines(renamed)] == [o.tolist() for o in outlines(plain)]
    r = invoke(
        "import",
        tmp_path / "renamed.dxf",
        "-l",
        "fixed=GROUND",
        "-j",
        "BEDDING_PLANES=bedding",
        "-j",
        "JOINT_cross=cross",
    )
    assert r.exit_code == 0, r.stderr


# ------------------------------------------------------------------ hostile drawings
def _hostile(tmp_path: Path, case: str) -> Path:
    path = tmp_path / f"{case}.dxf"
    p = parts()
    if case == "open-outline":
        doc = ezdxf.new()
        msp = doc.modelspace()
        msp.add_lwpolyline(p["outline"], close=False, dxfattribs={"layer": "OUTLINE"})
        msp.add_lwpolyline(p["fixed"][0], close=True, dxfattribs={"layer": "FIXED"})
        doc.saveas(path)
    elif case == "self-crossing-outline":
        bow = [(0, -5), (24, 10), (24, -5), (0, 10)]
        draw(tmp_path, path.name, outline=bow)
    elif case == "self-crossing-trace":
        zigzag = [(2, 8), (12, -2), (12, 8), (2, -2)]
        draw(tmp_path, path.name, traces={"bedding": [zigzag]})
    elif case == "no-fixed-layer":
        draw(tmp_path, path.name, fixed=[])
    elif case == "arc":
        doc = ezdxf.readfile(draw(tmp_path, path.name))
        doc.modelspace().add_lwpolyline(
            [(2, 2, 0, 0, 0.5), (5, 5)], format="xyseb", dxfattribs={"layer": "JOINT_bedding"}
        )
        doc.saveas(path)
    elif case == "spline":
        doc = ezdxf.readfile(draw(tmp_path, path.name))
        doc.modelspace().add_spline([(2, 2), (3, 4), (5, 5)], dxfattribs={"layer": "OUTLINE"})
        doc.saveas(path)
    elif case == "fixed-apart":
        far = [(100, 0), (110, 0), (110, 5), (100, 5)]
        draw(tmp_path, path.name, fixed=[*p["fixed"], far])
    elif case == "fixed-across":  # over the toe and beyond it (found by fuzzing)
        draw(tmp_path, path.name, fixed=[*p["fixed"], [(20, 5), (30, 5), (30, -1), (20, -1)]])
    elif case == "water-turns-back":
        draw(tmp_path, path.name, water=[(0, 6), (12, 1), (8, 0), (24, -1)])
    elif case == "wiggly-crest":  # 10,050 vertices on one block's crest
        x = np.linspace(5.5, 2.0, 10_050)  # within one block's crest
        crest = list(zip(x, 10.0 + 0.01 * (np.arange(x.size) % 2), strict=True))
        draw(tmp_path, path.name, outline=[*p["outline"][:4], *crest, (0, 10)])
    elif case == "empty":
        path.write_bytes(b"")
    elif case == "blank-drawing":
        ezdxf.new().saveas(path)
    elif case == "not-dxf":
        path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(range(256)))
    elif case == "truncated":
        text = draw(tmp_path, "whole.dxf").read_text()
        path.write_text(text[: len(text) // 2])
    elif case == "dwg":
        path.write_bytes(b"AC1027\x00\x00\x00\x00binary")
    elif case == "comma-decimal":  # a coordinate written 20,5 (found by fuzzing)
        lines = draw(tmp_path, "whole.dxf").read_text().splitlines()
        at = lines.index("ENTITIES")
        x = next(i for i in range(at, len(lines)) if lines[i].strip() == "10") + 1
        lines[x] = "20,5"
        path.write_text("\n".join(lines) + "\n")
    return path


HOSTILE = {
    "open-outline": ("is open", "apart", "close the polyline"),
    "self-crossing-outline": ("crosses itself at (12, 2.5)",),
    "self-crossing-trace": ("layer JOINT_bedding", "crosses itself"),
    "no-fixed-layer": ("no layer FIXED", "fixed ground"),
    "arc": ("arcs (bulges)", "explode"),
    "spline": ("SPLINE", "not a line or polyline"),
    "fixed-apart": ("lies apart from the outline",),
    "fixed-across": ("layer FIXED: LWPOLYLINE #", "crosses the outline", "inside the outline"),
    "water-turns-back": ("water table", "turns back at (8, 0)"),
    "empty": ("the file is empty",),
    # refused by the cut, not after 37 s of writing and reading the model file
    # (a 200,000-vertex outline)
    "wiggly-crest": ("10,053 vertices, more than the limit of 10,000", "fewer vertices"),
    "blank-drawing": ("no layer OUTLINE",),
    "not-dxf": ("not a DXF file",),
    "truncated": ("incomplete", "EOF"),
    "dwg": ("DWG",),
    "comma-decimal": ("structural errors", '"20,5"'),
}


@pytest.mark.parametrize("case", sorted(HOSTILE))
def test_a_hostile_drawing_gives_exit_2_and_one_line(tmp_path, case):
    path = _hostile(tmp_path, case)
    line = assert_refused(invoke("import", path), path.name, *HOSTILE[case])
    # the same drawing named by a model file: the same problem, at `geometry`
    (tmp_path / "model.yaml").write_text(MODEL.replace("section.dxf", path.name))
    line = assert_refused(
        invoke("check", tmp_path / "model.yaml"),
        "model.yaml:",
        "geometry",
        path.name,
        *HOSTILE[case],
    )
    assert line.count("error:") == 1


def test_a_fixed_region_across_the_outline_is_refused_beside_or_along_it_is_not(tmp_path):
    """Found by fuzzing: a FIXED rectangle over the toe, half outside the
    outline, grew the ground into a 5 m wall beyond the drawn slope.  A region
    beside the outline (sharing its edge) adds ground, one inside marks it;
    one across its edge is refused, naming the entity and how far it reaches."""
    p = parts()
    across = draw(
        tmp_path, "across.dxf", fixed=[*p["fixed"], [(20, 5), (30, 5), (30, -1), (20, -1)]]
    )
    handle = [e.dxf.handle for e in ezdxf.readfile(across).modelspace().query("*[layer=='FIXED']")]
    assert_refused(
        invoke("import", across, "--out", tmp_path / "across.yaml"),
        "across.dxf",
        f"the fixed region (layer FIXED: LWPOLYLINE #{handle[-1]}) crosses the outline",
        "it reaches 7.81 outside it, to (30, 5)",  # from the corner (24, 0)
        "draw the FIXED region inside the outline",
    )
    assert not (tmp_path / "across.yaml").exists()
    # beside (sharing the edge x = 24 or the face), overlapping it by round-off,
    # inside along its edge or out by round-off: all read, at site coordinates too
    eps = 1e-9
    fine = {
        "beside": [(24, -5), (30, -5), (30, 0), (24, 0)],
        "beside-overlap": [(24 - eps, -5), (30, -5), (30, 0), (24 - eps, 0)],
        "inside-along": [(22, -3), (24, -3), (24, 0), (22, 0)],
        "inside-out-by-eps": [(20, -3), (24 + eps, -3), (24 + eps, 0), (20, 0)],
        "beside-face": [(14, 0), (16, 0), (10, 10)],
        "inside-face": [(14, 0), (10, 10), (10, 0)],
    }
    for name, region in fine.items():
        for shift in ((0.0, 0.0), SITE):
            move = [(x + shift[0], y + shift[1]) for x, y in region]
            dxf = draw(tmp_path, f"{name}.dxf", shift=shift, fixed=[*parts(shift)["fixed"], move])
            blocks = cut_section(read_section(dxf))
            assert blocks.fixed.any() and blocks.n_free > 0, name


def test_a_repaired_number_is_one_line_in_a_child_process(tmp_path):
    """ezdxf logs each number it repairs while reading; in a process of its
    own (no test harness catching the log) the refusal is still one line."""
    import subprocess
    import sys

    path = _hostile(tmp_path, "comma-decimal")
    r = subprocess.run(
        [sys.executable, "-m", "rockdem", "import", path.name],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert_refused(r, "structural errors", '"20,5"')


def test_missing_file_unknown_layer_and_unknown_joint(tmp_path):
    assert_refused(invoke("import", tmp_path / "nope.dxf"), "nope.dxf: file not found")
    assert_refused(invoke("import", tmp_path), "is a folder", "give a DXF file")
    dxf = draw(tmp_path)
    assert_refused(
        invoke("import", dxf, "--layer", "fixed=GROUND"),
        "no layer 'GROUND'",
        "its layers:",
        "FIXED",
    )
    assert_refused(invoke("import", dxf, "--layer", "roof=R"), "layers.roof", "not a part")
    # one layer in two parts was "layer FIXED holds 3 polylines"
    assert_refused(
        invoke("import", dxf, "--layer", "outline=FIXED"),
        "layer FIXED is both the outline and the fixed",
        "its own layer",
    )
    assert_refused(invoke("import", dxf, "-j", "JOINT_X=bedding"), "no layer 'JOINT_X'")
    (tmp_path / "model.yaml").write_text(MODEL.replace("  cross:", "  crossing:"))
    assert_refused(
        invoke("check", tmp_path / "model.yaml"),
        "model.yaml",
        "layer JOINT_cross",
        "no joint 'cross'",
    )
    (tmp_path / "model.yaml").write_text(
        MODEL.replace(
            "{dxf: section.dxf}", "{dxf: section.dxf, layers: {joints: {JOINT_cross: nope}}}"
        )
    )
    assert_refused(
        invoke("check", tmp_path / "model.yaml"),
        "geometry.layers.joints.JOINT_cross",
        "joint 'nope' is not defined",
    )
    (tmp_path / "model.yaml").write_text(MODEL.replace("section.dxf", "missing.dxf"))
    assert_refused(
        invoke("check", tmp_path / "model.yaml"), "geometry.dxf", "missing.dxf", "file not found"
    )
    (tmp_path / "model.yaml").write_text(MODEL.replace("loads: {water_unit_weight: 9.81}", ""))
    assert_refused(invoke("check", tmp_path / "model.yaml"), "water table", "water_unit_weight")
    (tmp_path / "model.yaml").write_text(MODEL + "blocks: [{vertices: [[0, 0], [1, 0], [1, 1]]}]\n")
    assert_refused(invoke("check", tmp_path / "model.yaml"), "not both blocks and geometry")


def test_bolts_are_passive_bolts_or_anchors_pulling_from_the_face(tmp_path):
    head = (11.0, 7.5)  # on the face (10, 10) - (14, 0): x = 10 + (10 - y) * 0.4
    tail = (head[0] - 6.0, head[1] - 1.6)
    dxf = draw(tmp_path, bolts=[(tail, head)])  # drawn from the far end: the head is found
    assert_refused(invoke("import", dxf), "1 bolts but neither", "--bolt-force", "--bolt-capacity")
    (tmp_path / "model.yaml").write_text(MODEL)
    assert_refused(invoke("check", tmp_path / "model.yaml"), "geometry.bolt", "geometry.bolt_force")
    angle = math.degrees(math.atan2(tail[1] - head[1], tail[0] - head[0]))
    # active anchors
    anchors = MODEL.replace("section.dxf}", "section.dxf, bolt_force: 80}")
    (tmp_path / "model.yaml").write_text(anchors)
    model, cfg = load_model(tmp_path / "model.yaml")
    (bolt,) = [p for p in model.loads.points if p.name == "drawn bolt 1"]
    assert (bolt.x, bolt.y) == head
    assert math.hypot(bolt.fx, bolt.fy) == pytest.approx(80)
    assert math.degrees(math.atan2(bolt.fy, bolt.fx)) == pytest.approx(angle)
    assert cfg.supports == []  # the echo keeps the file as written
    # passive bolts: head, direction and length from the drawing
    passive = MODEL.replace(
        "section.dxf}", "section.dxf, bolt: {capacity: 150, axial_stiffness: 1.0e+5}}"
    )
    (tmp_path / "model.yaml").write_text(passive)
    model, _ = load_model(tmp_path / "model.yaml")
    (bolt,) = model.bolts
    assert tuple(bolt.head) == head and bolt.capacity == 150
    assert bolt.angle == pytest.approx(angle) and bolt.length == pytest.approx(math.hypot(6, 1.6))
    assert bolt.installed == "before_loads"
    later = passive.replace("1.0e+5}", "1.0e+5, installed: after_loads}")
    (tmp_path / "model.yaml").write_text(later)
    assert load_model(tmp_path / "model.yaml")[0].bolts[0].installed == "after_loads"
    # the imported file says the same
    r = invoke("import", dxf, "--bolt-capacity", "150", "--bolt-stiffness", "1e5")
    assert r.exit_code == 0, r.stderr
    imported, _ = parse_model(r.stdout)
    (same,) = imported.bolts
    assert tuple(same.head) == tuple(bolt.head) and same.angle == bolt.angle
    assert same.length == bolt.length
    both = passive.replace("section.dxf,", "section.dxf, bolt_force: 80,")
    (tmp_path / "model.yaml").write_text(both)
    assert_refused(invoke("check", tmp_path / "model.yaml"), "both `bolt` and `bolt_force`")


def test_a_bolt_drawn_through_to_the_back_edge_has_its_head_on_the_face(tmp_path):
    """Found by fuzzing: a bolt line from the back edge (on the fixed ground)
    to the face, both ends on the outline, took its head at the back: the
    anchor acted on the fixed block ("supports[0]: ... acts on a fixed block")."""
    head = (11.0, 7.5)  # on the face
    back = (0.0, 7.5)  # on the back edge, in the fixed strip behind x = 1
    dxf = draw(tmp_path, bolts=[(back, head)])
    anchors = MODEL.replace("section.dxf}", "section.dxf, bolt_force: 80}")
    (tmp_path / "model.yaml").write_text(anchors)
    model, _ = load_model(tmp_path / "model.yaml")
    (bolt,) = [p for p in model.loads.points if p.name == "drawn bolt 1"]
    assert (bolt.x, bolt.y) == head and bolt.fx < 0  # pulling into the slope
    assert invoke("import", dxf, "--bolt-force", "80").exit_code == 0


def test_a_bolt_drawn_twice_is_refused(tmp_path):
    """Found by fuzzing: a bolt copied onto itself in CAD doubled the bolting
    without a word."""
    head = (11.0, 7.5)
    tail = (head[0] - 6.0, head[1] - 1.6)
    dxf = draw(tmp_path, bolts=[(tail, head), (head, tail)])
    assert_refused(invoke("import", dxf, "--bolt-force", "80"), "lies on bolt 1 (a copy?)")


def test_the_imported_file_says_which_joint_the_ground_takes_and_drops_template_trials(
    tmp_path,
):
    """Found by fuzzing: without a template the first joint took every
    contact with the fixed ground, unsaid; with one, its stabilisation trials
    (the template's own block ids) were carried into the new model."""
    dxf = draw(tmp_path)
    r = invoke("import", dxf)
    assert "# contacts with the fixed ground and untraced contacts take joint 'bedding'" in (
        r.stdout
    )
    template = MODEL + "stabilisation:\n  target_fos: 1.5\n  trials: [{remove: [3, 4]}]\n"
    (tmp_path / "t.yaml").write_text(template.replace("geometry: {dxf: section.dxf}\n", ""))
    text, _, _ = model_text(dxf, template=tmp_path / "t.yaml")
    _, cfg = parse_model(text)
    assert cfg.stabilisation.target_fos == 1.5 and cfg.stabilisation.trials == []


# ------------------------------------------------------------------ results out
@pytest.fixture(scope="module")
def fos_results(tmp_path_factory):
    """`rockdem fos --out DIR --format all` of the drawn section (unstable at F ~ 1.1)."""
    folder = tmp_path_factory.mktemp("fos")
    draw(folder)
    (folder / "model.yaml").write_text(MODEL)
    out = folder / "out"
    r = invoke(
        "fos",
        folder / "model.yaml",
        "--out",
        out,
        "--format",
        "vtk,geojson",
        "--format",
        "dxf",
        "--quiet",
    )
    assert r.exit_code == 0, r.stderr
    model, _ = load_model(folder / "model.yaml")
    return out, model


def _rows(out: Path, table: str) -> list[dict]:
    return json.loads((out / "result.json").read_text())[table]


def test_vtk_files_read_back_with_their_cells_and_fields(fos_results):
    meshio = pytest.importorskip("meshio")
    out, model = fos_results
    blocks, faces = _rows(out, "blocks"), _rows(out, "interfaces")
    mesh = meshio.read(out / "blocks.vtu")
    b = model.blocks
    assert sum(len(c.data) for c in mesh.cells) == b.n_blocks
    assert all(c.type == "polygon" for c in mesh.cells)
    assert len(mesh.points) == len(b.vertices)  # every block its own vertices
    ids = np.concatenate(mesh.cell_data["block_id"])
    assert ids.tolist() == [row["id"] for row in blocks]
    disp = np.concatenate(mesh.cell_data["displacement"])
    assert np.array_equal(disp[:, 0], [row["ux"] for row in blocks])
    assert np.array_equal(disp[:, 1], [row["uy"] for row in blocks])
    modes = np.concatenate(mesh.cell_data["failure_mode"])
    unstable = np.concatenate(mesh.cell_data["unstable"])
    expect = [-1 if r["fixed"] else rd.modes.MODES.index(r["failure_mode"]) for r in blocks]
    assert modes.tolist() == expect
    assert (unstable == 1).sum() >= 1  # the mechanism at the limit
    assert ((unstable == 1) == (modes > 0)).all()
    # vertex displacement: the block's rigid motion at the vertex
    k = int(np.argmax(np.abs(disp[:, 0]) + np.abs(disp[:, 1])))
    conn = np.concatenate([c.data.reshape(-1) for c in mesh.cells])  # cells in block order
    v = conn[model.blocks.offsets[k]]  # block k's first vertex
    rot = blocks[k]["rotation"]
    c = model.blocks.centroid[k]
    u = mesh.point_data["displacement"][v]
    p = mesh.points[v]
    assert u[0] == pytest.approx(blocks[k]["ux"] - rot * (p[1] - c[1]), abs=1e-15)
    assert u[1] == pytest.approx(blocks[k]["uy"] + rot * (p[0] - c[0]), abs=1e-15)
    lines = meshio.read(out / "interfaces.vtu")
    assert [c.type for c in lines.cells] == ["line"]
    assert len(lines.cells[0].data) == len(faces) and len(lines.points) == 2 * len(faces)
    sn = lines.cell_data["normal_stress"][0]
    assert np.array_equal(sn, [row["normal_stress"] for row in faces])
    state = lines.cell_data["state"][0]
    assert state.tolist() == [("elastic", "shear", "tension").index(r["state"]) for r in faces]
    assert (state > 0).any()
    start = lines.points[lines.cells[0].data[:, 0], :2]
    assert np.allclose(start, [[r["start_x"], r["start_y"]] for r in faces], rtol=0, atol=0)


def test_geojson_is_valid_and_counts_every_feature(fos_results):
    out, model = fos_results
    data = json.loads((out / "section.geojson").read_text())
    assert data["type"] == "FeatureCollection"
    layers = [f["properties"]["layer"] for f in data["features"]]
    n_faces = len(_rows(out, "interfaces"))
    assert layers.count("block") == model.blocks.n_blocks
    assert layers.count("joint") == len(model.joint_lines)
    assert layers.count("interface") == n_faces
    assert layers.count("water_table") == 1
    assert len(data["features"]) == model.blocks.n_blocks + len(model.joint_lines) + n_faces + 1
    for f in data["features"]:
        assert f["type"] == "Feature" and set(f) >= {"geometry", "properties"}
        if f["geometry"]["type"] == "Polygon":
            ring = np.array(f["geometry"]["coordinates"][0])
            assert (ring[0] == ring[-1]).all() and len(ring) >= 4
            x, y = ring[:-1].T
            assert np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y) > 0  # counter-clockwise
    unstable = [
        f["properties"]["id"]
        for f in data["features"]
        if f["properties"]["layer"] == "block" and f["properties"]["unstable"]
    ]
    assert unstable == sorted(json.loads((out / "result.json").read_text())["mechanism_blocks"])


def test_result_dxf_has_unstable_blocks_and_failed_joints_on_their_layers(fos_results):
    out, model = fos_results
    doc = ezdxf.readfile(out / "result.dxf")
    msp = doc.modelspace()
    count = {}
    for e in msp:
        count[e.dxf.layer] = count.get(e.dxf.layer, 0) + 1
    mech = json.loads((out / "result.json").read_text())["mechanism_blocks"]
    failed = [r for r in _rows(out, "interfaces") if r["state"] != "elastic"]
    assert count["UNSTABLE"] == len(mech) >= 1
    assert count["FAILED_JOINTS"] == len(failed) >= 1
    assert count["BLOCKS"] + count["FIXED"] == model.blocks.n_blocks
    assert count["BLOCK_IDS"] == model.blocks.n_blocks
    assert count["WATER"] == 1
    assert doc.header["$INSUNITS"] == 6  # metres, from `units`
    drawn = sorted(
        tuple(np.round([(p[0], p[1]) for p in e.vertices_in_wcs()], 9).ravel())
        for e in msp.query('LWPOLYLINE[layer=="UNSTABLE"]')
    )
    b = model.blocks
    index = b.index_of(mech)
    assert drawn == sorted(tuple(np.round(b.outline(int(i)), 9).ravel()) for i in index)


def test_format_options(tmp_path, fos_results):
    out, _ = fos_results
    assert not (out / "springs.vtu").exists()
    (tmp_path / "box.yaml").write_text((out.parent / "model.yaml").read_text())
    draw(tmp_path)
    assert_refused(
        invoke("run", tmp_path / "box.yaml", "--format", "vtk"), "--format", "needs --out"
    )
    assert_refused(
        invoke("run", tmp_path / "box.yaml", "--out", tmp_path / "o", "--format", "png"),
        "'png' is not a result format",
    )
    r = invoke(
        "run", tmp_path / "box.yaml", "--out", tmp_path / "o", "--format", "csv,geojson", "-q"
    )
    assert r.exit_code == 0, r.stderr
    written = {p.name for p in (tmp_path / "o").iterdir()}
    assert written - set(RESULT_FILES) == {"section.geojson"}
    # existing exchange files are not replaced without --overwrite, with nothing written
    assert_refused(
        invoke("run", tmp_path / "box.yaml", "--out", tmp_path / "o", "--format", "geojson"),
        "already holds",
    )
    r = invoke(
        "run",
        tmp_path / "box.yaml",
        "--out",
        tmp_path / "o",
        "--format",
        "all",
        "--overwrite",
        "-q",
    )
    assert r.exit_code == 0, r.stderr
    assert (tmp_path / "o" / "blocks.vtu").exists() and (tmp_path / "o" / "result.dxf").exists()


def test_results_never_write_over_the_models_drawing(tmp_path):
    """A section drawn in result.dxf, its results asked for in the same folder
    as DXF: refused (exit 2, one line), even with --overwrite; the drawing is
    unchanged."""
    dxf = draw(tmp_path, name="result.dxf")
    (tmp_path / "model.yaml").write_text(MODEL.replace("section.dxf", "result.dxf"))
    before = dxf.read_bytes()
    res = invoke(
        "run", tmp_path / "model.yaml", "--out", tmp_path, "--format", "dxf", "--overwrite"
    )
    assert res.exit_code == 2, res.output
    assert "would write result.dxf over" in res.output
    assert dxf.read_bytes() == before


def test_a_grid_of_traces_beyond_the_block_limit_is_refused_before_the_cut(tmp_path):
    """Found by fuzzing: 1,500 x 1,500 crossing traces (3,000 segments, within
    the segment limit) cut 2.25 million blocks, and noding them ran out of
    memory (5.6 GB, exit 1) before the block limit was checked.  The
    crossings are now counted first (Euler: at least crossings - traces
    blocks).  Here 120 x 120 traces against a limit of 10,000 blocks; the
    same grid within a limit of 20,000 is cut (14,400 blocks, more than
    the 14,160 the count promises)."""
    import time

    from rockdem.exchange.dxf_entities import DxfError

    v = [
        [(1.0 + 21.5 * (i + 0.5) / 120, -4.0), (1.0 + 21.5 * (i + 0.5) / 120, 9.0)]
        for i in range(120)
    ]
    h = [
        [(0.5, -2.9 + 2.8 * (j + 0.5) / 120), (23.5, -2.9 + 2.8 * (j + 0.5) / 120)]
        for j in range(120)
    ]
    path = draw(tmp_path, traces={"bedding": v, "cross": h}, water=None)
    section = read_section(path)
    start = time.monotonic()
    counted = "cross each other at least 14,400 times: they would cut at least 14,160"
    with pytest.raises(DxfError, match=counted):
        cut_section(section, max_blocks=10_000)
    assert time.monotonic() - start < 5.0
    assert len(cut_section(section, max_blocks=20_000).polygons) > 14_160


def test_a_section_too_wide_for_its_blocks_is_refused_at_the_drawing(tmp_path):
    """Found by fuzzing: a section 1e9 m wide with 10 m high blocks cut blocks
    (7 m) thinner than the drawing's tolerance (1e-8 of its size), which reached
    the user as a raw "1 validation error for BlockSpec"."""
    from rockdem.exchange.dxf_entities import DxfError

    wide = 1e9
    path = draw(
        tmp_path,
        outline=[(0, 0), (wide, 0), (wide, 10), (0, 10)],
        fixed=[[(0, 0), (wide, 0), (wide, 3), (0, 3)]],
        traces={"bedding": [], "cross": []},
        water=None,
    )
    with pytest.raises(DxfError, match=r"collapses: it is thinner than the drawing's tolerance"):
        cut_section(read_section(path))


def test_an_empty_drawing_name_is_called_empty(tmp_path):
    """Found by fuzzing: `geometry: {dxf: ''}` read "is a folder" (the model's own)."""
    from rockdem.config import ModelFileError

    text = MODEL.replace("geometry: {dxf: section.dxf}", "geometry: {dxf: ''}")
    with pytest.raises(ModelFileError, match=r"geometry\.dxf: is empty"):
        parse_model(text, source=str(tmp_path / "m.yaml"))


def test_overwriting_results_refuses_to_leave_another_formats_files(tmp_path, fos_results):
    """Found by fuzzing: results with VTK, then another model's results over
    them with --overwrite and no --format left the first model's .vtu files
    beside the second's tables.  Refused, naming the files; asking for the
    format too replaces them."""
    out, _ = fos_results
    (tmp_path / "box.yaml").write_text((out.parent / "model.yaml").read_text())
    draw(tmp_path)
    folder = tmp_path / "o"
    first = invoke("run", tmp_path / "box.yaml", "--out", folder, "--format", "vtk", "-q")
    assert first.exit_code == 0, first.stderr
    vtu = (folder / "blocks.vtu").read_bytes()
    again = invoke("run", tmp_path / "box.yaml", "--out", folder, "--overwrite", "-q")
    assert_refused(again, "holds blocks.vtu, interfaces.vtu of an earlier run")
    assert (folder / "blocks.vtu").read_bytes() == vtu  # nothing removed
    both = invoke(
        "run", tmp_path / "box.yaml", "--out", folder, "--overwrite", "--format", "vtk", "-q"
    )
    assert both.exit_code == 0, both.stderr


def test_a_trace_drawn_through_the_toe_cuts_there_wherever_the_drawing_lies():
    """A bedding trace drawn through the toe, a reflex corner of the section,
    runs through rock on both sides of it.  Whether GEOS split it at the
    toe followed the round-off of the drawing's coordinates: moved by 60
    random offsets up to 1e4, the blocks on either side of the toe came out
    as one bow-tie block (86.08 m^2 for 28.35 + 57.74) in 23 of them."""
    import shapely

    from rockdem.exchange.dxf_cut import cut_section
    from rockdem.exchange.dxf_in import Section, Trace

    crest = 10.0 / np.tan(np.radians(60.0))
    outline = np.array([(-10, -6), (20, -6), (20, 10), (crest, 10), (0, 0), (-10, 0)], float)
    ground = np.array([(-10, -6), (20, -6), (20, -5), (-10, -5)], float)
    slope = np.tan(np.radians(30.0))
    trace = np.array([(-9.0, -9.0 * slope), (22.0, 22.0 * slope)])  # through (0, 0)

    def areas(shift):
        line = Trace("bedding", "JOINT_bedding", trace + shift)
        drawn = Section("x", outline + shift, (ground + shift,), (line,), None, (), 6, 1.0, {}, {})
        return sorted(float(shapely.Polygon(p).area) for p in cut_section(drawn).polygons)

    here = areas(np.zeros(2))
    assert here == pytest.approx([28.349365, 30.0, 57.735027, 235.048095], abs=1e-5)
    for shift in np.random.default_rng(0).uniform(-1e4, 1e4, (60, 2)):
        assert areas(shift) == pytest.approx(here, abs=1e-6), shift
