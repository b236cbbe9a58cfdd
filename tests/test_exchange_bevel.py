"""The plates bevelled under their glazing strips are in the exchange models the solids beams.step holds, not
the cut outline extruded (whose raised corner stood up to Δ + (t/2)·sin λ into the strip): model.ifc
(``IfcFacetedBrep``, tessellated by ifcopenshell's kernel), model.3dm (a closed mesh, rhino3dm) and model.glb
(trimesh) each have the volume of the beams.step solid and run into no strip they carry, measured with
manifold3d on the strips of model.glb; ``ppfab verify`` names a face of such a plate moved in model.ifc.
"""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import numpy as np
import pytest

from fabrication.verify.rhino import placed_objects

from conftest import REPO


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> Path:
    """examples/smallest_roof.toml (24 of its 40 strips lean more than 2° off their plates) built and written."""
    from fabrication import build, load_design
    from fabrication.progress import Progress
    from fabrication.writers import write_all

    out = tmp_path_factory.mktemp("exchange_bevel") / "out"
    out.mkdir()
    write_all(build(load_design(REPO / "examples" / "smallest_roof.toml")), out, Progress(quiet=True), parallel=False)
    return out


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def _bevelled(built: Path) -> list[dict[str, str]]:
    return [r for r in _rows(built / "bevels.csv") if r["bevel"] not in ("", "square")]


def _glb_meshes(built: Path) -> dict:
    """Each node of model.glb as a trimesh in ppfab's millimetres, z up."""
    import trimesh

    from fabrication.writers.glb import MM_TO_GLTF

    scene = trimesh.load(str(built / "model.glb"), force="scene", process=False)
    back = np.linalg.inv(MM_TO_GLTF)
    out = {}
    for name in scene.graph.nodes_geometry:
        transform, geometry = scene.graph[name]
        m = scene.geometry[geometry]
        out[name] = trimesh.Trimesh(trimesh.transform_points(m.vertices, transform) @ back.T, m.faces, process=False)
    return out


def _rhino_volumes(built: Path) -> dict[str, float]:
    """The volume of every closed mesh of model.3dm by the divergence theorem (numpy, about its centre)."""
    import rhino3dm

    out = {}
    for obj in placed_objects(rhino3dm.File3dm.Read(str(built / "model.3dm")))[0]:
        g = obj.geometry
        if isinstance(g, rhino3dm.Mesh) and g.IsClosed:
            p = np.array([[g.Vertices[i].X, g.Vertices[i].Y, g.Vertices[i].Z] for i in range(len(g.Vertices))])
            t = np.array([[g.Faces[i][0], g.Faces[i][1], g.Faces[i][2]] for i in range(g.Faces.Count)])
            p = p - p.mean(axis=0)
            out[obj.attributes.Name] = abs(float(np.einsum("ij,ij->i", p[t[:, 0]],
                                                           np.cross(p[t[:, 1]], p[t[:, 2]])).sum()) / 6.0)
    return out


def _ifc_volumes(built: Path) -> dict[str, float]:
    import ifcopenshell
    import ifcopenshell.geom
    import ifcopenshell.util.shape as us

    f = ifcopenshell.open(str(built / "model.ifc"))
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    out = {}
    for member in f.by_type("IfcMember"):
        shape = ifcopenshell.geom.create_shape(settings, member)
        out[member.Name] = us.get_volume(shape.geometry) * 1e9          # the kernel works in metres
    return out


def test_bevelled_plates_have_the_step_solids_volume_in_every_model(built):
    from fabrication.verify._step_read import read_step_solids

    plates = sorted({r["plate"] for r in _bevelled(built)})
    assert len(plates) >= 10
    step = {s.name: float(s.solid.volume) for s in read_step_solids(built / "beams.step")}
    ifc, rhino, glb = _ifc_volumes(built), _rhino_volumes(built), _glb_meshes(built)
    for pid in plates:
        want = step[pid]
        assert abs(ifc[pid] - want) <= 1e-6 * want, (pid, ifc[pid], want)
        # model.3dm and model.glb keep single-precision vertices: about 1e-7 of the coordinates
        assert abs(rhino[pid] - want) <= 1e-4 * want, (pid, rhino[pid], want)
        assert glb[pid].is_watertight and abs(abs(glb[pid].volume) - want) <= 1e-4 * want, pid


def test_bevelled_plates_do_not_run_into_their_strips_in_the_models(built):
    """manifold3d's common part of each bevelled plate and its strip (both from model.glb, and the plate also
    from model.ifc as ifcopenshell tessellates it): under 0.05 mm thick along the strip's normal (the strip's
    thinnest direction), where the cut outline extruded stood up to Δ + (t/2)·sin λ into it."""
    import ifcopenshell
    import ifcopenshell.geom
    import ifcopenshell.util.shape as us
    import manifold3d as m3

    def manifold(vertices: np.ndarray, faces: np.ndarray):
        return m3.Manifold(m3.Mesh(vert_properties=np.asarray(vertices, dtype=np.float32),
                                   tri_verts=np.asarray(faces, dtype=np.uint32)))

    def depth(a, b, u: np.ndarray) -> float:
        common = a ^ b
        if common.is_empty() or common.volume() < 1e-6:
            return 0.0
        z = np.asarray(common.to_mesh().vert_properties)[:, :3] @ u
        return float(z.max() - z.min())

    glb = _glb_meshes(built)
    f = ifcopenshell.open(str(built / "model.ifc"))
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    ifc = {}
    for member in f.by_type("IfcMember"):
        g = ifcopenshell.geom.create_shape(settings, member).geometry
        ifc[member.Name] = manifold(np.asarray(us.get_vertices(g)) * 1e3, us.get_faces(g))
    rows = _bevelled(built)
    assert max(float(r["delta_mm"]) for r in rows) > 1.0          # the extruded cut outline overlapped by more
    worst = 0.0
    for r in rows:
        strip = glb[r["strip"]]
        centred = strip.vertices - strip.vertices.mean(axis=0)
        u = np.linalg.svd(centred, full_matrices=False)[2][2]       # across the strip: its thinnest direction
        s = manifold(strip.vertices, strip.faces)
        plate = glb[r["plate"]]
        worst = max(worst, depth(s, manifold(plate.vertices, plate.faces), u), depth(s, ifc[r["plate"]], u))
    assert worst < 0.05


def test_verify_names_a_face_of_a_bevelled_plate_moved_in_the_ifc(built, tmp_path):
    """One top-face corner of a bevelled plate's faceted solid moved 2 mm off the face: the ifc check names the
    plate (its solid no longer ±t/2 about its support plane)."""
    import ifcopenshell

    from fabrication.verify import Verification
    from fabrication.verify.ifc import check_ifc

    out = tmp_path / "copy"
    shutil.copytree(built, out)
    f = ifcopenshell.open(str(out / "model.ifc"))
    pid = _bevelled(built)[0]["plate"]
    member = next(m for m in f.by_type("IfcMember") if m.Name == pid)
    from ifcopenshell.util.representation import resolve_representation

    brep = next(it for r in member.Representation.Representations for it in resolve_representation(r).Items
                if it.is_a("IfcFacetedBrep"))
    top = max(brep.Outer.CfsFaces, key=lambda face: face.Bounds[0].Bound.Polygon[0].Coordinates[2])
    point = top.Bounds[0].Bound.Polygon[0]
    x, y, z = point.Coordinates
    point.Coordinates = (x, y, z + 2.0)
    f.write(str(out / "model.ifc"))
    v = Verification(out)
    check_ifc(v)
    assert {fi.element for fi in v.findings} == {pid}, [str(fi) for fi in v.findings[:5]]
    assert any("about its support plane" in fi.message for fi in v.findings)


def test_the_ifc_checks_reading_of_a_bevelled_plate_is_the_kernels(built):
    """The ifc check reads a bevelled plate's ``IfcFacetedBrep`` itself (``faceted_plate``: every bound's points
    at once, each face's vector area from them): its volume is ifcopenshell's kernel's and beams.step's, its
    vertices are the kernel's tessellation's, and its two largest faces' rings are the plate's two faces (each
    flat, parallel to the other, a plate's thickness apart)."""
    import ifcopenshell
    import ifcopenshell.geom

    from fabrication.verify._step_read import read_step_solids
    from fabrication.verify._shapes import set_distance
    from fabrication.verify.ifc import faceted_plate

    plates = sorted({r["plate"] for r in _bevelled(built)})
    step = {s.name: s.solid for s in read_step_solids(built / "beams.step")}
    f = ifcopenshell.open(str(built / "model.ifc"))
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    thick = {r["part_id"]: float(r["thickness_mm"]) for r in _rows(built / "parts.csv") if r["part_id"] in plates}
    seen = 0
    for member in f.by_type("IfcMember"):
        if member.Name not in plates:
            continue
        got = faceted_plate(member)
        assert got is not None, member.Name
        pts, volume, ring_a, ring_b = got
        want = float(step[member.Name].volume)
        assert abs(volume - want) <= 1e-6 * want, (member.Name, volume, want)
        kernel = np.asarray(ifcopenshell.geom.create_shape(settings, member).geometry.verts).reshape(-1, 3) * 1e3
        assert set_distance(np.unique(np.round(pts, 6), axis=0), kernel) <= 1e-3, member.Name
        for ring in (ring_a, ring_b):
            centred = ring - ring.mean(axis=0)
            assert np.linalg.svd(centred, compute_uv=False)[2] <= 1e-6 * np.abs(centred).max(), member.Name
        n = np.linalg.svd(ring_a - ring_a.mean(axis=0))[2][2]
        assert abs(abs(float(((ring_b - ring_a[0]) @ n).mean())) - thick[member.Name]) <= 1e-6, member.Name
        seen += 1
    assert seen == len(plates)


def test_the_ifc_checks_property_set_is_ifcopenshells(built, tmp_path):
    """``named_pset`` reads one property set as ``ifcopenshell.util.element.get_psets`` merges it — the type's
    first, the occurrence's over it — on every element of model.ifc (PPFAB_Part on the occurrences, the common
    sets on types and occurrences) and on a plate whose type carries a PPFAB_Part set the occurrence's overrides
    in part."""
    import ifcopenshell
    import ifcopenshell.api
    import ifcopenshell.util.element as ue

    from fabrication.contract import IFC_PSET
    from fabrication.verify.ifc import named_pset

    f = ifcopenshell.open(str(built / "model.ifc"))
    elements = f.by_type("IfcElement")
    for name in (IFC_PSET, "Pset_PlateCommon", "Pset_MemberCommon", "Qto_PlateBaseQuantities", "no such set"):
        assert [named_pset(e, name) for e in elements] == [ue.get_psets(e).get(name) for e in elements], name
    assert sum(named_pset(e, IFC_PSET) is not None for e in elements) >= 40
    plate = next(e for e in f.by_type("IfcPlate") if ue.get_type(e) is not None)
    t = ue.get_type(plate)
    pset = ifcopenshell.api.run("pset.add_pset", f, product=t, name=IFC_PSET)
    ifcopenshell.api.run("pset.edit_pset", f, pset=pset, properties={"part_id": "from the type", "extra": "kept"})
    got = named_pset(plate, IFC_PSET)
    assert got == ue.get_psets(plate)[IFC_PSET]
    assert got["extra"] == "kept" and got["part_id"] == plate.Name


def test_the_glb_checks_closedness_and_volumes_are_trimeshs(built, tmp_path):
    """``mesh_facts`` measures the meshes of model.glb in batches: closed where trimesh's ``is_watertight`` says so and
    the volume of trimesh's ``volume`` (1e-9 relative) — on the written meshes and on copies with a triangle taken
    away, one doubled, and every triangle turned (closed, the volume negated); and the glb check names a part
    whose mesh lost a triangle."""
    import shutil

    import trimesh

    from fabrication.verify import Verification
    from fabrication.verify.glb import check_glb, mesh_facts

    scene = trimesh.load(str(built / "model.glb"), force="scene", process=False)
    meshes = dict(scene.geometry)
    for k, (name, mesh) in enumerate(list(meshes.items())[:30]):
        f = np.asarray(mesh.faces)
        f = (f[1:], np.vstack([f, f[:1]]), f[:, ::-1])[k % 3]
        meshes[f"{name} changed"] = trimesh.Trimesh(np.asarray(mesh.vertices), f, process=False)
    first = next(iter(scene.geometry.values()))
    meshes["a vertex it does not have"] = trimesh.Trimesh(np.asarray(first.vertices), np.asarray(first.faces) + 1,
                                                          process=False, validate=False)
    closed, volumes = mesh_facts(meshes)
    # in batches of about 50 triangles (each batch's arrays apart): the same facts
    assert mesh_facts(meshes, batch=50) == (closed, volumes)
    assert not closed.pop("a vertex it does not have")
    meshes.pop("a vertex it does not have")
    assert sum(not c for c in closed.values()) == 20
    for name, mesh in meshes.items():
        assert closed[name] == mesh.is_watertight, name
        if closed[name]:
            assert volumes[name] == pytest.approx(float(mesh.volume), rel=1e-9), name
    # a part's mesh with a triangle taken away, written back: the check names it
    node = next(n for n in scene.graph.nodes_geometry if n.startswith("P-"))
    geometry = scene.graph[node][1]
    broken = scene.geometry[geometry]
    scene.geometry[geometry] = trimesh.Trimesh(broken.vertices, broken.faces[1:], process=False)
    folder = tmp_path / "out"
    shutil.copytree(built, folder)
    (folder / "model.glb").write_bytes(trimesh.exchange.gltf.export_glb(scene))
    v = Verification(folder)
    check_glb(v)
    named = {f.element for f in v.findings if "mesh is not closed" in f.message}
    assert node in named and all(n.startswith("P-") for n in named), named
