"""The STEP template writer (fabrication/writers/step_template.py): what it writes is read back, solid by solid, by
the CAD kernel (the STEP translator), by verify's text-level reader and by a third reader built here on the
steputils parser; repeated shapes are written once and placed per occurrence."""

from __future__ import annotations

import numpy as np
import pytest

from fabrication.contract import COLOURS
from fabrication.verify._step_read import kernel_sample, read_step_solids
from fabrication.verify._step_text_read import read_text_solids
from fabrication.writers.step_template import Assembly, PlanarSolid, real, step_text, write_step
from ppfab.errors import FabricationError
from ppfab.frame import Frame

OUTLINES = {
    "box": np.array([[0.0, -30.0], [1234.567, -30.0], [1234.567, 30.0], [0.0, 30.0]]),
    "triangle": np.array([[0.0, 0.0], [500.0, 0.0], [120.0, 333.3]]),
    "ell": np.array([[0.0, 0.0], [400.0, 0.0], [400.0, 100.0], [100.0, 100.0], [100.0, 300.0], [0.0, 300.0]]),
    "clockwise": np.array([[0.0, 0.0], [0.0, 200.0], [150.0, 260.0], [310.0, 90.0], [200.0, -40.0]]),
}


def _frame(rng: np.random.Generator) -> Frame:
    ex = rng.normal(size=3)
    ex /= np.linalg.norm(ex)
    ey = np.cross(rng.normal(size=3), ex)
    ey /= np.linalg.norm(ey)
    return Frame(rng.uniform(-20000.0, 20000.0, size=3), ex, ey)


def _area(q: np.ndarray) -> float:
    """Shoelace area of a polygon (its absolute value)."""
    return 0.5 * abs(float(np.sum(q[:, 0] * np.roll(q[:, 1], -1) - np.roll(q[:, 0], -1) * q[:, 1])))


def _solids() -> tuple[list[PlanarSolid], list[float], list[str]]:
    """Fifteen prisms in random frames: three boxes of one shape under two assemblies (instanced), the others
    of their own shapes, one glass colour with transparency; their volumes by the shoelace formula and the
    beam each sits under."""
    rng = np.random.default_rng(31)
    solids, volumes, beams = [], [], []
    k = 0
    for name, q in OUTLINES.items():
        for rep in range(3 if name == "box" else 2):
            shift = np.array([17.0 * rep, -3.0]) if name == "box" else np.array([0.0, 0.0])
            outline = q + shift if name == "box" else q * (1.0 + 0.1 * rep)
            height = 6.0 if name == "box" else 4.0 + rep
            colour = COLOURS["glass"] if name == "triangle" else COLOURS["rows"]
            solids.append(PlanarSolid.prism(f"GS-{k:02d}", colour, outline, _frame(rng), 2.5, height))
            volumes.append(_area(outline) * height)
            beams.append(f"B-{k % 2}")
            k += 1
    return solids, volumes, beams


def _tree(solids: list[PlanarSolid], beams: list[str]) -> Assembly:
    groups: dict[str, list] = {}
    for s, b in zip(solids, beams):
        groups.setdefault(b, []).append(s)
    return Assembly("Demo roof glazing", [Assembly(b, kids) for b, kids in groups.items()])


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """The file of :func:`_solids` and the solids, volumes and beams in file order (depth first by beam)."""
    solids, volumes, beams = _solids()
    path = tmp_path_factory.mktemp("tpl") / "glazing.step"
    write_step(_tree(solids, beams), path, "glazing of a demo")
    order = sorted(range(len(solids)), key=lambda k: (beams[k], k))
    return path, [solids[k] for k in order], [volumes[k] for k in order], [beams[k] for k in order]


def _distance(a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance from a point of either set to the nearest of the other."""
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    return float(max(d.min(axis=0).max(), d.min(axis=1).max()))


def test_the_kernel_reads_every_solid_as_written(written):
    path, solids, volumes, beams = written
    read = read_step_solids(path, colours=True)
    assert [s.name for s in read] == [s.label for s in solids]
    assert [s.path for s in read] == [("Demo roof glazing", b) for b in beams]
    for got, want, vol in zip(read, solids, volumes):
        pts = np.array([tuple(v) for v in got.solid.vertices()])
        assert len(pts) == len(want.vertices)
        assert _distance(pts, want.placed()) <= 1e-9                 # mm, frames 20 m from the origin
        assert got.solid.is_valid                                    # BRepCheck
        assert got.solid.volume == pytest.approx(vol, rel=1e-9)
        assert got.colour is not None
        assert max(abs(a - b) for a, b in zip(got.colour[:3], want.colour[:3])) <= 1e-6
        # alpha: the kernel's reader gives 1 for the glass, as for a file the kernel itself wrote; the text
        # reader reads the transparency (test_the_text_reader_agrees)


def test_the_text_reader_agrees(written):
    path, solids, volumes, beams = written
    read = read_text_solids(path)
    assert [(s.name, s.path) for s in read] == [(s.label, ("Demo roof glazing", b)) for s, b in zip(solids, beams)]
    for got, want, vol in zip(read, solids, volumes):
        assert got.problems() == []
        assert _distance(got.points, want.placed()) <= 1e-9
        assert got.volume == pytest.approx(vol, rel=1e-9)
        assert got.colour == pytest.approx(want.colour, abs=1e-12)
    assert kernel_sample(path, read) == []


def test_repeated_shapes_are_written_once_and_placed_per_occurrence(written, tmp_path):
    path, solids, volumes, beams = written
    data = path.read_bytes()
    assert data.count(b"= MANIFOLD_SOLID_BREP(") == len(solids) - 2           # three boxes of one shape
    assert data.count(b"= NEXT_ASSEMBLY_USAGE_OCCURRENCE(") == len(solids) + 2  # one per solid and per beam
    flat = tmp_path / "flat.step"
    write_step(_tree(solids, beams), flat, "glazing of a demo", instance=False)
    assert flat.read_bytes().count(b"= MANIFOLD_SOLID_BREP(") == len(solids)
    boxes = [s for s in solids if len(s.vertices) == 8][:3]
    placed = {s.name: s for s in read_step_solids(path) if s.name in {b.label for b in boxes}}
    assert len(placed) == 3
    for b in boxes:                                                          # each box where it belongs
        assert _distance(np.array([tuple(v) for v in placed[b.label].solid.vertices()]), b.placed()) <= 1e-9
    centres = [b.placed().mean(axis=0) for b in boxes]
    assert min(np.linalg.norm(centres[i] - centres[j]) for i in range(3) for j in range(i)) > 100.0


def test_two_writes_are_byte_identical(written, tmp_path):
    path, solids, volumes, beams = written
    again = write_step(_tree(solids, beams), tmp_path / "glazing.step", "glazing of a demo")
    assert again.read_bytes() == path.read_bytes()
    head = path.read_bytes().partition(b"ENDSEC;")[0]
    assert b"FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'))" in head
    assert b"'2000-01-01T00:00:00'" in head and b"FILE_DESCRIPTION(('ppfab " in head


def steputils_solids(path) -> dict[str, tuple[np.ndarray, float, list[tuple[np.ndarray, float]]]]:
    """A third reader on the steputils parser (ISO 10303-21 only): the product tree, placements and B-reps are
    followed here.  Per product name: its vertices placed ``(n, 3)``, the volume summed over fan triangles of
    its planar faces' oriented loops (straight edges only: meaningless where a face has a circle), and its
    circles placed as ``(centre (3,), radius)``."""
    p21 = pytest.importorskip("steputils.p21", reason="steputils is not installed (pip install steputils)")
    ents = {}
    for ref, inst in p21.readfile(str(path)).data[0].instances.items():
        if hasattr(inst, "entity"):
            ents[str(ref)] = (inst.entity.name, list(inst.entity.params))
        else:
            ents[str(ref)] = ("", [(e.name, list(e.params)) for e in inst.entities])

    def xyz(r) -> np.ndarray:
        return np.array([float(x) for x in ents[str(r)][1][1]])

    def axis(r) -> np.ndarray:
        _, o, z, x = ents[str(r)][1]
        z, x = xyz(z), xyz(x)
        m = np.eye(4)
        m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, np.cross(z, x), z, xyz(o)
        return m

    by_kind: dict[str, list[str]] = {}
    for r, (kind, _) in ents.items():
        by_kind.setdefault(kind, []).append(r)
    place = {}
    for r in by_kind["CONTEXT_DEPENDENT_SHAPE_REPRESENTATION"]:
        rel, pds = ents[r][1]
        parts = dict(ents[str(rel)][1])
        idt = parts["REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION"][0]
        a1, a2 = ents[str(idt)][1][2:4]
        place[str(ents[str(pds)][1][2])] = axis(a2) @ np.linalg.inv(axis(a1))
    brep_of = {}
    for r in by_kind["SHAPE_DEFINITION_REPRESENTATION"]:
        pds, rep = ents[r][1]
        items = [str(i) for i in ents[str(rep)][1][1]]
        breps = [i for i in items if ents[i][0] == "MANIFOLD_SOLID_BREP"]
        if breps:
            brep_of[str(ents[str(pds)][1][2])] = breps[0]
    found = {}
    for r in by_kind["NEXT_ASSEMBLY_USAGE_OCCURRENCE"]:
        _, name, _, parent, child, _ = ents[r][1]
        if str(child) not in brep_of:
            continue
        m = place[r]
        up = {str(ents[pr][1][4]): pr for pr in by_kind["NEXT_ASSEMBLY_USAGE_OCCURRENCE"]}
        while str(parent) in up:                                        # the parents' placements up to the root
            pr = up[str(parent)]
            m = place[pr] @ m
            parent = ents[pr][1][3]
        loops, circles = [], {}
        for face in ents[str(ents[brep_of[str(child)]][1][1])][1][1]:
            _, bounds, _, same = ents[str(face)][1]
            for b in bounds:
                _, loop, orient = ents[str(b)][1]
                ring = []
                for oe in ents[str(loop)][1][1]:
                    edge, forward = ents[str(oe)][1][3], ents[str(oe)][1][4] == ".T."
                    v1, v2, curve = ents[str(edge)][1][1:4]
                    ring.append(xyz(ents[str(v1 if forward else v2)][1][1]))
                    if ents[str(curve)][0] == "CIRCLE":                  # each circular edge once
                        c = axis(ents[str(curve)][1][1]) @ np.array([0.0, 0.0, 0.0, 1.0])
                        circles[str(edge)] = ((m @ c)[:3], float(ents[str(curve)][1][2]))
                ring = np.array(ring) @ m[:3, :3].T + m[:3, 3]
                loops.append(ring if (orient == ".T.") == (same == ".T.") else ring[::-1])
        pts = np.unique(np.round(np.vstack(loops), 9), axis=0)
        c = pts.mean(axis=0)
        vol = sum(float(np.dot(r0 - c, np.cross(r1 - c, r2 - c))) for ring in loops
                  for r0, r1, r2 in zip([ring[0]] * (len(ring) - 2), ring[1:-1], ring[2:])) / 6.0
        found[name] = (pts, vol, list(circles.values()))
    return found


def test_a_third_reader_on_steputils_finds_the_same_solids(written):
    """steputils parses the file; the product tree, placements and B-reps are followed apart from ppfab's
    readers, and volumes summed over fan triangles of the oriented face loops."""
    path, solids, volumes, beams = written
    found = steputils_solids(path)
    assert sorted(found) == sorted(s.label for s in solids)
    for s, vol in zip(solids, volumes):
        pts, got, circles = found[s.label]
        assert _distance(pts, s.placed()) <= 1e-9 and circles == []
        assert got == pytest.approx(vol, rel=1e-9)


def test_bad_input_is_refused_by_name():
    f = Frame(np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    with pytest.raises(FabricationError, match="GS-1: a prism needs an outline of at least 3 points"):
        PlanarSolid.prism("GS-1", COLOURS["rows"], np.zeros((2, 2)), f, 0.0, 1.0)
    with pytest.raises(FabricationError, match="GS-2: a prism needs a positive height"):
        PlanarSolid.prism("GS-2", COLOURS["rows"], OUTLINES["box"], f, 0.0, 0.0)
    ok = PlanarSolid.prism("GS-3", COLOURS["rows"], OUTLINES["box"], f, 0.0, 1.0)
    sheared = PlanarSolid(ok.label, ok.colour, ok.vertices, ok.faces, np.diag([1.0, 2.0, 1.0, 1.0]))
    with pytest.raises(FabricationError, match="GS-3: its placement is not a rigid motion"):
        step_text(Assembly("x", [sheared]), "x.step")
    broken = PlanarSolid(ok.label, ok.colour, ok.vertices * np.nan, ok.faces, ok.placement)
    with pytest.raises(FabricationError, match="not a finite number"):
        step_text(Assembly("x", [broken]), "x.step")


def test_reals_are_written_exactly():
    for x in (1.0, -0.0, 1e-07, 1234.5678, 0.1 + 0.2, -2.5e300, 1.0 / 3.0):
        text = real(x)
        assert "." in text and "e" not in text
        assert float(text) == x


def test_panes_of_a_real_surface_of_revolution_are_instanced_and_read_back_on_their_faces(tmp_path):
    """DOI__rot4_def1_sparse_rot.obj (WWmore/DOI, objs/obj_rot/rot4_def1_sparse_rot.obj): the faces of one ring
    are rotated copies, so their panes share B-reps; every pane read back (text reader; kernel on the tree and
    one solid per kind; the kernel on every solid) lies on its face's least-squares plane (numpy's SVD here) and
    10 mm outside it."""
    from conftest import shared_file
    from fabrication.writers.step import export_panels_step
    from ppfab.io import load_mesh

    corners = np.asarray(load_mesh(shared_file("DOI__rot4_def1_sparse_rot.obj")).face_corners, dtype=float)[:400]
    ids = [f"P-{k:04d}" for k in range(len(corners))]
    path = export_panels_step(corners, tmp_path / "panels.step", thickness=10.0, ids=ids, name="rot4")
    breps = path.read_bytes().count(b"= MANIFOLD_SOLID_BREP(")
    assert breps < len(corners) // 3                                  # of 400 panes
    text = read_text_solids(path)
    assert [s.name for s in text] == ids and all(s.problems() == [] for s in text)
    assert kernel_sample(path, text) == []
    kernel = {s.name: np.array([tuple(v) for v in s.solid.vertices()]) for s in read_step_solids(path)}
    for k, s in enumerate(text):
        c = corners[k]
        n = np.linalg.svd(c - c.mean(axis=0))[2][2]
        n = n if n @ np.cross(c[2] - c[0], c[3] - c[1]) > 0 else -n
        for pts in (s.points, kernel[s.name]):
            d = np.sort((pts - c.mean(axis=0)) @ n)
            assert len(d) == 8
            assert np.abs(d[:4]).max() <= 1e-6 and np.abs(d[4:] - 10.0).max() <= 1e-6, (s.name, d)


def test_an_instanced_shape_is_rebuilt_once_for_the_erection_check_and_moved_where_each_solid_stands(written):
    """The erection check's bodies of an instanced file (three boxes, one B-rep): each moved from the first box's
    body (``bodies_of``) is the body rebuilt from that solid alone (``body_of``) — the same corners as point sets,
    the same polygon area and thickness, the same solid (manifold3d: nothing of either outside the other) — and every
    solid's placed faces hold its placed vertices."""
    from fabrication.verify._bodies import bodies_of, body_of

    path, solids, volumes, beams = written
    read = read_text_solids(path)
    by_brep: dict[int, list] = {}
    for s in read:
        by_brep.setdefault(s.brep, []).append(s)
    shared = [group for group in by_brep.values() if len(group) > 1]
    assert [len(g) for g in shared] == [3]
    moved = bodies_of({s.name: s for s in read})
    for s in read:
        alone = body_of(s)
        got = moved[s.name]
        assert _distance(got.corners, alone.corners) <= 1e-9
        assert got.flat.area == pytest.approx(alone.flat.area, rel=1e-12)
        assert got.thick == pytest.approx(alone.thick, abs=1e-9)
        assert abs(float(got.n @ alone.n)) == pytest.approx(1.0, abs=1e-12)
        a, b = got.shape(), alone.shape()
        assert a.volume() == pytest.approx(alone.flat.area * alone.thick, rel=1e-9)
        assert (a - b).volume() <= 1e-6 * a.volume() and (b - a).volume() <= 1e-6 * a.volume()
        for f in s.faces():                                  # the lazily placed faces carry the placed vertices
            idx = np.concatenate([lp.vertices for lp in f.loops])
            assert np.abs((s.points[idx] - f.origin) @ f.normal).max() <= 1e-9


def test_the_file_is_written_in_pieces_with_the_bytes_of_the_whole_text(tmp_path, monkeypatch):
    """``write_step`` writes the DATA section a few records at a time (a large file is never one string): the file
    holds exactly the bytes of ``step_text``, whatever the size of the pieces, and the text-level reader reads
    every solid from it."""
    from fabrication.writers import step_template

    solids, _, beams = _solids()
    whole = step_text(_tree(solids, beams), "glazing.step", "glazing of a demo")
    assert whole.count(b";\n#") > 300
    for size in (1, 7, 20_000):
        monkeypatch.setattr(step_template, "PIECE_RECORDS", size)
        (tmp_path / f"p{size}").mkdir()
        path = write_step(_tree(solids, beams), tmp_path / f"p{size}" / "glazing.step", "glazing of a demo")
        assert path.read_bytes() == whole
    assert len(read_text_solids(path)) == len(solids)


def test_writing_leaves_no_reference_cycle_to_collect(tmp_path):
    """A write lets go of the file's lines when it returns: with the cyclic collector off, nothing it made is left
    in a reference cycle (a recursive closure over the lines held them until the next collection)."""
    from conftest import left_for_the_collector

    solids, _, beams = _solids()
    path, left = left_for_the_collector(
        lambda: write_step(_tree(solids, beams), tmp_path / "glazing.step", "glazing of a demo"))
    assert path.stat().st_size > 0 and left == 0
