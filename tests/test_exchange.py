"""The exchange files reopened with their own libraries and compared with parts.csv, nodes.csv and the mesh:
model.ifc (ifcopenshell), model.3dm (rhino3dm), beams.step / panels.step (the CAD kernel's reader and the STEP
text), model.glb (trimesh), the glass order and its dimensioned per-type DXFs, and the R12 / R2000 copies (ezdxf).
"""

import csv
import json
import re
import shutil

import numpy as np
import pytest

from fabrication.cli import main
from fabrication.contract import RETENTION_KINDS
from fabrication.verify.rhino import placed_objects
from ppfab.io import load_mesh

from conftest import small_design

NAME = "exchange test Überdach"
DESIGN = small_design(5, 4, name=NAME, extra="""
[beams]
depth = 150.0
thickness = 12.0
max_length = 5000.0
material = "S355 steel plate"
[panels]
gap = 16.0
edge_finish = "ground"
[output]
dxf_r12 = true
dxf_r2000 = true
""")


def rows(path):
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    root = tmp_path_factory.mktemp("exchange")
    design = root / "d.toml"
    design.write_text(DESIGN, encoding="utf-8")
    out = root / "out"
    assert main(["build", str(design), "-o", str(out), "--quiet"]) == 0
    return out


@pytest.fixture(scope="module")
def parts(built):
    return {r["part_id"]: r for r in rows(built / "parts.csv")}


@pytest.fixture(scope="module")
def mesh(built):
    return load_mesh(built / "mesh.obj")


def test_manifest_lists_the_exchange_files(built):
    m = json.loads((built / "manifest.json").read_text())
    for key, name in (("ifc", "model.ifc"), ("rhino", "model.3dm"), ("glb", "model.glb")):
        assert m["files"][key] == name and name in m["sha256"]
    assert m["files"]["dxf_r12"] and all(f.startswith("dxf_r12/") for f in m["files"]["dxf_r12"])
    assert len(m["files"]["dxf_r2000"]) == len(m["files"]["dxf_r12"]) == (
        len(m["files"]["glass_sheets"]) + len(m["files"]["beam_sheets"]) + len(m["files"]["panel_type_dxfs"]))


def test_verify_passes_on_every_file_kind(built, capsys):
    assert main(["verify", str(built)]) == 0
    out = capsys.readouterr().out
    for name in ("glass_order", "dxf_legacy", "step", "ifc", "rhino", "glb"):
        assert name in out


# -- IFC --------------------------------------------------------------------------------------------------

def test_ifc_reopens_with_one_element_per_part_and_the_parts_data(built, parts):
    import ifcopenshell
    import ifcopenshell.util.element as ue
    import ifcopenshell.util.unit as uu
    import ifcopenshell.validate

    f = ifcopenshell.open(str(built / "model.ifc"))
    assert f.schema == "IFC4"
    log = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(f, log)
    assert log.statements == []
    # units: millimetres, m², m³, kg
    assert uu.calculate_unit_scale(f) == pytest.approx(1e-3)
    for unit_type, name, prefix in (("LENGTHUNIT", "METRE", "MILLI"), ("AREAUNIT", "SQUARE_METRE", None),
                                    ("VOLUMEUNIT", "CUBIC_METRE", None), ("MASSUNIT", "GRAM", "KILO")):
        u = uu.get_project_unit(f, unit_type)
        assert (u.Name, u.Prefix) == (name, prefix)
    panels = {k: r for k, r in parts.items() if r["kind"] == "panel"}
    beams = {k: r for k, r in parts.items() if r["kind"] == "beam"}
    plates = [p for p in f.by_type("IfcPlate") if p.PredefinedType != "SHEET"]     # not the pressure plates
    members = [m for m in f.by_type("IfcMember") if m.PredefinedType == "MEMBER"]
    # glazing strips and splice cover plates are user-defined members named by their kind
    extra = {m.Name: m.ObjectType for m in f.by_type("IfcMember") if m.PredefinedType != "MEMBER"}
    assert extra == {k: r["kind"] for k, r in parts.items() if r["kind"] in ("strip", "splice")}
    assert len(plates) == len(panels) and len(members) == len(beams)
    assert {p.Name for p in plates} == set(panels) and {m.Name for m in members} == set(beams)
    assert {p.PredefinedType for p in plates} == {"CURTAIN_PANEL"}
    assert len({e.GlobalId for e in f.by_type("IfcRoot")}) == len(f.by_type("IfcRoot"))
    for e in list(plates) + list(f.by_type("IfcMember")):                 # every part, strips and splices too
        row = parts[e.Name]
        ps = ue.get_psets(e)["PPFAB_Part"]
        assert ps["part_id"] == e.Name and ps["nest_tag"] == row["nest_tag"] and ps.get("type_id", "") == row["type_id"]
        assert ps.get("sheet", "") == (int(row["sheet"]) if row["sheet"] else "") and ps["material"] == row["material"]
        weight = row["weight_kg"] or row["mass_kg"]
        assert ps["weight_kg"] == pytest.approx(float(weight), rel=1e-12)
        assert ps["area_mm2"] == pytest.approx(float(row["area_mm2"]), rel=1e-12)
        if row["kind"] == "panel":
            assert ps["planarity_dev_mm"] == pytest.approx(float(row["planarity_dev_mm"]), abs=1e-12)
            qto = ue.get_psets(e)["Qto_PlateBaseQuantities"]
            assert qto["Width"] == pytest.approx(float(row["thickness_mm"]))
        else:
            assert ps.get("beam_id", "") == row["beam_id"] and ps["family"] == row["family"]
            qto = ue.get_psets(e)["Qto_MemberBaseQuantities"]
            if row["length_mm"]:                                           # beam plates and strips
                assert qto["Length"] == pytest.approx(float(row["length_mm"]))
            else:
                assert row["kind"] == "splice" and "Length" not in qto
        holes = float(row.get("holes") or 0) * np.pi / 4.0 * float(row.get("hole_mm") or 0.0) ** 2
        assert qto["NetArea"] == pytest.approx((float(row["area_mm2"]) - holes) * 1e-6, rel=1e-12)    # m², net
        if row["kind"] == "panel":                     # the make-up's layers, outside ply first
            layers = ue.get_material(e, should_skip_usage=True)
            assert layers.LayerSetName == row["material"]
            assert [x.LayerThickness for x in layers.MaterialLayers] == [8.0, 1.52, 8.0]
            assert ue.get_type(e).Name == row["type_id"]
        else:
            assert ue.get_material(e).Name == row["material"]


def test_ifc_spatial_structure_and_beam_assemblies(built, parts):
    import ifcopenshell
    import ifcopenshell.util.element as ue

    f = ifcopenshell.open(str(built / "model.ifc"))
    (project,) = f.by_type("IfcProject")
    (roof,) = f.by_type("IfcRoof")
    assert project.Name == NAME and roof.Name == NAME
    storey = ue.get_container(roof)
    assert storey.is_a("IfcBuildingStorey")
    assert ue.get_aggregate(storey).is_a("IfcBuilding") and ue.get_aggregate(ue.get_aggregate(storey)).is_a("IfcSite")
    assert ue.get_aggregate(ue.get_aggregate(ue.get_aggregate(storey))) == project
    for plate in f.by_type("IfcPlate"):
        assert ue.get_aggregate(plate) == roof and ue.get_container(plate) == storey
    for member in f.by_type("IfcMember"):
        if member.PredefinedType != "MEMBER":
            continue
        assembly = ue.get_aggregate(member)
        assert assembly.is_a("IfcElementAssembly") and assembly.Name == parts[member.Name]["beam_id"]
        assert ue.get_aggregate(assembly) == roof
    assert len(f.by_type("IfcElementAssembly")) == len({r["beam_id"] for r in parts.values() if r["kind"] == "beam"})


def test_ifc_solids_have_the_parts_volume_where_the_mesh_is(built, parts, mesh):
    """ifcopenshell's geometry kernel tessellates every element: its volume is area × thickness (less the bolt
    holes of plates and cover plates; a beam plate's is its solid's in beams.step, bevelled under its strips or
    not), a pane lies
    parallel to its mesh face at the height of its solid in panels.step (on its gaskets), a plate on its support
    plane (independent of ppfab's own readers)."""
    import ifcopenshell
    import ifcopenshell.geom
    import ifcopenshell.util.shape as us

    from fabrication.verify._step_read import read_step_solids

    step = {s.name: np.array([tuple(p) for p in s.solid.vertices()]) for s in read_step_solids(built / "panels.step")}
    plates = {s.name: float(s.solid.volume) for s in read_step_solids(built / "beams.step")}
    f = ifcopenshell.open(str(built / "model.ifc"))
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    it = ifcopenshell.geom.iterator(settings, f)
    assert it.initialize()
    seen = set()
    while True:
        shape = it.get()
        name = f.by_id(shape.id).Name
        row = parts[name]
        seen.add(name)
        if row["kind"] == "screw":                # the screws of a plate: no area × thickness of their own
            if not it.next():
                break
            continue
        t = float(row["thickness_mm"])
        volume = us.get_volume(shape.geometry) * 1e9                    # the kernel works in metres
        # bolt holes (parts.csv holes x hole_mm) are cut: the kernel tessellates their circles, within 2 %
        n, hole = float(row.get("holes") or 0), np.pi / 4.0 * float(row.get("hole_mm") or 0.0) ** 2
        full = float(row["area_mm2"]) * t
        if row["kind"] == "beam":                 # the plate of beams.step, bevelled or not (its holes exact there)
            assert abs(volume - plates[name]) <= 1e-7 * full + 0.02 * n * hole * t, (name, volume, plates[name])
        else:
            assert abs(volume - (full - n * hole * t)) <= 1e-7 * full + 0.02 * n * hole * t, (name, volume, full)
        x = np.asarray(us.get_vertices(shape.geometry)) * 1e3
        if row["kind"] == "panel":
            c = mesh.vertices[mesh.faces[int(row["face"])]]
            n = np.linalg.svd(c - c.mean(axis=0))[2][2]
            d = np.sort((x - c.mean(axis=0)) @ n)
            sign = 1.0 if abs(d[-1]) > abs(d[0]) else -1.0
            d = d if sign > 0 else -d[::-1]
            seat = float(np.min(sign * (step[name] - c.mean(axis=0)) @ n))
            assert 5.0 < seat < 20.0                                     # strip 8 + gasket 3 mm, ± the gasket tilt
            assert d[0] == pytest.approx(seat, abs=1e-6) and d[-1] == pytest.approx(seat + t, abs=1e-6)
        elif row["kind"] == "beam":
            plane = np.array(json.loads(row["plane"]))
            d = x @ plane[:3] + plane[3]
            assert np.abs(d).max() == pytest.approx(0.5 * t, abs=1e-6) and d.min() < 0 < d.max()
        if not it.next():
            break
    assert seen == set(parts)


@pytest.mark.slow
def test_ifc_passes_the_express_rules(built):
    import ifcopenshell
    import ifcopenshell.validate

    log = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(ifcopenshell.open(str(built / "model.ifc")), log, express_rules=True)
    assert log.statements == []


def test_ifc_structural_analysis_model_follows_the_nodes_and_edges(built, parts, mesh):
    """The analysis hand-off: one curve member per mesh edge and one point connection per node, each member's
    ends at its nodes' system points (the mesh vertex moved half the beam depth, 150 mm, along the node axis of
    nodes.csv), its local z axis orthogonal to it and within a few degrees of the node axes, named after the plate
    that carries the edge (the two pieces of a splice across it), the section the plate's 12 x 150 rectangle, the boundary nodes (counted from mesh.obj's
    edges with one face) pinned, all grouped in one analysis model that serves the building."""
    import ifcopenshell

    f = ifcopenshell.open(str(built / "model.ifc"))
    [model] = f.by_type("IfcStructuralAnalysisModel")
    members, connections = f.by_type("IfcStructuralCurveMember"), f.by_type("IfcStructuralPointConnection")
    faces = [tuple(int(k) for k in face) for face in mesh.faces]
    edge_faces: dict[tuple[int, int], int] = {}
    for face in faces:
        for a, b in zip(face, face[1:] + face[:1]):
            edge_faces[(min(a, b), max(a, b))] = edge_faces.get((min(a, b), max(a, b)), 0) + 1
    nodes = rows(built / "nodes.csv")
    assert len(members) == len(edge_faces) and len(connections) == len(nodes)
    pos = {n["node_id"]: np.array([float(n[k]) for k in "xyz"]) for n in nodes}
    axis = {n["node_id"]: np.array([float(n[f"axis_{k}"]) for k in "xyz"]) for n in nodes}
    system = {k: pos[k] + 75.0 * axis[k] / np.linalg.norm(axis[k]) for k in pos}
    by_vertex = {int(n["vertex"]): n["node_id"] for n in nodes}
    point = {c.Name: np.array(c.Representation.Representations[0].Items[0].VertexGeometry.Coordinates)
             for c in connections}
    assert max(np.linalg.norm(point[k] - system[k]) for k in system) < 1e-3          # nodes.csv: 0.1 µm
    seen = set()
    for m in members:
        e = m.Representation.Representations[0].Items[0]
        a, b = (np.array(v.VertexGeometry.Coordinates) for v in (e.EdgeStart, e.EdgeEnd))
        ka, kb = m.Name.split("/")
        assert np.linalg.norm(a - system[ka]) < 1e-3 and np.linalg.norm(b - system[kb]) < 1e-3
        va, vb = (int(n["vertex"]) for n in nodes if n["node_id"] in (ka, kb))
        seen.add((min(va, vb), max(va, vb)))
        z = np.array(m.Axis.DirectionRatios)
        assert abs(z @ (b - a)) / np.linalg.norm(b - a) < 1e-9
        mean = axis[ka] / np.linalg.norm(axis[ka]) + axis[kb] / np.linalg.norm(axis[kb])
        assert np.degrees(np.arccos(np.clip(z @ mean / np.linalg.norm(mean), -1, 1))) < 15.0
        carried = [set(json.loads(parts[pid]["nodes"])) for pid in m.Description.split("+")]   # one plate or two
        assert {va, vb} <= set().union(*carried) and all(c & {va, vb} for c in carried), (m.Name, m.Description)
        ends = [r.RelatedStructuralConnection.Name for r in m.ConnectedBy]
        assert sorted(ends) == sorted([ka, kb])
    assert seen == set(edge_faces)
    boundary = {v for e, c in edge_faces.items() if c == 1 for v in e}
    supported = {c.Name for c in connections if c.AppliedCondition is not None}
    assert supported == {by_vertex[v] for v in boundary}
    [rel] = [r for r in f.by_type("IfcRelAssociatesMaterial") if r.RelatingMaterial.is_a("IfcMaterialProfileSet")]
    prof = rel.RelatingMaterial.MaterialProfiles[0].Profile
    assert (prof.XDim, prof.YDim) == (12.0, 150.0) and set(rel.RelatedObjects) == set(members)
    [group] = model.IsGroupedBy
    assert set(group.RelatedObjects) == set(members) | set(connections)
    assert [b.Name for r in model.ServicesBuildings for b in r.RelatedBuildings] == [NAME]


def test_bolt_holes_are_cut_in_the_ifc_and_rhino_solids(built, parts):
    """Every beam plate and splice cover plate carries the bolt holes parts.csv lists, as circular voids of its
    IFC profile and inner profiles of its Rhino extrusion, each of the hole diameter and inside the outline; a
    plate bevelled under its strips (an IFC faceted solid, a Rhino mesh) as inner bounds of both its faces,
    polygons of the hole's area, and as the genus of its closed mesh (Euler: V − E + F = 2 − 2·holes)."""
    import ifcopenshell
    import rhino3dm
    from ifcopenshell.util.representation import resolve_representation
    from shapely.geometry import Point, Polygon

    f = ifcopenshell.open(str(built / "model.ifc"))
    drilled = {pid: r for pid, r in parts.items() if r["kind"] in ("beam", "splice") and int(r["holes"] or 0)}
    assert drilled and any(r["kind"] == "beam" for r in drilled.values())
    for e in f.by_type("IfcElement"):
        row = parts.get(e.Name)
        if row is None or row["kind"] not in ("beam", "splice"):
            continue
        body = [it for r in e.Representation.Representations for it in resolve_representation(r).Items]
        breps = [it for it in body if it.is_a("IfcFacetedBrep")]
        if breps:                                # a plate bevelled under its strips
            faces = sorted(breps[0].Outer.CfsFaces, key=lambda fc: -len(fc.Bounds))[:2]
            for fc in faces:
                outer = Polygon([p.Coordinates[:2] for p in fc.Bounds[0].Bound.Polygon])
                inner = [Polygon([p.Coordinates[:2] for p in b.Bound.Polygon]) for b in fc.Bounds[1:]]
                assert len(inner) == int(row["holes"] or 0), e.Name
                for h in inner:
                    assert h.area == pytest.approx(np.pi / 4.0 * float(row["hole_mm"]) ** 2, rel=1e-9)
                    assert outer.contains(h)
            continue
        [solid] = [it for it in body if it.is_a("IfcExtrudedAreaSolid")]
        inner = list(getattr(solid.SweptArea, "InnerCurves", None) or ())
        assert len(inner) == int(row["holes"] or 0), e.Name
        outline = Polygon([p.Coordinates for p in solid.SweptArea.OuterCurve.Points])
        for c in inner:
            assert c.is_a("IfcCircle") and 2.0 * c.Radius == pytest.approx(float(row["hole_mm"]))
            assert outline.contains(Point(c.Position.Location.Coordinates).buffer(c.Radius))
    objects, problems = placed_objects(rhino3dm.File3dm.Read(str(built / "model.3dm")))
    assert problems == []
    seen = 0
    for o in objects:
        row = drilled.get(o.attributes.Name)
        if row is None:
            continue
        g = o.geometry
        if isinstance(g, rhino3dm.Mesh):         # a plate bevelled under its strips: a closed mesh of genus holes
            faces = g.Faces.Count
            assert g.IsClosed and 2 - len(g.Vertices) + faces // 2 == 2 * int(row["holes"]), o.attributes.Name
            seen += 1
            continue
        assert g.ProfileCount - 1 == int(row["holes"]), o.attributes.Name
        assert all(2.0 * g.Profile3d(k, 0.0).Radius == pytest.approx(float(row["hole_mm"]))
                   for k in range(1, g.ProfileCount))
        seen += 1
    assert seen == len(drilled)


def test_a_prism_with_holes_is_a_closed_mesh_of_the_net_volume():
    """A plate with two bolt holes as the glTF writer meshes it: watertight, outward (positive volume), its volume
    (trimesh) the outline's area less the two circles' times the thickness, the outline's corners first."""
    import trimesh

    from fabrication.writers._elements import Element
    from ppfab.frame import Frame

    frame = Frame(np.array([10.0, 20.0, 30.0]), np.array([0.6, 0.8, 0.0]), np.array([0.0, 0.0, 1.0]))
    outline = np.array([[0.0, 0.0], [400.0, 0.0], [400.0, 150.0], [0.0, 150.0]])
    el = Element("B-U00", "beam", "rows", "B-U00", outline, frame, -6.0, 12.0,
                 holes=np.array([[60.0, 75.0, 22.0], [340.0, 75.0, 22.0]]))
    v, f = el.prism_mesh()
    mesh = trimesh.Trimesh(v, f, process=False)
    assert mesh.is_watertight and mesh.volume > 0
    assert mesh.volume == pytest.approx((400.0 * 150.0 - 2 * np.pi * 11.0 ** 2) * 12.0, rel=1e-9)
    assert np.allclose(v[:4], frame.to3d(outline) - 6.0 * frame.normal)


def test_cap_triangles_tile_the_outline_counter_clockwise_on_its_own_corners():
    """On 400 random star-shaped outlines (either orientation, a third with a hole): as many triangles as a
    triangulation of the corners has, every one counter-clockwise, on the outline's corners only, their areas
    adding up to shapely's area of the polygon."""
    import shapely

    from fabrication.writers._elements import cap_triangles

    rng = np.random.default_rng(5)
    checked = 0
    for k in range(400):
        n = int(rng.integers(3, 12))
        angle = np.sort(rng.uniform(0.0, 2.0 * np.pi, n))
        radius = rng.uniform(0.5, 1.0, n) * rng.uniform(10.0, 2000.0)
        outline = np.c_[radius * np.cos(angle), radius * np.sin(angle)][:: 1 if k % 2 else -1]
        holes = []
        if k % 3 == 0:
            t = -np.linspace(0.0, 2.0 * np.pi, int(rng.integers(6, 16)), endpoint=False)
            holes = [0.1 * radius.min() * np.c_[np.cos(t), np.sin(t)]]
        polygon = shapely.Polygon(outline, holes)
        if not polygon.is_valid:
            continue
        tri = cap_triangles(outline, holes)
        pts = np.concatenate([outline] + holes)
        a, b, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
        doubled = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
        assert len(tri) == len(pts) + 2 * len(holes) - 2
        assert (doubled >= 0).all() and tri.min() >= 0 and tri.max() < len(pts)
        assert 0.5 * doubled.sum() == pytest.approx(polygon.area, rel=1e-9)
        checked += 1
    assert checked > 300


def test_the_screws_of_a_plate_are_one_mesh_of_a_prism_per_screw():
    """An element of copies (a plate's screws) meshes as each copy's own prism, one after the other: the same
    vertices and faces as meshing each copy alone."""
    from dataclasses import replace

    import shapely
    import trimesh

    from fabrication.writers._elements import Element
    from ppfab.frame import Frame

    frame = Frame(np.array([10.0, 20.0, 30.0]), np.array([0.6, 0.8, 0.0]), np.array([0.0, 0.0, 1.0]))
    t = np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False)
    circle = 3.0 * np.c_[np.cos(t), np.sin(t)]
    copies = np.array([[0.0, 0.0], [250.0, 0.0], [500.0, 40.0]])
    el = Element("S-1", "screw", "retention", "", circle, frame, 0.0, 40.0, copies=copies)
    v, f = el.prism_mesh()
    alone = [replace(el, frame=fr, copies=None).prism_mesh() for fr in el.copy_frames()]
    assert np.array_equal(v, np.concatenate([a for a, _ in alone]))
    assert np.array_equal(f, np.concatenate([b + 24 * k for k, (_, b) in enumerate(alone)]))
    for part in trimesh.Trimesh(v, f, process=False).split(only_watertight=False):
        assert part.is_watertight and part.volume == pytest.approx(shapely.Polygon(circle).area * 40.0, rel=1e-9)


# -- Rhino ------------------------------------------------------------------------------------------------

def test_rhino_layers_names_user_text_and_objects(built, parts, mesh):
    import rhino3dm

    f = rhino3dm.File3dm.Read(str(built / "model.3dm"))
    assert f.Settings.ModelUnitSystem == rhino3dm.UnitSystem.Millimeters
    assert (f.Created.year, f.LastEdited.year) == (2000, 2000)            # fixed time stamps
    layers = [la.FullPath for la in f.Layers]
    assert layers == ["glass", "beams", "beams::rows", "beams::cols", "nodes", "mesh", "retention",
                      "retention::setting_block", "retention::stop", "retention::pressure_gasket",
                      "retention::pressure_plate", "retention::screw", "retention::cover_cap"]
    nodes = rows(built / "nodes.csv")
    objs, problems = placed_objects(f)                     # block instances placed: a part each
    assert problems == []
    assert len(objs) == len(parts) + len(nodes) + 1
    by_name = {o.attributes.Name: o for o in objs}
    assert set(parts) <= set(by_name) and {n["node_id"] for n in nodes} <= set(by_name)
    for pid, row in parts.items():
        o = by_name[pid]
        layer = layers[o.attributes.LayerIndex]
        if row["kind"] in RETENTION_KINDS:           # on a layer per kind (test_retention_parts.py)
            assert layer == f"retention::{row['kind']}"
            continue
        assert layer == ("glass" if row["kind"] == "panel" else f"beams::{row['family']}")
        text = dict(o.attributes.GetUserStrings())
        for key in ("part_id", "nest_tag", "type_id", "sheet", "material", "area_mm2"):
            assert text.get(key, "") == row[key], (pid, key)            # a strip has no type and no sheet
        assert text["weight_kg"] == (row["weight_kg"] or row["mass_kg"])
        g = o.geometry
        if isinstance(g, rhino3dm.Mesh):          # a plate bevelled under its strips: its two faces differ
            assert row["kind"] == "beam" and g.IsClosed, pid
            continue
        assert isinstance(g, rhino3dm.Extrusion) and g.IsSolid
        bottom = g.Profile3d(0, 0.0)
        pts = np.array([[bottom.Point(i).X, bottom.Point(i).Y, bottom.Point(i).Z] for i in range(bottom.PointCount)])
        assert np.allclose(pts[0], pts[-1])                                # a closed profile
        if row["kind"] == "panel":
            assert len(pts) == 5
    for n in nodes:
        line = by_name[n["node_id"]].geometry
        start = np.array([line.PointAtStart.X, line.PointAtStart.Y, line.PointAtStart.Z])
        end = np.array([line.PointAtEnd.X, line.PointAtEnd.Y, line.PointAtEnd.Z])
        axis = np.array([float(n[c]) for c in ("axis_x", "axis_y", "axis_z")])
        assert np.allclose(start, mesh.vertices[int(n["vertex"])], atol=1e-6)
        assert np.allclose(end - start, 150.0 * axis, atol=1e-6)           # the beam depth along the axis
        assert dict(by_name[n["node_id"]].attributes.GetUserStrings())["beams"] == n["beams"]
    m = by_name["mesh"].geometry
    assert len(m.Vertices) == len(mesh.vertices) and len(m.Faces) == len(mesh.faces) == m.Faces.QuadCount


# -- STEP -------------------------------------------------------------------------------------------------

def step_tree(path):
    """The product tree of a STEP file read from its text (independent of the kernel): name → child names."""
    data = path.read_text(encoding="ascii").partition("DATA;")[2]
    ents = {int(m.group(1)): re.sub(r"\s+", " ", m.group(2))
            for m in re.finditer(r"#(\d+)\s*=\s*(.*?);\s*(?=#\d+\s*=|ENDSEC)", data, re.S)}

    def refs(text):
        return [int(r) for r in re.findall(r"#(\d+)", text)]

    product = {k: re.match(r"PRODUCT\('((?:[^']|'')*)'", t).group(1) for k, t in ents.items()
               if t.startswith("PRODUCT(")}
    formation = {k: refs(t)[0] for k, t in ents.items() if t.startswith("PRODUCT_DEFINITION_FORMATION(")}
    definition = {k: product[formation[refs(t)[0]]] for k, t in ents.items() if t.startswith("PRODUCT_DEFINITION(")}
    tree: dict[str, list[str]] = {}
    children = set()
    for t in ents.values():
        if t.startswith("NEXT_ASSEMBLY_USAGE_OCCURRENCE("):
            parent, child = refs(t)[:2]
            tree.setdefault(definition[parent], []).append(definition[child])
            children.add(definition[child])
    roots = [n for n in tree if n not in children]
    return tree, roots


def test_beams_step_product_tree_as_a_reader_sees_it(built, parts):
    from build123d import Solid, import_step

    from fabrication.verify._shapes import frame_of
    from fabrication.verify.bevels import plate_faces
    from ppfab.metrics import polygon_area

    beams = {k: r for k, r in parts.items() if r["kind"] == "beam"}
    # the STEP text: design → families → beams → plates
    tree, roots = step_tree(built / "beams.step")
    assert roots == ["exchange test Uberdach"]                     # the product name, folded to ASCII
    assert sorted(tree[roots[0]]) == sorted({r["family"] for r in beams.values()})
    for family in tree[roots[0]]:
        for beam in tree[family]:
            kids = tree.get(beam, [])
            assert sorted(kids) == sorted(k for k, r in beams.items() if r["beam_id"] == beam)
            assert all(beams[k]["family"] == family for k in kids)
    assert sum(len(tree.get(b, [])) for f in tree[roots[0]] for b in tree[f]) == len(beams)
    # the CAD kernel's reader: the same tree, the names, the colours by family
    shape = import_step(str(built / "beams.step"))
    assert shape.label == "exchange_test_Uberdach"                # build123d's reader writes spaces as _
    colours = {}
    for fam in shape.children:
        for beam in fam.children:
            for solid in beam.children:
                assert isinstance(solid, Solid) and beams[solid.label]["beam_id"] == beam.label
                assert beams[solid.label]["family"] == fam.label
                colours.setdefault(fam.label, set()).add(tuple(round(c, 3) for c in tuple(solid.color)[:3]))
                row = beams[solid.label]                               # the faces less its splice holes
                holes = np.pi / 4 * float(row.get("holes") or 0) * float(row.get("hole_mm") or 0) ** 2
                faces = plate_faces(solid, frame_of(row))              # a bevelled top edge moves them apart
                assert polygon_area(faces.cut) == pytest.approx(float(row["area_mm2"]), rel=1e-6)
                mean = 0.5 * (polygon_area(faces.front) + polygon_area(faces.back))
                assert solid.volume == pytest.approx((mean - holes) * 12.0, rel=1e-6)
    assert all(len(c) == 1 for c in colours.values()) and len(set().union(*colours.values())) == len(colours)
    head = (built / "beams.step").read_text(encoding="ascii").partition("ENDSEC;")[0]
    assert r"'ppfab 0.1.0: beam plates of exchange test \X2\00DC\X0\berdach'" in head
    assert "'2000-01-01T00:00:00'" in head and "'ppfab 0.1.0',''" in head and "Author" not in head


def test_panels_step_product_tree(built, parts):
    tree, roots = step_tree(built / "panels.step")
    assert roots == ["exchange test Uberdach"] and tree[roots[0]] == ["glass"]
    panels = {k: r for k, r in parts.items() if r["kind"] == "panel"}
    rows = {f"P-U{int(r['face_i']):02d}" for r in panels.values()}
    assert sorted(tree["glass"]) == sorted(rows)                          # one assembly per row of faces
    assert sorted(k for row in tree["glass"] for k in tree[row]) == sorted(panels)
    assert all(k.startswith(row + "-") for row in tree["glass"] for k in tree[row])


# -- GLB --------------------------------------------------------------------------------------------------

def test_glb_node_names_and_bounds(built, parts):
    import trimesh
    from build123d import import_step

    from fabrication.writers.step import named_solids

    scene = trimesh.load(str(built / "model.glb"), force="scene")
    assert sorted(scene.graph.nodes_geometry) == sorted(parts)
    back = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]]) * 1e3            # glTF metres, y up → mm, z up
    solids = dict(named_solids(import_step(str(built / "beams.step"))))
    lo_all = []
    for name in scene.graph.nodes_geometry:
        transform, geom = scene.graph[name]
        mesh = scene.geometry[geom]
        pts = trimesh.transform_points(mesh.vertices, transform) @ back.T
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        lo_all.append((lo, hi))
        row = parts[name]
        assert mesh.is_watertight
        if row["kind"] == "screw":                # a prism per screw of the plate (test_retention_parts.py)
            continue
        holes = float(row.get("holes") or 0) * np.pi / 4.0 * float(row.get("hole_mm") or 0.0) ** 2   # drilled
        if row["kind"] == "beam":                 # the plate of beams.step, bevelled under its strips or not
            assert abs(mesh.volume) * 1e9 == pytest.approx(solids[name].volume, rel=1e-4)
        else:
            assert abs(mesh.volume) * 1e9 == pytest.approx(
                (float(row["area_mm2"]) - holes) * float(row["thickness_mm"]), rel=1e-4)
        if row["kind"] == "beam":                                         # the same box as the STEP solid
            bb = solids[name].bounding_box()
            assert np.allclose(lo, [bb.min.X, bb.min.Y, bb.min.Z], atol=0.05)
            assert np.allclose(hi, [bb.max.X, bb.max.Y, bb.max.Z], atol=0.05)
    lo = np.min([a for a, _ in lo_all], axis=0)
    hi = np.max([b for _, b in lo_all], axis=0)
    sb = scene.bounds @ back.T
    assert np.allclose(np.minimum(sb[0], sb[1]), lo, atol=0.05) and np.allclose(np.maximum(sb[0], sb[1]), hi,
                                                                               atol=0.05)


# -- glass order and DXF -----------------------------------------------------------------------------------

def test_glass_order_shapes_check_out_by_independent_formulas(built, parts, mesh):
    order = rows(built / "glass_order.csv")
    assert sum(int(r["quantity"]) for r in order) == sum(r["kind"] == "panel" for r in parts.values())
    for r in order:
        c = np.array([[float(r[f"c{k}_x_mm"]), float(r[f"c{k}_y_mm"])] for k in range(1, 5)])
        e = {k: float(r[f"edge_{k}{k % 4 + 1}_mm"]) for k in range(1, 5)}
        d13, d24 = float(r["diag_13_mm"]), float(r["diag_24_mm"])
        a = [float(r[f"angle_{k}_deg"]) for k in range(1, 5)]
        # law of cosines in the triangles of the diagonals (angles from lengths only)
        cos2 = (e[1] ** 2 + e[2] ** 2 - d13 ** 2) / (2 * e[1] * e[2])
        cos4 = (e[3] ** 2 + e[4] ** 2 - d13 ** 2) / (2 * e[3] * e[4])
        cos1 = (e[4] ** 2 + e[1] ** 2 - d24 ** 2) / (2 * e[4] * e[1])
        assert np.degrees(np.arccos(cos2)) == pytest.approx(a[1], abs=2e-3)
        assert np.degrees(np.arccos(cos4)) == pytest.approx(a[3], abs=2e-3)
        assert np.degrees(np.arccos(cos1)) == pytest.approx(a[0], abs=2e-3)
        assert sum(a) == pytest.approx(360.0, abs=2e-3)
        assert c[0].tolist() == [0.0, 0.0] and c[1, 1] == 0.0 and c[1, 0] == pytest.approx(e[1], abs=0.01)
        # the mesh face of the first pane, inset by half the gap: the same edges
        first = parts[r["parts"].split(";")[0]]
        face = mesh.vertices[mesh.faces[int(first["face"])]]
        mid = face - face.mean(axis=0)
        q = mid @ np.linalg.svd(mid)[2][:2].T
        lengths = np.linalg.norm(np.roll(q, -1, axis=0) - q, axis=1)
        assert sorted(lengths) == pytest.approx(sorted(e.values()), abs=30.0)        # inset by 8 mm per side
        # the default make-up 8 HS / 1.52 PVB / 8 HS: 16 mm of glass at 2500 kg/m³, 1.52 mm of PVB at 1070 kg/m³
        assert float(r["weight_kg"]) == pytest.approx(float(r["area_mm2"]) * 1e-6 * (16e-3 * 2500 + 1.52e-3 * 1070),
                                                      rel=1e-3)
        assert r["makeup"] == "8 HS / 1.52 PVB / 8 HS" and r["laminated"] == "yes" and r["heat_soak"] == "no"
        assert float(r["thickness_tolerance_mm"]) == pytest.approx(0.3 + 0.3 + 0.1)
        assert r["edge_finish"] == "ground" and r["coated_side"] == "none"


def test_per_type_dxf_is_dimensioned_with_the_edges_and_diagonals(built):
    import ezdxf

    for r in rows(built / "glass_order.csv"):
        doc = ezdxf.readfile(built / r["file"])
        dims = [e for e in doc.modelspace() if e.dxftype() == "DIMENSION"]
        assert {e.dxf.layer for e in dims} == {"DIM"} and len(dims) == 6
        got = sorted(e.get_measurement() for e in dims)
        want = sorted([float(r[f"edge_{k}{k % 4 + 1}_mm"]) for k in range(1, 5)] + [float(r["diag_13_mm"]),
                                                                                    float(r["diag_24_mm"])])
        assert np.allclose(got, want, atol=0.006)
        (cut,) = [e for e in doc.modelspace() if e.dxftype() == "LWPOLYLINE" and e.dxf.layer == "CUT"]
        pts = np.array(list(cut.get_points("xy")))
        # the DXF draws the pane in its nesting frame: move corner 1 to the origin and edge 12 onto +x
        t = np.arctan2(*(pts[1] - pts[0])[::-1])
        pts = (pts - pts[0]) @ np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
        assert np.allclose(pts, [[float(r[f"c{k}_x_mm"]), float(r[f"c{k}_y_mm"])] for k in range(1, 5)],
                           atol=0.006)


def test_per_type_dxf_texts_keep_clear_of_the_dimensions(built):
    """On every per-type DXF the pane's label keeps clear of the two dimensioned diagonals and their texts, and the
    title runs through no dimension's line (extension lines included): each text's box (0.8 heights a character,
    1.2 heights deep) is tested against the lines the dimensions render (ezdxf's virtual entities)."""
    import ezdxf
    from shapely.geometry import LineString, Polygon

    def box(e, centred: bool) -> Polygon:
        h, a = float(e.dxf.height), np.radians(float(e.dxf.get("rotation", 0.0)))
        w = 0.8 * len(e.dxf.text) * h
        u, v = np.array([np.cos(a), np.sin(a)]), np.array([-np.sin(a), np.cos(a)])
        if centred:
            c = np.array(tuple(e.dxf.align_point)[:2])
            pts = [c + s * 0.5 * w * u + r * 0.6 * h * v for s, r in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        else:
            o = np.array(tuple(e.dxf.insert)[:2])
            pts = [o - 0.1 * h * v, o + w * u - 0.1 * h * v, o + w * u + 1.1 * h * v, o + 1.1 * h * v]
        return Polygon(pts)

    files = [built / r["file"] for r in rows(built / "glass_order.csv")]
    assert files
    for path in files:
        msp = ezdxf.readfile(path).modelspace()
        lines, dim_texts = [], []
        for dim in msp.query("DIMENSION"):
            for ve in dim.virtual_entities():
                if ve.dxftype() == "LINE":
                    lines.append(LineString([tuple(ve.dxf.start)[:2], tuple(ve.dxf.end)[:2]]))
                elif ve.dxftype() == "MTEXT":
                    c, h = np.array(tuple(ve.dxf.insert)[:2]), float(ve.dxf.char_height)
                    dim_texts.append(Polygon([c + [-3 * h, -0.6 * h], c + [3 * h, -0.6 * h], c + [3 * h, 0.6 * h],
                                              c + [-3 * h, 0.6 * h]]))
        (cut,) = msp.query("LWPOLYLINE[layer=='CUT']")
        q = np.array(list(cut.get_points("xy")))
        diagonals = [LineString([q[0], q[2]]), LineString([q[1], q[3]])]
        texts = list(msp.query("TEXT"))
        titles = [e for e in texts if e.dxf.get("align_point") is None]
        labels = [e for e in texts if e.dxf.get("align_point") is not None]
        assert len(titles) == 1 and labels
        title = box(titles[0], centred=False)
        assert not any(title.intersects(ln) for ln in lines), (path.name, titles[0].dxf.text)
        for e in labels:
            b = box(e, centred=True)
            assert not any(b.intersects(d) for d in diagonals), (path.name, e.dxf.text)
            assert not any(b.intersects(d) for d in dim_texts), (path.name, e.dxf.text)


@pytest.mark.parametrize("version, code", [("r12", "AC1009"), ("r2000", "AC1015")])
def test_legacy_dxf_reopens_and_keeps_the_outlines(built, version, code):
    import ezdxf

    from fabrication.writers.dxf import read_sheet_dxf

    m = json.loads((built / "manifest.json").read_text())
    for rel in m["files"][f"dxf_{version}"]:
        old = ezdxf.readfile(built / rel)
        assert old.dxfversion == code and not old.audit().has_errors
        main_rel = rel.split("/", 1)[1]
        a, b = read_sheet_dxf(built / rel), read_sheet_dxf(built / main_rel)
        assert [p.part_id for p in a.parts] == [p.part_id for p in b.parts]
        assert [p.nest_tag for p in a.parts] == [p.nest_tag for p in b.parts]
        for p, q in zip(a.parts, b.parts):
            assert p.closed and np.array_equal(p.points, q.points)
        assert a.labels == b.labels and a.marks == b.marks and np.allclose(a.dimensions, b.dimensions)
        kinds = {e.dxftype() for e in old.modelspace()}
        assert ("LWPOLYLINE" in kinds) == (version == "r2000") and ("POLYLINE" in kinds) == (version == "r12")


# -- verify finds damage ---------------------------------------------------------------------------------------

def test_verify_names_an_ifc_property_changed_and_a_3dm_object_moved(built, tmp_path, capsys):
    import ifcopenshell
    import ifcopenshell.util.element as ue
    import rhino3dm

    out = tmp_path / "copy"
    shutil.copytree(built, out)
    f = ifcopenshell.open(str(out / "model.ifc"))
    plate = f.by_type("IfcPlate")[3]
    pset = f.by_id(ue.get_psets(plate)["PPFAB_Part"]["id"])
    for prop in pset.HasProperties:
        if prop.Name == "nest_tag":
            prop.NominalValue = f.create_entity("IfcIdentifier", "G99-999")
    f.write(str(out / "model.ifc"))
    model = rhino3dm.File3dm.Read(str(out / "model.3dm"))
    moved = next(o for o in model.Objects if o.Attributes.Name.startswith("B-"))
    moved.Geometry.Translate(rhino3dm.Vector3d(0.0, 0.0, 25.0))          # up, in the plate's own (upright) plane
    model.Write(str(out / "model.3dm"), 7)
    assert main(["verify", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"model.ifc: {plate.Name}: PPFAB_Part.nest_tag is 'G99-999'" in err
    assert f"model.3dm: {moved.Attributes.Name}: outline is 25 mm from where its DXF outline puts it" in err


def test_repeated_parts_are_block_instances_of_one_body_each(built, parts):
    """Parts of one repeated shape are instances of one block (its single body an instance-definition object);
    each block is placed by two or more parts of one kind, by rigid motions; every part is placed once."""
    import rhino3dm

    f = rhino3dm.File3dm.Read(str(built / "model.3dm"))
    objects, problems = placed_objects(f)
    assert problems == []
    by_block: dict[str, list[str]] = {}
    for o in objects:
        if o.block:
            by_block.setdefault(o.block, []).append(o.attributes.Name)
    assert len(by_block) == len(f.InstanceDefinitions) >= 3
    bodies = [o for o in f.Objects if o.Attributes.Mode == rhino3dm.ObjectMode.InstanceDefinitionObject]
    assert len(bodies) == len(by_block)
    kinds = {parts[name]["kind"] for names in by_block.values() for name in names}
    assert len(kinds) >= 3, kinds
    for block, names in by_block.items():
        assert len(names) >= 2 and len({parts[n]["kind"] for n in names}) == 1, block
        assert block.startswith(parts[names[0]]["kind"]), block
    placed = [o.attributes.Name for o in objects if o.attributes.Name in parts]
    assert sorted(placed) == sorted(parts)
    instanced = sum(len(n) for n in by_block.values())
    assert len(list(f.Objects)) == len(objects) + len(bodies)
    assert instanced > len(by_block)                       # fewer bodies than parts drawn by them


def test_verify_names_a_moved_and_a_stretched_block_instance_and_a_moved_strip(built, parts, tmp_path, capsys):
    """A retention box's block instance moved 25 mm (placed by its block's transform, not by a body of its own), an
    instance whose transform stretches its block by 0.1 % (not a rigid motion) and a glazing strip moved 25 mm off
    its span are each named by verify."""
    import rhino3dm

    out = tmp_path / "copy"
    shutil.copytree(built, out)
    model = rhino3dm.File3dm.Read(str(out / "model.3dm"))
    refs = [o for o in model.Objects if isinstance(o.Geometry, rhino3dm.InstanceReference)]
    moved, stretched = [o for o in refs if parts[o.Attributes.Name]["kind"] in RETENTION_KINDS][:2]
    strip = next(o for o in model.Objects if parts.get(o.Attributes.Name, {}).get("kind") == "strip")
    for obj in (moved, strip):
        obj.Geometry.Translate(rhino3dm.Vector3d(0.0, 0.0, 25.0))
    stretched.Geometry.Transform(rhino3dm.Transform.Scale(rhino3dm.Point3d(0.0, 0.0, 0.0), 1.001))
    model.Write(str(out / "model.3dm"), 7)
    assert main(["verify", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"model.3dm: {moved.Attributes.Name}: solid is 25 mm from the box its parts.csv row places" in err
    found = re.search(rf"model.3dm: {strip.Attributes.Name}: strip is ([\d.]+) mm from the box its span", err)
    assert found and float(found.group(1)) > 10.0, err
    assert f"model.3dm: {stretched.Attributes.Name}: the transform of its block" in err
    assert "is not a rigid motion" in err


# -- reproducibility and a real mesh ------------------------------------------------------------------------

def test_two_builds_in_separate_processes_are_byte_identical(tmp_path):
    """Different hash seeds and memory layouts: the STEP colours (written in address order by the kernel),
    the IFC GlobalIds, the Rhino ids and time stamps, the R12 header dates must not change a byte."""
    import hashlib
    import os
    import subprocess
    import sys

    from conftest import REPO

    design = tmp_path / "tiny.toml"
    design.write_text(small_design(3, 2, u_range=(-2.0, 2.0), v_range=(-1.5, 1.5), name="tiny",
                                   extra="[output]\ndxf_r12 = true\n"), encoding="utf-8")
    trees = []
    for k, seed in enumerate(("1", "2")):
        out = tmp_path / f"out{k}"
        env = dict(os.environ, PYTHONHASHSEED=seed,
                   PYTHONPATH=os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]))
        code = "from fabrication.cli import main; raise SystemExit(main(['build', %r, '-o', %r, '--quiet']))"
        subprocess.run([sys.executable, "-c", code % (str(design), str(out))], env=env, check=True)
        trees.append({str(p.relative_to(out)): hashlib.sha256(p.read_bytes()).hexdigest()
                      for p in sorted(out.rglob("*")) if p.is_file()})
    assert trees[0].keys() == trees[1].keys()
    assert {"model.ifc", "model.3dm", "model.glb", "beams.step", "panels.step"} <= set(trees[0])
    assert sorted(k for k in trees[0] if trees[0][k] != trees[1][k]) == []


def test_exchange_files_of_a_real_mesh(tmp_path):
    """A patch of a real conical PP mesh (DOI rot4_def1_sparse_rot, 8 × 7 faces): every file verifies, beams
    of one plate keep distinct GlobalIds from their assembly."""
    import ifcopenshell

    import fabrication
    from fabrication.design import parse_design
    from ppfab.io import write_obj
    from ppfab.mesh import QuadGrid

    from conftest import shared_file

    grid = load_mesh(shared_file("DOI__rot4_def1_sparse_rot.obj")).to_grid()
    write_obj(QuadGrid(np.ascontiguousarray(grid.vertices[20:29, 0:8])), tmp_path / "patch.obj")
    doc = {"design": {"name": "rot4 patch"}, "geometry": {"mesh": str(tmp_path / "patch.obj"), "scale": 3000.0},
           "beams": {"fallback": "segmented"},          # its boundary polylines become beams of one plate each
           "nesting": {"time_budget": 0.5}, "beam_nesting": {"time_budget": 0.5}}
    b = fabrication.build(parse_design(doc))
    out = b.write(tmp_path / "out")
    v = b.verify()
    assert v.ok, [str(f) for f in v.findings[:5]]
    assert {"ifc", "rhino", "glb", "glass_order", "step"} <= set(v.checked)
    f = ifcopenshell.open(str(out / "model.ifc"))
    single = [a for a in f.by_type("IfcElementAssembly") if len(a.IsDecomposedBy[0].RelatedObjects) == 1]
    assert single, "the patch has beams of a single plate"
    for a in single:
        (member,) = a.IsDecomposedBy[0].RelatedObjects
        assert member.Name == a.Name and member.GlobalId != a.GlobalId
    panes = [p for p in f.by_type("IfcPlate") if p.PredefinedType == "CURTAIN_PANEL"]    # pressure plates: SHEET
    assert len(panes) == len(b.panels.panels) == 56


def test_a_coated_pane_cannot_be_mirrored(tmp_path, capsys):
    p = tmp_path / "d.toml"
    p.write_text(small_design(2, 2, extra="[panels]\ncoated_side = \"outside\"\nmirror_allowed = true\n"))
    assert main(["build", str(p), "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ppfab: error:") and "coated on the outside cannot be turned over" in err
    assert "Traceback" not in err and not (tmp_path / "o").exists()
    p.write_text(small_design(2, 2, extra="[panels]\ncoated_side = \"top\"\n"))
    assert main(["build", str(p), "-o", str(tmp_path / "o")]) == 2
    assert "'none', 'outside', 'inside'" in capsys.readouterr().err


def test_ifc_shares_its_materials_types_panes_and_passes_the_express_rules(built, parts):
    """One IfcMaterial per material name and none orphaned; every panel type an IfcPlateType, every repeated plate
    type an IfcMemberType; the common property sets; ifcopenshell's validator with the EXPRESS rules finds nothing."""
    import ifcopenshell
    import ifcopenshell.util.element as ue
    import ifcopenshell.validate

    f = ifcopenshell.open(str(built / "model.ifc"))
    names = [m.Name for m in f.by_type("IfcMaterial")]
    others = {r["material"] for r in parts.values() if r["kind"] != "panel"}
    assert sorted(names) == sorted(others | {"heat-strengthened glass (EN 1863-1)", "PVB interlayer"})
    assert all(f.get_inverse(m) for m in f.by_type("IfcMaterial"))               # every one used
    panel_types = {r["type_id"] for r in parts.values() if r["kind"] == "panel"}
    assert sorted(t.Name for t in f.by_type("IfcPlateType")) == sorted(panel_types)
    for t in f.by_type("IfcMemberType"):
        (rel,) = t.Types
        assert len(rel.RelatedObjects) >= 2
        if t.ElementType in (None, "splice"):           # beam plates, cover plates: their parts.csv type id
            assert {parts[o.Name]["type_id"] for o in rel.RelatedObjects} == {t.Name}
        else:                                            # glazing strips: typed by their size
            assert t.ElementType == "strip" and {parts[o.Name]["kind"] for o in rel.RelatedObjects} == {"strip"}
    for plate in (p for p in f.by_type("IfcPlate") if p.PredefinedType == "CURTAIN_PANEL"):
        common = ue.get_psets(plate)["Pset_PlateCommon"]
        assert common["Reference"] == parts[plate.Name]["type_id"] and common["LoadBearing"] is False
    for member in f.by_type("IfcMember"):
        assert ue.get_psets(member)["Pset_MemberCommon"]["LoadBearing"] is True
    # the common set of a typed part is its type's, written once on the type (Reference = the type's name); an
    # untyped part carries its own (Reference = its type id or part id)
    for product in f.by_type("IfcElement"):
        if product.Name not in parts:                   # the roof, the beams' assemblies
            continue
        own = [r.RelatingPropertyDefinition.Name for r in product.IsDefinedBy if r.is_a("IfcRelDefinesByProperties")]
        common = [n for n in own if n.startswith("Pset_") and n.endswith("Common")]
        t = ue.get_type(product)
        if t is None:
            assert len(common) == 1
            ref = ue.get_psets(product)[common[0]]["Reference"]
            assert ref in (parts[product.Name].get("type_id") or product.Name, product.Name)
        else:
            assert common == []
            (pset,) = [q for q in t.HasPropertySets if q.Name.startswith("Pset_")]
            assert ue.get_psets(product)[pset.Name]["Reference"] == t.Name
    log = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(f, log, express_rules=True)
    assert log.statements == []


def test_ifc_properties_are_shared_by_the_sets_that_hold_the_same_value(built, parts):
    """One IfcPropertySingleValue per distinct name, value and unit, held by every property set that has it (IFC4
    lets a property belong to any number of sets); each part still reads its own values (ifcopenshell's
    ``get_psets``, compared with parts.csv above)."""
    import ifcopenshell
    import ifcopenshell.util.element as ue

    f = ifcopenshell.open(str(built / "model.ifc"))
    props = f.by_type("IfcPropertySingleValue")
    keys = [(p.Name, p.NominalValue.is_a(), p.NominalValue.wrappedValue, p.Unit.id() if p.Unit else 0) for p in props]
    assert len(set(keys)) == len(keys)                               # no two alike
    held = sum(len(s.HasProperties) for s in f.by_type("IfcPropertySet"))
    assert held > 2 * len(props)                                     # most are shared
    kinds = {p.Name: ue.get_psets(p)["PPFAB_Part"]["kind"] for p in f.by_type("IfcElement") if p.Name in parts}
    assert kinds == {k: r["kind"] for k, r in parts.items() if k in kinds}
    (kind_panel,) = [p for p in props if p.Name == "kind" and p.NominalValue.wrappedValue == "panel"]
    assert len(kind_panel.PartOfPset) == sum(r["kind"] == "panel" for r in parts.values())


def test_the_ifc_checks_placements_agree_with_ifcopenshells_and_project_the_reference_direction(built):
    """:func:`fabrication.verify.ifc.axis2placement` and :func:`transformation_operator` against
    ``ifcopenshell.util.placement`` on every placement and mapped item of the file (to 1e-12), and on a reference
    direction that is not normal to the axis, against Gram–Schmidt by hand (IFC4's IfcBuildAxes projects it;
    ifcopenshell's ``a2p`` does not)."""
    import ifcopenshell
    import ifcopenshell.util.placement as up

    from fabrication.verify.ifc import IfcReading, axis2placement, transformation_operator

    f = ifcopenshell.open(str(built / "model.ifc"))
    reading = IfcReading()
    for lp in f.by_type("IfcLocalPlacement"):
        assert np.abs(reading.placement(lp) - up.get_local_placement(lp)).max() < 1e-9
    items = f.by_type("IfcMappedItem")
    assert items
    for it in items:
        assert np.abs(reading.mapped(it) - up.get_mappeditem_transformation(it)).max() < 1e-9
        assert np.abs(transformation_operator(it.MappingTarget)
                      - up.get_cartesiantransformationoperator3d(it.MappingTarget)).max() < 1e-12
    g = ifcopenshell.file(schema="IFC4")
    z, ref = np.array([0.0, 0.6, 0.8]), np.array([1.0, 1.0, 0.0])
    p = g.createIfcAxis2Placement3D(g.createIfcCartesianPoint((5.0, -2.0, 7.0)), g.createIfcDirection(tuple(z)),
                                    g.createIfcDirection(tuple(ref)))
    x = ref - ref.dot(z) * z
    x /= np.linalg.norm(x)
    want = np.eye(4)
    want[:3, 0], want[:3, 1], want[:3, 2], want[:3, 3] = x, np.cross(z, x), z, (5.0, -2.0, 7.0)
    got = axis2placement(p)
    assert np.abs(got - want).max() < 1e-12
    assert np.abs(got[:3, :3].T @ got[:3, :3] - np.eye(3)).max() < 1e-12


def test_a_ring_is_opened_where_numpy_finds_its_ends_close():
    """``open_ring`` drops a ring's closing point exactly where ``np.allclose`` finds its first and last points
    close: rings closed, closed to within its tolerances, and open by just more than them, at sizes from 1 mm to
    100 km."""
    from fabrication.verify._shapes import open_ring

    rng = np.random.default_rng(7)
    dropped = 0
    for _ in range(3000):
        scale = 10.0 ** rng.uniform(0, 8)
        ring = rng.normal(size=(5, 3)) * scale
        ring[-1] = ring[0] + rng.choice([0.0, 1.0]) * (1e-8 + 1e-5 * np.abs(ring[0])) * rng.uniform(0.5, 1.5, 3)
        got = open_ring(ring)
        closed = np.allclose(ring[0], ring[-1])
        dropped += closed
        assert len(got) == (4 if closed else 5) and np.array_equal(got, ring[:len(got)])
    assert 1000 < dropped < 2800
