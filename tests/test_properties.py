"""Property-based tests (hypothesis) across the core and the panel layer: flattening is an isometry,
offsets keep planarity and the PP property, grid recovery is independent of vertex order."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ppfab.faceimage import pp_from_face_image
from ppfab.mesh import QuadMesh
from ppfab.metrics import face_planarity, plane_residual, polyline_planarity

from conftest import smooth_face_image


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(400.0, 2500.0), st.floats(0.0, 30.0))
def test_flattening_a_planar_quad_is_an_isometry(seed, size, gap):
    from fabrication.panels import PanelParams, make_panels

    rng = np.random.default_rng(seed)
    # a convex quad: corners on a circle at sorted random angles, jittered radius; no edge shorter than
    # about a quarter of the size (a quad with a 3 mm edge cannot be inset by gap/2 = 15 mm)
    ang = np.sort(rng.uniform(0, 2 * np.pi, 4))
    steps = np.diff(np.r_[ang, ang[0] + 2 * np.pi])
    if steps.max() > 0.9 * np.pi or steps.min() < 0.3:
        ang = np.array([0.2, 1.8, 3.3, 4.9]) + rng.uniform(-0.2, 0.2, 4)
    rad = size * rng.uniform(0.8, 1.2, 4)
    flat = np.stack([rad * np.cos(ang), rad * np.sin(ang), np.zeros(4)], axis=1)
    corners = flat @ random_rotation(rng).T + rng.uniform(-5e4, 5e4, 3)
    mesh = QuadMesh(corners, np.array([[0, 1, 2, 3]]))
    panel = make_panels(mesh, PanelParams(gap=0.0, planarity_tolerance=1e-3))[0]
    # the flat outline maps back onto the 3D corners, and edge lengths / angles are kept
    back = panel.frame.to3d(panel.outline)
    d = np.linalg.norm(back[:, None] - corners[None], axis=-1).min(axis=1)
    assert d.max() < 1e-6
    e2 = np.linalg.norm(np.roll(panel.outline, -1, 0) - panel.outline, axis=1)
    e3 = np.linalg.norm(np.roll(back, -1, 0) - back, axis=1)
    assert np.abs(e2 - e3).max() < 1e-6
    if gap > 0:
        inset = make_panels(mesh, PanelParams(gap=gap, planarity_tolerance=1e-3))[0]
        # every inset corner lies gap/2 from both face edges meeting at its corner (in the face plane)
        o3 = inset.frame.to3d(inset.outline)
        for k, c in enumerate(inset.corner_index):
            for a_, b_ in ((corners[c - 1], corners[c]), (corners[c], corners[(c + 1) % 4])):
                t = (b_ - a_) / np.linalg.norm(b_ - a_)
                w = o3[k] - a_
                assert abs(np.linalg.norm(w - (w @ t) * t) - gap / 2) < 1e-6


@settings(max_examples=30, deadline=None)
@given(st.integers(2, 9), st.integers(2, 9), st.integers(0, 1000), st.floats(-0.05, 0.05))
def test_offsets_keep_planarity_and_pp(m, n, seed, distance):
    from ppfab.transforms.pp import offset_along_axes

    grid = pp_from_face_image(*smooth_face_image(m, n, seed))
    for mode in ("parallel", "f_transform"):
        off = offset_along_axes(grid, distance, mode=mode)
        assert face_planarity(off.face_corners).max() <= 1e-9
        assert plane_residual(off.rows(), grid.support_u).max() <= 1e-9
        assert plane_residual(off.cols(), grid.support_w).max() <= 1e-9
        if min(off.shape) >= 3:
            assert polyline_planarity(off.rows()).max() <= 1e-9
    # the parallel offset has parallel edges (a Combesure transform, §2.2.3)
    off = offset_along_axes(grid, distance, mode="parallel")
    e0, e1 = np.diff(grid.vertices, axis=1), np.diff(off.vertices, axis=1)
    cross = np.linalg.norm(np.cross(e0, e1), axis=-1) / (np.linalg.norm(e0, axis=-1) ** 2)
    assert cross.max() < 1e-9


@settings(max_examples=25, deadline=None)
@given(st.integers(1, 7), st.integers(1, 7), st.integers(0, 10_000))
def test_grid_recovery_is_independent_of_vertex_order(m, n, seed):
    grid = pp_from_face_image(*smooth_face_image(m, n, seed % 97))
    rng = np.random.default_rng(seed)
    qm = grid.to_quadmesh()
    perm = rng.permutation(len(qm.vertices))
    faces = np.argsort(perm)[qm.faces]
    faces = np.array([np.roll(f, rng.integers(4)) for f in faces])[rng.permutation(len(faces))]
    back = QuadMesh(qm.vertices[perm], faces).to_grid()
    assert sorted(back.shape) == sorted(grid.shape)
    assert np.allclose(np.sort(back.vertices.reshape(-1, 3), axis=0), np.sort(grid.vertices.reshape(-1, 3), axis=0))
    # every recovered face is a face of the input with the same orientation
    src = {tuple(np.roll(f, -int(np.argmin(f)))) for f in faces.tolist()}
    ids = back.vertex_ids
    quads = np.stack([ids[:-1, :-1], ids[1:, :-1], ids[1:, 1:], ids[:-1, 1:]], -1).reshape(-1, 4)
    assert all(tuple(np.roll(q, -int(np.argmin(q)))) in src for q in quads.tolist())
