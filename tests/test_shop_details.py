"""Shop details a steel fabricator needs: slots for the thickest plate EN 10029 allows and with vertical play,
bolts.csv, material and thickness on every DXF, bar end allowances of the strip cut list, the minimum slope
warning (docs/glazing.md)."""

from __future__ import annotations

import csv
import logging
import shutil
from pathlib import Path

import numpy as np
import pytest
from conftest import small_vault
from shapely.geometry import LineString, Polygon

from fabrication.beams import BeamParams, build_beams
from fabrication.beams.samples import sample_pp_grid
from fabrication.beams.tolerance import en10029_upper_deviation
from fabrication.glazing.bolts import BoltSpec, bolt_set, standard_length
from fabrication.glazing.cutlist import cut_bars
from fabrication.glazing.slope import DRAINAGE_NOTE, flat_panes
from ppfab.errors import DesignError
from ppfab.schema import parse_params
from ppfab.support.pp import support_pp

# -- slots ---------------------------------------------------------------------------------------------------


def test_en10029_class_a_upper_deviations():
    assert [en10029_upper_deviation(t) for t in (8.0, 12.0, 14.9, 15.0, 20.0, 24.9)] == [1.2, 1.2, 1.2, 1.3, 1.3, 1.3]
    with pytest.raises(DesignError, match="outside EN 10029"):
        parse_params(BeamParams, {"thickness": 2.0}, "beams")
    assert parse_params(BeamParams, {"thickness": 2.0, "clearance": 0.5}, "beams").clearance == 0.5
    with pytest.raises(DesignError, match="'auto'"):
        parse_params(BeamParams, {"clearance": "wide"}, "beams")


@pytest.mark.parametrize("t", [8.0, 10.0, 12.0, 15.0, 20.0])
def test_square_slots_are_the_thickest_plate_plus_the_fit(t):
    s = support_pp(sample_pp_grid(3, 4, bend=0.0, tilt=0.0))
    prm = BeamParams(thickness=t, max_length=0)
    widths = [sl.width for p in build_beams(s, prm).plates for sl in p.slots]
    assert len(widths) == 12                    # 2 × 3 interior nodes, 2 slots each
    dev = en10029_upper_deviation(t)
    assert min(widths) >= t + dev + 0.5 - 1e-9 and max(widths) <= t + dev + 0.5 + 1e-9


def _strip(g: np.ndarray, c: float, h: float, big: float = 1e5) -> Polygon:
    """``{P : |g·P + c| ≤ h}`` (2D) as a long rectangle."""
    n = float(np.linalg.norm(g))
    p0 = -c * g / n ** 2
    d = np.array([-g[1], g[0]]) / n
    w = h / n * g / n
    return Polygon([p0 - big * d - w, p0 + big * d - w, p0 + big * d + w, p0 - big * d + w])


def _intrusion(params: BeamParams, actual: float) -> float:
    """Largest area (mm²) of material of a slotted plate that a crossing plate ``actual`` mm thick meets inside
    the slot's depth, over every half-lap slot and three levels through the plate (its faces at the thickest
    plate EN 10029 allows and its mid-plane); 0 when every crossing plate goes in."""
    s = support_pp(sample_pp_grid(4, 6))         # bent and tilted: plates cross at up to some 25° off square
    bs = build_beams(s, params)
    worst, n = 0.0, 0
    for j in bs.joints:
        if j.kind != "halflap":
            continue
        for pid in j.parts:
            a = bs.by_id[pid]
            other = bs.by_id[next(q for q in j.parts if q != pid)]
            sl = next(x for x in a.slots if x.node == j.vertex)
            f, nb = a.frame, other.plane[:3] / np.linalg.norm(other.plane[:3])
            db = other.plane[3] / np.linalg.norm(other.plane[:3])
            body = Polygon(a.outline)
            # inside the slot's reach: from the open edge to 0.01 mm short of its closed end
            along = sl.direction
            lim = sl.length - 0.01 if sl.from_top else sl.length + 0.01
            side = np.array([-along[1], along[0]])
            far = 1e4
            if sl.from_top:
                reach = Polygon([sl.origin - far * along - far * side, sl.origin + lim * along - far * side,
                                 sl.origin + lim * along + far * side, sl.origin - far * along + far * side])
            else:
                reach = Polygon([sl.origin + lim * along - far * side, sl.origin + far * along - far * side,
                                 sl.origin + far * along + far * side, sl.origin + lim * along + far * side])
            zmax = 0.5 * params.slot_thickness
            for z in (-zmax, 0.0, zmax):
                g = np.array([nb @ f.ex, nb @ f.ey])
                c = float(nb @ (f.origin + z * f.normal) + db)
                crossing = _strip(g, c, 0.5 * actual).intersection(reach)
                worst = max(worst, crossing.intersection(body).area)
                n += 1
    assert n >= 3 * 2 * 6
    return worst


def test_a_16_3_mm_plate_goes_into_the_slot_cut_for_a_15_mm_plate():
    """Measured on the outlines with shapely: the crossing plate at the EN 10029 maximum 15 + 1.3 mm meets no
    material of the slotted plate inside the slot, at either face of a plate that is itself 16.3 mm thick; with
    the old rule (t + 1 mm) it does."""
    auto = BeamParams(thickness=15.0, max_length=0)
    assert auto.slot_thickness == pytest.approx(16.3)
    assert _intrusion(auto, 16.3) < 1e-6
    assert _intrusion(BeamParams(thickness=15.0, max_length=0, clearance=1.0), 16.3) > 1.0


def test_half_lap_slots_reach_half_the_depth_plus_the_play_on_both_plates():
    s = support_pp(sample_pp_grid(4, 6))
    prm = BeamParams(max_length=0, depth=200.0, slot_play=3.0)
    bs = build_beams(s, prm)
    seen = {True: 0, False: 0}
    for p in bs.plates:
        body = Polygon(p.outline)
        for sl in p.slots:
            # the slot's centre line, from well above the top edge to well below the bottom edge, cut by the outline
            line = LineString([sl.origin - prm.depth * sl.direction, sl.origin + 2 * prm.depth * sl.direction])
            hit = line.intersection(body)
            spans = [np.asarray(g.coords) for g in getattr(hit, "geoms", [hit]) if not g.is_empty]
            alphas = sorted(float((q - sl.origin) @ sl.direction) for sp in spans for q in sp)
            # material along the line: from the slot's closed end to the bottom edge (from top), or the reverse
            if sl.from_top:
                assert alphas[0] == pytest.approx(0.5 * prm.depth + prm.slot_play, abs=1e-6)
                assert alphas[-1] == pytest.approx(prm.depth, abs=1e-6)
            else:
                assert alphas[0] == pytest.approx(0.0, abs=1e-6)
                assert prm.depth - alphas[-1] == pytest.approx(0.5 * prm.depth + prm.slot_play, abs=1e-6)
            seen[sl.from_top] += 1
    assert seen[True] == seen[False] > 0
    with pytest.raises(DesignError, match="slot_play"):
        parse_params(BeamParams, {"depth": 100.0, "slot_play": 50.0}, "beams")


# -- bolts ---------------------------------------------------------------------------------------------------


def test_bolt_length_from_the_grip_by_hand():
    # M20 8.8, category A: grip 10 + 12 + 10 = 32; 2 ISO 7089 washers 3 mm; ISO 4032 nut 18 mm; 5 mm thread
    # out of the nut: 32 + 6 + 18 + 5 = 61 → the next standard length 65; thread out of the nut 65 − 56 = 9
    a = bolt_set("SP-U00-00A", "B-U00", ("B-U00-S00", "B-U00-S01"), BoltSpec.parse("M20 8.8"), "A", 10.0, 12.0, 8,
                 5.0)
    assert (a.grip_mm, a.min_length_mm, a.length_mm) == (32.0, 61.0, 65)
    row = a.row()
    assert row["projection_mm"] == 9.0 and row["quantity"] == 8 and row["preload"] == "non-preloaded"
    assert row["bolt"] == "ISO 4014 M20x65 8.8" and row["nut"] == "ISO 4032 M20 m=18"
    # preloaded (category C): EN 14399-6 washers 4 mm: 32 + 8 + 18 + 5 = 63 → 65
    c = bolt_set("S", "B", ("a", "b"), BoltSpec.parse("M20 10.9"), "C", 10.0, 12.0, 8, 5.0)
    assert (c.min_length_mm, c.length_mm, c.row()["preload"]) == (63.0, 65, "preloaded")
    # a thicker beam: 2 × 15 + 20 = 50 + 6 + 18 + 5 = 79 → 80 (10 mm steps above 70)
    assert bolt_set("S", "B", ("a", "b"), BoltSpec.parse("M20 8.8"), "A", 15.0, 20.0, 4, 5.0).length_mm == 80
    assert [standard_length(x) for x in (20.0, 66.0, 70.0, 70.5, 159.0, 161.0)] == [20, 70, 70, 80, 160, 180]
    with pytest.raises(DesignError, match="grade 8.8 or 10.9"):
        bolt_set("S", "B", ("a", "b"), BoltSpec.parse("M20 4.6"), "B", 10.0, 12.0, 8, 5.0)
    with pytest.raises(DesignError, match="not a bolt"):
        BoltSpec.parse("M21 8.8")


# -- strip cuts ----------------------------------------------------------------------------------------------


def test_strips_stay_clear_of_the_bar_ends():
    lengths = {"A": 2990.0, "B": 2987.0}          # 2990 + 3 + 2987 = 5980 = 6000 − 2 × 10
    cuts, _ = cut_bars(lengths, 6000.0, 3.0, 10.0)
    assert {c.bar for c in cuts} == {0}
    assert min(c.start for c in cuts) == pytest.approx(10.0)
    assert max(c.start + c.length for c in cuts) == pytest.approx(5990.0)
    cuts, _ = cut_bars({"A": 2990.0, "B": 2988.0}, 6000.0, 3.0, 10.0)     # 1 mm too long for one bar
    assert len({c.bar for c in cuts}) == 2
    with pytest.raises(ValueError, match="squared off each end"):
        cut_bars({"A": 5985.0}, 6000.0, 3.0, 10.0)


# -- a built folder ------------------------------------------------------------------------------------------


class _Log(logging.Handler):
    def __init__(self):
        super().__init__(logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record):
        self.messages.append(record.getMessage())


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """The small vault (bolted splices) with glazing.min_slope_deg = 5°, built and written (the checks of this
    file are run on it one by one), with the warnings of the build."""
    from fabrication.design import load_design
    from fabrication.progress import Progress
    from fabrication.pipeline.stages import build
    from fabrication.writers import write_all

    root = tmp_path_factory.mktemp("shop")
    (root / "d.toml").write_text(small_vault("shop") + "\n[glazing]\nmin_slope_deg = 5.0\n")
    log = _Log()
    logger = logging.getLogger("ppfab")
    logger.addHandler(log)
    try:
        b = build(load_design(root / "d.toml"))
    finally:
        logger.removeHandler(log)
    out = root / "out"
    out.mkdir()
    write_all(b, out, Progress(quiet=True), parallel=False)
    return b, out, log.messages


def _verify(out: Path, *names: str):
    from fabrication.verify import Verification, load_checks

    v = Verification(out)
    checks = {c.name: c for c in load_checks()}
    for name in ("manifest", "parts", *names):
        checks[name].run(v)
    return v


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def test_bolts_csv_lists_every_bolted_splice(built, tmp_path):
    b, out, _ = built
    rows = _rows(out / "bolts.csv")
    parts = {r["part_id"]: r for r in _rows(out / "parts.csv")}
    covers = [r for r in parts.values() if r["kind"] == "splice" and r["part_id"].endswith("A")]
    assert len(rows) == len(covers) == len(b.glazing.splices) > 0
    manifest = (out / "manifest.json").read_text()
    assert '"bolts_csv": "bolts.csv"' in manifest
    for r in rows:
        cover = parts[r["splice"]]
        beam = parts[cover["joins"].split(";")[0]]
        grip = 2 * float(cover["thickness_mm"]) + float(beam["thickness_mm"])
        assert float(r["grip_mm"]) == pytest.approx(grip) == 32.0
        assert int(r["length_mm"]) == 65 and float(r["projection_mm"]) == pytest.approx(65 - grip - 2 * 3 - 18)
        assert int(r["quantity"]) == int(cover["holes"])
        assert (r["size"], r["grade"], r["category"]) == ("M20", "8.8", "A")
    v = _verify(out, "bolts")
    assert v.findings == [] and "bolts" in v.checked
    bad = tmp_path / "bad"
    shutil.copytree(out, bad)
    text = (bad / "bolts.csv").read_text().splitlines()
    text[1] = text[1].replace(",65,", ",60,", 1)
    (bad / "bolts.csv").write_text("\n".join(text) + "\n")
    found = [str(f) for f in _verify(bad, "bolts").findings if f.file == "bolts.csv" and f.element]
    assert len(found) == 1 and "row 1 column length_mm" in found[0] and "'60'" in found[0]


def _dxfs(out: Path) -> list[Path]:
    import json

    files = json.loads((out / "manifest.json").read_text())["files"]
    rels = [x for k in ("glass_sheets", "beam_sheets", "panel_type_dxfs", "splice_dxfs") for x in files.get(k, [])]
    return [out / r for r in rels]


def test_every_dxf_names_its_material_and_thickness(built, tmp_path):
    import ezdxf

    _, out, _ = built
    parts = {r["part_id"]: r for r in _rows(out / "parts.csv")}
    by_type = {r["type_id"]: r for r in parts.values() if r["kind"] == "splice"}
    paths = _dxfs(out)
    kinds = {p.parent.name for p in paths}
    assert {"glass", "beams", "splices"} <= kinds
    for path in paths:
        doc = ezdxf.readfile(path)
        cuts = doc.modelspace().query('LWPOLYLINE[layer=="CUT"]')
        assert len(cuts) > 0, path
        stock = set()
        for e in cuts:
            x = dict(str(t.value).split("=", 1) for t in e.get_xdata("PPFAB"))
            row = parts.get(x["part_id"]) or by_type[x["part_id"]]
            assert x["material"] == row["material"] and float(x["thickness_mm"]) == float(row["thickness_mm"])
            stock.add((x["material"], x["thickness_mm"]))
        assert len(stock) == 1, path
        ((material, thickness),) = stock
        assert doc.header.custom_vars.get("PPFAB_MATERIAL") == material
        assert doc.header.custom_vars.get("PPFAB_THICKNESS_MM") == thickness
        titles = [t.dxf.text for t in doc.modelspace().query('TEXT[layer=="LABEL"]')]
        assert any(t.endswith(f"material {material}, thickness {thickness} mm") for t in titles), path
    v = _verify(out, "dxf_stock")
    assert v.findings == [] and "dxf_stock" in v.checked
    bad = tmp_path / "bad"
    shutil.copytree(out, bad)
    sheet = next(p for p in _dxfs(bad) if p.parent.name == "beams")
    doc = ezdxf.readfile(sheet)
    e = doc.modelspace().query('LWPOLYLINE[layer=="CUT"]')[0]
    tags = [(t.code, str(t.value).replace("thickness_mm=12", "thickness_mm=10")) for t in e.get_xdata("PPFAB")]
    e.set_xdata("PPFAB", tags)
    doc.saveas(sheet)
    rel = str(sheet.relative_to(bad))
    found = [str(f) for f in _verify(bad, "dxf_stock").findings if f.file == rel and f.element]
    assert len(found) == 1 and "'10'" in found[0] and "'12'" in found[0]


def test_no_strip_is_cut_within_the_bar_end_allowance(built, tmp_path):
    b, out, _ = built
    a, bar = b.glazing.params.bar_end_allowance, b.glazing.params.bar_length
    assert a == 10.0
    rows = _rows(out / "strip_cuts.csv")
    assert len(rows) == len(b.glazing.strips) > 0
    assert min(float(r["start_mm"]) for r in rows) >= a - 1e-9
    assert max(float(r["start_mm"]) + float(r["length_mm"]) for r in rows) <= bar - a + 1e-9
    assert any(abs(float(r["start_mm"]) - a) < 1e-9 for r in rows)
    v = _verify(out, "strip_cuts")
    assert v.findings == []
    bad = tmp_path / "bad"
    shutil.copytree(out, bad)
    text = (bad / "strip_cuts.csv").read_text().splitlines()
    first = next(k for k, line in enumerate(text) if k and float(line.split(",")[1]) == 10.0)
    cells = text[first].split(",")
    cells[1] = "0.0"
    text[first] = ",".join(cells)
    (bad / "strip_cuts.csv").write_text("\n".join(text) + "\n")
    found = [str(f) for f in _verify(bad, "strip_cuts").findings]
    assert any("start_mm" in f and "10.000" in f for f in found), found


def _slope_of(corners: np.ndarray) -> float:
    """Slope (degrees) of the least-squares plane through a face's corners (SVD), z up."""
    c = corners - corners.mean(axis=0)
    n = np.linalg.svd(c)[2][-1]
    return float(np.degrees(np.arccos(abs(n[2]) / np.linalg.norm(n))))


def test_panes_flatter_than_the_minimum_slope_are_named(built):
    b, out, messages = built
    slopes = {p.part_id: _slope_of(p.corners_3d) for p in b.panels.panels}
    flat = sorted(pid for pid, s in slopes.items() if s < 5.0)
    assert 0 < len(flat) < len(slopes)
    warned = [m for m in messages if "glazing.min_slope_deg" in m]
    assert len(warned) == 1 and f"{len(flat)} pane(s)" in warned[0] and DRAINAGE_NOTE in warned[0]
    named = {pid for pid in slopes if f"{pid} (" in warned[0]}
    assert sorted(named) == flat
    report = (out / "report.html").read_text(encoding="utf-8")
    assert "Drainage:" in report and all(pid in report for pid in flat)


def test_the_default_has_two_near_flat_panes():
    from fabrication.design import load_design
    from fabrication.progress import Progress
    from fabrication.pipeline.stages import stage_geometry, stage_panels, stage_quality

    d = load_design(None)
    p = Progress(quiet=True)
    g = stage_geometry(d, p, False)
    panels = stage_panels(d, g, p, stage_quality(g, p)).panels
    got = flat_panes(panels, d.glazing.min_slope_deg)
    want = sorted(q.part_id for q in panels if _slope_of(q.corners_3d) < 2.0)
    assert [f.part_id for f in got] == want == ["P-U10-V07", "P-U11-V07"]
    assert all(0.5 < f.slope_deg < 2.0 for f in got)


# -- splice holes in the beam pieces -------------------------------------------------------------------------


def test_every_splice_bolt_hole_is_cut_in_the_beam_piece_under_it(built, tmp_path):
    import ezdxf
    from shapely.geometry import Point

    b, out, _ = built
    by_id = b.beams.by_id
    splices = b.glazing.splices
    assert len(splices) > 0
    matched: dict[str, set[int]] = {}
    for s in splices:
        for q in s.frame.to3d(s.holes):
            found = []
            for pid in s.pieces:
                piece = by_id[pid]
                xy = piece.frame.to2d(q[None])[0]
                d = np.linalg.norm(piece.holes[:, :2] - xy, axis=1) if len(piece.holes) else np.zeros(0)
                inside = Polygon(piece.outline).contains(Point(xy))
                hit = [int(k) for k in np.flatnonzero(d <= 0.01)]
                assert bool(hit) == inside, (pid, xy)   # cut where (and only where) the piece's material is
                for k in hit:
                    assert piece.holes[k, 2] == s.hole
                    matched.setdefault(pid, set()).add(k)
                found += hit
            assert len(found) == 1                      # in exactly one of the two pieces
    holed = {p.part_id: len(p.holes) for p in b.beams.plates if len(p.holes)}
    assert holed == {pid: len(ks) for pid, ks in matched.items()}       # and no other hole
    assert sum(holed.values()) == sum(len(s.holes) for s in splices)
    # the plate sheets carry them as CUT circles; verify maps them back and finds every one
    circles = sum(len(ezdxf.readfile(p).modelspace().query('CIRCLE[layer=="CUT"]')) for p in _dxfs(out)
                  if p.parent.name == "beams")
    assert circles == sum(holed.values())
    v = _verify(out, "splice_holes")
    assert v.findings == [] and "splice_holes" in v.checked
    bad = tmp_path / "bad"
    shutil.copytree(out, bad)
    sheet = next(p for p in _dxfs(bad) if p.parent.name == "beams" and
                 len(ezdxf.readfile(p).modelspace().query('CIRCLE[layer=="CUT"]')))
    doc = ezdxf.readfile(sheet)
    circle = doc.modelspace().query('CIRCLE[layer=="CUT"]')[0]
    circle.dxf.center = (circle.dxf.center[0] + 0.05, circle.dxf.center[1])
    doc.saveas(sheet)
    found = [str(f) for f in _verify(bad, "splice_holes").findings if f.element]
    # the bolt hole of both cover plates (A and B) has no hole under it, and the moved hole is stray
    assert len(found) == 3, found
    assert sum("0.050 mm away" in f for f in found) == 2 and sum("no splice cover plate" in f for f in found) == 1


def test_beams_step_carries_the_splice_holes(built):
    from fabrication.verify._step_read import read_step_solids

    b, out, _ = built
    holed = [p for p in b.beams.plates if len(p.holes)]
    assert holed
    solids = {s.name: s.solid for s in read_step_solids(out / "beams.step")}
    for p in holed:
        s = solids[p.part_id]
        cylinders = [f for f in s.faces() if str(f.geom_type).endswith("CYLINDER")]
        assert len(cylinders) == len(p.holes)
        # the rims of the holes: circles centred on the holes, on both faces
        rims = [e for e in s.edges() if str(e.geom_type).endswith("CIRCLE")]
        assert len(rims) >= 2 * len(p.holes)
        for e in rims:
            c = np.array(tuple(e.arc_center))
            xy = p.frame.to2d(c[None])[0]
            assert float(np.linalg.norm(p.holes[:, :2] - xy, axis=1).min()) < 1e-6
        net = p.area - len(p.holes) * np.pi / 4 * 22.0 ** 2
        assert s.volume == pytest.approx(net * p.thickness, rel=1e-6)


@pytest.mark.parametrize("version", ["R12", "R2000", "R2010"])
def test_older_dxf_versions_keep_the_stock_and_the_holes(version, tmp_path):
    """The R12/R2000 copies carry the material and thickness in XDATA and title (custom properties exist
    from R2004 on only) and the bolt holes as CUT circles."""
    import ezdxf

    from fabrication.beams.flat import HoledPart
    from fabrication.writers.dxf import read_sheet_dxf, write_part_dxf

    part = HoledPart("B-U00-S00", "beam", np.array([[0.0, 0.0], [300.0, 0.0], [300.0, 150.0], [0.0, 150.0]]),
                     meta={"material": "S355", "thickness_mm": 12.0}, holes=np.array([[50.0, 75.0, 22.0]]))
    path = write_part_dxf(part, tmp_path / "p.dxf", "B-U00-S00", version=version)
    content = read_sheet_dxf(path)
    assert content.audit_errors == [] and content.other_entities == []
    x = content.parts[0].xdata
    assert (x["material"], x["thickness_mm"]) == ("S355", "12")
    assert [(h.part_id, h.diameter, tuple(h.centre)) for h in content.holes] == [("B-U00-S00", 22.0, (50.0, 75.0))]
    assert any(t.endswith("material S355, thickness 12 mm") for t in content.labels)
    custom = dict(ezdxf.readfile(path).header.custom_vars) if version == "R2010" else {}
    assert custom.get("PPFAB_MATERIAL", "S355") == "S355" and (version != "R2010" or "PPFAB_MATERIAL" in custom)
