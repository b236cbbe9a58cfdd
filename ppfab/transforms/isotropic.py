"""Isotropic Möbius transformations of the weighted face image (paper Remark 2.2, §2.3.4).

A support structure has *orthogonal nodes* when its weighted normal image
``M_N`` (the face image with the 4th coordinate forgotten) is a circular mesh;
its face image ``M_F ⊂ R^4`` has planar quads (Prop. 2.4).  Remark 2.2: the
16-dimensional group of *isotropic Möbius transformations* of R^4 (``x4``
isotropic) preserves "four points lie in a 2-plane and project onto a circular
quad", so it maps such face images to face images of meshes with orthogonal
nodes.

We realise the group linearly on the lifted coordinates
``ξ = (|n|², n1, n2, n3, 1, d)`` of a weighted plane ``(n, d)``: a 6×6 matrix
``[[L, 0], [ℓ, λ]]`` where ``L`` (5×5) preserves the form ``|n|² − a b`` up to scale
(a Möbius transformation of R³ on ``n``, 10 dimensions) and the last row
``d' = λ d + κ a + β·n + c b`` adds an isotropic-sphere term (6 dimensions).  The
image point is ``n' = ξ'_{1:4} / ξ'_4``, ``d' = ξ'_5 / ξ'_4``.  Generators:
translation, rotation, scaling of ``n`` (``d`` kept), the inversion
``(n, d) ↦ ρ² (n, d) / |n − m|²`` (after moving ``m`` to 0) and the shear of ``d``.

Why the property is preserved: four coplanar points ``p_k = (n_k, d_k)`` have an
affine dependence ``Σ a_k p_k = 0``, ``Σ a_k = 0``; concyclic ``n_k`` satisfy
``|n_k|² = 2 m·n_k + const``, hence ``Σ a_k |n_k|² = 0`` and the lifts ``ξ_k`` are
linearly dependent with the same coefficients.  A linear map keeps that
dependence, so the images are again coplanar (dependence of ``(n', d', 1)``) and
concyclic (dependence of ``(|n'|², n', 1)``).

A conical mesh has the orthogonal-node structure of its cone axes: its unit
face planes ``M°_F`` project onto ``M°_N ⊂ S²`` with planar faces (§2.3.3).
:func:`isotropic_transform` applies a transformation to them and rebuilds the mesh by
Prop. 2.5 (vertex = the common point of its four planes), with the node axes of
the new support structure.  The result keeps planar faces and the orthogonal-node
property; it is conical again only when ``L`` maps the unit sphere to itself
(then the map is a Laguerre transformation), and its polylines are generally no
longer planar.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ppfab import planes as pl
from ppfab.conical.cones import axis_of_normals, extended_planes, vertex_planes
from ppfab.errors import GeometryError
from ppfab.folds import check_folds
from ppfab.mesh import QuadGrid

# lifted coordinates: 0 = a (|n|²), 1..3 = n, 4 = b (1), 5 = d


def lift(P: np.ndarray) -> np.ndarray:
    """``(n, d) (..., 4) ↦ ξ = (|n|², n, 1, d) (..., 6)``."""
    P = pl.as_planes(P)
    n = P[..., :3]
    return np.concatenate([np.einsum("...i,...i->...", n, n)[..., None], n, np.ones(P.shape[:-1] + (1,)),
                           P[..., 3:4]], axis=-1)


def project(xi: np.ndarray) -> np.ndarray:
    """``ξ ↦ (ξ_{1:4}, ξ_5) / ξ_4`` (..., 4)."""
    xi = np.asarray(xi, dtype=float)
    b = xi[..., 4:5]
    if np.any(np.abs(b) <= 1e-14 * np.abs(xi).max(axis=-1, keepdims=True)):
        raise GeometryError("an isotropic Möbius transformation sends a face plane to infinity "
                            "(a normal lies on the inversion centre)")
    return np.concatenate([xi[..., 1:4], xi[..., 5:6]], axis=-1) / b


@dataclass(frozen=True)
class IsotropicMobius:
    """An isotropic Möbius transformation of R^4 as a 6×6 matrix on lifted coordinates (see module doc)."""

    M: np.ndarray = field(default_factory=lambda: np.eye(6))

    def __post_init__(self):
        M = np.array(self.M, dtype=float)
        if M.shape != (6, 6) or not np.all(np.isfinite(M)):
            raise GeometryError("an isotropic Möbius transformation needs a finite 6×6 matrix")
        if np.any(M[:5, 5] != 0):
            raise GeometryError("the first five lifted coordinates must not depend on d (isotropic direction)")
        L = M[:5, :5]
        Q = np.zeros((5, 5))
        Q[1:4, 1:4] = np.eye(3)
        Q[0, 4] = Q[4, 0] = -0.5
        LQL = L.T @ Q @ L
        k = LQL[1, 1]
        if abs(k) <= 1e-14 or np.abs(LQL - k * Q).max() > 1e-9 * max(1.0, abs(k)) or M[5, 5] == 0:
            raise GeometryError("the matrix is not an isotropic Möbius transformation: its 5×5 block must "
                                "preserve |n|² − a·b up to scale and λ must be nonzero")
        M.flags.writeable = False
        object.__setattr__(self, "M", M)

    def __call__(self, P: np.ndarray) -> np.ndarray:
        """Image of weighted planes / points of R^4 ``(..., 4)``."""
        return project(lift(P) @ self.M.T)

    def __matmul__(self, other: "IsotropicMobius") -> "IsotropicMobius":
        return IsotropicMobius(self.M @ other.M)

    # -- generators ------------------------------------------------------------------------------
    @classmethod
    def translation(cls, t: np.ndarray) -> "IsotropicMobius":
        """``n ↦ n + t`` (``d`` kept)."""
        t = np.asarray(t, dtype=float)
        M = np.eye(6)
        M[0, 1:4] = 2 * t
        M[0, 4] = t @ t
        M[1:4, 4] = t
        return cls(M)

    @classmethod
    def rotation(cls, R: np.ndarray) -> "IsotropicMobius":
        """``n ↦ R n`` (``R`` orthogonal)."""
        M = np.eye(6)
        M[1:4, 1:4] = np.asarray(R, dtype=float)
        return cls(M)

    @classmethod
    def inversion(cls, center: np.ndarray | None = None, radius: float = 1.0) -> "IsotropicMobius":
        """``(n, d) ↦ (m + ρ² (n − m) / |n − m|², ρ² d / |n − m|²)``: inversion of the normal image in the
        sphere ``(m, ρ)``, the weighted plane rescaled with it."""
        m = np.zeros(3) if center is None else np.asarray(center, dtype=float)
        r2 = float(radius) ** 2
        inv = np.eye(6)
        inv[0, 0], inv[4, 4], inv[0, 4], inv[4, 0] = 0.0, 0.0, r2 * r2, 1.0
        inv[1:4, 1:4] *= r2
        inv[5, 5] = r2
        return cls.translation(m) @ cls(inv) @ cls.translation(-m)

    @classmethod
    def special_conformal(cls, b: np.ndarray) -> "IsotropicMobius":
        """Inversion ∘ translation by ``b`` ∘ inversion: ``n ↦ (n + b|n|²) / (1 + 2 b·n + |b|²|n|²)``, the
        identity for ``b = 0`` (small ``b``: a small deformation)."""
        inv = cls.inversion()
        return inv @ cls.translation(b) @ inv

    @classmethod
    def shear(cls, lam: float = 1.0, beta: np.ndarray | None = None, c: float = 0.0, kappa: float = 0.0
              ) -> "IsotropicMobius":
        """``d ↦ λ d + β·n + c + κ |n|²`` (``n`` kept)."""
        M = np.eye(6)
        M[5, 5] = lam
        M[5, 1:4] = np.zeros(3) if beta is None else np.asarray(beta, dtype=float)
        M[5, 4] = c
        M[5, 0] = kappa
        return cls(M)

    @property
    def preserves_unit_sphere(self) -> bool:
        """True when the normal part maps ``S²`` to itself (then the transform is a Laguerre map and
        conical meshes stay conical)."""
        n = np.random.default_rng(0).normal(size=(16, 3))
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        out = self(np.concatenate([n, np.zeros((16, 1))], axis=1))[:, :3]
        return bool(np.allclose(np.linalg.norm(out, axis=1), 1.0, atol=1e-9))


# -- residuals ------------------------------------------------------------------------------------

def quad_planarity_4d(F: np.ndarray) -> np.ndarray:
    """For every vertex, the four face-image points around it: smallest/largest singular value of their
    edge vectors in R^4 (0 when they span only a 2-plane), ``(rows, cols)``."""
    Q = np.stack([F[:-1, :-1], F[1:, :-1], F[1:, 1:], F[:-1, 1:]], axis=-2)
    D = Q[..., 1:, :] - Q[..., :1, :]
    s = np.linalg.svd(D, compute_uv=False)
    return s[..., 2] / np.maximum(s[..., 0], 1e-300)


def quad_circularity(F: np.ndarray) -> np.ndarray:
    """For every vertex, the four normal-image points ``n`` around it: relative smallest singular value of
    their lifts ``(|n|², n, 1)`` (0 when concyclic), ``(rows, cols)``."""
    Q = np.stack([F[:-1, :-1], F[1:, :-1], F[1:, 1:], F[:-1, 1:]], axis=-2)
    X = lift(Q)[..., :5]
    X = X / np.linalg.norm(X, axis=-1, keepdims=True)
    s = np.linalg.svd(X, compute_uv=False)
    return s[..., 3] / np.maximum(s[..., 0], 1e-300)


CONICAL_TOLERANCE = 1e-6
"""Largest distance (radians, to first order) of the unit face normals at a vertex (ghosts included) from
their common circle for :func:`isotropic_transform` to accept a grid as conical — the tolerance of
:func:`ppfab.conical.cones.laguerre_transform`."""


def isotropic_transform(grid: QuadGrid, T: IsotropicMobius, check: bool = True, max_residual: float = 1e-7,
                        min_span: float = 1e-9, max_conical: float = CONICAL_TOLERANCE) -> QuadGrid:
    """Apply an isotropic Möbius transformation to the conical face image ``M°_F`` of a grid (Remark 2.2).

    The unit face planes (ghosts included, :func:`ppfab.conical.extended_planes`) are mapped; each
    vertex becomes the common point of its four mapped planes (Prop. 2.5) and its node axis the line
    common to the four support planes ``f_{k+1} − f_k`` around it.

    Returns a grid with the weighted image in ``face_image`` and the unit planes, ghosts included, in
    ``extended_face_planes``.  Raises :class:`GeometryError` when the input is not conical (the unit
    normals at a vertex further than ``max_conical`` from a common circle: its unit face planes have no
    orthogonal-node structure, and the four support planes around a vertex of the image would not share
    an axis — torsion), when the
    four mapped planes of a vertex do not determine one point — their unit normals span only a plane
    (smallest/largest singular value of the 4×3 normal matrix ``≤ min_span``: the planes share a line) —
    or do not meet (relative residual ``s₃/s₀`` of the 4×4 plane matrix above ``max_residual``: the
    input had no orthogonal-node structure), and :class:`~ppfab.errors.FoldError` (with ``check``)
    when the image folds.
    """
    E = extended_planes(grid)
    res = axis_of_normals(vertex_planes(grid, E)[..., :3])[2]
    if np.max(res, initial=0.0) > max_conical:
        idx = tuple(int(k) for k in np.argwhere(res == res.max())[0])
        raise GeometryError(f"the mesh is not conical at vertex {idx} (normals off their circle by {res.max():.3g} "
                            f"> {max_conical:g}); an isotropic Möbius map needs the orthogonal-node structure of "
                            "a conical mesh (make it conical first: ppfab optimize --keep-conical)",
                            element=f"vertex {idx}", value=float(res.max()))
    F = T(E)
    P = vertex_planes(grid, F)                                  # (rows, cols, 4, 4) weighted
    sn = np.linalg.svd(pl.normalize(P)[..., :3], compute_uv=False)
    span = sn[..., 2] / np.maximum(sn[..., 0], 1e-300)          # 0: the normals span a plane, the planes a line
    if np.min(span) <= min_span:
        bad = np.argwhere(span <= min_span)                     # the first in index order (not the smallest:
        idx = tuple(int(k) for k in bad[0])                     # among exact zeros that is rounding noise)
        more = f"; {len(bad) - 1} more vertices like it" if len(bad) > 1 else ""
        raise GeometryError(f"the four face planes at vertex {idx} do not meet in a single point (their normals span "
                            f"only a plane, s₂/s₀ = {span[idx]:.3g}{more}; repeated ghost faces at a boundary?)",
                            element=f"vertex {idx}", value=float(span[idx]))
    U, s, Vt = np.linalg.svd(P)
    h = Vt[..., 3, :]                                           # null vector (x, w) of the four planes
    rel = s[..., 3] / np.maximum(s[..., 0], 1e-300)
    if np.max(rel) > max_residual:
        idx = tuple(int(k) for k in np.argwhere(rel == rel.max())[0])
        raise GeometryError(f"the four face planes at vertex {idx} do not meet in a point after the transformation "
                            f"(relative residual {rel.max():.3g}): the input has no orthogonal-node structure",
                            element=f"vertex {idx}", value=float(rel.max()))
    if np.any(np.abs(h[..., 3]) <= 1e-12):
        idx = tuple(int(k) for k in np.argwhere(np.abs(h[..., 3]) <= 1e-12)[0])
        raise GeometryError(f"vertex {idx} goes to infinity under the transformation", element=f"vertex {idx}")
    v = h[..., :3] / h[..., 3:4]
    S = np.stack([P[..., (k + 1) % 4, :] - P[..., k, :] for k in range(4)], axis=-2)[..., :3]
    _, _, Vs = np.linalg.svd(S)
    axes = Vs[..., 2, :]
    nbar = pl.normalize(P)[..., :3].sum(axis=-2)
    axes = axes * -np.sign(np.einsum("...i,...i->...", axes, nbar))[..., None]
    inner = F[1:-1, 1:] if grid.closed else F[1:-1, 1:-1]
    out = QuadGrid(v, closed=grid.closed, face_image=inner, axes=axes, vertex_ids=grid.vertex_ids,
                   extended_face_planes=pl.normalize(F), meta=grid.meta)
    if check:
        check_folds(out, reference=inner, context="the isotropic Möbius image")
    return out
