"""Laguerre transformations of spheres and planes, and the Möbius transformations of normals (§2.1, §4.3).

Conventions (paper §2.1.1):

* an oriented sphere is ``X = (x, y, z, r)`` (eq. 1); ``r > 0`` means outward normals;
  points are spheres of radius 0;
* the Minkowski product is ``<<X1, X2>> = X1ᵀ J X2``, ``J = diag(1, 1, 1, −1)`` (eq. 2);
* an oriented plane is a unit 4-vector ``(n, d)``, ``n·x + d = 0``; it is in oriented
  contact with the sphere ``(c, r)`` (normals agree at the contact point) iff
  ``n·c + d + r = 0``, i.e. ``<<N, X>> + d = 0`` with the null vector ``N = (n, −1)``;
* a Laguerre transformation is ``X ↦ λ A X + T`` with ``Aᵀ J A = J`` (a Lorentz matrix).

It maps planes to planes: ``N ↦ A N`` and ``d ↦ λ d − <<A N, T>>``, rescaled so the
4th coordinate of ``N`` is −1 again.  On unit normals this is the Möbius
transformation of ``S²`` (§2.1.2); in the paper's homogeneous normal coordinates
``(n : 1)`` (§4.3) its matrix is ``J A J`` (:meth:`LaguerreMap.mobius_matrix`),
again a Lorentz matrix.

A conical mesh is transformed exactly (§2.1.3): the faces around a vertex ``v``
touch the cone with axis ``a`` and ``a·n = c``; in sphere space that cone is the
line of spheres ``(v, 0) + t (a, −c)``.  The image line contains exactly one
sphere of radius 0, the new vertex (:func:`ppfab.conical.cones.laguerre_transform`).  The offset at
constant face–face distance ``δ`` is the Laguerre map with ``T = (0, 0, 0, δ)``.

:func:`minkowski_polar` projects a general 4×4 matrix onto the Lorentz group
(Minkowski polar decomposition ``M = A S``, Higham 2003, Kintzel 2005), as §4.3
requires after a linear fit of ``A``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ppfab import planes as pl
from ppfab.errors import GeometryError

J = pl.J


def lorentz_residual(A: np.ndarray) -> float:
    """``max |Aᵀ J A − J|`` (0 for a Lorentz matrix)."""
    A = np.asarray(A, dtype=float)
    return float(np.abs(A.T @ J @ A - J).max())


def is_lorentz(A: np.ndarray, tol: float = 1e-9) -> bool:
    """``Aᵀ J A = J`` within ``tol`` (entrywise)."""
    return lorentz_residual(A) <= tol


def minkowski_reflection(H: np.ndarray) -> np.ndarray:
    """The Lorentz matrix ``I − 2 H Hᵀ J / <<H, H>>`` reflecting in the Minkowski-orthogonal hyperplane of ``H``."""
    H = np.asarray(H, dtype=float)
    hh = float(pl.minkowski_inner(H, H))
    if abs(hh) <= 1e-14 * max(1.0, float(H @ H)):
        raise GeometryError(f"a Minkowski reflection needs a non-null normal, <<H, H>> = {hh:.3g}", value=hh)
    return np.eye(4) - 2.0 * np.outer(H, J @ H) / hh


def boost(direction: np.ndarray, rapidity: float) -> np.ndarray:
    """Lorentz boost mixing the unit spatial ``direction`` with the radius coordinate by ``rapidity``."""
    u = np.asarray(direction, dtype=float)
    u = u / np.linalg.norm(u)
    ch, sh = np.cosh(rapidity), np.sinh(rapidity)
    A = np.eye(4)
    A[:3, :3] += (ch - 1.0) * np.outer(u, u)
    A[:3, 3] = sh * u
    A[3, :3] = sh * u
    A[3, 3] = ch
    return A


def spatial(R: np.ndarray) -> np.ndarray:
    """The Lorentz matrix ``diag(R, 1)`` of a rotation (or reflection) ``R`` of R³."""
    A = np.eye(4)
    A[:3, :3] = np.asarray(R, dtype=float)
    return A


def minkowski_polar(M: np.ndarray, tol: float = 1e-14, maxiter: int = 100) -> tuple[np.ndarray, np.ndarray]:
    """Minkowski polar decomposition ``M = A S`` with ``Aᵀ J A = J`` and ``S`` J-selfadjoint (``J Sᵀ J = S``).

    ``S = (M^# M)^{1/2}`` with ``M^# = J Mᵀ J``, computed by the scaled Newton
    iteration ``X ← ½(μ X + (μ X)^{−#})`` that converges quadratically to ``A``
    (Higham, Mackey, Mackey, Tisseur 2004).  Exists iff ``M^# M`` has no
    eigenvalue on the closed negative real axis; otherwise :class:`GeometryError`.

    Examples
    --------
    >>> A, S = minkowski_polar(2.0 * boost([1, 0, 0], 0.3))
    >>> bool(np.allclose(A, boost([1, 0, 0], 0.3))), bool(np.allclose(S, 2 * np.eye(4)))
    (True, True)
    """
    M = np.asarray(M, dtype=float)
    if M.shape != (4, 4) or not np.all(np.isfinite(M)):
        raise GeometryError(f"minkowski_polar needs a finite 4×4 matrix, got shape {M.shape}")
    ev = np.linalg.eigvals(J @ M.T @ J @ M)
    scale = max(float(np.abs(ev).max()), 1e-300)
    bad = (np.abs(ev.imag) <= 1e-10 * scale) & (ev.real <= 1e-12 * scale)
    if np.any(bad):
        raise GeometryError("the matrix has no Minkowski polar decomposition: J Mᵀ J M has the eigenvalue "
                            f"{float(ev[bad][0].real):.3g} on the non-positive real axis", value=float(ev[bad][0].real))
    X = M.copy()
    for _ in range(maxiter):
        Xi = J @ np.linalg.inv(X).T @ J            # X^{-#}
        mu = (abs(np.linalg.det(Xi)) / abs(np.linalg.det(X))) ** 0.125
        new = 0.5 * (mu * X + Xi / mu)
        done = np.abs(new - X).max() <= tol * max(1.0, np.abs(new).max())
        X = new
        if done:
            break
    A = X
    S = J @ A.T @ J @ M                             # A^{-1} = A^#
    S = 0.5 * (S + J @ S.T @ J)
    return A, S


def project_lorentz(M: np.ndarray, orthochronous: bool = True) -> np.ndarray:
    """The Lorentz factor of ``M`` (§4.3): ``M`` is scaled to ``|det| = 1`` first; with
    ``orthochronous`` the sign is chosen so that ``A[3, 3] > 0`` (``A`` and ``−A`` act alike on normals)."""
    M = np.asarray(M, dtype=float)
    det = np.linalg.det(M)
    if abs(det) <= 1e-300:
        raise GeometryError("cannot project a singular matrix onto the Lorentz group", value=float(det))
    A, _ = minkowski_polar(M / abs(det) ** 0.25)
    if orthochronous and A[3, 3] < 0:
        A = -A
    return A


@dataclass(frozen=True)
class LaguerreMap:
    """``X ↦ λ A X + T`` on oriented spheres ``(x, y, z, r)``, with its action on oriented planes and normals.

    Parameters
    ----------
    A : (4, 4) Lorentz matrix (``Aᵀ J A = J``; checked to 1e-9)
    lam : nonzero scale factor ``λ``
    T : (4,) translation in sphere space (``(t, 0)`` moves, ``(0, 0, 0, τ)`` changes every radius by ``τ``)
    """

    A: np.ndarray = field(default_factory=lambda: np.eye(4))
    lam: float = 1.0
    T: np.ndarray = field(default_factory=lambda: np.zeros(4))

    def __post_init__(self):
        A = np.array(self.A, dtype=float)
        T = np.array(self.T, dtype=float)
        if A.shape != (4, 4) or T.shape != (4,):
            raise GeometryError("a Laguerre map needs A (4, 4) and T (4,)")
        res = lorentz_residual(A)
        if res > 1e-9 * max(1.0, float(np.abs(A).max()) ** 2):
            raise GeometryError(f"A is not a Lorentz matrix: |AᵀJA − J| = {res:.3g} (use project_lorentz)", value=res)
        if self.lam == 0 or not np.isfinite(self.lam):
            raise GeometryError(f"the scale λ of a Laguerre map must be finite and nonzero, got {self.lam}")
        A.flags.writeable = False
        T.flags.writeable = False
        object.__setattr__(self, "A", A)
        object.__setattr__(self, "T", T)

    # -- constructors ------------------------------------------------------------------------
    @classmethod
    def reflection(cls, H: np.ndarray, Z: np.ndarray) -> "LaguerreMap":
        """Minkowski reflection ``X ↦ X − 2 <<X − Z, H>> / <<H, H>> · H``: fixes every sphere ``X`` with
        ``<<X − Z, H>> = 0`` (in particular the points of the plane of eq. 16)."""
        A = minkowski_reflection(H)
        Z = np.asarray(Z, dtype=float)
        return cls(A, 1.0, Z - A @ Z)

    @classmethod
    def offset(cls, distance: float) -> "LaguerreMap":
        """Every oriented plane moves by ``distance`` along its normal (every radius grows by ``distance``):
        the offset at constant face–face distance (§2.1.3)."""
        return cls(np.eye(4), 1.0, np.array([0.0, 0.0, 0.0, float(distance)]))

    # -- actions -------------------------------------------------------------------------------
    def spheres(self, X: np.ndarray) -> np.ndarray:
        """Image of spheres ``(..., 4)``."""
        return self.lam * np.asarray(X, dtype=float) @ self.A.T + self.T

    def planes(self, P: np.ndarray) -> np.ndarray:
        """Image of oriented planes ``(..., 4)`` (unit or not: they are normalised first)."""
        P = pl.normalize(P)
        N = np.concatenate([P[..., :3], -np.ones(P.shape[:-1] + (1,))], axis=-1)
        M = N @ self.A.T
        d = self.lam * P[..., 3] - pl.minkowski_inner(M, self.T)
        k = -M[..., 3]
        return np.concatenate([M[..., :3], d[..., None]], axis=-1) / k[..., None]

    def plane_matrix(self) -> np.ndarray:
        """``B (5, 5)`` of the action on planes in homogeneous form: a unit plane ``(n, d)`` written as
        ``X = (n, −1, d)`` maps to ``Y = B X``, ``B = [[A, 0], [−(J T)ᵀ A, λ]]``, and :meth:`planes` is
        ``(Y[:3], Y[4]) / (−Y[3])``.  Composed maps are products of these matrices."""
        B = np.zeros((5, 5))
        B[:4, :4] = self.A
        B[4, :4] = -(J @ self.T) @ self.A
        B[4, 4] = self.lam
        return B

    def normals(self, n: np.ndarray) -> np.ndarray:
        """The Möbius transformation of unit normals ``(..., 3)`` induced by the map (§2.1.2)."""
        n = np.asarray(n, dtype=float)
        M = np.concatenate([n, -np.ones(n.shape[:-1] + (1,))], axis=-1) @ self.A.T
        return M[..., :3] / (-M[..., 3:4])

    def mobius_matrix(self) -> np.ndarray:
        """The matrix ``J A J`` acting on the paper's homogeneous normals ``(n : 1)`` (§4.3)."""
        return J @ self.A @ J

    def __matmul__(self, other: "LaguerreMap") -> "LaguerreMap":
        """Composition ``self ∘ other``."""
        return LaguerreMap(self.A @ other.A, self.lam * other.lam, self.lam * self.A @ other.T + self.T)

    def inverse(self) -> "LaguerreMap":
        Ai = J @ self.A.T @ J
        return LaguerreMap(Ai, 1.0 / self.lam, -(Ai @ self.T) / self.lam)
