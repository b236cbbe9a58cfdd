"""DXF cutting sheets, per-type DXFs, parts and order lists — re-read with the real readers."""

from __future__ import annotations

import csv
import hashlib
import json
import subprocess
import sys

import numpy as np
import pytest

from conftest import REPO, smooth_face_image
from fabrication.writers.dxf import check_sheet_dxf, read_sheet_dxf, write_sheet_dxfs
from fabrication.flatpart import FlatPart, place_points
from fabrication.nesting import NestingParams, nest, verify_nesting
from fabrication.panels import PanelParams, make_panels
from fabrication.contract import PARTS_CONTRACT_COLUMNS as CONTRACT_COLUMNS
from fabrication.parts import order_rows, part_rows, write_order_list, write_parts_csv, write_parts_json
from fabrication.writers.dxf import write_type_dxfs
from ppfab.errors import VerificationError
from ppfab.faceimage import pp_from_face_image

GAP = 10.0


@pytest.fixture(scope="module")
def build(tmp_path_factory):
    g, h = smooth_face_image(6, 5, 0)
    grid = pp_from_face_image(g, h)
    panels = make_panels(grid, PanelParams(gap=GAP), scale=4000.0)
    parts = [p.flat_part() for p in panels]
    params = NestingParams(sheet=[2400, 1600], margin=[12, 8, 10, 6], spacing=8, time_budget=0.5, mode="auto")
    res = nest(parts, params)
    verify_nesting(parts, res, params)
    out = tmp_path_factory.mktemp("dxf")
    paths = write_sheet_dxfs(parts, res, out / "sheets", prefix="glass_sheet", title="toughened 10 mm")
    return grid, panels, parts, params, res, paths, out


def edge_lengths_angles(poly):
    e = np.roll(poly, -1, axis=0) - poly
    ln = np.linalg.norm(e, axis=1)
    ein = np.roll(e, 1, axis=0)
    ang = np.arctan2(ein[:, 0] * e[:, 1] - ein[:, 1] * e[:, 0], np.einsum("ij,ij->i", ein, e))
    return ln, ang


def test_every_sheet_reads_back_audited_and_complete(build):
    grid, panels, parts, params, res, paths, _ = build
    assert len(paths) == res.sheets >= 2
    x0, y0, x1, y1 = params.usable()
    by_id = {p.part_id: p for p in panels}
    seen = {}
    for k, path in enumerate(paths):
        c = check_sheet_dxf(path)                     # ezdxf.readfile + audit + layers + XDATA
        assert c.insunits == 4 and c.dxfversion >= "AC1015"
        assert np.allclose(np.sort(c.sheet_outline, axis=0)[[0, -1]], [[0, 0], [2400, 1600]])
        assert np.allclose(c.trim_outline.min(0), [x0, y0]) and np.allclose(c.trim_outline.max(0), [x1, y1])
        from shapely.geometry import Polygon
        polys = []
        for part in c.parts:
            assert part.part_id not in seen
            seen[part.part_id] = (k, part.nest_tag)
            pts = part.points
            assert pts.min(0)[0] >= x0 - 1e-6 and pts.min(0)[1] >= y0 - 1e-6
            assert pts.max(0)[0] <= x1 + 1e-6 and pts.max(0)[1] <= y1 + 1e-6
            # congruent to the 3D face inset by gap/2: compare with the panel's 3D outline
            ref = by_id[part.part_id].outline_3d()
            e3 = np.roll(ref, -1, axis=0) - ref
            l3 = np.linalg.norm(e3, axis=1)
            a3 = np.arccos(np.clip(np.einsum("ij,ij->i", -np.roll(e3, 1, axis=0), e3) /
                                   (np.roll(l3, 1) * l3), -1, 1))
            l2, turn = edge_lengths_angles(pts)
            assert np.abs(l2 - l3).max() < 1e-6
            assert np.abs((np.pi - turn) - a3).max() < 1e-6
            polys.append(Polygon(pts))
        for i in range(len(polys)):
            for j in range(i + 1, len(polys)):
                assert polys[i].distance(polys[j]) >= params.spacing - 1e-6
        assert len(c.labels) == 1 + 2 * len(c.parts) and c.marks == len(c.parts)
    assert sorted(seen) == sorted(p.part_id for p in panels)            # each panel exactly once
    tags = {pl.part_id: (pl.sheet, pl.nest_tag) for pl in res.placements}
    assert seen == tags


def test_inset_is_half_the_gap_from_the_mesh_edges(build):
    """The DXF outline's edges lie gap/2 inside the face's (projected) edge lines."""
    grid, panels, parts, params, res, paths, _ = build
    for p in panels[:12]:
        c = p.corners_3d[p.corner_index]
        n = p.frame.normal
        proj = c - np.outer((c - p.frame.origin) @ n, n)
        flat = p.frame.to2d(proj)
        for k in range(4):
            a, b = flat[k], flat[(k + 1) % 4]
            d = (b - a) / np.linalg.norm(b - a)
            inward = np.array([-d[1], d[0]])
            assert (p.outline[k] - a) @ inward == pytest.approx(GAP / 2, abs=1e-9)
            assert (p.outline[(k + 1) % 4] - a) @ inward == pytest.approx(GAP / 2, abs=1e-9)


def test_bytes_are_deterministic_across_processes(build, tmp_path):
    grid, panels, parts, params, res, paths, _ = build
    again = write_sheet_dxfs(parts, res, tmp_path / "again", prefix="glass_sheet", title="toughened 10 mm")
    digest = [hashlib.sha256(p.read_bytes()).hexdigest() for p in paths]
    assert digest == [hashlib.sha256(p.read_bytes()).hexdigest() for p in again]
    code = (
        "import numpy as np, sys\n"
        "from fabrication.flatpart import FlatPart, Placement\n"
        "from fabrication.writers.dxf import CuttingSheet\n"
        "b = CuttingSheet((1000, 800), (5, 5, 995, 795), 'x')\n"
        "b.add_part(FlatPart('A', 'panel', np.array([[0,0],[300,0],[250,200.5]])), Placement('A', 0, 100, 50, 90, False, 'S01-001'))\n"
        "b.write(sys.argv[1])\n"
    )
    outs = []
    for k in range(2):
        f = tmp_path / f"p{k}.dxf"
        subprocess.run([sys.executable, "-c", code, str(f)], cwd=REPO, check=True)
        outs.append(f.read_bytes())
    assert outs[0] == outs[1] and b"$TDCREATE" in outs[0]


def test_parts_lists_and_order_list_round_trip(build):
    grid, panels, parts, params, res, paths, out = build
    rows = part_rows(parts, res.placements, [p.name for p in paths])
    csv_path = write_parts_csv(rows, out / "parts.csv")
    json_path = write_parts_json(rows, out / "parts.json", {"sheets": res.sheets})
    with open(csv_path, newline="") as fh:
        table = list(csv.DictReader(fh))
    assert list(table[0])[: len(CONTRACT_COLUMNS)] == CONTRACT_COLUMNS
    for col in ("face", "face_i", "face_j", "type_id", "material", "thickness_mm", "width_mm", "height_mm",
                "perimeter_mm", "weight_kg", "planarity_dev_mm"):
        assert col in table[0]
    assert len(table) == len(panels) and len({r["nest_tag"] for r in table}) == len(panels)
    doc = json.loads(json_path.read_text())
    assert doc["units"] == "mm" and len(doc["parts"]) == len(panels) and doc["sheets"] == res.sheets
    # x, y, rotation_deg of parts.csv map each flat outline onto its CUT outline in the sheet's DXF
    dxf_parts = {}
    for path in paths:
        for dp in read_sheet_dxf(path).parts:
            dxf_parts[dp.part_id] = (path.name, dp.points)
    by_id = {p.part_id: p for p in parts}
    from fabrication.flatpart import Placement
    for r in table:
        pl = Placement(r["part_id"], int(r["sheet"]) - 1, float(r["x"]), float(r["y"]), float(r["rotation_deg"]),
                       bool(int(r["mirrored"])), r["nest_tag"])
        name, pts = dxf_parts[r["part_id"]]
        assert name == r["sheet_file"]
        assert np.abs(place_points(by_id[r["part_id"]].outline, pl) - pts).max() < 1e-5
        assert int(r["face"]) == by_id[r["part_id"]].meta["face"]
    # deterministic text
    assert write_parts_csv(rows, out / "parts2.csv").read_bytes() == csv_path.read_bytes()
    # order list and one flat DXF per type
    files = write_type_dxfs(parts, out / "types")
    orders = order_rows(parts, params.rotations, files)
    order_path = write_order_list(orders, out / "order_list.csv")
    with open(order_path, newline="") as fh:
        olist = list(csv.DictReader(fh))
    assert sum(int(r["quantity"]) for r in olist) == len(panels)
    assert len(olist) == len({p.type_id for p in panels}) == len(files)
    for r in olist:
        c = check_sheet_dxf(out / "types" / r["file"], require_sheet=False)
        assert len(c.parts) == 1
        rep = by_id[r["parts"].split(";")[0]]
        assert np.abs(c.parts[0].points - rep.outline).max() < 1e-9
        assert r["rotations"] == "0;90;180;270" and r["material"] == rep.meta["material"]


def test_checker_rejects_a_broken_file(tmp_path):
    import ezdxf

    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 4
    for name in ("SHEET", "TRIM", "CUT", "LABEL", "MARK"):
        doc.layers.add(name)
    doc.modelspace().add_lwpolyline([(0, 0), (10, 0), (10, 10)], close=True, dxfattribs={"layer": "CUT"})
    f = tmp_path / "bad.dxf"
    doc.saveas(f)
    with pytest.raises(VerificationError, match="no PPFAB part_id"):
        check_sheet_dxf(f, require_sheet=False)
    doc.header["$INSUNITS"] = 1
    doc.saveas(f)
    with pytest.raises(VerificationError, match=r"\$INSUNITS is 1"):
        check_sheet_dxf(f)


def test_mirrored_placement_keeps_the_outline_counter_clockwise(tmp_path):
    from fabrication.writers.dxf import CuttingSheet
    from fabrication.flatpart import Placement

    part = FlatPart("T", "panel", np.array([[0, 0], [300, 0], [40, 200.0]]), mirror_allowed=True)
    b = CuttingSheet((1000, 1000), (0, 0, 1000, 1000))
    b.add_part(part, Placement("T", 0, 500, 300, 90.0, True, "S01-001"))
    c = check_sheet_dxf(b.write(tmp_path / "m.dxf"))
    x, y = c.parts[0].points.T
    assert 0.5 * (x @ np.roll(y, -1) - y @ np.roll(x, -1)) == pytest.approx(part.area)
