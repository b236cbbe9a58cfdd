"""The installers' drawings, read back as SVG (xml.etree): the key plan names every panel and beam plate once
(glazing strips and splice plates lie on their beams), each panel label lies in its face as seen from above, no
two labels of a view overlap (text measured with matplotlib's font metrics, not with the writer's estimate),
and every node with plates is on the sheet of its type."""

import csv
import re
import shutil
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from ppfab.io import load_mesh

from conftest import built_folder, small_vault

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
    names = [t.text for t in labels]
    # every panel and beam plate, once (glazing strips and splice plates lie on their beams, named on them)
    assert sorted(names) == sorted(r["part_id"] for r in parts if r["kind"] in ("panel", "beam"))
    # panel labels inside their face seen from above (the OBJ face, y flipped into SVG's frame)
    mesh = load_mesh(built / "mesh.obj")
    polys = [Polygon(mesh.vertices[f][:, :2]) for f in mesh.faces]
    face_of = {r["part_id"]: int(r["face"]) for r in parts if r["kind"] == "panel"}
    fx0, fy1 = map(float, root.get("data-frame").split())           # picture (x, y) -> (x - x0, y1 - y)
    inside = 0
    for pid, f in face_of.items():
        q = np.asarray(polys[f].exterior.coords)
        face_svg = Polygon(np.c_[q[:, 0] - fx0, fy1 - q[:, 1]])
        t = [x for x in labels if x.text == pid][0]
        assert face_svg.contains(_measured_box(t)), pid
        inside += 1
    assert inside == len(face_of) > 0


@pytest.mark.parametrize("view", ["key_plan", "elevation_front", "elevation_side"])
def test_labels_do_not_overlap(built, view):
    from shapely import STRtree

    _, texts = _texts(built / "drawings" / f"{view}.svg")
    labels = [t for t in texts if t.get("data-part")]
    assert labels
    labels += [t for t in texts if not t.get("data-part")]          # the title, scale, extent, north: all text
    boxes = [_measured_box(t) for t in labels]
    tree = STRtree(boxes)
    for i, b in enumerate(boxes):
        hits = [int(j) for j in tree.query(b, predicate="intersects") if j != i]
        assert not hits, (view, labels[i].text, [labels[j].text for j in hits])
    for t in labels:
        rot = re.findall(r"rotate\(([-0-9.e]+)", t.get("transform", ""))
        assert -45.0 < -float(rot[0] if rot else 0.0) <= 135.0         # reads from the bottom or the right edge


@pytest.mark.parametrize("view", ["key_plan", "elevation_front", "elevation_side"])
def test_views_carry_a_true_scale_bar_and_their_extent(built, view):
    """Each view has a scale bar whose drawn length (picture mm, the SVG's units) is the length its label says,
    and states its extent, which equals the extent of the mesh's vertices (mesh.obj) along the view's axes; the
    key plan has a north arrow pointing up the sheet (+y)."""
    root, texts = _texts(built / "drawings" / f"{view}.svg")
    [bar] = [g for g in root.iter(f"{NS}g") if g.get("class") == "scale-bar"]
    xs = [float(v.split(",")[0]) for p in bar.iter(f"{NS}polygon") for v in p.get("points").split()]
    drawn = max(xs) - min(xs)
    said = [t.text for t in texts if re.fullmatch(r"[0-9.]+ (m|mm)", t.text or "")]
    assert len(said) == 1
    value, unit = said[0].split()
    assert drawn == pytest.approx(float(value) * (1000.0 if unit == "m" else 1.0), abs=0.2)
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
    """On every node sheet no two texts overlap (measured with the font's metrics) and every label reads from
    the bottom or the right edge; a plate that ends at the node is drawn on one side of it only (a corner's two
    plates meet in an L), a plate running through on both sides."""
    from shapely import STRtree

    sheets = sorted((built / "drawings" / "nodes").glob("node_type_*.svg"))
    assert sheets
    roles = set()
    for path in sheets:
        root, texts = _texts(path)
        boxes = [_measured_box(t) for t in texts]
        tree = STRtree(boxes)
        for i, b in enumerate(boxes):
            hits = [int(j) for j in tree.query(b, predicate="intersects") if j != i]
            assert not hits, (path.name, texts[i].text, [texts[j].text for j in hits])
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
    """Eight panes stacked above one another (a wall or an overhang seen from above): no two labels overlap,
    and the ids without room at their place are listed below the view."""
    from shapely import STRtree

    from fabrication.drawings import view_svg

    class Pane:
        def __init__(self, k):
            self.part_id = f"P-STACKED-{k:02d}"
            self._pts = np.array([[0, 0, 100.0 * k], [1000, 0, 100.0 * k], [1000, 400, 100.0 * k],
                                  [0, 400, 100.0 * k]])

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
