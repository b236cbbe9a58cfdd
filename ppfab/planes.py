"""Weighted planes in R^4 and the Laguerre/Minkowski helpers of §2.1.

A weighted plane is a 4-vector ``p = (n, d)`` meaning ``n·x + d = 0``
(paper eq. 4).  The weight (the length of ``n``) matters for the weighted
face image (§2.2.1): differences of weighted face planes are the support
planes, eq. (5).  Every function here works on stacks ``(..., 4)`` so a whole
grid is handled in one call.

Spheres are 4-vectors ``(x, y, z, r)`` (eq. 1) with the Minkowski inner
product ``<<X1, X2>> = x1·x2 + y1·y2 + z1·z2 − r1·r2 = X1ᵀ J X2`` (eq. 2).
"""

from __future__ import annotations

import numpy as np

from .errors import GeometryError

J = np.diag([1.0, 1.0, 1.0, -1.0])
"""The Minkowski metric of eq. (2)/(3), ``diag(1, 1, 1, −1)``."""


def as_planes(planes: np.ndarray) -> np.ndarray:
    """Return ``planes`` as a float array of shape ``(..., 4)`` (checked)."""
    p = np.asarray(planes, dtype=float)
    if p.shape[-1] != 4:
        raise GeometryError(f"weighted planes need 4 coordinates (n, d), got shape {p.shape}")
    return p


def normalize(planes: np.ndarray) -> np.ndarray:
    """Scale each plane so its normal has unit length (Hessian normal form).

    Parameters
    ----------
    planes : (..., 4) float, ``n·x + d = 0``

    Returns
    -------
    (..., 4) float with ``|n| = 1``; a plane with ``n = 0`` raises.

    Examples
    --------
    >>> normalize(np.array([0.0, 0.0, 2.0, -4.0]))
    array([ 0.,  0.,  1., -2.])
    """
    p = as_planes(planes)
    norm = np.linalg.norm(p[..., :3], axis=-1, keepdims=True)
    if np.any(norm == 0) or not np.all(np.isfinite(p)):
        raise GeometryError("a plane has a zero or non-finite normal vector")
    return p / norm


def signed_distance(planes: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Signed Euclidean distance of ``points (..., 3)`` from ``planes (..., 4)`` (broadcast)."""
    p = normalize(planes)
    x = np.asarray(points, dtype=float)
    return np.einsum("...i,...i->...", p[..., :3], x) + p[..., 3]


def evaluate(planes: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``n·x + d`` for weighted planes (no normalisation), broadcast over stacks."""
    p = as_planes(planes)
    x = np.asarray(points, dtype=float)
    return np.einsum("...i,...i->...", p[..., :3], x) + p[..., 3]


def plane_through_points(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Unit plane through three points ``(..., 3)`` each; collinear points raise."""
    a, b, c = (np.asarray(t, dtype=float) for t in (a, b, c))
    n = np.cross(b - a, c - a)
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    scale = np.maximum.reduce([np.linalg.norm(b - a, axis=-1), np.linalg.norm(c - a, axis=-1)])
    if np.any(length[..., 0] <= 1e-14 * np.maximum(scale, 1e-300) ** 2):
        raise GeometryError("three points that should span a plane are collinear")
    n = n / length
    return np.concatenate([n, -np.einsum("...i,...i->...", n, a)[..., None]], axis=-1)


def fit_plane(points: np.ndarray, weights: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares planes of point stacks.

    Parameters
    ----------
    points : (..., k, 3) float, ``k >= 3``
    weights : (..., k) float, optional; zero weight removes a point (padding)

    Returns
    -------
    planes : (..., 4) unit planes minimising the sum of squared distances
    residual : (...,) largest absolute distance of a (weighted) point from its plane
    """
    x = np.asarray(points, dtype=float)
    w = np.ones(x.shape[:-1]) if weights is None else np.asarray(weights, dtype=float)
    wsum = w.sum(axis=-1, keepdims=True)
    centroid = np.einsum("...k,...ki->...i", w, x) / wsum
    y = (x - centroid[..., None, :]) * np.sqrt(w)[..., None]
    cov = np.einsum("...ki,...kj->...ij", y, y)
    _, vecs = np.linalg.eigh(cov)
    n = vecs[..., :, 0]
    d = -np.einsum("...i,...i->...", n, centroid)
    planes = np.concatenate([n, d[..., None]], axis=-1)
    dist = np.abs(np.einsum("...ki,...i->...k", x, n) + d[..., None])
    residual = np.where(w > 0, dist, 0.0).max(axis=-1)
    return planes, residual


def intersect_three(p1: np.ndarray, p2: np.ndarray, p3: np.ndarray,
                    min_sine: float = 0.0) -> np.ndarray:
    """Intersection points of three planes, for whole stacks at once.

    Solves ``[n1; n2; n3] x = −[d1; d2; d3]`` for every index of the
    broadcast stack (no Python loop).

    Parameters
    ----------
    p1, p2, p3 : (..., 4) float, weighted planes
    min_sine : raise :class:`GeometryError` where the three unit normals span
        a volume (|det|) below this value, i.e. the planes are (nearly) parallel
        to one line and the point is ill defined.

    Returns
    -------
    (..., 3) float
    """
    p1, p2, p3 = np.broadcast_arrays(*(normalize(p) for p in (p1, p2, p3)))
    a = np.stack([p1[..., :3], p2[..., :3], p3[..., :3]], axis=-2)
    rhs = -np.stack([p1[..., 3], p2[..., 3], p3[..., 3]], axis=-1)
    det = np.linalg.det(a)
    bad = np.abs(det) <= max(min_sine, 1e-14)
    if np.any(bad):
        idx = tuple(int(k) for k in np.argwhere(bad)[0])
        value = float(np.abs(det[idx]))
        raise GeometryError(
            f"three planes do not meet in a single point at index {idx} "
            f"(|det| of their unit normals = {value:.2e})", element=str(idx), value=value)
    return np.linalg.solve(a, rhs[..., None])[..., 0]


def line_of_two_planes(p1: np.ndarray, p2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The line ``p1 ∩ p2`` as (point closest to the origin, unit direction), stacked."""
    a, b = normalize(p1), normalize(p2)
    direction = np.cross(a[..., :3], b[..., :3])
    length = np.linalg.norm(direction, axis=-1, keepdims=True)
    if np.any(length <= 1e-14):
        raise GeometryError("two planes that should meet in a line are parallel")
    direction = direction / length
    third = np.concatenate([direction, np.zeros(direction.shape[:-1] + (1,))], axis=-1)
    point = intersect_three(a, b, third)
    return point, direction


def line_angle(u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Unsigned angle in ``[0, π/2]`` between lines with directions ``u`` and ``w`` ``(..., 3)`` of any length:
    ``atan2(|u × w|, |u · w|)``, accurate at every angle (``arccos`` of a normalised dot product turns one
    rounding near parallel lines into about 2e-8 rad).  A zero direction is no line; it reads ``π/2``, the
    worst angle, so that it cannot pass a check for small angles."""
    u, w = np.asarray(u, dtype=float), np.asarray(w, dtype=float)
    s = np.linalg.norm(np.cross(u, w), axis=-1)
    c = np.abs(np.einsum("...i,...i->...", u, w))
    degenerate = (np.linalg.norm(u, axis=-1) == 0) | (np.linalg.norm(w, axis=-1) == 0)
    return np.where(degenerate, np.pi / 2, np.arctan2(s, c))


def angle_between(p1: np.ndarray, p2: np.ndarray) -> np.ndarray:
    """Unsigned angle in ``[0, π/2]`` between plane normals (the dihedral angle of the two planes), by
    :func:`line_angle` of the normals; a plane with a zero normal raises (:func:`normalize`)."""
    return line_angle(normalize(p1)[..., :3], normalize(p2)[..., :3])


def minkowski_inner(x1: np.ndarray, x2: np.ndarray) -> np.ndarray:
    """``<<X1, X2>> = x1 x2 + y1 y2 + z1 z2 − r1 r2`` (eq. 2), broadcast over stacks."""
    a = np.asarray(x1, dtype=float)
    b = np.asarray(x2, dtype=float)
    return np.einsum("...i,...i->...", a[..., :3], b[..., :3]) - a[..., 3] * b[..., 3]


def tangential_distance_squared(x1: np.ndarray, x2: np.ndarray) -> np.ndarray:
    """Squared tangential distance ``d²(X1, X2) = <<X1 − X2, X1 − X2>>`` of oriented spheres (eq. 2).

    Positive when the spheres are in spacelike position (a common oriented
    tangent plane exists and the tangential distance is real), zero for
    oriented contact.
    """
    diff = np.asarray(x1, dtype=float) - np.asarray(x2, dtype=float)
    return minkowski_inner(diff, diff)


def sphere_to_plane_coordinates(spheres: np.ndarray) -> np.ndarray:
    """Sphere ``(c, r)`` → the 4-vector ``g`` of §3.1.3 with ``|x|² + g[:3]·x + g[3] = 0``.

    The radical plane of two spheres then has weighted coordinates ``g − h``.
    For ``|x − c|² = r²``: ``g[:3] = −2c``, ``g[3] = |c|² − r²``.
    """
    s = np.asarray(spheres, dtype=float)
    c, r = s[..., :3], s[..., 3]
    return np.concatenate([-2.0 * c, (np.einsum("...i,...i->...", c, c) - r * r)[..., None]], axis=-1)
