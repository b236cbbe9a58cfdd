"""Beam plates and splice cover plates written from the STEP template (fabrication/writers/step_template.py): round
bolt holes (a circle on each face and a cylindrical face with a seam) and plates bevelled under their strips (the
solid between two face outlines).  Each file is read back by the CAD kernel's STEP reader and by verify's text-level
reader, and every solid is held to the one the kernel builds itself from the same plate (polygon faces sewn, holes
cut by boolean subtraction of cylinders: ``fabrication.writers.step.plate_solid``) and to a volume worked out here
(the prismatoid rule, exact for a solid whose cross-section area is quadratic in the height)."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REPO
from kernel_solids import stages
from test_step_template import _frame, steputils_solids
from fabrication.contract import COLOURS
from fabrication.verify._step_read import kernel_sample, read_step_solids
from fabrication.verify._step_text_read import read_text_solids
from fabrication.writers.step_template import Assembly, PlanarSolid, step_text, write_step
from ppfab.errors import FabricationError
from ppfab.frame import Frame


def _shoelace(q: np.ndarray) -> float:
    return 0.5 * abs(float(np.sum(q[:, 0] * np.roll(q[:, 1], -1) - np.roll(q[:, 0], -1) * q[:, 1])))


def _prismatoid(top: np.ndarray, bottom: np.ndarray, t: float) -> float:
    """Volume between two outlines with corresponding corners a height ``t`` apart, joined by ruled sides:
    ``t/6 (A_top + 4 A_mid + A_bottom)`` (the section's area is quadratic in the height)."""
    return t / 6.0 * (_shoelace(top) + 4.0 * _shoelace(0.5 * (top + bottom)) + _shoelace(bottom))


def _distance(a: np.ndarray, b: np.ndarray) -> float:
    if len(a) == 0 and len(b) == 0:
        return 0.0
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    return float(max(d.min(axis=0).max(), d.min(axis=1).max()))


def _kernel_corners_and_centres(solid) -> tuple[np.ndarray, np.ndarray]:
    """A kernel solid's vertices not on a circle, and its circles' centres (each once)."""
    from build123d import GeomType

    circles = [e for e in solid.edges() if e.geom_type == GeomType.CIRCLE]
    centres = np.array([tuple(e.arc_center) for e in circles]).reshape(-1, 3)
    on_circle = np.array([tuple(e.start_point()) for e in circles]).reshape(-1, 3)
    pts = np.array([tuple(v) for v in solid.vertices()])
    if len(on_circle):
        pts = pts[np.linalg.norm(pts[:, None] - on_circle[None], axis=2).min(axis=1) > 1e-9]
    return pts, np.unique(np.round(centres, 9), axis=0)


def _text_corners(solid) -> np.ndarray:
    on_arc = {int(lp.vertices[k]) for f in solid.shell for lp in f.loops for k, a in enumerate(lp.arcs)
              if a is not None}
    return solid.points[[i for i in range(len(solid.points)) if i not in on_arc]]


@pytest.fixture(scope="module")
def plates_written(tmp_path_factory):
    """The plates of examples/smallest_roof.toml bevelled under their strips (14 of 24, each with the bolt holes of
    its splices), written as beams.step from the template."""
    from fabrication.beams.bevel_cut import bevelled_beams
    from fabrication.writers.step import beam_tree

    beams, glazing = stages(REPO / "examples" / "smallest_roof.toml")
    plates = list(bevelled_beams(beams, glazing).plates)
    path = tmp_path_factory.mktemp("plates") / "beams.step"
    write_step(beam_tree(plates, "smallest roof"), path, "beam plates of smallest roof")
    return plates, path, glazing


def test_plates_have_holes_and_bevels(plates_written):
    plates, _, _ = plates_written
    assert sum(bool(p.bevels) and len(p.holes) > 0 for p in plates) >= 10
    assert sum(not p.bevels for p in plates) >= 5


def test_the_kernel_reads_each_plate_as_it_builds_it_itself(plates_written):
    """Every plate read back by the kernel is valid (BRepCheck) and equals the solid the kernel makes from the same
    plate: the same corners and circle centres to 1e-9 mm, the same volume to 1e-9; and that volume is the
    prismatoid's less the holes."""
    from fabrication.beams.bevel_cut import face_outlines
    from fabrication.writers.step import plate_solid

    plates, path, _ = plates_written
    read = {s.name: s for s in read_step_solids(path, colours=True)}
    assert sorted(read) == sorted(p.part_id for p in plates)
    for p in plates:
        got, made = read[p.part_id].solid, plate_solid(p)
        assert got.is_valid, p.part_id
        a, ca = _kernel_corners_and_centres(got)
        b, cb = _kernel_corners_and_centres(made)
        assert len(a) == len(b) and _distance(a, b) <= 1e-9, p.part_id
        assert len(ca) == len(cb) == 2 * len(p.holes) and _distance(ca, cb) <= 1e-9, p.part_id  # a circle per face
        front, back = face_outlines(p)
        want = _prismatoid(front, back, p.thickness) - p.thickness * float(np.sum(np.pi / 4.0 * p.holes[:, 2] ** 2))
        assert got.volume == pytest.approx(made.volume, rel=1e-9)
        assert got.volume == pytest.approx(want, rel=1e-9)
        colour = read[p.part_id].colour
        assert colour is not None
        family = "rows" if p.family == 0 else "cols"
        assert max(abs(x - y) for x, y in zip(colour[:3], COLOURS[family][:3])) <= 1e-6


def test_the_text_reader_agrees_with_the_kernel(plates_written):
    plates, path, _ = plates_written
    kernel = {s.name: s.solid for s in read_step_solids(path)}
    text = read_text_solids(path)
    assert {s.name: s.path for s in text} == {p.part_id: ("smallest roof", "rows" if p.family == 0 else "cols",
                                                          p.beam_id) for p in plates}
    for s in text:
        assert s.problems() == [], s.name
        k = kernel[s.name]
        assert s.volume == pytest.approx(k.volume, rel=1e-9)
        corners, centres = _kernel_corners_and_centres(k)
        assert _distance(_text_corners(s), corners) <= 1e-9
        assert _distance(np.unique(np.round(s.circle_centres(), 9), axis=0), centres) <= 1e-9
    assert kernel_sample(path, text) == []


def test_splice_cover_plates_are_one_shape_per_type_each_where_it_stands(plates_written, tmp_path):
    """splices.step from the template: the two cover plates of a splice share one B-rep (and splices of one type);
    the kernel places each where the kernel-built cover plate (polygon with circles extruded) stands."""
    from fabrication.writers.glazing import splice_prisms, splice_solids

    _, _, glazing = plates_written
    prisms = splice_prisms(glazing)
    path = tmp_path / "splices.step"
    write_step(Assembly("smallest roof splices", prisms), path, "splice cover plates")
    assert path.read_bytes().count(b"= MANIFOLD_SOLID_BREP(") <= len(prisms) // 2
    read = {s.name: s.solid for s in read_step_solids(path)}
    text = {s.name: s for s in read_text_solids(path)}
    made = {s.label: s for s in splice_solids(glazing)}
    assert sorted(read) == sorted(made) == sorted(text)
    for name, solid in read.items():
        assert solid.is_valid
        a, ca = _kernel_corners_and_centres(solid)
        b, cb = _kernel_corners_and_centres(made[name])
        assert _distance(a, b) <= 1e-9 and _distance(ca, cb) <= 1e-9 and len(ca) == len(cb) > 0
        assert solid.volume == pytest.approx(made[name].volume, rel=1e-9)
        assert text[name].volume == pytest.approx(solid.volume, rel=1e-9) and text[name].problems() == []


def test_drilled_and_bevelled_solids_in_random_frames(tmp_path):
    """Prisms with holes (one shape twice, instanced), a loft with a corner that closes on one face (a side face
    turns into a triangle) and holes, a clockwise loft: the kernel and the text reader read each valid, with the
    prismatoid's volume less the holes, the holes' centres where they were put."""
    rng = np.random.default_rng(7)
    box = np.array([[0.0, 0.0], [600.0, 0.0], [600.0, 120.0], [0.0, 120.0]])
    holes = np.array([[60.0, 60.0, 22.0], [540.0, 60.0, 22.0], [300.0, 40.0, 13.0]])
    # a bevel moves the long upper edge down 10 mm on the top face, parallel to itself: the short edge beside it
    # shrinks to a point there, so its side face is a triangle; every side face joins two parallel edges
    bottom = np.array([[0.0, 0.0], [500.0, 0.0], [500.0, 100.0], [480.0, 110.0], [0.0, 110.0]])
    top = np.array([[0.0, 0.0], [500.0, 0.0], [500.0, 100.0], [500.0, 100.0], [0.0, 100.0]])
    frames = [_frame(rng) for _ in range(4)]
    solids = [PlanarSolid.prism("B-1", COLOURS["rows"], box, frames[0], -5.0, 10.0, holes),
              PlanarSolid.prism("B-2", COLOURS["rows"], box, frames[1], -5.0, 10.0, holes),
              PlanarSolid.loft("B-3", COLOURS["cols"], top, bottom, frames[2], 12.0, holes[:1] * [0.5, 0.5, 1.0]),
              PlanarSolid.loft("B-4", None, top[::-1], bottom[::-1], frames[3], 8.0)]
    want = [(_shoelace(box) - np.pi / 4 * float(np.sum(holes[:, 2] ** 2))) * 10.0] * 2
    want += [_prismatoid(top, bottom, 12.0) - np.pi / 4 * 22.0 ** 2 * 12.0, _prismatoid(top, bottom, 8.0)]
    centres = [np.column_stack([holes[:, :2], np.zeros(3)]), np.column_stack([holes[:, :2], np.zeros(3)]),
               np.array([[30.0, 30.0, 0.0]]), np.zeros((0, 3))]
    path = write_step(Assembly("demo", solids), tmp_path / "plates.step", "plates")
    assert path.read_bytes().count(b"= MANIFOLD_SOLID_BREP(") == 3            # B-1 and B-2 one shape
    assert path.read_bytes().count(b"= CYLINDRICAL_SURFACE(") == 4
    kernel = {s.name: s.solid for s in read_step_solids(path)}
    text = {s.name: s for s in read_text_solids(path)}
    for s, vol, c, f in zip(solids, want, centres, frames):
        k = kernel[s.label]
        assert k.is_valid and k.volume == pytest.approx(vol, rel=1e-9), s.label
        assert text[s.label].problems() == [] and text[s.label].volume == pytest.approx(vol, rel=1e-9)
        placed = f.origin + c[:, :1] * f.ex + c[:, 1:2] * f.ey
        _, kc = _kernel_corners_and_centres(k)
        if len(c):                                             # a circle on each face: its centre on the axis
            on_axis = np.linalg.norm(np.cross(kc[:, None] - placed[None], f.normal), axis=2).min(axis=1)
            assert len(kc) == 2 * len(c) and on_axis.max() <= 1e-9
        assert _distance(_text_corners(text[s.label]), _kernel_corners_and_centres(k)[0]) <= 1e-9
    assert len(text["B-3"].points) == 4 + 5 + 1 * 2            # the two corners meeting on the top face merged
    third = steputils_solids(path)                             # a third reader, apart from ppfab's and the kernel's
    assert sorted(third) == sorted(s.label for s in solids)
    for s, c, f in zip(solids, centres, frames):
        placed = f.origin + c[:, :1] * f.ex + c[:, 1:2] * f.ey
        got = third[s.label][2]
        assert len(got) == 2 * len(c) == 2 * len(s.bores)                 # a circle on each face
        for centre, radius in got:                                    # on a hole's axis, of its radius
            k = int(np.argmin(np.linalg.norm(np.cross(centre - placed, f.normal), axis=1)))
            assert np.linalg.norm(np.cross(centre - placed[k], f.normal)) <= 1e-9
            assert radius == pytest.approx(s.bores[k].radius, abs=1e-12)
        corners = _text_corners(text[s.label])                        # the same corners as the text reader
        far = third[s.label][0]
        far = far[np.linalg.norm(far[:, None] - corners[None], axis=2).min(axis=1) <= 1e-9]
        assert len(far) == len(corners)


def test_holes_that_are_not_inside_the_plate_are_refused_by_name():
    f = Frame(np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    box = np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 50.0], [0.0, 50.0]])
    with pytest.raises(FabricationError, match=r"B-1: hole 1 at \(95.0, 25.0\), Ø 12 mm, is not inside"):
        PlanarSolid.prism("B-1", None, box, f, 0.0, 10.0, np.array([[95.0, 25.0, 12.0]]))
    with pytest.raises(FabricationError, match="B-2: hole 1 .* is not inside"):
        PlanarSolid.prism("B-2", None, box, f, 0.0, 10.0, np.array([[150.0, 25.0, 12.0]]))
    with pytest.raises(FabricationError, match="B-3: holes 1 and 2 .* overlap"):
        PlanarSolid.prism("B-3", None, box, f, 0.0, 10.0, np.array([[30.0, 25.0, 12.0], [40.0, 25.0, 12.0]]))
    with pytest.raises(FabricationError, match="B-4: hole 1 needs a finite centre and a positive diameter"):
        PlanarSolid.prism("B-4", None, box, f, 0.0, 10.0, np.array([[30.0, 25.0, 0.0]]))
    with pytest.raises(FabricationError, match="B-5: its two face outlines turn opposite ways"):
        PlanarSolid.loft("B-5", None, box, box[::-1], f, 10.0)
    top = box.copy()
    top[1, 0] = 80.0                                          # the top face is narrower: the hole leaves it
    with pytest.raises(FabricationError, match="B-6: hole 1 .* is not inside"):
        PlanarSolid.loft("B-6", None, top, box, f, 10.0, np.array([[85.0, 10.0, 8.0]]))
    ok = PlanarSolid.prism("B-7", None, box, f, 0.0, 10.0, np.array([[50.0, 25.0, 12.0]]))
    assert b"CYLINDRICAL_SURFACE" in step_text(Assembly("x", [ok]), "x.step")
