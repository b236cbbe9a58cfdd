"""The installers' drawings, read back as SVG (xml.etree): the key plan names every panel and beam plate once
(glazing strips and splice plates lie on their beams), each panel label lies in its face as seen from above, no
two texts of a sheet overlap and no text crosses a drawn line (text measured with matplotlib's font metrics, not
with the writer's estimate, :mod:`sheet_geometry`), every sheet is on its paper with a frame and a title block,
and every node with plates is on the sheet of its type."""

import csv
import re
import shutil
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from ppfab.io import load_mesh

from conftest import built_folder, small_vault
from sheet_geometry import crossings, overlaps, svg_sheet

NS = "{http://www.w3.org/2000/svg}"
SMALL = small_vault("drawings")
built = built_folder("drawings", SMALL)


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _texts(path):
    root = ET.parse(path).getroot()
    assert root.tag == f"{NS}svg"
    return root, list(root.iter(f"{NS}text"))


def _measured_box(t):
    """The box of an SVG text from matplotlib's metrics of DejaVu Sans Mono (the font the drawings name)."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import TextPath
    from shapely.geometry import Polygon

    h = float(t.get("font-size"))
    ext = TextPath((0, 0), t.text, size=h, prop=FontProperties(family="DejaVu Sans Mono")).get_extents()
    w = ext.x1                                 # advance from the text's start
    x0 = 0.0 if t.get("text-anchor") == "start" else -0.5 * w
    local = np.array([[x0, -0.6 * h], [x0 + w, -0.6 * h], [x0 + w, 0.6 * h], [x0, 0.6 * h]])
    rot = re.findall(r"rotate\(([-0-9.e]+)", t.get("transform", ""))
    a = np.radians(float(rot[0])) if rot else 0.0
    r = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    return Polygon(local @ r.T + [float(t.get("x")), float(t.get("y"))])


def test_key_plan_names_every_part_once_inside_its_face(built):
    from shapely.geometry import Polygon

    parts = _rows(built / "parts.csv")
    root, texts = _texts(built / "drawings" / "key_plan.svg")
    labels = [t for t in texts if t.get("data-part")]
    names = [t.text for t in labels] + [t.text for t in texts if t.get("data-listed")]   # at their place or listed
    # every panel and beam plate, once (glazing strips and splice plates lie on their beams, named on them)
    assert sorted(names) == sorted(r["part_id"] for r in parts if r["kind"] in ("panel", "beam"))
    # panel labels inside their face seen from above (the OBJ face, y flipped into SVG's frame)
    mesh = load_mesh(built / "mesh.obj")
    polys = [Polygon(mesh.vertices[f][:, :2]) for f in mesh.faces]
    face_of = {r["part_id"]: int(r["face"]) for r in parts if r["kind"] == "panel"}
    [view] = [el for el in root if el.get("data-frame")]                # the view nested in the sheet
    fx0, fy1 = map(float, view.get("data-frame").split())           # picture (x, y) -> (x - x0, y1 - y)
    inside = 0
    for pid, f in face_of.items():
        q = np.asarray(polys[f].exterior.coords)
        face_svg = Polygon(np.c_[q[:, 0] - fx0, fy1 - q[:, 1]])
        t = [x for x in labels if x.text == pid]
        if t:
            assert face_svg.contains(_measured_box(t[0])), pid
            inside += 1
    assert inside >= 0.75 * len(face_of) > 0


def test_no_text_overlaps_another_or_crosses_a_line_on_any_sheet(built):
    """Every text of every sheet (views, node sheets, erection drawing; title blocks, lists and scale bars
    included), measured with the font's metrics in paper mm: no two overlap, none is crossed by a drawn line
    (panel outlines, plate lines, bands, frame and title-block rules), all read from the bottom or the right edge,
    all at least 2.5 mm high on paper and every panel (beam) label as high as every other."""
    sheets = sorted((built / "drawings").rglob("*.svg"))
    assert len(sheets) >= 5
    counted = 0
    for path in sheets:
        root, texts, lines = svg_sheet(path)
        assert texts and lines, path.name
        assert not overlaps(texts), (path.name, overlaps(texts)[:5])
        assert not crossings(texts, lines), (path.name, crossings(texts, lines)[:5])
        for t in texts:
            rot = re.findall(r"rotate\(([-0-9.e]+)", t.element.get("transform", ""))
            assert -45.0 < -float(rot[0] if rot else 0.0) <= 135.0, (path.name, t.text)
            assert t.height >= 2.5 - 1e-6, (path.name, t.text, t.height)
        for kind in ("panel", "beam"):
            hs = {round(t.height, 6) for t in texts if t.element.get("data-class") == kind}
            assert len(hs) <= 1, (path.name, kind, hs)
        counted += len(texts)
    assert counted > 100


def test_sheets_are_on_a1_with_a_title_block_numbered_within_the_set(built):
    """Every sheet is A1 (841 x 594 mm) with a frame inside the paper and the grid reference of ISO 5457 in its
    margins (fields 1-16 along the top and bottom, A-M without I along the sides); its title block names the
    project, the sheet, its number of the total (1..N once each, N the number of sheets) and the scale; a view's
    picture is its model extent divided by a standard scale's denominator."""
    design_name = "drawings"
    sheets = sorted((built / "drawings").rglob("*.svg"))
    numbers = []
    for path in sheets:
        root = ET.parse(path).getroot()
        assert (root.get("width"), root.get("height"), root.get("viewBox")) == ("841mm", "594mm", "0 0 841 594")
        [frame] = [r for r in root.iter(f"{NS}rect") if r.get("class") == "frame"]
        x, y, w, h = (float(frame.get(k)) for k in ("x", "y", "width", "height"))
        assert x >= 20.0 - 1e-9 and y >= 10.0 - 1e-9 and x + w <= 831.0 + 1e-9 and y + h <= 584.0 + 1e-9
        fields = {t.get("data-field"): t.text for t in root.iter(f"{NS}text") if t.get("data-field")}
        assert fields["project"] == design_name, path.name
        m = re.fullmatch(r"sheet (\d+) of (\d+)", fields["sheet"])
        assert m and int(m.group(2)) == len(sheets), (path.name, fields["sheet"])
        numbers.append(int(m.group(1)))
        for view in (el for el in root if el.get("data-frame")):
            s = float(view.get("data-scale"))
            if view.get("data-view") in ("plan", "front", "side", "erection"):
                assert int(s) in (1, 2, 5, 10, 20, 25, 50, 100, 200, 250, 500, 1000), path.name
                assert fields["scale"] == f"scale 1:{int(s)}"
            vb = [float(c) for c in view.get("viewBox").split()]
            assert float(view.get("width")) == pytest.approx(vb[2] / s, rel=1e-5)
        grid = [t.text for g in root.iter(f"{NS}g") if g.get("class") == "grid-reference" for t in g.iter(f"{NS}text")]
        assert sorted(grid) == sorted([str(k) for k in range(1, 17)] * 2 + list("ABCDEFGHJKLM") * 2), path.name
    assert sorted(numbers) == list(range(1, len(sheets) + 1))


@pytest.mark.parametrize("view", ["key_plan", "elevation_front", "elevation_side"])
def test_views_carry_a_true_scale_bar_and_their_extent(built, view):
    """Each view has a scale bar whose drawn length (picture mm, the SVG's units) is the length its label says,
    and states its extent, which equals the extent of the mesh's vertices (mesh.obj) along the view's axes; the
    key plan has a north arrow pointing up the sheet (+y)."""
    root, texts = _texts(built / "drawings" / f"{view}.svg")
    [bar] = [g for g in root.iter(f"{NS}g") if g.get("class") == "scale-bar"]
    xs = [float(v.split(",")[0]) for p in bar.iter(f"{NS}polygon") for v in p.get("points").split()]
    drawn = (max(xs) - min(xs)) * float(root.get("data-scale"))      # paper mm times the scale's denominator
    said = [t.text for t in texts if re.fullmatch(r"[0-9.]+ (m|mm)", t.text or "")]
    assert len(said) == 1
    value, unit = said[0].split()
    scale = float(root.get("data-scale"))
    assert drawn == pytest.approx(float(value) * (1000.0 if unit == "m" else 1.0), abs=0.01 * scale)
    v = load_mesh(built / "mesh.obj").vertices
    axes = {"key_plan": (0, 1), "elevation_front": (0, 2), "elevation_side": (1, 2)}[view]
    [extent] = [t.text for t in texts if (t.text or "").startswith("extent ")]
    numbers = [float(s.replace(" ", "")) for s in re.findall(r"([0-9][0-9 ]*) mm", extent)]
    want = [float(np.ptp(v[:, a])) for a in axes]
    assert numbers == pytest.approx(want, abs=1.0), (extent, want)
    arrows = [p for p in root.iter(f"{NS}polygon") if p.get("class") == "north-arrow"]
    assert len(arrows) == (1 if view == "key_plan" else 0)
    if arrows:
        pts = np.array([[float(c) for c in q.split(",")] for q in arrows[0].get("points").split()])
        assert pts[0, 1] < pts[1:, 1].min()                  # the tip is the highest point (SVG y runs down)


def test_node_sheets_hold_every_node_once_with_angles_within_the_type(built):
    nodes = {r["node_id"]: r for r in _rows(built / "nodes.csv") if r["beams"]}
    seen: dict[str, str] = {}
    for path in sorted((built / "drawings" / "nodes").glob("node_type_*.svg")):
        _, texts = _texts(path)
        ids = [m.group(1) for t in texts if (m := re.match(r"(N\d+) ", t.text or ""))]
        dih = [float(nodes[n]["dihedral_deg"]) for n in ids if nodes[n]["dihedral_deg"]]
        if dih:
            assert max(dih) - min(dih) <= 1.0 + 1e-9, path.name                 # the 1° grid of the types
        joints = {nodes[n]["joint"] for n in ids}
        assert len(joints) == 1, path.name
        for n in ids:
            assert n not in seen, (n, path.name, seen.get(n))
            seen[n] = path.name
            for b in nodes[n]["beams"].split(";"):                          # the beams are named on the sheet
                assert any(t.text and b in t.text for t in texts), (n, b)
    assert sorted(seen) == sorted(nodes)


def test_node_sheets_have_no_overlapping_text_and_corners_meet_in_an_l(built):
    """On every node sheet no two texts overlap (measured with the font's metrics, in paper mm) and every label
    reads from the bottom or the right edge; a plate that ends at the node is drawn on one side of it only (a
    corner's two plates meet in an L), a plate running through on both sides."""
    sheets = sorted((built / "drawings" / "nodes").glob("node_type_*.svg"))
    assert sheets
    roles = set()
    for path in sheets:
        root, texts = _texts(path)
        assert not overlaps(svg_sheet(path)[1]), path.name
        for t in texts:
            rot = re.findall(r"rotate\(([-0-9.e]+)", t.get("transform", ""))
            assert -45.0 < -float(rot[0] if rot else 0.0) <= 135.0, (path.name, t.text)
        centre = [p for p in root.iter(f"{NS}polyline") if p.get("class") == "node-centre"]
        pts = np.array([[float(c) for c in q.split(",")] for q in centre[0].get("points").split()])
        c = pts.mean(axis=0)
        for band in (p for p in root.iter(f"{NS}polygon") if p.get("data-role") is not None):
            q = np.array([[float(x) for x in s.split(",")] for s in band.get("points").split()])
            axis = q[1] - q[0]
            along = (q - c) @ (axis / np.linalg.norm(axis))
            roles.add(band.get("data-role"))
            if band.get("data-role") == "end":
                assert along.min() > -0.2 or along.max() < 0.2, (path.name, band.get("data-part"))  # 0.1 rounding
            else:
                assert along.min() < -10.0 and along.max() > 10.0, (path.name, band.get("data-part"))
    assert {"through", "end"} <= roles


def test_verify_names_a_part_missing_from_the_key_plan(built, tmp_path):
    from fabrication.verify import verify

    bad = tmp_path / "bad"
    shutil.copytree(built, bad)
    plan = bad / "drawings" / "key_plan.svg"
    text = plan.read_text()
    victim = re.search(r'data-part="(P-[^"]+)"', text).group(1)
    plan.write_text(re.sub(rf'<text[^>]*data-part="{victim}"[^>]*>{victim}</text>', "", text))
    found = [str(f) for f in verify(bad).findings]
    assert any("not on the key plan" in f and victim in f for f in found), found


def test_panels_overlapping_in_plan_keep_their_labels_apart():
    """Eight panes stacked above one another (a wall or an overhang seen from above), each with room for one
    label on paper: no two labels overlap, and the ids without room at their place are listed below the view."""
    from shapely import STRtree

    from fabrication.drawings import view_svg

    class Pane:
        def __init__(self, k):
            self.part_id = f"P-STACKED-{k:02d}"
            self._pts = np.array([[0, 0, 100.0 * k], [30, 0, 100.0 * k], [30, 6, 100.0 * k],
                                  [0, 6, 100.0 * k]])                 # 30 x 6 mm at 1:1: room for one id

        def outline_3d(self):
            return self._pts

    res = view_svg("plan", [Pane(k) for k in range(8)], [], "stack")
    root = ET.fromstring(res.svg)
    texts = list(root.iter(f"{NS}text"))
    assert {f"P-STACKED-{k:02d}" for k in range(8)} <= {t.text for t in texts}
    placed = [t for t in texts if t.get("data-part")]
    assert 0 < len(placed) < 8 and res.unfit
    boxes = [_measured_box(t) for t in placed]
    tree = STRtree(boxes)
    assert all(len([j for j in tree.query(b, predicate="intersects") if j != i]) == 0 for i, b in enumerate(boxes))


def test_no_text_overlaps_or_crosses_a_line_on_any_dxf(built):
    """Every DXF of the build (cutting sheets, per-type panes with their dimensions, cover plates), texts
    measured with ezdxf's text size tools: on each face of a sheet no two texts overlap and no drawn line crosses a
    text except a dimension's own lines; a cover plate's label lies inside its plate, off its skewed ends."""
    import ezdxf
    from shapely.geometry import Polygon

    from sheet_geometry import dxf_problems, dxf_sheet

    files = [p for p in sorted(built.rglob("*.dxf")) if "dxf_r" not in p.parent.name]
    assert len(files) >= 5
    for path in files:
        over, cross = dxf_problems(path)
        assert not over, (path.name, over[:5])
        assert not cross, (path.name, cross[:5])
    splices = sorted((built / "splices").glob("*.dxf"))
    assert splices
    for path in splices:
        doc = ezdxf.readfile(path)
        [plate] = [Polygon([p[:2] for p in e.get_points()])
                   for e in doc.modelspace().query("LWPOLYLINE[layer=='CUT']")]
        texts, _ = dxf_sheet(path)
        [label] = [t for t in texts if re.fullmatch(rf"{re.escape(path.stem)} x\d+", t.text)]
        assert plate.buffer(-2.9).contains(label.box), (path.name, label.box.bounds, plate.bounds)
        assert label.height >= 3.0


def test_verify_finds_a_sheet_off_its_paper_and_a_cover_plate_label_off_its_plate(built, tmp_path):
    """A label shrunk under 2.5 mm on paper, a frame removed, a paper size that does not exist and a cover plate's
    label moved over the plate's end are each reported, naming the file; the build's own files give no finding."""
    import ezdxf

    from fabrication.verify import Verification
    from fabrication.verify.drawings import check_sheet
    from fabrication.verify.dxf import check_splice_label

    sheets = [p.relative_to(built).as_posix() for p in sorted((built / "drawings").rglob("*.svg"))]
    splices = [p.relative_to(built).as_posix() for p in sorted((built / "splices").glob("*.dxf"))]
    clean = Verification(built)
    for rel in sheets:
        check_sheet(clean, rel)
    for rel in splices:
        check_splice_label(clean, rel)
    assert not clean.findings, [str(f) for f in clean.findings]
    bad = tmp_path / "bad"
    shutil.copytree(built / "drawings", bad / "drawings")
    shutil.copytree(built / "splices", bad / "splices")
    plan = bad / "drawings" / "key_plan.svg"
    text = plan.read_text()
    m = re.search(r'font-size="([0-9.]+)"([^>]*data-class="panel")', text)
    small = float(m.group(1)) * 0.5
    plan.write_text(text[:m.start()] + f'font-size="{small:g}"{m.group(2)}' + text[m.end():])
    side = bad / "drawings" / "elevation_side.svg"
    side.write_text(side.read_text().replace('class="frame"', 'class="border"'))
    node = sorted((bad / "drawings" / "nodes").glob("*.svg"))[0]
    node.write_text(node.read_text().replace('data-paper="A1"', 'data-paper="A2"'))
    doc = ezdxf.readfile(bad / splices[0])
    [label] = [t for t in doc.modelspace().query("TEXT[layer=='LABEL']") if " - " not in t.dxf.text]
    right = max(p[0] for p in doc.modelspace().query("LWPOLYLINE[layer=='CUT']")[0].get_points())
    label.dxf.insert = (right - 10.0, label.dxf.insert[1])              # over the plate's right end
    doc.saveas(bad / splices[0])
    v = Verification(bad)
    for rel in sheets:
        check_sheet(v, rel)
    for rel in splices:
        check_splice_label(v, rel)
    found = [str(f) for f in v.findings]
    assert any("key_plan.svg" in f and "under 2.5 mm" in f for f in found), found
    assert any("key_plan.svg" in f and "panel labels are 2 heights" in f for f in found), found
    assert any("elevation_side.svg" in f and "no frame" in f for f in found), found
    assert any(node.name in f and "'A2' is not a paper size" in f for f in found), found
    assert [f for f in found if splices[0] in f] == [f"{splices[0]}: {label.dxf.text}: type label runs over the "
                                                     "plate's outline"]


def test_drawings_pdf_has_a_page_per_sheet_at_its_paper_size_and_is_reproducible(built, tmp_path):
    """``drawings/drawings.pdf`` (listed in the manifest) has one page per SVG sheet, each 841 x 594 mm (its
    MediaBox in points), and drawing the same sheets again gives the same bytes (no creation date)."""
    import json

    from fabrication.writers.drawings import sheet_register  # noqa: F401  (the order the PDF follows)
    from fabrication.writers.drawings_pdf import write_pdf

    manifest = json.loads((built / "manifest.json").read_text())
    assert manifest["files"]["drawings_pdf"] == "drawings/drawings.pdf"
    data = (built / "drawings" / "drawings.pdf").read_bytes()
    sheets = sorted((built / "drawings").rglob("*.svg"))
    boxes = re.findall(rb"/MediaBox \[\s*0 0 ([0-9.]+) ([0-9.]+)\s*\]", data)
    assert len(boxes) == len(sheets)
    for w, h in boxes:
        assert (float(w), float(h)) == pytest.approx((841 / 25.4 * 72, 594 / 25.4 * 72), abs=0.01)
    assert b"CreationDate" not in data
    one, two = tmp_path / "a.pdf", tmp_path / "b.pdf"
    write_pdf(sheets[:2], one)
    write_pdf(sheets[:2], two)
    assert one.read_bytes() == two.read_bytes()
    assert len(re.findall(rb"/Type /Page\b", one.read_bytes())) == 2


class _GridPane:
    """A 1.5 x 1.2 m pane in plan at column ``i``, row ``j`` of a grid, named ``name`` or by its place."""

    def __init__(self, i: int, j: int, name: str = ""):
        self.part_id = name or f"P-{i:02d}-{j:02d}"
        self._pts = np.array([[1500.0 * i, 1200.0 * j, 0], [1500.0 * (i + 1), 1200.0 * j, 0],
                              [1500.0 * (i + 1), 1200.0 * (j + 1), 0], [1500.0 * i, 1200.0 * (j + 1), 0]])

    def outline_3d(self):
        return self._pts


def test_a3_sheet_scales_the_view_down_and_keeps_text_at_2_5_mm(tmp_path):
    """The same panes on A3: the sheet is 420 x 297 mm, the view at a standard scale no larger than on A1, every
    text at least 2.5 mm on paper; a paper that does not exist is refused naming the ones that do."""
    from fabrication.design import load_design
    from fabrication.drawings import view_svg
    from ppfab.errors import DesignError

    panes = [_GridPane(i, j) for i in range(24) for j in range(2)]       # 36 m x 2.4 m
    a1 = view_svg("plan", panes, [], "grid")
    a3 = view_svg("plan", panes, [], "grid", paper="A3")
    assert (a1.scale, a3.scale) == (50, 100)            # 36 m: 720 mm at 1:50 fits A1's 803 mm, not A3's 382 mm
    path = tmp_path / "a3.svg"
    path.write_text(a3.svg)
    root, texts, lines = svg_sheet(path)
    assert root.get("viewBox") == "0 0 420 297"
    assert min(t.height for t in texts) >= 2.5 - 1e-9
    assert not overlaps(texts) and not crossings(texts, lines)
    assert sorted(a3.labelled + a3.unfit) == sorted(p.part_id for p in panes)
    design = tmp_path / "d.toml"
    design.write_text(small_vault("paper").replace("[panels]", '[output]\npaper = "A2"\n[panels]'))
    with pytest.raises(DesignError, match="'A0', 'A1', 'A3'"):
        load_design(design)


@pytest.mark.slow
def test_every_text_of_an_example_build_is_clear(tmp_path):
    """Every text of every sheet and every DXF of a full example build is clear (the sheet-wide and DXF-wide
    tests above), the key plan names every panel and beam plate, at its place or in the list below the view.
    With ``PPFAB_FULL`` the bundled default (30 A1 sheets, key plan and elevations at 1:50, 272 DXF files);
    in the small form the ``smallest_roof`` example."""
    from fabrication.cli import main

    from conftest import FULL

    out = tmp_path / "out"
    assert main(["build", "-o", str(out), "--quiet"] + ([] if FULL else ["--example", "smallest_roof"])) == 0
    test_no_text_overlaps_another_or_crosses_a_line_on_any_sheet(out)
    test_no_text_overlaps_or_crosses_a_line_on_any_dxf(out)
    _, texts = _texts(out / "drawings" / "key_plan.svg")
    named = sorted(t.text for t in texts if t.get("data-part") or t.get("data-listed"))
    assert named == sorted(r["part_id"] for r in _rows(out / "parts.csv") if r["kind"] in ("panel", "beam"))
    if FULL:
        root = ET.parse(out / "drawings" / "key_plan.svg").getroot()
        assert root.get("data-scale") == "50"


def test_a_list_that_fits_no_scale_is_refused_naming_the_paper():
    """A hundred panes stacked in plan whose ids (120 characters) list one per row: no standard scale leaves
    room for the list on A3, and the refusal names the view, the paper and the key that gives a larger one."""
    from fabrication.drawings import view_svg

    class Pane:
        def __init__(self, k):
            self.part_id = f"P-{k:03d}-" + "X" * 115
            self._pts = np.array([[0, 0, 10.0 * k], [30, 0, 10.0 * k], [30, 6, 10.0 * k], [0, 6, 10.0 * k]])

        def outline_3d(self):
            return self._pts

    with pytest.raises(ValueError, match=r'Key plan .*do not fit A3 paper .*\[output\] paper = "A1"'):
        view_svg("plan", [Pane(k) for k in range(100)], [], "stack", paper="A3")


def test_a_view_too_large_for_a1_goes_on_a0_and_the_largest_paper_says_what_else_to_do(tmp_path):
    """A 48 m row of panes is drawn at 1:100 on A1 (960 mm at 1:50 is wider than A1's drawing area) and at 1:50 on
    A0, whose sheet is 1189 x 841 mm with the grid reference of 24 by 16 fields, every part named and the sheet
    clean for verify's sheet check; a list of ids that fits no scale on A1 is refused naming A0, and on A0 (the
    largest paper) naming what else gives room."""
    from fabrication.drawings import view_svg
    from fabrication.paper import GRID_FIELDS, SheetInfo
    from fabrication.verify import Verification
    from fabrication.verify.drawings import check_sheet

    panes = [_GridPane(i, j) for i in range(32) for j in range(2)]       # 48 m x 2.4 m
    a1 = view_svg("plan", panes, [], "row")
    a0 = view_svg("plan", panes, [], "row", sheet=SheetInfo("row", "Key plan", 1, 1, "A0"))
    assert (a1.scale, a0.scale) == (100, 50)
    (tmp_path / "drawings").mkdir()
    (tmp_path / "drawings" / "a0.svg").write_text(a0.svg)
    root, texts, lines = svg_sheet(tmp_path / "drawings" / "a0.svg")
    assert (root.get("width"), root.get("height"), root.get("viewBox")) == ("1189mm", "841mm", "0 0 1189 841")
    grid = {t.text for t in root.iter("{http://www.w3.org/2000/svg}text") if t.get("data-class") == "grid"}
    cols, rows = GRID_FIELDS["A0"]
    assert grid == {str(k) for k in range(1, cols + 1)} | set("ABCDEFGHJKLMNPRS"), grid     # ISO 5457: no I, O, Q
    assert rows == 16
    assert not overlaps(texts) and not crossings(texts, lines)
    assert sorted(a0.labelled + a0.unfit) == sorted(p.part_id for p in panes)
    v = Verification(tmp_path)
    check_sheet(v, "drawings/a0.svg")
    assert not v.findings, [str(f) for f in v.findings]
    stacked = [_GridPane(0, 0, f"P-{k:03d}-" + "X" * 400) for k in range(250)]  # one id per row, 250 rows on any paper
    for k, p in enumerate(stacked):
        p._pts = p._pts + [0.0, 0.0, 10.0 * k]
    with pytest.raises(ValueError, match=r'do not fit A1 paper .*\[output\] paper = "A0"'):
        view_svg("plan", stacked, [], "stack")
    with pytest.raises(ValueError, match=r"do not fit A0 paper .*A0 is the largest paper ppfab draws on: fewer, "
                                         r"larger panels"):
        view_svg("plan", stacked, [], "stack", sheet=SheetInfo("stack", "Key plan", 1, 1, "A0"))


def test_title_block_dates_and_fits_long_names(monkeypatch):
    """The issue date is SOURCE_DATE_EPOCH's day when set and "-" otherwise (never the clock); a design name
    longer than the title block's row is cut to fit it, ending in "~"."""
    from fabrication.paper import TEXT_MM, TITLE_BLOCK_WIDTH, PaperSheet, SheetInfo, issue_date

    monkeypatch.delenv("SOURCE_DATE_EPOCH", raising=False)
    assert issue_date() == "-"
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1764547200")              # 2025-12-01 00:00 UTC
    assert issue_date() == "2025-12-01"
    page = PaperSheet(SheetInfo("a very long project name " * 5, "Key plan", 3, 7, "A3", issue_date()), 100)
    page.frame()
    fields = {t.get("data-field"): t.text for t in page.root.iter("text") if t.get("data-field")}
    assert fields["date"] == "date 2025-12-01" and fields["sheet"] == "sheet 3 of 7"
    assert fields["scale"] == "scale 1:100"
    assert fields["project"].endswith("~")
    assert 0.8 * TEXT_MM["project"] * len(fields["project"]) <= TITLE_BLOCK_WIDTH - 4.0


def test_report_lists_each_node_type_with_all_its_sheets(built):
    """The report's node-type table names, in a type's row, its sheet and every continuation sheet of it."""
    html = (built / "report.html").read_text(encoding="utf-8")
    rows = [re.findall(r"<t[dh][^>]*>(.*?)</t[dh]>", tr, flags=re.S) for tr in re.findall(r"<tr>(.*?)</tr>", html, re.S)]
    sheet_cell = {r[0]: r[-1] for r in rows if r and re.fullmatch(r"NT\d+", r[0])}
    files = sorted((built / "drawings" / "nodes").glob("node_type_*.svg"))
    assert files and len(sheet_cell) == len({re.sub(r"-\d+$", "", f.stem) for f in files})
    for f in files:
        type_id = re.sub(r"-\d+$", "", f.stem).removeprefix("node_type_")
        assert f"nodes/{f.name}" in sheet_cell[type_id], (f.name, sheet_cell[type_id])


def test_verify_counts_the_pdf_pages_and_their_paper(built, tmp_path):
    """verify reads drawings.pdf: a page per sheet, each the size of its sheet's paper; a page dropped from the
    list and a page turned to A3 are each a finding naming the file."""
    import shutil

    from fabrication.verify import Verification
    from fabrication.verify.drawings import check_pdf

    sheets = [p.relative_to(built).as_posix() for p in sorted((built / "drawings").rglob("*.svg"))]
    clean = Verification(built)
    check_pdf(clean, "drawings/drawings.pdf", sheets)
    assert not clean.findings, clean.findings
    short = Verification(built)
    check_pdf(short, "drawings/drawings.pdf", sheets + ["drawings/key_plan.svg"])
    assert [f.file for f in short.findings] == ["drawings/drawings.pdf"] and "page(s) for" in short.findings[0].message
    copy = tmp_path / "copy"
    shutil.copytree(built / "drawings", copy / "drawings")
    pdf = copy / "drawings" / "drawings.pdf"
    data = pdf.read_bytes()
    a1 = re.search(rb"/MediaBox \[\s*0 0 [0-9.]+ [0-9.]+\s*\]", data).group(0)
    pdf.write_bytes(data.replace(a1, b"/MediaBox [ 0 0 1190.55 841.89 ]", 1))       # one page of A3
    turned = Verification(copy)
    check_pdf(turned, "drawings/drawings.pdf", sheets)
    assert len(turned.findings) == 1 and "paper sizes" in turned.findings[0].message


def test_pdf_shapes_batched_by_style_keep_the_sheet_s_paint_order():
    """drawings.pdf draws runs of same-style shapes as one collection: a red square, a blue one over it and a red
    one over that must still paint in that order (rendered with matplotlib's Agg, colours read at the pixels)."""
    import xml.etree.ElementTree as ET

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fabrication.writers.drawings_pdf import draw_sheet

    svg = ('<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">'
           '<rect x="0" y="0" width="60" height="60" fill="#ff0000" stroke="none"/>'
           '<rect x="5" y="5" width="10" height="10" fill="#ff0000" stroke="none"/>'
           '<polygon points="20,20 80,20 80,80 20,80" fill="#0000ff" stroke="none"/>'
           '<rect x="40" y="40" width="50" height="50" fill="#ff0000" stroke="none"/></svg>')
    fig = plt.figure(figsize=(1, 1), dpi=100)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_xlim(0, 100)
    ax.set_ylim(100, 0)
    ax.set_axis_off()
    draw_sheet(ax, ET.fromstring(svg))
    fig.canvas.draw()
    img = np.asarray(fig.canvas.buffer_rgba())[:, :, :3].astype(int)
    plt.close(fig)
    at = {name: tuple(img[y, x]) for name, (x, y) in
          {"red under": (10, 30), "blue over red": (30, 30), "red over blue": (60, 60), "blue alone": (30, 75),
           "paper": (95, 5)}.items()}
    assert at["red under"] == (255, 0, 0) and at["red over blue"] == (255, 0, 0)
    assert at["blue over red"] == (0, 0, 255) and at["blue alone"] == (0, 0, 255)
    assert at["paper"] == (255, 255, 255)
