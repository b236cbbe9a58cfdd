"""The glass retention as parts of the build: every setting block, stop, pressure gasket, pressure plate, cover cap
and plate's screws is a row of parts.csv, an element of model.ifc, model.3dm and model.glb and a row of
erection.csv, placed where glazing.step has it; the pressure plates' bending between their screws is checked.

Measured apart from the code that made them: the boxes of parts.csv against the solids of glazing.step (the STEP
reader of the kernel), the IFC with ifcopenshell's placement utilities, the plate bending with the beam formulas
written out here, the masses from each row's own dimensions and densities.
"""

from __future__ import annotations

import csv
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from fabrication.verify._step_read import read_step_solids
from fabrication.verify.rhino import placed_objects

from conftest import small_design
from tamper import write_rows

BOXES = ("setting_block", "stop", "pressure_gasket", "pressure_plate", "cover_cap")


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> Path:
    """A 4 × 3 vault with pressure plates, written with its exchange models (one build for the module)."""
    from fabrication import build
    from fabrication.design import load_design
    from fabrication.progress import Progress
    from fabrication.writers import write_all

    root = tmp_path_factory.mktemp("retention_parts")
    (root / "d.toml").write_text(small_design(4, 3, name="retention parts"))
    out = root / "out"
    out.mkdir()
    write_all(build(load_design(root / "d.toml")), out, Progress(quiet=True))
    return out


def rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def corners(row: dict[str, str]) -> np.ndarray:
    """The eight corners of a retention box from its parts.csv row (origin + a·L·x + b·W·y + c·H·n)."""
    f = json.loads(row["frame"])
    o, x, y, n = (np.array(f[k]) for k in ("origin", "x_dir", "y_dir", "normal"))
    L, W, H = (float(row[k]) for k in ("length_mm", "width_mm", "height_mm"))
    return np.array([o + a * L * x + b * W * y + c * H * n for a in (0, 1) for b in (0, 1) for c in (0, 1)])


def test_every_retention_part_is_a_parts_row_placed_on_its_glazing_step_solid(built):
    parts = rows(built / "parts.csv")
    retention = rows(built / "retention.csv")
    by_kind = {k: [r for r in parts if r["kind"] == k] for k in BOXES + ("screw",)}
    for kind in BOXES:
        assert sorted(r["part_id"] for r in by_kind[kind]) == \
            sorted(r["part_id"] for r in retention if r["kind"] == kind) != [], kind
    plates = {r["part_id"]: r for r in retention if r["kind"] == "pressure_plate"}
    screws = {r["owner"]: r for r in by_kind["screw"]}
    assert set(screws) == set(plates)                     # one screw row (a BOM line) per plate
    for pid, plate in plates.items():
        assert int(screws[pid]["quantity"]) == int(plate["screws"]) == \
            len(screws[pid]["screw_stations_mm"].split(";")) >= 2
    solids = {s.name: s.solid for s in read_step_solids(built / "glazing.step")}
    worst = 0.0
    for r in parts:
        if r["kind"] in BOXES:
            verts = np.array([tuple(p) for p in solids[r["part_id"]].vertices()])
            box = corners(r)
            d = np.linalg.norm(box[:, None] - verts[None], axis=2)
            worst = max(worst, float(d.min(axis=1).max()), float(d.min(axis=0).max()))
            assert abs(solids[r["part_id"]].volume - float(r["area_mm2"]) * float(r["thickness_mm"])) < 1e-3 * \
                float(r["area_mm2"]) * float(r["thickness_mm"])
    assert worst < 1e-3                                   # the box of every row is its STEP solid's
    # each screw stands in the joint's centre line over its strip, from the strip's top through the plate
    strip_top = {s: solids[s] for s in {r["strip"] for r in by_kind["screw"]}}
    for r in by_kind["screw"]:
        f = json.loads(r["frame"])
        o, x, n = (np.array(f[k]) for k in ("origin", "x_dir", "normal"))
        top = np.array([tuple(p) for p in strip_top[r["strip"]].vertices()]) @ n
        assert float(o @ n) == pytest.approx(float(top.max()), abs=1e-3)
        plate = np.array([tuple(p) for p in solids[r["owner"]].vertices()])
        for s in (float(v) for v in r["screw_stations_mm"].split(";")):
            foot = o + s * x
            along = (plate - foot) @ n
            assert along.max() < float(r["length_mm"]) < along.max() + 0.8 * float(r["diameter_mm"]) + 1e-6
    # the masses of the rows from their own dimensions and densities (cover caps: a 2 mm channel)
    density = {"setting_block": 1300, "stop": 7850, "pressure_gasket": 1200, "pressure_plate": 2700}
    for r in parts:
        L, W, H = (float(r.get(k) or 0) for k in ("length_mm", "width_mm", "height_mm"))
        if r["kind"] in density:
            assert float(r["mass_kg"]) == pytest.approx(L * W * H * density[r["kind"]] * 1e-9, rel=1e-3, abs=1e-4)
        elif r["kind"] == "cover_cap":
            assert float(r["mass_kg"]) == pytest.approx(L * (W + 2 * H) * 2.0 * 2700e-9, rel=1e-3, abs=1e-4)
        elif r["kind"] == "screw":
            d = float(r["diameter_mm"])
            assert float(r["mass_kg"]) == pytest.approx(int(r["quantity"]) * math.pi / 4 * d * d
                                                        * float(r["length_mm"]) * 8000e-9, rel=1e-3, abs=1e-4)


def test_the_exchange_models_hold_every_retention_part_where_parts_csv_places_it(built):
    import ifcopenshell
    import ifcopenshell.util.placement as up
    import trimesh
    import rhino3dm

    parts = {r["part_id"]: r for r in rows(built / "parts.csv")}
    kinds = {k: sum(r["kind"] == k for r in parts.values()) for k in BOXES + ("screw",)}
    f = ifcopenshell.open(str(built / "model.ifc"))
    assert len(f.by_type("IfcMechanicalFastener")) == kinds["screw"]
    assert len(f.by_type("IfcDiscreteAccessory")) == kinds["setting_block"] + kinds["stop"] + kinds["pressure_gasket"]
    assert len(f.by_type("IfcCovering")) == kinds["cover_cap"]
    assert sum(p.PredefinedType == "SHEET" for p in f.by_type("IfcPlate")) == kinds["pressure_plate"]
    total = 0
    for fastener in f.by_type("IfcMechanicalFastener"):
        row = parts[fastener.Name]
        items = fastener.Representation.Representations[0].Items
        assert len(items) == int(row["quantity"])
        total += len(items)
        frame = json.loads(row["frame"])
        o, x = np.array(frame["origin"]), np.array(frame["x_dir"])
        m = np.asarray(up.get_local_placement(fastener.ObjectPlacement))
        feet = sorted(float(((m @ np.r_[it.Position.Location.Coordinates, 1.0])[:3] - o) @ x) for it in items)
        want = [float(s) for s in row["screw_stations_mm"].split(";")]
        assert np.allclose(feet, want, atol=1e-6)
        assert {it.SweptArea.Radius for it in items} == {0.5 * float(row["diameter_mm"])}
    assert total == sum(int(r["quantity"]) for r in parts.values() if r["kind"] == "screw")
    # glTF: a node per row; a box node's vertices are its row's corners, converted back to mm
    scene = trimesh.load(str(built / "model.glb"), force="scene", process=False)
    from fabrication.writers.glb import MM_TO_GLTF

    back = np.linalg.inv(MM_TO_GLTF)
    names = set(scene.graph.nodes_geometry)
    assert {p for p, r in parts.items() if r["kind"] in BOXES + ("screw",)} <= names
    block = next(p for p, r in parts.items() if r["kind"] == "setting_block")
    transform, geom = scene.graph[block]
    pts = trimesh.transform_points(scene.geometry[geom].vertices, transform) @ back.T
    assert np.linalg.norm(corners(parts[block])[:, None] - pts[None], axis=2).min(axis=1).max() < 1e-2
    # Rhino: a layer per kind holding exactly the rows of that kind
    model = rhino3dm.File3dm.Read(str(built / "model.3dm"))
    layers = [la.FullPath for la in model.Layers]
    on: dict[str, int] = {}
    objects, problems = placed_objects(model)             # a block instance counts, its block's body does not
    assert problems == []
    for obj in objects:
        on[layers[obj.attributes.LayerIndex]] = on.get(layers[obj.attributes.LayerIndex], 0) + 1
    for kind, count in kinds.items():
        assert on.get(f"retention::{kind}", 0) == count, kind


def test_erection_sets_blocks_before_their_pane_and_the_clamp_after_the_panes_it_holds(built):
    parts = {r["part_id"]: r for r in rows(built / "parts.csv")}
    order = {r["part_id"]: r for r in rows(built / "erection.csv")}
    assert {p for p, r in parts.items() if r["kind"] in BOXES + ("screw",)} <= set(order)
    bites = rows(built / "bites.csv")
    panes_on = {}
    for b in bites:
        panes_on.setdefault(b["strip"], set()).add(b["panel"])
    for pid, r in parts.items():
        step = int(order[pid]["step"])
        d = np.array([float(order[pid][f"direction_{c}"]) for c in "xyz"])
        if r["kind"] in ("setting_block", "stop"):
            assert step < int(order[r["owner"]]["step"])
        elif r["kind"] in ("pressure_gasket", "pressure_plate", "screw", "cover_cap"):
            assert all(step > int(order[p]["step"]) for p in panes_on[r["strip"]])
        if r["kind"] in BOXES + ("screw",):                # moved in along the inside of its frame's normal
            assert np.allclose(d, -np.array(json.loads(r["frame"])["normal"]), atol=1e-6)
    steps = {r["kind"]: int(r["step"]) for r in order.values()}
    assert steps["pressure_gasket"] < steps["pressure_plate"] < steps["screw"] < steps["cover_cap"]


def _bending(w: float, stations: list[float], length: float, b: float, t: float, f: float, e: float,
             gq: float) -> tuple[float, float, float]:
    """Stress (N/mm²), deflection (mm) and its limit of a plate on screws, written out independently: the worst
    of a simply supported span ``w s² / 8`` and an end cantilever ``w a² / 2`` over ``b t² / 6``; deflection
    ``5 w s⁴ / 384 E I`` or ``w a⁴ / 8 E I`` at the characteristic load."""
    s = max(np.diff(stations)) if len(stations) > 1 else 0.0
    a = max(stations[0], length - stations[-1])
    stress = max(w * s * s / 8, w * a * a / 2) * 6 / (b * t * t)
    i = b * t ** 3 / 12
    spans = [(5 * (w / gq) * s ** 4 / (384 * e * i), s / 200), ((w / gq) * a ** 4 / (8 * e * i), 2 * a / 200)]
    d, lim = max(spans, key=lambda p: p[0] / p[1])
    return stress, d, lim


def test_pressure_plate_bending_is_the_beam_formula_under_the_panes_suction(built):
    parts = {r["part_id"]: r for r in rows(built / "parts.csv")}
    manifest = json.loads((built / "manifest.json").read_text())
    gl = manifest["fabrication"]["glazing"]
    q = float(gl["wind_suction"]) * float(gl["load_factor"]) * 1e-3       # N/mm²
    panes_on: dict[str, set[str]] = {}
    for b in rows(built / "bites.csv"):
        panes_on.setdefault(b["strip"], set()).add(b["panel"])
    plates = [r for r in rows(built / "retention.csv") if r["kind"] == "pressure_plate"]
    assert plates
    for r in plates:
        strip = "GS" + r["part_id"][2:]
        w = sum(q * float(parts[p]["area_mm2"]) / float(parts[p]["perimeter_mm"]) for p in panes_on[strip])
        xs = [float(x) for x in r["screw_stations_mm"].split(";")]
        stress, d, lim = _bending(w, xs, float(r["length_mm"]), float(r["width_mm"]), float(r["height_mm"]),
                                  150.0, 70000.0, float(gl["load_factor"]))
        assert float(r["plate_load_N_mm"]) == pytest.approx(w, rel=2e-3)
        assert float(r["plate_stress_N_mm2"]) == pytest.approx(stress, rel=5e-3, abs=0.01)
        assert float(r["plate_stress_limit_N_mm2"]) == pytest.approx(150.0 / 1.1, abs=0.01)   # EN AW-6060 T66
        assert float(r["plate_deflection_mm"]) == pytest.approx(d, rel=5e-3, abs=1e-4)
        assert float(r["plate_deflection_limit_mm"]) == pytest.approx(lim, abs=1e-3)
    restraint = rows(built / "restraint.csv")
    assert all(0 < float(x["plate_utilisation"]) < 1 for x in restraint)


def retention_findings(folder: Path) -> list[str]:
    """What ``ppfab verify``'s retention check finds in ``folder`` (the check alone: the rest of verify reads
    every file and costs seconds)."""
    from fabrication.verify import Verification
    from fabrication.verify.retention import check_retention

    v = Verification(folder)
    check_retention(v)
    assert "retention" in v.checked
    return [str(f) for f in v.findings]


def test_a_plate_bent_beyond_its_limit_is_refused_by_the_check_and_named_by_verify(built, tmp_path):
    from fabrication.glazing.retention_strength import PLATE_MATERIALS, plate_bending

    weak = plate_bending("CP-X", 10.0, (125.0, 375.0, 625.0), 750.0, 50.0, 8.0,
                         PLATE_MATERIALS["EN AW-6060 T66"], 1.5)
    assert weak.stress == pytest.approx(10.0 * 250 ** 2 / 8 * 6 / (50 * 64)) and weak.utilisation > 1
    assert any("above f/γ" in t for t in weak.failures())
    assert retention_findings(built) == []
    # the same folder with twenty times the wind suction in its manifest: verify recomputes and names the plates
    folder = tmp_path / "strong_wind"
    shutil.copytree(built, folder, ignore=shutil.ignore_patterns("model.*", "drawings", "*.dxf"))
    m = json.loads((folder / "manifest.json").read_text())
    m["fabrication"]["glazing"]["wind_suction"] = 20.0 * float(m["fabrication"]["glazing"]["wind_suction"])
    (folder / "manifest.json").write_text(json.dumps(m, indent=2))
    found = retention_findings(folder)
    bent = [f for f in found if "between its screws" in f]
    plates = [r for r in rows(built / "retention.csv") if r["kind"] == "pressure_plate"]
    assert bent and all(f.startswith("retention.csv: CP-") for f in bent)
    assert len({f.split(":")[1] for f in bent}) == len(plates)     # 20 × the suction bends every plate too far


def test_verify_names_a_screw_row_deleted_and_a_block_moved_in_parts_csv(built, tmp_path):
    folder = tmp_path / "tampered"
    shutil.copytree(built, folder, ignore=shutil.ignore_patterns("model.*", "drawings", "*.dxf"))
    parts = rows(folder / "parts.csv")
    screw = next(r for r in parts if r["kind"] == "screw")
    block = next(r for r in parts if r["kind"] == "setting_block")
    frame = json.loads(block["frame"])
    frame["origin"] = [c + 5.0 * n for c, n in zip(frame["origin"], frame["x_dir"])]      # 5 mm along the edge
    block["frame"] = json.dumps(frame)
    write_rows(folder / "parts.csv", [r for r in parts if r is not screw])
    found = retention_findings(folder)
    assert sorted(found) == sorted([f"parts.csv: {block['part_id']}: its row places it 5 mm from its solid in "
                                    "glazing.step",
                                    f"parts.csv: {screw['part_id']}: the screws of {screw['owner']} have no row"])


def test_the_summary_and_report_weights_are_the_parts_csv_rows_of_every_kind(built):
    parts = rows(built / "parts.csv")
    summary = json.loads((built / "manifest.json").read_text())["summary"]
    mass: dict[str, float] = {}
    for r in parts:
        mass[r["kind"]] = mass.get(r["kind"], 0.0) + float(r.get("mass_kg") or r.get("weight_kg") or 0.0)
    assert set(mass) >= set(BOXES) | {"panel", "beam", "strip", "screw"}
    n = len(parts)
    assert summary["glass_weight_kg"] == pytest.approx(mass["panel"], abs=5e-4 * n)
    assert summary["beam_mass_kg"] == pytest.approx(mass["beam"], abs=5e-4 * n)
    assert summary["steel_mass_kg"] == pytest.approx(mass["beam"] + mass["strip"] + mass.get("splice", 0.0),
                                                     abs=5e-4 * n)
    held = sum(mass[k] for k in BOXES + ("screw",))
    assert held > 0 and summary["retention_mass_kg"] == pytest.approx(held, abs=5e-5 * n)
    report = (built / "report.html").read_text(encoding="utf-8")
    assert f"{summary['retention_mass_kg']:.1f} kg" in report and f"{summary['steel_mass_kg'] / 1000:.2f} t" in report


@pytest.mark.slow
def test_a_real_mesh_patch_lists_models_and_erects_its_retention(tmp_path):
    """A 5 × 5 patch of the surface of revolution DOI__rot4_def1_sparse_rot.obj (shared test data: WWmore/DOI,
    objs/obj_rot/rot4_def1_sparse_rot.obj, see the data README), built and self-verified by
    ``ppfab build``: every retention part of retention.csv is a parts.csv row, an IFC element and an erection
    row, the screw rows hold every station."""
    import ifcopenshell

    from ppfab.io import load_mesh, write_obj
    from ppfab.mesh import QuadGrid

    from conftest import shared_file
    from fabrication.cli import main

    grid = load_mesh(shared_file("DOI__rot4_def1_sparse_rot.obj")).to_grid()
    write_obj(QuadGrid(np.ascontiguousarray(grid.vertices[20:26, 0:6])), tmp_path / "patch.obj")
    (tmp_path / "d.toml").write_text(f'[design]\nname = "rot4 patch"\n[geometry]\n'
                                     f'mesh = "{(tmp_path / "patch.obj").as_posix()}"\nscale = 3000.0\n'
                                     '[beams]\nfallback = "segmented"\n[glazing]\nbevel_min_deg = 45.0\n'
                                     '[nesting]\ntime_budget = 0.5\n'
                                     "[beam_nesting]\ntime_budget = 0.5\n")
    out = tmp_path / "out"
    assert main(["build", str(tmp_path / "d.toml"), "-o", str(out), "--quiet"]) == 0      # verify passed in it
    parts = {r["part_id"]: r for r in rows(out / "parts.csv")}
    retention = rows(out / "retention.csv")
    assert len(retention) > 0 and all(parts[r["part_id"]]["kind"] == r["kind"] for r in retention)
    plates = [r for r in retention if r["kind"] == "pressure_plate"]
    screws = [r for r in parts.values() if r["kind"] == "screw"]
    assert len(screws) == len(plates) and sum(int(r["quantity"]) for r in screws) == \
        sum(int(r["screws"]) for r in plates)
    f = ifcopenshell.open(str(out / "model.ifc"))
    named = {e.Name for e in f.by_type("IfcElement")}
    assert {r["part_id"] for r in retention} | {r["part_id"] for r in screws} <= named
    erected = {r["part_id"] for r in rows(out / "erection.csv")}
    assert set(parts) <= erected


def test_a_plate_material_without_a_strength_is_refused_naming_the_key():
    from ppfab.errors import DesignError

    from fabrication.glazing.retention_strength import plate_material

    assert plate_material("EN AW-6060 T66 anodised") == (150.0, 1.1, 70000.0)
    assert plate_material("S355J2") == (355.0, 1.0, 210000.0)
    with pytest.raises(DesignError) as exc:
        plate_material("oak")
    text = str(exc.value)
    assert "pressure_plate_material" in text and "'oak'" in text and "\n" not in text
