"""The glass where it sits: every pane of panels.step rests on the gaskets of glazing.step without entering them.

Measured from the written files by routes of their own, apart from the placing code (fabrication.glazing.seat)
and from the clash check of ppfab verify (manifold3d):

* interpenetration by the CAD kernel's boolean common of each pane with the strips and gaskets near it;
* contact by rays (trimesh, on the gaskets exported from the kernel as STL) cast from the pane's underside along
  its normal, at stations along every edge and across the first ``min_bite`` millimetres of glass;
* a pane lifted or lowered in panels.step (manifest resealed) is named by ``ppfab verify`` with its gap or depth.

On four builds, as the writers leave them: a small PP vault, the example ``smallest_roof`` (kinks of up to 20°:
its gaskets tilt by 10° under the panes) and patches of two real meshes of the shared data: DOI rot4_def1_sparse_rot
(conical PP) and DOS conical1 optimised to P (WWmore/DOS, objs/obj_pq/conical1.obj).
"""

from __future__ import annotations

import csv
import hashlib
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from fabrication.cli import main
from fabrication.glazing.seat import SEAT_TOLERANCE
from fabrication.verify._solids import BOX_KINDS
from fabrication.verify._step_read import read_step_solids
from fabrication.verify.rhino import placed_objects

from conftest import REPO, shared_file, small_vault

TOL = SEAT_TOLERANCE


def written(design: Path, out: Path) -> Path:
    """The files of a build of ``design`` written into ``out`` by every writer (the folder the build would
    deliver, before its own self-check: these tests measure the glass themselves)."""
    from fabrication import build
    from fabrication.design import load_design
    from fabrication.progress import Progress
    from fabrication.writers import write_all

    b = build(load_design(design))
    out.mkdir()
    files = write_all(b, out, Progress(quiet=True))
    assert "panels_step" in files and "glazing_step" in files
    return out


@pytest.fixture(scope="module")
def vault(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("clash_vault")
    (root / "d.toml").write_text(small_vault("clash vault"))
    return written(root / "d.toml", root / "out")


@pytest.fixture(scope="module")
def example(tmp_path_factory) -> Path:
    return written(REPO / "examples" / "smallest_roof.toml", tmp_path_factory.mktemp("clash_example") / "out")


@pytest.fixture(scope="module")
def real(tmp_path_factory) -> Path:
    from ppfab.io import load_mesh, write_obj
    from ppfab.mesh import QuadGrid

    root = tmp_path_factory.mktemp("clash_real")
    grid = load_mesh(shared_file("DOI__rot4_def1_sparse_rot.obj")).to_grid()
    write_obj(QuadGrid(np.ascontiguousarray(grid.vertices[20:29, 0:8])), root / "patch.obj")
    (root / "d.toml").write_text(f'[design]\nname = "rot4 patch"\n[geometry]\nmesh = "{(root / "patch.obj").as_posix()}"\n'
                                 "scale = 3000.0\n[beams]\nfallback = \"segmented\"\n[nesting]\ntime_budget = 0.5\n"
                                 "[beam_nesting]\ntime_budget = 0.5\n")
    return written(root / "d.toml", root / "out")


@pytest.fixture(scope="module")
def real_p(tmp_path_factory) -> Path:
    """A 9 × 8 patch of DOS conical1 (shared data; a conical planar-quad mesh whose polylines are not planar)
    optimised to P in its rows, on a P support with segmented columns, glass in structural silicone."""
    from ppfab.io import load_mesh, write_obj
    from ppfab.mesh import QuadGrid

    root = tmp_path_factory.mktemp("clash_real_p")
    grid = load_mesh(shared_file("DOS__conical1.obj")).to_grid()
    write_obj(QuadGrid(np.ascontiguousarray(grid.vertices[12:21, 10:18])), root / "patch.obj")
    (root / "d.toml").write_text(
        f'[design]\nname = "conical1 patch"\n[geometry]\nmesh = "{(root / "patch.obj").as_posix()}"\n'
        'scale = 1500.0\n[optimize]\nfamilies = "rows"\ntarget_delta_f = 1e-7\ntarget_delta_p = 1e-7\n'
        '[support]\nmethod = "p"\nfamily = "rows"\n[beams]\njoint = "segmented"\ncontinuous = "rows"\n'
        'fallback = "segmented"\n[panels]\ngap = 24.0\n[glazing]\nretention = "silicone"\nmax_tilt_deg = 13.5\n'
        "[nesting]\ntime_budget = 0.5\n[beam_nesting]\ntime_budget = 0.5\n")
    return written(root / "d.toml", root / "out")


BUILDS = ["vault", "example", "real", "real_p"]


def points(solid) -> np.ndarray:
    return np.array([tuple(p) for p in solid.vertices()], dtype=float)


def read(folder: Path) -> tuple[dict, dict, dict]:
    """Panes (name → solid), gaskets and strips (name → solid) as the kernel reads them back."""
    panes = {s.name: s.solid for s in read_step_solids(folder / "panels.step")}
    support = {s.name: s.solid for s in read_step_solids(folder / "glazing.step")}
    return panes, {k: s for k, s in support.items() if k.startswith("GK-")}, \
        {k: s for k, s in support.items() if k.startswith("GS-")}


def rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def down_of(pane: np.ndarray, gaskets: np.ndarray) -> np.ndarray:
    """The pane's unit normal pointing to the gaskets (``gaskets``: their vertices near the pane)."""
    c = pane.mean(axis=0)
    n = np.linalg.svd(pane - c)[2][2]
    return n if float(((gaskets - c) @ n).mean()) > 0 else -n


# -- the seat against a formula ---------------------------------------------------------------------------------

@pytest.mark.parametrize("alpha", [0.0, 1.4, 10.0])
def test_the_seat_is_the_highest_gasket_point_under_the_pane(alpha):
    """A pane in z = 0 (normal +z) over y ≥ 10 mm; under its edge y = 0 a strip whose gasket top is tilted by α
    about the edge so that it rises into the pane (a ridge), under its far edge y = 1010 a level one.  The
    highest point of the tilted gasket under the pane is its far long edge, y = 30 cos α − 11 sin α, at
    z = 30 sin α + 11 cos α: the seat; the pane stands off the level gasket (top at 11 mm) by the rest."""
    from types import SimpleNamespace

    from fabrication.glazing.seat import seat_pane
    from fabrication.glazing.strips import Strip
    from ppfab.frame import Frame

    a = np.radians(alpha)
    pane = SimpleNamespace(part_id="P-0000", frame=Frame(np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 1.0, 0])),
                           outline=np.array([[0.0, 10.0], [1000.0, 10.0], [1000.0, 1000.0], [0.0, 1000.0]]))
    tilted = Strip("GS-U00-00", 0, (0, 1), "B-U00", Frame(np.zeros(3), np.array([1.0, 0, 0]),
                                                          np.array([0, np.cos(a), np.sin(a)])),
                   0.0, 1000.0, 60.0, 8.0, (True, True))
    level = Strip("GS-U01-00", 1, (2, 3), "B-U01", Frame(np.array([0.0, 1010.0, 0.0]), np.array([1.0, 0, 0]),
                                                         np.array([0, 1.0, 0])),
                  0.0, 1000.0, 60.0, 8.0, (True, True))
    seat = seat_pane(pane, [tilted, level], 3.0, 11.0)
    want = 30.0 * np.sin(a) + 11.0 * np.cos(a)
    assert seat.offset == pytest.approx(want, abs=1e-9)
    gaps = {c.strip: c.gap for c in seat.contacts}
    assert gaps["GS-U00-00"] == pytest.approx(0.0, abs=1e-12)
    assert gaps["GS-U01-00"] == pytest.approx(want - 11.0, abs=1e-9)
    assert seat.largest_gap == pytest.approx(want - 11.0, abs=1e-9)


# -- interpenetration: the kernel's boolean common ------------------------------------------------------------

@pytest.mark.parametrize("name", BUILDS)
def test_no_pane_enters_a_strip_or_gasket(name, request):
    no_pane_enters_a_strip_or_gasket(request.getfixturevalue(name))


def no_pane_enters_a_strip_or_gasket(folder: Path) -> None:
    """The common of every pane with every strip and gasket whose box meets its own is empty or thinner than the
    tolerance below the pane's underside; every pane touches (its box meets) at least three gaskets."""
    panes, gaskets, strips = read(folder)
    support = {**gaskets, **strips}
    boxes = {k: (points(s).min(axis=0), points(s).max(axis=0)) for k, s in support.items()}
    pairs = 0
    for pid, pane in panes.items():
        p = points(pane)
        lo, hi = p.min(axis=0) - 0.5, p.max(axis=0) + 0.5
        near = [k for k, (a, b) in boxes.items() if np.all(a <= hi) and np.all(b >= lo)]
        assert sum(k.startswith("GK-") for k in near) >= 3, (pid, near)
        down = down_of(p, np.vstack([points(support[k]) for k in near]))
        under = float((p @ down).max())                          # the underside, along the normal to the gaskets
        for k in near:
            pairs += 1
            common = pane & support[k]
            if common is not None and common.volume > 1e-9:
                depth = under - float((points(common) @ down).min())   # how far the part reaches into the pane
                assert depth <= TOL, f"{pid} enters {k} by {depth:.3f} mm"
    assert pairs >= 3 * len(panes)


IN_PLACE_MM = 0.25
"""The fit of the steel and glazing in place (``fabrication.verify.erection.TOLERANCE``): a plate's top corner
under a strip it leans against where its edge is not bevelled rises at most ``(t/2)·sin(bevel_min_deg)`` (0.21 mm
on a 12 mm plate, docs/glazing.md)."""


def _slab(pts: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Centre, unit normal and half-thickness of a flat part from its vertices (least squares)."""
    c = pts.mean(axis=0)
    n = np.linalg.svd(pts - c)[2][2]
    return c, n, 0.5 * float(np.ptp((pts - c) @ n))


def _depth(common, solids) -> float:
    """How deep a common part is: its least extent along the normals of the planar faces of ``solids``."""
    pts = points(common)
    normals = [np.asarray(tuple(f.normal_at()), dtype=float) for s in solids for f in s.faces()
               if f.geom_type.name == "PLANE"]
    return min(float(np.ptp(pts @ n)) for n in normals)


@pytest.mark.parametrize("name", BUILDS)
def test_no_strip_gasket_or_beam_plate_enters_another(name, request):
    no_strip_gasket_or_beam_plate_enters_another(request.getfixturevalue(name))


def no_strip_gasket_or_beam_plate_enters_another(folder: Path) -> None:
    """Strips, gaskets, setting blocks, stops, pressure gaskets and plates, cover caps (glazing.step) and beam
    plates (beams.step) as the CAD kernel reads them back: the kernel's boolean common of every pair near each
    other (boxes meeting, a part's corners reaching a plate's slab) is empty or thinner than the fit in place, so
    the designed contacts (a strip on its plate, the gasket on its strip, consecutive strips at a node, a block on
    its gasket, a cap on its pressure plate) are touches, not overlaps.  A stop in the joint under a ridge stood
    0.37 mm in the pressure gasket over it on the real dome (tests/test_real_builds.py) before it was capped.  Before the running strips met on their mitre
    plane, the gaskets of ``smallest_roof``'s valley nodes ran 1.24 mm into the next span's gasket."""
    _, gaskets, strips = read(folder)
    plates = {s.name: s.solid for s in read_step_solids(folder / "beams.step")}
    glazing = {s.name: s.solid for s in read_step_solids(folder / "glazing.step")}    # with the retention parts
    pts = {k: points(s) for k, s in {**glazing, **plates}.items()}
    boxes = {k: (p.min(axis=0) - 0.5, p.max(axis=0) + 0.5) for k, p in pts.items()}
    slabs = {k: _slab(pts[k]) for k in plates}

    def near(a: str, b: str) -> bool:
        (la, ha), (lb, hb) = boxes[a], boxes[b]
        if not (np.all(la <= hb) and np.all(lb <= ha)):
            return False
        for plate, other in ((a, b), (b, a)):
            if plate in slabs:
                c, n, half = slabs[plate]
                h = (pts[other] - c) @ n
                if h.min() > half + 0.5 or h.max() < -half - 0.5:
                    return False
        return True

    names = sorted(glazing) + sorted(plates)
    pairs, worst = 0, (0.0, "", "")
    for i, a in enumerate(names):
        if a in plates:
            break                                   # plate against plate: the beams' own checks (joints, slots)
        for b in names[i + 1:]:
            if not near(a, b):
                continue
            pairs += 1
            solids = (glazing[a], glazing.get(b, plates.get(b)))
            common = solids[0] & solids[1]
            if common is not None and common.volume > 1e-6:
                depth = _depth(common, solids)
                if depth > worst[0]:
                    worst = (depth, a, b)
    assert pairs >= 2 * len(strips)                  # every strip met at least its gasket and its plate
    assert worst[0] <= IN_PLACE_MM, f"{worst[1]} enters {worst[2]} by {worst[0]:.3f} mm"


# -- contact: rays from the pane's underside onto the gaskets (trimesh) ---------------------------------------

def gasket_mesh(gaskets: dict, tmp: Path):
    """All gaskets as one trimesh mesh, each exported by the kernel as an STL file and read back by trimesh."""
    import trimesh
    from build123d import export_stl

    meshes = []
    for k, solid in gaskets.items():
        path = tmp / f"{k}.stl"
        assert export_stl(solid, str(path), tolerance=1e-3)
        meshes.append(trimesh.load(str(path), force="mesh"))
    return trimesh.util.concatenate(meshes)


class Everything:
    """A broad phase that offers every triangle to every ray (trimesh's ray_triangle_id asks an R-tree, ``rtree``,
    for candidates; the triangles near one pane are few, so all of them are tested exactly)."""

    def __init__(self, triangles: np.ndarray):
        self.count = len(triangles)
        flat = triangles.reshape(-1, 3)
        self.bounds = np.concatenate([flat.min(axis=0), flat.max(axis=0)]) if len(flat) else np.zeros(6)

    def intersection(self, bounds) -> range:
        return range(self.count)


STEP = 0.5
"""mm between the rays cast across a pane edge."""


@pytest.mark.parametrize("name", BUILDS)
def test_rays_from_every_pane_edge_land_on_a_gasket_within_the_bite(name, request, tmp_path):
    rays_from_every_pane_edge_land_on_a_gasket_within_the_bite(request.getfixturevalue(name), tmp_path)


def rays_from_every_pane_edge_land_on_a_gasket_within_the_bite(folder: Path, tmp_path: Path) -> None:
    """From the underside of every pane, at three stations along the middle of each edge and every 0.5 mm from
    the edge to ``min_bite`` into the glass (and on to 35 mm), a ray along the pane's normal: within the bite
    every ray hits a gasket, no hit lies above the underside by more than the tolerance (no penetration), the
    nearest hit of each pane lies on its underside within the tolerance (it bears), and the nearest hit of each
    edge within the wedge of the tilts of its pane's edges (``bites.csv``) across the strip width."""
    from trimesh.ray.ray_triangle import ray_triangle_id

    m = json.loads((folder / "manifest.json").read_text())
    fab = m["fabrication"]
    min_bite, width = float(fab["panels"]["min_bite"]), float(fab["glazing"]["width"])
    tilt: dict[str, float] = {}
    for r in rows(folder / "bites.csv"):
        tilt[r["panel"]] = max(tilt.get(r["panel"], 0.0), float(r["tilt_deg"]))
    panes, gaskets, _ = read(folder)
    mesh = gasket_mesh(gaskets, tmp_path)
    triangles = np.asarray(mesh.triangles)
    centres = triangles.mean(axis=1)
    tops = np.asarray(mesh.vertices)
    across = np.arange(0.05, 35.0, STEP)
    inside = across <= min_bite - 0.5
    lift = 1.0                                              # rays start inside the glass, 1 mm above its underside
    for pid, pane in panes.items():
        p = points(pane)
        c = p.mean(axis=0)
        radius = np.linalg.norm(p - c, axis=1).max() + width
        near = tops[np.linalg.norm(tops - c, axis=1) < radius]
        local = triangles[np.linalg.norm(centres - c, axis=1) < radius + 0.5 * np.linalg.norm(
            triangles - centres[:, None], axis=2).max(axis=1)] if len(triangles) else triangles
        down = down_of(p, near)
        h = p @ down
        ring = p[h > 0.5 * (h.min() + h.max())]                # the underside's corners
        e1 = ring[0] - ring.mean(axis=0)
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(down, e1)
        ring = ring[np.argsort(np.arctan2((ring - c) @ e2, (ring - c) @ e1))]
        best_pane = np.inf
        wedge = TOL + width * np.tan(np.radians(tilt[pid])) + STEP * np.tan(np.radians(tilt[pid]))
        for k in range(len(ring)):
            a, b = ring[k], ring[(k + 1) % len(ring)]
            d = (b - a) / np.linalg.norm(b - a)
            u = np.cross(down, d)
            u = u if (ring.mean(axis=0) - a) @ u > 0 else -u     # into the pane
            starts = np.array([a + s * (b - a) + r * u for s in (0.35, 0.5, 0.65) for r in across])
            origins = starts - lift * down
            index_ray = np.arange(len(origins))
            _, hit_ray, locs = ray_triangle_id(local, origins, np.tile(down, (len(origins), 1)), tree=Everything(local),
                                               multiple_hits=False)
            dist = np.full(len(origins), np.inf)
            dist[hit_ray] = np.einsum("ij,j->i", locs - origins[hit_ray], down) - lift
            missed = index_ray[np.tile(inside, 3) & ~np.isfinite(dist)]
            assert len(missed) == 0, f"{pid} edge {k}: {len(missed)} rays within the bite hit no gasket"
            hit = dist[np.isfinite(dist)]
            assert hit.min() >= -TOL, f"{pid} edge {k}: a gasket {-hit.min():.3f} mm above the underside"
            assert hit.min() <= wedge, f"{pid} edge {k}: nearest gasket {hit.min():.3f} mm below, wedge {wedge:.3f}"
            best_pane = min(best_pane, float(hit.min()))
        assert best_pane <= TOL + STEP * np.tan(np.radians(tilt[pid])), f"{pid} stands {best_pane:.3f} mm off"


# -- tampering: a pane moved along its normal ------------------------------------------------------------------

def moved_pane(built: Path, tmp: Path, shift: float) -> tuple[Path, str]:
    """A copy of ``built`` with its first pane moved ``shift`` mm away from its gaskets along its normal in
    panels.step (same product tree otherwise) and the manifest's sha256 resealed."""
    from build123d import Location

    from fabrication.verify._step_read import read_step_solids as reread
    from fabrication.writers.step import _export_glass

    copy = tmp / "copy"
    shutil.copytree(built, copy)
    solids = reread(copy / "panels.step")
    _, gaskets, _ = read(copy)
    target = solids[0].name
    out = []
    for s in solids:
        solid = s.solid
        if s.name == target:
            p = points(solid)
            near = np.vstack([points(g) for g in gaskets.values()])
            near = near[np.linalg.norm(near - p.mean(axis=0), axis=1) < 2000.0]
            up = -down_of(p, near) * shift
            solid = solid.moved(Location((float(up[0]), float(up[1]), float(up[2]))))
        solid.label = s.name
        out.append(solid)
    m = json.loads((copy / "manifest.json").read_text())
    _export_glass(out, [s.name for s in solids], copy / "panels.step", m["design"].get("name", ""))
    m["sha256"]["panels.step"] = hashlib.sha256((copy / "panels.step").read_bytes()).hexdigest()
    (copy / "manifest.json").write_text(json.dumps(m, indent=2))
    return copy, target


def test_a_pane_lifted_3_mm_is_named_with_its_gap(vault, tmp_path, capsys):
    copy, pid = moved_pane(vault, tmp_path, 3.0)
    capsys.readouterr()
    assert main(["verify", str(copy), "--quiet"]) == 1
    err = capsys.readouterr().err
    found = re.search(rf"panels\.step: {pid}: bears on no gasket: the nearest, (GK-\S+), is ([0-9.]+) mm below it", err)
    assert found, err[-2000:]
    assert float(found.group(2)) == pytest.approx(3.0, abs=0.02)
    assert not re.search(r"penetrates G[KS]-", err)      # only the pressure gasket over it (CG-), which it lifts into


def test_a_pane_lowered_2_mm_is_named_with_its_depth(vault, tmp_path, capsys):
    copy, pid = moved_pane(vault, tmp_path, -2.0)
    capsys.readouterr()
    assert main(["verify", str(copy), "--quiet"]) == 1
    err = capsys.readouterr().err
    depths = [float(x) for x in re.findall(rf"panels\.step: {pid}: penetrates GK-\S+ of glazing\.step by ([0-9.]+) mm",
                                           err)]
    assert depths and max(depths) == pytest.approx(2.0, abs=0.02), err[-2000:]
    assert "bears on no gasket" not in err


@pytest.mark.parametrize("name", BUILDS)
def test_the_written_panes_pass_verify(name, request):
    """ppfab verify's clash check, its panels.step check and the pane placement of the IFC, Rhino and glTF
    checks find nothing in the files as written."""
    from fabrication.verify import verify

    v = verify(request.getfixturevalue(name))
    assert {"clash", "panels_step", "ifc", "rhino", "glb"} <= set(v.checked)
    mine = [str(f) for f in v.findings if f.file == "panels.step" or "face" in f.message and "plane" in f.message]
    assert mine == []


def test_every_model_places_the_panes_and_the_glazing_parts_alike(vault):
    """The corners of every pane in model.glb (trimesh, glTF metres back to mm) and model.3dm (rhino3dm, the
    extrusion's bottom and top profiles) are those of its solid in panels.step (the kernel), within the
    glTF's float32 rounding; so are those of every strip and retention part of glazing.step in model.3dm, where
    repeated shapes are block instances (the block's body moved by the instance's transform)."""
    import rhino3dm
    import trimesh
    from scipy.spatial import cKDTree

    from fabrication.writers.glb import MM_TO_GLTF

    step = {s.name: points(s.solid) for s in read_step_solids(vault / "panels.step")}

    def far(a: np.ndarray, b: np.ndarray) -> float:
        return float(max(cKDTree(b).query(a)[0].max(), cKDTree(a).query(b)[0].max()))

    scene = trimesh.load(str(vault / "model.glb"), force="scene", process=False)
    back = np.linalg.inv(MM_TO_GLTF)
    seen = 0
    for name in scene.graph.nodes_geometry:
        if name in step:
            transform, geometry = scene.graph[name]
            pts = trimesh.transform_points(scene.geometry[geometry].vertices, transform) @ back.T
            assert far(pts[:, :3], step[name]) < 5e-3, name
            seen += 1
    assert seen == len(step)
    glazing = {s.name: points(s.solid) for s in read_step_solids(vault / "glazing.step")}
    objects, problems = placed_objects(rhino3dm.File3dm.Read(str(vault / "model.3dm")))
    assert problems == []
    seen, instanced = 0, 0
    for obj in objects:
        name = obj.attributes.Name
        solid = step.get(name, glazing.get(name))
        if solid is not None and isinstance(obj.geometry, rhino3dm.Extrusion):
            rings = []
            for t in (0.0, 1.0):                                 # the bottom and the top profile, as polylines
                c = obj.geometry.Profile3d(0, t)
                rings += [[c.Point(i).X, c.Point(i).Y, c.Point(i).Z] for i in range(c.PointCount - 1)]
            assert far(np.array(rings), solid) < 1e-6, name
            seen += 1
            instanced += bool(obj.block)
    with open(vault / "parts.csv", newline="", encoding="utf-8") as fh:
        kinds = [r["kind"] for r in csv.DictReader(fh)]
    assert seen == sum(k in ("panel", "strip") + BOX_KINDS for k in kinds)
    assert instanced >= kinds.count("setting_block")        # repeated shapes: the blocks of one size at least
