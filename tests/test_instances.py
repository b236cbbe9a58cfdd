"""Repeated parts drawn once: element types in model.ifc (occurrences of one type whose shape, an
IfcRepresentationMap, each maps by a rigid motion), instanced meshes in model.glb; the classification the design
names.

Built on the bundled default's roof at a third of its size (8 × 6 faces, the same half-turn symmetry: 48 panes
in 24 congruent pairs), read with ifcopenshell and its geometry kernel and with trimesh, and compared with the
glass as cut (the per-type DXF, ezdxf) and with the same parts in the STEP files (the CAD kernel's reader).
"""

import csv
import shutil
import subprocess
import sys
import tomllib
from collections import defaultdict
from itertools import combinations

import numpy as np
import pytest

from fabrication.cli import main
from fabrication.design import DEFAULT_DESIGN
from fabrication.writers._elements import Element
from fabrication.writers._instances import fit_motion
from ppfab.frame import Frame

from conftest import small_design

CLASSIFICATION = """
[output]
report = false
rhino = false
[output.classification]
system = "Uniclass 2015"
edition = "v1.30"
panel = "Pr_00_00_00 the glass code of a test"
strip = "Pr_00_00_01"
"""


def half_turn_vault() -> str:
    """The default design on a smaller parameter box with fewer faces: symmetric under a half turn, so its parts
    pair up."""
    text = DEFAULT_DESIGN.read_text(encoding="utf-8")
    for old, new in (("u_range = [-15.0, 15.0]", "u_range = [-6.0, 6.0]"), ("v_range = [-10.0, 10.0]",
                     "v_range = [-4.5, 4.5]"), ("faces_u = 22", "faces_u = 8"), ("faces_v = 15", "faces_v = 6")):
        assert old in text
        text = text.replace(old, new)
    return text.replace("time_budget = 6.0", "time_budget = 1.0") + CLASSIFICATION


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    root = tmp_path_factory.mktemp("ifc_types")
    (root / "d.toml").write_text(half_turn_vault(), encoding="utf-8")
    assert main(["build", str(root / "d.toml"), "-o", str(root / "out"), "--quiet"]) == 0
    return root / "out"


@pytest.fixture(scope="module")
def parts(built):
    with open(built / "parts.csv", newline="", encoding="utf-8") as fh:
        return {r["part_id"]: r for r in csv.DictReader(fh)}


@pytest.fixture(scope="module")
def ifc(built):
    import ifcopenshell

    return ifcopenshell.open(str(built / "model.ifc"))


def is_mapped(e) -> bool:
    return any(it.is_a("IfcMappedItem") for r in e.Representation.Representations for it in r.Items)


def world_vertices(f) -> dict[str, np.ndarray]:
    """Part id → the vertices ``(n, 3)`` mm of its body as ifcopenshell's geometry kernel places it."""
    import ifcopenshell.geom
    import ifcopenshell.util.shape as us

    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    it = ifcopenshell.geom.iterator(settings, f)
    assert it.initialize()
    out = {}
    while True:
        shape = it.get()
        out[f.by_id(shape.id).Name] = np.asarray(us.get_vertices(shape.geometry), dtype=float) * 1e3
        if not it.next():
            return out


def test_repeated_parts_are_occurrences_of_one_type_with_one_shape(ifc, parts):
    """Every panel type an IfcPlateType, every cover-plate type of two or more plates an IfcMemberType, the strips
    of one length one IfcMemberType; each type holds one shape and its occurrences map it (the panes all, the
    half-turn pairs of strips, caps and cover plates); ifcopenshell's validator with the EXPRESS rules finds
    nothing."""
    import ifcopenshell.util.element as ue
    import ifcopenshell.validate

    panes = {k: r for k, r in parts.items() if r["kind"] == "panel"}
    assert len(panes) == 48
    plate_types = {t.Name: t for t in ifc.by_type("IfcPlateType") if t.PredefinedType == "CURTAIN_PANEL"}
    assert sorted(plate_types) == sorted({r["type_id"] for r in panes.values()}) and len(plate_types) == 24
    splice_count: dict[str, int] = defaultdict(int)
    for r in parts.values():
        if r["kind"] == "splice":
            splice_count[r["type_id"]] += 1
    member_types = {t.Name: t for t in ifc.by_type("IfcMemberType")}
    assert {n for n, t in member_types.items() if t.ElementType == "splice"} == \
        {k for k, n in splice_count.items() if n >= 2}
    strip_types = [t for t in member_types.values() if t.ElementType == "strip"]
    assert strip_types
    for t in strip_types:                          # one length, width and thickness per type (parts.csv)
        (rel,) = t.Types
        rows = [parts[o.Name] for o in rel.RelatedObjects]
        assert len(rows) >= 2 and {r["kind"] for r in rows} == {"strip"}
        for key in ("length_mm", "width_mm", "thickness_mm"):
            values = [float(r[key]) for r in rows]
            assert max(values) - min(values) <= 2e-3, (t.Name, key, values)
    mapped: dict[str, int] = defaultdict(int)
    for e in ifc.by_type("IfcElement"):
        if e.Name not in parts:
            continue
        t = ue.get_type(e)
        items = [it for r in e.Representation.Representations for it in r.Items]
        if any(it.is_a("IfcMappedItem") for it in items):
            assert t is not None and len(t.RepresentationMaps) == 1
            assert len(items) == 1 and items[0].MappingSource == t.RepresentationMaps[0]
            assert e.Representation.Representations[0].RepresentationType == "MappedRepresentation"
            mapped[parts[e.Name]["kind"]] += 1
    kinds = defaultdict(int)
    for r in parts.values():
        kinds[r["kind"]] += 1
    assert mapped["panel"] == 48
    assert mapped["strip"] == kinds["strip"] and mapped["cover_cap"] == kinds["cover_cap"]
    assert 0 < mapped["splice"] <= kinds["splice"]
    log = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(ifc, log, express_rules=True)
    assert log.statements == []


def test_a_mapped_pane_is_its_type_as_cut_on_its_own_face(built, ifc, parts):
    """The pane the IFC kernel places is the outline cut for its type (the CUT polyline of the per-type DXF: equal
    corner-to-corner distances, the four edges and two diagonals), lying within the type tolerance of the pane
    in panels.step, as thick as the glass."""
    import ezdxf

    from fabrication.verify._step_read import read_step_solids

    step = {s.name: np.array([tuple(p) for p in s.solid.vertices()]) for s in read_step_solids(built / "panels.step")}
    world = world_vertices(ifc)
    tol = tomllib.loads(half_turn_vault()).get("panels", {}).get("congruence_tolerance", 1.0)
    for pid, row in parts.items():
        if row["kind"] != "panel":
            continue
        cut = [e for e in ezdxf.readfile(built / "glass" / "types" / f"type_{row['type_id']}.dxf").modelspace()
               if e.dxftype() == "LWPOLYLINE" and e.dxf.layer == "CUT"]
        (poly,) = cut
        corners = np.array([(x, y) for x, y, *_ in poly.get_points()])
        x = world[pid]
        assert len(x) == 8                                   # a prism of four corners
        n = np.linalg.svd(x - x.mean(axis=0))[2][2]
        d = (x - x.mean(axis=0)) @ n
        assert np.ptp(d) == pytest.approx(float(row["thickness_mm"]), abs=1e-6)
        base = x[d < d.mean()]
        ifc_d = sorted(float(np.linalg.norm(a - b)) for a, b in combinations(base, 2))
        cut_d = sorted(float(np.linalg.norm(a - b)) for a, b in combinations(corners, 2))
        assert np.allclose(ifc_d, cut_d, atol=1e-6), (pid, ifc_d, cut_d)
        own = step[pid]
        gap = np.linalg.norm(x[:, None, :] - own[None, :, :], axis=2).min(axis=1).max()
        assert gap <= tol + 1e-6, (pid, gap)


def test_mapped_strips_caps_and_cover_plates_are_where_the_step_files_put_them(built, ifc, parts):
    """Every mapped part other than a pane lies where glazing.step / splices.step have it (each IFC vertex within
    1e-4 mm of a STEP vertex and back): its type's shape moved onto it is its own body."""
    step = step_vertices(built)
    world = world_vertices(ifc)
    seen = 0
    for e in ifc.by_type("IfcElement"):
        row = parts.get(e.Name)
        if row is None or row["kind"] == "panel" or not is_mapped(e) or e.Name not in step:
            continue
        x, s = world[e.Name], step[e.Name]
        if row["kind"] == "splice":                # bolt holes: tessellated here, exact circles there
            assert np.abs(x.min(axis=0) - s.min(axis=0)).max() <= 1e-4, e.Name          # the outline's extremes
            assert np.abs(x.max(axis=0) - s.max(axis=0)).max() <= 1e-4, e.Name
        else:
            d = np.linalg.norm(x[:, None, :] - s[None, :, :], axis=2)
            assert max(d.min(axis=0).max(), d.min(axis=1).max()) <= 1e-4, (e.Name, d.min(axis=1).max())
        seen += 1
    assert seen > 100


def step_vertices(built) -> dict[str, np.ndarray]:
    """Part id → the vertices ``(n, 3)`` mm of its solid in panels.step, glazing.step and splices.step."""
    from fabrication.verify._step_read import read_step_solids

    out = {}
    for name in ("panels.step", "glazing.step", "splices.step"):
        out.update({s.name: np.array([tuple(p) for p in s.solid.vertices()]) for s in read_step_solids(built / name)})
    return out


def test_glb_stores_a_repeated_mesh_once_and_places_it_where_the_part_is(built, parts):
    """model.glb has a node per part; a part congruent with the first of its type is a node holding that part's
    mesh, placed by a rotation and shift: read with trimesh and taken back to mm, its corners are the part's
    corners in the STEP files (float32 vertices: within 1e-3 mm; a cover plate, whose bolt holes are polygons
    here, by the extremes of its outline)."""
    import trimesh

    from fabrication.writers.glb import MM_TO_GLTF

    scene = trimesh.load(str(built / "model.glb"), force="scene", process=False)
    nodes = list(scene.graph.nodes_geometry)
    assert sorted(nodes) == sorted(parts)
    shared = {n: scene.graph[n][1] for n in nodes if scene.graph[n][1] != n}
    assert len(scene.geometry) == len(nodes) - len(shared) and len(shared) > len(nodes) // 3
    assert {parts[n]["kind"] for n in shared} >= {"panel", "strip", "cover_cap", "splice"}
    step = step_vertices(built)
    back = np.linalg.inv(MM_TO_GLTF)
    for n, geometry in shared.items():
        transform = scene.graph[n][0]
        assert np.linalg.det(transform[:3, :3]) == pytest.approx(1.0, abs=1e-9)
        x = trimesh.transform_points(scene.geometry[geometry].vertices, transform) @ back.T
        s = step[n]
        if parts[n]["kind"] == "splice":           # bolt holes: 24-gons here, circles there
            assert np.abs(x.min(axis=0) - s.min(axis=0)).max() <= 1e-3, n
            assert np.abs(x.max(axis=0) - s.max(axis=0)).max() <= 1e-3, n
            continue
        d = np.linalg.norm(x[:, None, :] - s[None, :, :], axis=2)
        assert max(d.min(axis=0).max(), d.min(axis=1).max()) <= 1e-3, (n, d.min(axis=1).max())


def test_the_classification_reaches_the_parts_and_types_it_names(ifc, parts):
    """The project declares the system (name and edition); every pane and panel type carries the panel code with
    its title, every strip the strip code, and nothing else is classified."""
    import ifcopenshell.util.classification as uc

    (project,) = ifc.by_type("IfcProject")
    (system,) = [r.RelatingClassification for r in project.HasAssociations
                 if r.is_a("IfcRelAssociatesClassification")]
    assert (system.Name, system.Edition) == ("Uniclass 2015", "v1.30")
    for e in list(ifc.by_type("IfcElement")) + list(ifc.by_type("IfcElementType")):
        refs = [(r.Identification, r.Name) for r in uc.get_references(e)]
        kind = parts[e.Name]["kind"] if e.Name in parts else getattr(e, "ElementType", None)
        if e.is_a("IfcPlateType") and e.PredefinedType == "CURTAIN_PANEL":
            kind = "panel"
        if kind == "panel":
            assert refs == [("Pr_00_00_00", "the glass code of a test")], e.Name
        elif kind == "strip":
            assert refs == [("Pr_00_00_01", None)], e.Name
        else:
            assert refs == [], e.Name
        for r in uc.get_references(e):
            assert uc.get_classification(r) == system


@pytest.mark.parametrize("table, words", [
    ('system = "Uniclass 2015"\nroof = "Ss_30"', "output.classification.roof: is neither system"),
    ('panel = "Pr_1"', "output.classification.system: missing"),
    ('system = "Uniclass 2015"\npanel = ""', "output.classification.panel: must be a non-empty string"),
])
def test_a_bad_classification_is_one_line_and_writes_nothing(tmp_path, table, words):
    design = tmp_path / "d.toml"
    design.write_text(small_design(extra=f"\n[output.classification]\n{table}\n"), encoding="utf-8")
    r = subprocess.run([sys.executable, "-m", "fabrication.cli", "build", str(design), "-o", str(tmp_path / "out")],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and words in r.stderr, r.stderr
    assert not (tmp_path / "out").exists()


def test_verify_refuses_a_mirrored_or_foreign_mapping(built, tmp_path):
    """A pane whose mapping operator is turned into a mirror image, and a strip that maps another type's shape:
    verify names both."""
    import ifcopenshell

    from fabrication.verify import Verification
    from fabrication.verify.ifc import check_ifc

    out = tmp_path / "copy"
    shutil.copytree(built, out)
    f = ifcopenshell.open(str(out / "model.ifc"))
    pane = next(p for p in f.by_type("IfcPlate") if p.PredefinedType == "CURTAIN_PANEL" and is_mapped(p))
    op = pane.Representation.Representations[0].Items[0].MappingTarget
    op.Axis2 = f.create_entity("IfcDirection", DirectionRatios=tuple(-x for x in op.Axis2.DirectionRatios))
    strips = [m for m in f.by_type("IfcMember") if m.ObjectType == "strip" and is_mapped(m)]
    a = strips[0].Representation.Representations[0].Items[0]
    other = next(s for s in strips if s.Representation.Representations[0].Items[0].MappingSource != a.MappingSource)
    a.MappingSource = other.Representation.Representations[0].Items[0].MappingSource
    f.write(str(out / "model.ifc"))
    v = Verification(out)
    check_ifc(v)
    found = {(e.element, e.message) for e in v.findings}
    assert (pane.Name, "maps its type's shape by an operator that is not a rotation (mirrored, skewed or scaled)") \
        in found
    assert (strips[0].Name, "maps a shape that is not its type's") in found


def _element(outline, z0=0.0, height=12.0, holes=np.zeros((0, 3)), top=None) -> Element:
    frame = Frame(np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    return Element("X", "beam", "rows", "", np.asarray(outline, dtype=float), frame, z0, height, {}, holes,
                   outline_top=top)


@pytest.mark.parametrize("turned", [False, True])
def test_fit_motion_finds_a_known_motion_and_keeps_the_solid_in_its_slab(turned):
    """A pentagon with a hole, moved by a known rotation and shift (and turned over: mirrored in the plane, which
    in space is a half turn about an in-plane axis), with its corners listed from another start: the motion
    found is proper and puts every corner of the prism (bottom and top) on the moved one's — checked against
    the prism built from the moved outline, not by the function's own error."""
    a = np.array([[0.0, 0.0], [400.0, -20.0], [520.0, 180.0], [300.0, 330.0], [-40.0, 210.0]])
    holes = np.array([[200.0, 120.0, 22.0]])
    theta = 0.7
    rot = np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])
    shift = np.array([1234.5, -77.0])
    b = a * np.array([-1.0, 1.0]) if turned else a.copy()
    hb = holes[:, :2] * np.array([-1.0, 1.0]) if turned else holes[:, :2]
    b = (b @ rot.T + shift)[::-1] if turned else b @ rot.T + shift
    b = np.roll(b, 2, axis=0)
    shape = _element(a, z0=-6.0, holes=holes)
    other = _element(b, z0=-6.0, holes=np.c_[hb @ rot.T + shift, holes[:, 2]])
    m = fit_motion(shape, other)
    assert m is not None and m.error < 1e-9
    assert np.linalg.det(m.rotation) == pytest.approx(1.0) and np.allclose(m.rotation @ m.rotation.T, np.eye(3))
    prism = lambda o, z0, h: np.r_[np.c_[o, np.full(len(o), z0)], np.c_[o, np.full(len(o), z0 + h)]]  # noqa: E731
    moved = m.apply(prism(a, -6.0, 12.0))
    target = prism(b, -6.0, 12.0)
    assert np.linalg.norm(moved[:, None] - target[None], axis=2).min(axis=1).max() < 1e-9


def test_fit_motion_measures_a_moved_corner_and_refuses_what_cannot_fit():
    a = np.array([[0.0, 0.0], [400.0, 0.0], [400.0, 300.0], [0.0, 300.0]])
    b = a.copy()
    b[2] += [0.0, 0.05]
    m = fit_motion(_element(a), _element(b))
    assert m is not None and 0.02 < m.error <= 0.05
    assert fit_motion(_element(a), _element(a[:3])) is None                   # another corner count
    assert fit_motion(_element(a), _element(a, height=10.0)) is None          # another thickness
    bevel = a + [[0.0, 0.0], [3.0, 0.0], [3.0, 0.0], [0.0, 0.0]]
    m = fit_motion(_element(a, top=bevel), _element(a, top=a))               # the top faces differ by 3 mm
    assert m is not None and m.error == pytest.approx(3.0)
