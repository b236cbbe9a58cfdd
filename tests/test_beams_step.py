"""beams.step / panels.step: build123d solids, exported and re-imported."""

from __future__ import annotations

import numpy as np
import pytest

from fabrication.beams import BeamParams, build_beams
from fabrication.beams.samples import sample_p_grid, sample_pp_grid
from fabrication.writers.step import (build_solids, check_step, export_panels_step, export_step, named_solids,
                                      solid_vertices)
from ppfab.support.p import support_p
from ppfab.support.pp import support_pp

pytest.importorskip("build123d")


@pytest.fixture(scope="module")
def pp_step(tmp_path_factory):
    s = support_pp(sample_pp_grid(4, 5))
    bs = build_beams(s, BeamParams(max_length=0, depth=250.0, thickness=15.0))
    path = tmp_path_factory.mktemp("step") / "beams.step"
    export_step(build_solids(list(bs.plates)), path)
    return s, bs, path, solid_vertices(path)


def test_one_valid_plate_solid_per_beam_in_its_support_plane(pp_step):
    s, bs, path, _ = pp_step
    planes = {p.part_id: s.polyline_planes[p.polyline] for p in bs.plates}     # the support structure's own
    res = check_step(path, bs.plates, tol=1e-6, planes=planes)
    assert res.ok, res.problems
    assert res.solids == len(bs.plates) == sum(s.mesh.grid.shape)
    assert res.max_thickness_error < 1e-6
    from build123d import import_step

    pairs = named_solids(import_step(str(path)))
    assert sorted(n for n, _ in pairs) == sorted(p.part_id for p in bs.plates)
    for name, solid in pairs:
        p = bs.by_id[name]
        x = np.array([[v.X, v.Y, v.Z] for v in solid.vertices()])
        dist = x @ planes[name][:3] + planes[name][3]
        assert np.abs(np.abs(dist) - 7.5).max() < 1e-6                 # both faces, 15 mm apart
        assert (dist > 0).sum() == (dist < 0).sum() == len(p.outline)   # one extrusion of the outline
        assert solid.volume == pytest.approx(p.area * 15.0, rel=1e-9)


def test_slots_of_crossing_beams_share_the_node_axis_in_the_step_file(pp_step):
    s, bs, _, verts = pp_step
    t, d = bs.params.thickness, bs.params.depth
    n_checked = 0
    for j in bs.joints:
        if j.kind != "halflap":
            continue
        v, a = s.vertices[j.vertex], s.axes[j.vertex]
        for pid in j.parts:
            p = bs.by_id[pid]
            n = p.plane[:3]
            across = np.cross(n, a)
            across /= np.linalg.norm(across)
            # the closed end of the slot (slot_play past half the depth from its edge): four corners predicted
            # from the node axis alone
            sl = next(x for x in p.slots if x.node == j.vertex)
            at = 0.5 * d + (bs.params.slot_play if sl.from_top else -bs.params.slot_play)
            pred = np.array([v + at * a + sw * 0.5 * j.slot_width * across + sn * 0.5 * t * n
                             for sw in (-1, 1) for sn in (-1, 1)])
            x = verts[pid]
            gap = np.linalg.norm(x[None, :, :] - pred[:, None, :], axis=2).min(axis=1)
            assert gap.max() < 1e-6, (pid, j.vertex, gap)
            n_checked += 1
    m1, n1 = s.mesh.grid.shape
    assert n_checked == 2 * (m1 - 2) * (n1 - 2)


def test_segmented_p_mesh_step(tmp_path):
    s = support_p(sample_p_grid(3, 4), "rows")
    bs = build_beams(s, BeamParams(joint="segmented", max_length=0))
    path = export_step(build_solids(list(bs.plates)), tmp_path / "beams.step")
    res = check_step(path, bs.plates)
    assert res.ok, res.problems
    assert res.solids == 4 + 5 * 3
    assert "B-W02-S01" in solid_vertices(path)


def test_panels_step_for_clash_checks(tmp_path):
    g = sample_pp_grid(2, 3)
    corners = g.to_quadmesh().face_corners
    ids = [f"P-{i}-{j}" for i in range(2) for j in range(3)]
    path = export_panels_step(corners, tmp_path / "panels.step", thickness=10.0, ids=ids)
    verts = solid_vertices(path)
    assert sorted(verts) == sorted(ids)
    planes = g.face_planes.reshape(-1, 4)
    for k, name in enumerate(ids):
        dist = verts[name] @ planes[k, :3] + planes[k, 3]
        assert len(dist) == 8
        assert np.sort(dist)[:4] == pytest.approx(np.zeros(4), abs=1e-6)    # on the mesh face …
        assert np.sort(dist)[4:] == pytest.approx(np.full(4, 10.0), abs=1e-6)  # … and 10 mm outside


@pytest.mark.parametrize("clockwise", [False, True])
def test_placed_prism_is_the_outline_extruded_along_the_frame_normal(clockwise):
    """The kernel-built prism against the formula: vertices ``frame.to3d(outline) + z·n`` for ``z = z0`` and
    ``z0 + h``, volume = shoelace area × ``h``, valid for the kernel; for a non-convex (notched) outline in a
    tilted frame far from the origin, in either turning sense."""
    from OCP.BRepCheck import BRepCheck_Analyzer

    from fabrication.writers.step import _placed_prism
    from ppfab.frame import Frame

    outline = np.array([[0, 0], [900, 0], [900, 180], [520, 180], [520, 90], [480, 90], [480, 180], [0, 180]], float)
    if clockwise:
        outline = outline[::-1]
    rng = np.random.default_rng(7)
    ex = rng.normal(size=3)
    ex /= np.linalg.norm(ex)
    ey = np.cross(rng.normal(size=3), ex)
    ey /= np.linalg.norm(ey)
    frame = Frame(np.array([31_250.0, -18_400.0, 7_250.0]), ex, ey)
    z0, h = -7.5, 15.0
    solid = _placed_prism(outline, frame, z0, h, "B-U03-S00")
    assert BRepCheck_Analyzer(solid.wrapped).IsValid() and solid.label == "B-U03-S00"
    got = np.array([[v.X, v.Y, v.Z] for v in solid.vertices()])
    want = np.vstack([frame.to3d(outline) + z * frame.normal for z in (z0, z0 + h)])
    assert len(got) == len(want) == 16
    d = np.linalg.norm(got[:, None, :] - want[None, :, :], axis=2)
    assert d.min(axis=1).max() < 1e-6 and d.min(axis=0).max() < 1e-6
    x, y = outline.T
    area = 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
    assert solid.volume == pytest.approx(area * h, rel=1e-9)
    assert len(solid.faces()) == len(outline) + 2
