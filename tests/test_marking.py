"""Marking on the cutting sheets, read back with ezdxf: every label upright in the sheet frame and inside its
part clear of the edges and slots; the face mark of every beam plate on the side that the plate's 3D frame
(parts.csv, checked against beams.step) and its ``mirrored`` flag put up."""

import ast
import csv
from pathlib import Path

import numpy as np

from fabrication.marking import TextLine, face_marks, place_label, reads_from_bottom_or_right, upright_deg

from conftest import built_folder, small_vault

SMALL = small_vault("marking")
built = built_folder("marking", SMALL)


def _rows(out: Path) -> dict[str, dict]:
    with open(out / "parts.csv", newline="") as fh:
        return {r["part_id"]: r for r in csv.DictReader(fh)}


def _sheets(out: Path):
    """``(path, doc)`` of every cutting sheet, read with ezdxf."""
    import ezdxf

    for path in sorted((out / "beams").glob("*.dxf")) + sorted((out / "glass").glob("*.dxf")):
        yield path, ezdxf.readfile(path)


def _text_box(e) -> np.ndarray:
    """The box of a middle-centred TEXT entity measured by ezdxf's font metrics ``(4, 2)``, sheet coordinates."""
    from ezdxf.tools.text_size import text_size

    size = text_size(e)
    w, cap, total = size.width, size.cap_height, size.total_height
    local = np.array([[-w / 2, -cap / 2 - (total - cap)], [w / 2, -cap / 2 - (total - cap)], [w / 2, cap / 2],
                      [-w / 2, cap / 2]])
    a = np.radians(e.dxf.rotation)
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    p = e.dxf.align_point
    return local @ rot.T + np.array([p[0], p[1]])


def _cut_polygons(doc) -> dict[str, "object"]:
    from shapely.geometry import Polygon

    out = {}
    for e in doc.modelspace().query("LWPOLYLINE[layer=='CUT']"):
        pid = [v for c, v in e.get_xdata("PPFAB") if str(v).startswith("part_id=")][0].split("=", 1)[1]
        out[pid] = Polygon([(p[0], p[1]) for p in e.get_points("xy")])
    return out


def test_upright_angle():
    for a in np.linspace(-720, 720, 97):
        u = upright_deg(a)
        assert -45 < u <= 135 and abs(np.sin(np.radians(u - a))) < 1e-9
        assert reads_from_bottom_or_right(u) and not reads_from_bottom_or_right(u + 180.0)


def test_labels_are_upright_inside_their_part_and_clear_of_slots(built):
    from shapely import STRtree
    from shapely.geometry import Point, Polygon

    counts = {"plate": 0, "glass": 0}
    for path, doc in _sheets(built):
        cuts = _cut_polygons(doc)
        ids = list(cuts)
        tree = STRtree([cuts[k] for k in ids])
        for e in doc.modelspace().query("TEXT"):
            p = e.dxf.get("align_point")
            if p is None:
                assert e.dxf.layer == "LABEL" and e.dxf.insert[1] < 0, e.dxf.text
                continue                                  # the sheet title, left-aligned below the sheet
            hit = tree.query(Point(p[0], p[1]), predicate="within")
            assert len(hit) == 1, (path.name, e.dxf.text)
            poly = cuts[ids[int(hit[0])]]
            # one reading direction per sheet: from the bottom or the right edge (ISO 128), never opposite ways
            assert -45.0 < (e.dxf.rotation + 180.0) % 360.0 - 180.0 <= 135.0, (path.name, e.dxf.text, e.dxf.rotation)
            box = Polygon(_text_box(e))
            # inside the part, and clear of its outline (edges and slot notches alike) by 1 mm
            assert poly.buffer(-1.0).contains(box), (path.name, e.dxf.text, poly.exterior.distance(box))
            if e.dxf.layer in ("MARK", "LABEL"):
                counts["plate" if path.parent.name == "beams" else "glass"] += 1
    assert counts["plate"] > 0 and counts["glass"] > 0


def _sheet_to_3d(row: dict) -> tuple[np.ndarray, np.ndarray]:
    """The affine map sheet → 3D of a placed part, ``X = A s + b`` with ``A (3, 2)``, from parts.csv alone:
    part point ``p = M R⁻¹ (s − t)``, ``X = origin + p_x x_dir + p_y y_dir``."""
    frame = ast.literal_eval(row["frame"])
    a = np.radians(float(row["rotation_deg"]))
    rinv = np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]])
    m = np.diag([-1.0, 1.0]) if row["mirrored"] == "1" else np.eye(2)
    lin = np.stack([frame["x_dir"], frame["y_dir"]], axis=1) @ (m @ rinv)
    t = np.array([float(row["x"]), float(row["y"])])
    return lin, np.asarray(frame["origin"]) - lin @ t


def test_face_mark_is_on_the_side_the_3d_model_puts_up(built, both_turns: bool = True):
    """Every plate's face mark is on the face the 3D model puts up, on a plate placed as drawn and on one turned
    over on its sheet (``both_turns``: both occur on the build; where the nesting turned none over, the first)."""
    from fabrication.writers.step import solid_vertices

    rows = _rows(built)
    solids = solid_vertices(built / "beams.step")
    seen = {"0": 0, "1": 0}
    for path, doc in _sheets(built):
        if path.parent.name != "beams":
            continue
        msp = doc.modelspace()
        cuts = {}
        for e in msp.query("LWPOLYLINE[layer=='CUT']"):
            pid = [v for c, v in e.get_xdata("PPFAB") if str(v).startswith("part_id=")][0].split("=", 1)[1]
            cuts[pid] = np.array([(p[0], p[1]) for p in e.get_points("xy")])
        bevelled = {dict(str(v).split("=", 1) for _, v in e.get_xdata("PPFAB"))["part_id"]
                    for e in msp.query("LWPOLYLINE[layer=='BEVEL']")}
        faces: dict[tuple[str, str], list] = {}
        for e in msp.query("TEXT"):
            if e.dxf.layer in ("MARK", "MARK_BACK") and e.has_xdata("PPFAB"):
                x = dict(str(v).split("=", 1) for _, v in e.get_xdata("PPFAB"))
                if x.get("mark") == "face":
                    faces.setdefault((x["part_id"], e.dxf.layer), []).append(e)
        for pid, sheet_pts in cuts.items():
            row = rows[pid]
            lin, off = _sheet_to_3d(row)
            plane = np.asarray(ast.literal_eval(row["plane"]), dtype=float)
            n = plane[:3] / np.linalg.norm(plane[:3])
            t = float(row["thickness_mm"])
            # the map is the plate's: the DXF outline lands on the STEP solid's two faces (a plate bevelled under
            # its strips: each corner on one of them, the raised edge is on one face only)
            mid = sheet_pts @ lin.T + off
            verts = solids[pid]
            d = np.array([np.linalg.norm((mid + sgn * 0.5 * t * n)[:, None, :] - verts[None], axis=2).min(axis=1)
                          for sgn in (-1.0, 1.0)])
            assert (d.min(axis=0) if pid in bevelled else d.max(axis=0)).max() < 1e-3, (pid, d.max())
            # the face looking up from the sheet: the image of the sheet's +z under the (rigid) placement
            up = np.cross(lin[:, 0], lin[:, 1])
            family = {"rows": 0, "cols": 1}[row["family"]]
            top, under = face_marks(family, 1 if up @ n > 0 else -1)
            (mark,) = faces[(pid, "MARK")]
            (back,) = faces[(pid, "MARK_BACK")]
            assert mark.dxf.text == top and back.dxf.text == under, (pid, row["mirrored"], mark.dxf.text)
            assert back.dxf.text_generation_flag & 2 and not mark.dxf.text_generation_flag & 2
            seen[row["mirrored"]] += 1
    assert seen["0"] > 0 and (seen["1"] > 0 or not both_turns), seen       # both cases occur on this build


def test_a_label_avoids_slots_and_axis_lines():
    """A plate with a slot from the top in its middle and an axis line through it: the block fits beside them."""
    from shapely.geometry import LineString, Polygon

    outline = np.array([[0, 0], [600, 0], [600, 150], [310, 150], [310, 75], [290, 75], [290, 150], [0, 150]],
                       dtype=float)
    axis = np.array([[300.0, 75.0], [300.0, 0.0]])
    lines = [TextLine("B-U03-S01", "MARK"), TextLine("U+", "MARK"), TextLine("B07-012", "LABEL", 0.6)]
    where = place_label(outline, lines, margin=5.0, max_height=25.0, keep_out=(axis,))
    assert where.fits
    box = Polygon(where.box)
    assert Polygon(outline).buffer(-5.0 + 1e-9).contains(box)
    assert box.distance(LineString(axis)) >= 5.0 - 1e-9
    slot = Polygon([(290, 75), (310, 75), (310, 160), (290, 160)])
    assert box.distance(slot) >= 5.0 - 1e-9
    assert all(-45 < pl.rotation_deg <= 135 for pl in where.lines)


def test_verify_names_a_wrong_face_mark_and_an_upside_down_label(built, tmp_path):
    import shutil

    import ezdxf

    from fabrication.verify import verify

    bad = tmp_path / "bad"
    shutil.copytree(built, bad)
    path = sorted((bad / "beams").glob("*.dxf"))[0]
    doc = ezdxf.readfile(path)
    texts = doc.modelspace().query("TEXT[layer=='MARK']")
    face = [t for t in texts if t.dxf.text[-1] in "+-" and len(t.dxf.text) == 2][0]
    pid = [v for _, v in face.get_xdata("PPFAB") if v.startswith("part_id=")][0].split("=", 1)[1]
    face.dxf.text = face.dxf.text[0] + ("-" if face.dxf.text[1] == "+" else "+")
    labels = [t for t in doc.modelspace().query("TEXT[layer=='LABEL']") if t.dxf.get("align_point")]
    labels[0].dxf.rotation = 180.0
    labels[1].dxf.rotation = -87.0                    # reads downwards: from the left edge, against the others
    doc.saveas(path)
    found = [str(f) for f in verify(bad).findings]
    assert any(pid in f and "face marks" in f for f in found), found
    assert any("turned 180.0°" in f and "upside down" in f for f in found), found
    assert any("turned -87.0°" in f and "reads from the top or the left edge" in f for f in found), found

def test_a_label_fits_a_region_left_as_a_geometry_collection():
    """A difference can leave a geometry collection (a polygon and a stray line), whose boundary shapely does not
    define: the search still measures the clearance to the polygon's edge and places the box inside it, off
    the centroid (the first box tried, at the centroid of an L, does not fit)."""
    import shapely
    from shapely.geometry import GeometryCollection, LineString, Polygon

    from fabrication.marking import _fit

    ell = Polygon([(0, 0), (400, 0), (400, 60), (60, 60), (60, 400), (0, 400)])
    region = GeometryCollection([ell, LineString([(500, 0), (600, 0)])])
    assert region.boundary is None                  # the case: no boundary to measure against
    centre = _fit(region, ell.buffer(-10.0), 120.0, 20.0, 0.0, np.array([120.0, 120.0]))
    assert centre is not None
    a, b = centre - [60.0, 10.0], centre + [60.0, 10.0]
    box = shapely.box(a[0], a[1], b[0], b[1])
    assert ell.contains(box)


def test_the_shortcut_for_an_outline_with_no_room_changes_no_placement(monkeypatch):
    """``place_label`` skips its search where an outline cannot hold the smallest block (``_room_for``: the outline
    shrunk by the margin and half the block's depth is empty, or no two of its vertices are the block's width
    apart).  On 300 random quadrilaterals and slivers, with keep-out lines through them, every placement is the one
    the full search gives (fits, box, height, angle), and the shortcut is taken for some and not for others."""
    import fabrication.marking as mk

    rng = np.random.default_rng(7)
    cases = []
    for k in range(300):
        w, h = rng.uniform(5.0, 120.0), rng.uniform(1.0, 40.0)
        q = np.array([[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]]) + rng.normal(0.0, 0.1 * min(w, h), (4, 2))
        a = rng.uniform(0.0, np.pi)
        q = q @ np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]])
        lines = [mk.TextLine(f"P-U{k:02d}-V07" if k % 3 else "P-1", "LABEL")]
        keep = (q[[0, 2]],) if k % 4 == 0 else ()
        cases.append((q, lines, keep, rng.uniform(0.3, 1.5)))
    taken = []
    room = mk._room_for

    def counted(*args):
        got = room(*args)
        taken.append(not got)
        return got

    monkeypatch.setattr(mk, "_room_for", counted)
    fast = [mk.place_label(q, lines, margin=m, max_height=5.0, min_height=2.5, keep_out=keep, prefer_deg=0.0)
            for q, lines, keep, m in cases]
    monkeypatch.setattr(mk, "_room_for", lambda *args: True)
    full = [mk.place_label(q, lines, margin=m, max_height=5.0, min_height=2.5, keep_out=keep, prefer_deg=0.0)
            for q, lines, keep, m in cases]
    assert 30 <= sum(taken) <= 270, sum(taken)
    for a, b in zip(fast, full):
        assert a.fits == b.fits
        assert np.array_equal(a.box, b.box)
        assert [(x.height, x.rotation_deg) for x in a.lines] == [(x.height, x.rotation_deg) for x in b.lines]
    assert sum(p.fits for p in full) >= 30


def test_the_free_region_is_the_outline_less_each_keep_out_in_turn():
    """``free_region`` takes the keep-outs away at once (their union): on 20 random outlines, each with 5 to 250
    keep-out lines (pane outlines as closed convex rings, plate lines of one or two segments) and up to 20 label
    boxes, it is the region one difference per
    keep-out leaves (symmetric difference under 1e-6 of its area), and a point sample agrees with the distances:
    no point of it within the margin of a keep-out line's segments away from its ends."""
    import shapely
    from shapely.geometry import LineString, Polygon

    from fabrication.marking import free_region

    rng = np.random.default_rng(11)
    for k in range(20):
        w, h = rng.uniform(200.0, 4000.0), rng.uniform(50.0, 400.0)
        poly = Polygon(np.array([[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]]) + rng.normal(0.0, 5.0, (4, 2)))
        margin = rng.uniform(0.5, 15.0)
        lines = []
        for _ in range(int(rng.integers(5, 250))):
            p = rng.uniform([0.0, -0.2 * h], [w, 1.2 * h])
            if rng.random() < 0.5:                  # a pane's outline seen in the view: a closed convex ring
                a = np.sort(rng.uniform(0.0, 2.0 * np.pi, 4))
                q = p + rng.uniform(0.1, 0.4) * h * np.c_[np.cos(a), np.sin(a)] * [rng.uniform(1.0, 4.0), 1.0]
                lines.append(np.vstack([q, q[:1]]))
            else:                                   # a plate's top line: one or two segments
                q = p + rng.normal(0.0, 0.2 * h, (int(rng.integers(1, 3)), 2)).cumsum(axis=0)
                lines.append(np.vstack([p, q]))
        boxes = []
        for _ in range(int(rng.integers(0, 20))):
            c = rng.uniform([0.0, 0.0], [w, h])
            boxes.append(c + np.array([[-20.0, -4.0], [20.0, -4.0], [20.0, 4.0], [-20.0, 4.0]]))
        got = free_region(poly, tuple(lines), tuple(boxes), margin)
        want = poly.buffer(-margin, join_style="mitre")
        for m in lines:
            want = want.difference(LineString(m).buffer(margin, cap_style="flat"))
        for b in boxes:
            want = want.difference(Polygon(b).buffer(margin, join_style="mitre"))
        assert got.symmetric_difference(want).area <= 1e-6 * max(want.area, 1.0), k
        pts = rng.uniform([0.0, 0.0], [w, h], (2000, 2))
        inside = pts[shapely.contains_xy(got, pts[:, 0], pts[:, 1])]
        for m in lines:
            seg_a, seg_b = m[:-1], m[1:]
            d = seg_b - seg_a
            t = np.einsum("pij,ij->pi", inside[:, None, :] - seg_a[None], d) / np.maximum((d * d).sum(1), 1e-12)
            foot = seg_a[None] + np.clip(t, 0.0, 1.0)[..., None] * d[None]
            near = np.linalg.norm(inside[:, None, :] - foot, axis=2) < 0.999 * margin
            assert not np.any(near & (t > 1e-3) & (t < 1.0 - 1e-3)), k
