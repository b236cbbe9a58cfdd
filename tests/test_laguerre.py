"""Laguerre maps, Möbius transforms of normals, Minkowski polar projection, §4.3 edits and Remark 2.2."""

from __future__ import annotations


import numpy as np
import pytest

from ppfab.transforms import isotropic
from ppfab import planes as pl
from ppfab.conical.cones import conical_quality, extended_planes, offset_faces
from ppfab.constructions.conical_pp import Series, conical_pp_grid
from ppfab.constructions.conical_spheres import channel_mesh
from ppfab.conical.edit import ConicalEditor, edit_conical, fit_lorentz, mobius_of_laguerre
from ppfab.errors import FoldError, GeometryError
from ppfab.transforms.isotropic import IsotropicMobius, quad_circularity, quad_planarity_4d
from ppfab.conical.cones import laguerre_transform
from ppfab.transforms.laguerre import (J, LaguerreMap, boost, is_lorentz, lorentz_residual, minkowski_polar,
                                       project_lorentz, spatial)
from ppfab.metrics import quality
from ppfab.conical.spheres import SphereSpline, bisector_normals, reflections, w_planes

from conftest import conical_zoo

TOL = 1e-9
WAVY = np.array([[0, 0, 2, 5.0], [8, 3, 3, 6], [16, -2, 2.5, 5.5], [24, 0, 2, 4.5], [30, 2, 3, 5]])


def rotation(seed: int) -> np.ndarray:
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def random_lorentz(seed: int, rapidity: float = 0.3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return spatial(rotation(seed)) @ boost(rng.normal(size=3), rapidity) @ spatial(rotation(seed + 100))


def meshes():
    """A conical P mesh (spheres), conical PP meshes (spheres §4.2.4, eq. 11, sections)."""
    return conical_zoo()


MESHES = meshes()


def assert_conical_planar(grid, families, tol=TOL):
    q = conical_quality(grid)
    assert q.delta_f_max <= tol and q.angle_max <= tol and q.concyclic_max <= tol
    if "rows" in families:
        assert q.delta_p_rows_max <= tol
    if "cols" in families:
        assert q.delta_p_cols_max <= tol


# -- the group ---------------------------------------------------------------------------------------

@pytest.mark.parametrize("seed", range(4))
def test_lorentz_generators_and_polar_decomposition(seed):
    A = random_lorentz(seed)
    assert is_lorentz(A, 1e-12)
    M = A + 0.05 * np.random.default_rng(seed).normal(size=(4, 4))
    P, S = minkowski_polar(M)
    assert lorentz_residual(P) < 1e-12                      # P ∈ O(3,1)
    assert np.allclose(P @ S, M, atol=1e-12)                 # M = P S
    assert np.allclose(J @ S.T @ J, S, atol=1e-12)           # S J-selfadjoint
    assert np.all(np.linalg.eigvals(S).real > 0)
    assert np.allclose(project_lorentz(-3.0 * A), A, atol=1e-12)   # scale and sign removed


def test_polar_decomposition_fails_clearly():
    with pytest.raises(GeometryError, match="no Minkowski polar decomposition"):
        minkowski_polar(np.diag([1.0, 1.0, 1.0, 0.0]) + np.diag([0, 0, 0, 1e-20]) @ np.eye(4) * 0)
    with pytest.raises(GeometryError, match="not a Lorentz matrix"):
        LaguerreMap(np.diag([2.0, 1, 1, 1]))


def random_map(seed: int) -> LaguerreMap:
    rng = np.random.default_rng(seed)
    return LaguerreMap(random_lorentz(seed, 0.25), float(rng.uniform(0.7, 1.3)), rng.normal(scale=0.5, size=4))


@pytest.mark.parametrize("seed", range(3))
def test_laguerre_map_preserves_oriented_contact(seed):
    rng = np.random.default_rng(seed)
    L = random_map(seed)
    planes = pl.normalize(np.c_[rng.normal(size=(20, 3)), rng.normal(size=20)])
    # spheres touching each plane: centre anywhere, r = −(n·c + d)
    c = rng.normal(scale=3, size=(20, 3))
    r = -(np.einsum("ki,ki->k", planes[:, :3], c) + planes[:, 3])
    S2 = L.spheres(np.c_[c, r])
    P2 = L.planes(planes)
    assert np.allclose(np.linalg.norm(P2[:, :3], axis=1), 1.0)
    assert np.abs(np.einsum("ki,ki->k", P2[:, :3], S2[:, :3]) + P2[:, 3] + S2[:, 3]).max() < 1e-10
    # normals transform by the Möbius map, also in the paper's homogeneous form J A J on (n : 1)
    N = np.c_[planes[:, :3], np.ones(20)] @ L.mobius_matrix().T
    assert np.allclose(N[:, :3] / N[:, 3:], L.normals(planes[:, :3]))
    assert np.allclose(L.normals(planes[:, :3]), P2[:, :3])
    # group structure
    L2 = random_map(seed + 10)
    X = np.c_[c, r]
    assert np.allclose((L @ L2).spheres(X), L.spheres(L2.spheres(X)))
    assert np.allclose(L.inverse().spheres(L.spheres(X)), X)


@pytest.mark.parametrize("seed", range(3))
def test_plane_matrix_composes_and_keeps_oriented_contact(seed):
    """``(Y[:3], Y[4]) / −Y[3]`` with ``Y = B X``, ``X = (n, −1, d)``: a plane touching a sphere maps to a plane
    touching its image; the product of two matrices is the composed map (the propagation of conical_spheres)."""
    rng = np.random.default_rng(seed)
    L, L2 = random_map(seed), random_map(seed + 10)
    planes = pl.normalize(np.c_[rng.normal(size=(20, 3)), rng.normal(size=20)])
    c = rng.normal(scale=3, size=(20, 3))
    X = np.c_[c, -(np.einsum("ki,ki->k", planes[:, :3], c) + planes[:, 3])]    # spheres touching the planes

    def act(B: np.ndarray) -> np.ndarray:
        Y = np.c_[planes[:, :3], -np.ones(20), planes[:, 3]] @ B.T
        return np.c_[Y[:, :3], Y[:, 4]] / -Y[:, 3:4]

    for P2, S2 in ((act(L.plane_matrix()), L.spheres(X)),
                   (act(L.plane_matrix() @ L2.plane_matrix()), L.spheres(L2.spheres(X)))):
        assert np.abs(np.linalg.norm(P2[:, :3], axis=1) - 1).max() < 1e-12
        assert np.abs(np.einsum("ki,ki->k", P2[:, :3], S2[:, :3]) + P2[:, 3] + S2[:, 3]).max() < 1e-10


def test_mobius_transform_keeps_circles_on_the_sphere():
    rng = np.random.default_rng(3)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    b1 = np.cross(axis, [1.0, 0, 0])
    b1 /= np.linalg.norm(b1)
    b2 = np.cross(axis, b1)
    th = rng.uniform(0, 2 * np.pi, 9)
    circle = 0.6 * axis + 0.8 * (np.cos(th)[:, None] * b1 + np.sin(th)[:, None] * b2)
    out = random_map(5).normals(circle)
    _, res = pl.fit_plane(out)
    assert np.allclose(np.linalg.norm(out, axis=1), 1.0) and res < 1e-12


def test_reflection_fixes_w_plane_and_maps_neighbour_spheres():
    """Remark 4.4: with equal tangential distances σ_j(Z_{j−1}) = Z_{j+1}, and σ_j fixes W_j point by point."""
    Z, _ = SphereSpline(WAVY).sample_uniform(12)
    sig = reflections(Z)
    W = w_planes(Z)
    H = bisector_normals(Z)
    rng = np.random.default_rng(7)
    for j in range(1, 11):
        assert np.allclose(sig[j].spheres(Z[j - 1]), Z[j + 1], atol=1e-9)
        assert np.allclose(sig[j].spheres(Z[j]), Z[j])
        # random points of W_j (radius-0 spheres) are fixed, points off W_j are not
        x = rng.normal(scale=20.0, size=(50, 3)) + Z[j, :3]
        x = x - pl.signed_distance(W[j], x)[:, None] * W[j, :3]
        assert np.abs(pl.signed_distance(W[j], x)).max() < 1e-12
        X = np.c_[x, np.zeros(50)]
        assert np.abs(sig[j].spheres(X) - X).max() < 1e-9
        off = X + np.r_[W[j, :3], 0.0]
        assert np.abs(sig[j].spheres(off) - off).max() > 1e-3
        # and so is every sphere of the hyperplane <<X − Z_j, H_j>> = 0 (a random one: radius solved for)
        c = rng.normal(scale=5.0, size=(50, 3)) + Z[j, :3]
        h, h4 = H[j, :3], H[j, 3]
        r = Z[j, 3] + ((c - Z[j, :3]) @ h) / h4
        S = np.c_[c, r]
        assert np.abs(pl.minkowski_inner(S - Z[j], H[j])).max() < 1e-9
        assert np.abs(sig[j].spheres(S) - S).max() < 1e-8


def test_offset_map_is_the_conical_offset():
    grid, _ = MESHES["PP-eq11"]
    a = laguerre_transform(grid, LaguerreMap.offset(0.4))
    b = offset_faces(grid, 0.4)
    assert np.allclose(a.vertices, b.vertices, atol=1e-10)


# -- transforming meshes -----------------------------------------------------------------------------

@pytest.mark.parametrize("name", list(MESHES), ids=list(MESHES))
@pytest.mark.parametrize("seed", [0, 1])
def test_laguerre_transform_keeps_conical_p_and_pp(name, seed):
    grid, families = MESHES[name]
    out = laguerre_transform(grid, random_map(seed))
    assert np.abs(out.vertices - grid.vertices).max() > 0.1                # it really moved
    assert_conical_planar(out, families)
    assert quality(out).flipped_edges == 0


def test_laguerre_transform_rejects_non_conical_meshes():
    grid, _ = MESHES["PP-eq11"]
    bent = grid.with_vertices(grid.vertices + 0.05 * np.sin(grid.vertices[..., :1]))
    with pytest.raises(GeometryError, match="not conical at vertex"):
        laguerre_transform(bent, random_map(0))


@pytest.mark.parametrize("name", ["P-spheres", "PP-eq11"])
@pytest.mark.parametrize("seed", [0, 1])
def test_fixed_matrix_edit_reproduces_the_laguerre_image(name, seed):
    """§4.3 with A fixed (the Möbius part of a Laguerre map): eq. (17) holds exactly; without handles and
    fairness the solution is the Laguerre image itself, with fairness a parallel mesh of it."""
    grid, families = MESHES[name]
    L = LaguerreMap(spatial(rotation(seed)) @ boost(np.random.default_rng(seed).normal(size=3), 0.25))
    image = laguerre_transform(grid, L)
    res = edit_conical(grid, A=mobius_of_laguerre(L.A), fairness=0.0)
    assert res.constraint_residual < 1e-9 * 30
    assert np.abs(res.grid.vertices - image.vertices).max() < 1e-8
    fair = edit_conical(grid, A=mobius_of_laguerre(L.A), fairness=1e-2)
    assert np.abs(fair.grid.face_planes[..., :3] - image.face_planes[..., :3]).max() < 1e-9
    assert_conical_planar(fair.grid, families)


def test_parallel_edit_with_a_handle():
    grid, families = MESHES["P-spheres"]
    target = grid.vertices[6, 5] + [0.0, 0.0, 0.8]
    res = edit_conical(grid, handles={(6, 5): target})
    assert res.converged and res.constraint_residual < 1e-9
    moved = np.linalg.norm(res.grid.vertices[6, 5] - grid.vertices[6, 5])
    assert 0.3 < moved and res.handle_residual < 0.8                       # pulled towards the handle
    for e0, e1 in ((grid.edges_u(), res.grid.edges_u()), (grid.edges_v(), res.grid.edges_v())):
        cross = np.linalg.norm(np.cross(e0, e1), axis=-1) / (np.linalg.norm(e0, axis=-1) * np.linalg.norm(e1, axis=-1))
        assert cross.max() < 1e-9                                         # A = I: a parallel mesh
    assert_conical_planar(res.grid, families)


def test_fitting_the_matrix_recovers_a_laguerre_image():
    grid, families = MESHES["P-spheres"]
    L = LaguerreMap(boost([0.3, 0.2, 1.0], 0.2))
    image = laguerre_transform(grid, L)
    ij = np.argwhere(np.ones(grid.shape, bool))
    res = edit_conical(grid, handles=(ij, image.vertices.reshape(-1, 3)), fit_A=True, proximity=1e-8, fairness=0.0)
    B = mobius_of_laguerre(L.A)
    assert res.converged and res.lorentz_residual < 1e-12
    assert np.abs(res.A / res.A[3, 3] - B / B[3, 3]).max() < 1e-5
    assert res.handle_residual < 1e-4 and res.constraint_residual < 1e-9
    assert_conical_planar(res.grid, families)


def test_fit_with_few_handles_stays_conical_p():
    grid, families = MESHES["P-spheres"]
    handles = {(0, 0): grid.vertices[0, 0] + [0, -1.0, 0.5], (12, 10): grid.vertices[12, 10] + [0.5, 1.0, 0.0]}
    res = edit_conical(grid, handles=handles, fit_A=True)
    assert res.constraint_residual < 1e-9 and res.lorentz_residual < 1e-12
    assert not np.allclose(res.A, np.eye(4))
    start = ConicalEditor(grid).solve_fixed(np.eye(4), handles)
    assert res.handle_residual <= start.handle_residual + 1e-9              # A helps to reach the handles
    assert_conical_planar(res.grid, families)


def test_closed_grids_transform_and_edit():
    tube = channel_mesh(WAVY, 10, 16, (0, 0), closed=True)
    dome = conical_pp_grid(Series(), Series(cosh=[-12.0], poly=[0, 0, 1.5]), np.zeros(24), np.linspace(.2, 1.2, 7),
                           case="rotational", closed=True)
    L = LaguerreMap(boost([1.0, 0.0, 0.3], 0.2))
    for grid, families in ((tube, ("rows",)), (dome, ("rows", "cols"))):
        assert_conical_planar(laguerre_transform(grid, L), families)
        image = laguerre_transform(grid, L)
        res = edit_conical(grid, A=mobius_of_laguerre(L.A), fairness=0.0)
        assert np.abs(res.grid.vertices - image.vertices).max() < 1e-8
        res = edit_conical(grid, handles={(2, 3): grid.vertices[2, 3] + 0.3})
        assert res.constraint_residual < 1e-9 and quality(res.grid).flipped_edges == 0
        assert_conical_planar(res.grid, families)


def test_fit_lorentz_from_normals():
    grid, _ = MESHES["PP-eq11"]
    L = random_map(4)
    n = grid.face_planes[..., :3].reshape(-1, 3)
    A = fit_lorentz(n, L.normals(n))
    B = L.mobius_matrix()
    assert np.abs(A / A[3, 3] - B / B[3, 3]).max() < 1e-10


def test_edit_errors():
    grid, _ = MESHES["P-spheres"]
    with pytest.raises(GeometryError, match="not a Lorentz matrix"):
        edit_conical(grid, A=np.diag([1.0, 2.0, 1.0, 1.0]))
    with pytest.raises(GeometryError, match="outside the"):
        edit_conical(grid, handles={(99, 0): (0, 0, 0)})
    with pytest.raises(FoldError, match="edited conical mesh"):
        edit_conical(grid, handles={(6, 5): grid.vertices[6, 5] + [0, 0, -40.0]}, proximity=1e-6, fairness=1e-6)


# -- isotropic Möbius transformations (Remark 2.2) ----------------------------------------------------

def test_isotropic_generators_are_admissible_and_compose():
    T = IsotropicMobius.inversion([0.3, -0.2, 2.5], 1.5) @ IsotropicMobius.shear(1.2, [0.1, 0.2, -0.3], 0.5, 0.05)
    assert T.M.shape == (6, 6)
    p = np.array([[0.1, 0.2, 0.3, 0.4]])
    inv = IsotropicMobius.inversion([0.3, -0.2, 2.5], 1.5)
    assert np.allclose(inv(inv(p)), p)                                      # an involution
    with pytest.raises(GeometryError, match="not an isotropic Möbius"):
        IsotropicMobius(np.diag([1.0, 2.0, 1.0, 1.0, 1.0, 1.0]))
    assert IsotropicMobius.rotation(rotation(1)).preserves_unit_sphere
    assert not IsotropicMobius.special_conformal([0.1, 0, 0]).preserves_unit_sphere


@pytest.mark.parametrize("name", ["P-spheres", "PP-eq11"])
def test_isotropic_mobius_keeps_planar_circular_face_images(name):
    grid, _ = MESHES[name]
    E = extended_planes(grid)
    assert quad_planarity_4d(E).max() < 1e-12 and quad_circularity(E).max() < 1e-12
    T = IsotropicMobius.special_conformal([0.08, -0.05, 0.03]) @ IsotropicMobius.shear(1.1, [0.02, 0.0, -0.03],
                                                                                       0.3, 0.4)
    F = T(E)
    assert quad_planarity_4d(F).max() < 1e-10 and quad_circularity(F).max() < 1e-10
    out = isotropic.isotropic_transform(grid, T)
    assert np.abs(out.vertices - grid.vertices).max() > 0.05
    assert quality(out).delta_f_max < 1e-9 and quality(out).flipped_edges == 0
    # orthogonal nodes: the new normal image is circular, and the node axes lie in all four support planes
    P = np.stack([F[:-1, :-1], F[1:, :-1], F[1:, 1:], F[:-1, 1:]], axis=-2)
    S = np.stack([P[..., (k + 1) % 4, :3] - P[..., k, :3] for k in range(4)], axis=-2)
    S /= np.linalg.norm(S, axis=-1, keepdims=True)
    assert np.abs(np.einsum("...ki,...i->...k", S, out.axes)).max() < 1e-8


def test_isotropic_map_of_laguerre_type_keeps_the_mesh_conical():
    grid, families = MESHES["P-spheres"]
    T = IsotropicMobius.rotation(rotation(2)) @ IsotropicMobius.shear(1.0, [0.2, -0.1, 0.3], 0.5)
    assert T.preserves_unit_sphere
    out = isotropic.isotropic_transform(grid, T)
    assert_conical_planar(out, families)

