"""Translational surfaces: the simplest PP meshes (sanity example).

``x(s, t) = a(s) + b(t) − p`` with a profile ``a`` in a plane ε and a profile
``b`` in a plane φ.  The mesh ``v_ij = a(s_i) + b(t_j) − p`` has parallelogram
faces (``v_{i+1,j} − v_{ij} = a_{i+1} − a_i`` for every ``j``), each row
``v[i, :]`` is a translate of ``b`` and lies in the plane through ``a_i``
parallel to φ, each column in the plane through ``b_j`` parallel to ε.  So all
row support planes ``U_i`` are parallel (to φ), all column planes ``W_j`` are
parallel (to ε), and every node axis ``U_i ∩ W_j`` has the direction of
ε ∩ φ — the z axis with the default placement (ε = xz-plane with 2D points
``[x, z]``, φ = yz-plane with ``[y, z]``).  In face-image terms ``g`` and ``h``
have constant normal directions ``n_φ`` and ``n_ε`` up to scale.

With ``p`` the point where the profiles meet (when they do), the surface
contains both profiles.  Vertices are samples of the surface at equal arc-length
steps along each profile.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ppfab import planes as pl
from ..errors import DesignError, GeometryError
from ..mesh import QuadGrid
from ..schema import param
from ppfab.transforms.pp import with_face_image
from ..curves import PlanarCurve, fit_planar_curve
from ..frame import Frame
from .registry import construction


def translational_mesh(a: np.ndarray, b: np.ndarray, p: np.ndarray | None = None) -> QuadGrid:
    """PP mesh ``v[i, j] = a_i + b_j − p`` of two planar polylines.

    Parameters
    ----------
    a : (m+1, 3) — a planar polyline (the column direction: ``v[:, 0] = a + b_0 − p``)
    b : (n+1, 3) — a planar polyline (the row direction)
    p : (3,) — subtracted point (default ``b_0``, so column 0 is ``a`` itself)

    Raises
    ------
    GeometryError when a polyline is not planar (to 1e-9 of its size) or the two
    planes are parallel (no node axis).

    Examples
    --------
    >>> a = np.array([[x, 0, -x * x / 10] for x in range(-2, 3)], float)
    >>> b = np.array([[0, y, -y * y / 10] for y in range(-1, 2)], float)
    >>> translational_mesh(a, b, np.zeros(3)).vertices[0, 0].tolist()
    [-2.0, -1.0, -0.5]
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.ndim != 2 or b.ndim != 2 or a.shape[1] != 3 or b.shape[1] != 3 or len(a) < 2 or len(b) < 2:
        raise GeometryError(f"profiles need shapes (m+1, 3) and (n+1, 3) with m, n >= 1, got {a.shape}, {b.shape}")
    p = b[0] if p is None else np.asarray(p, dtype=float)
    normals: list[np.ndarray | None] = []
    for name, c in (("a", a), ("b", b)):
        if len(c) >= 3:
            plane, res = pl.fit_plane(c)
            size = float(np.linalg.norm(np.ptp(c, axis=0))) or 1.0
            if res > 1e-9 * size:
                raise GeometryError(f"profile {name} is not planar: a point is {res:.3g} off its plane", element=name,
                                    value=float(res))
            normals.append(plane[:3])
        else:
            normals.append(None)
    v = a[:, None, :] + b[None, :, :] - p
    na, nb = normals
    if na is not None and nb is not None:
        s = float(np.linalg.norm(np.cross(na, nb)))
        if s < np.sin(np.radians(1.0)):
            raise GeometryError(f"the planes of the two profiles are parallel ({np.degrees(np.arcsin(s)):.3g}°): "
                                f"the node axes (their common direction) are undefined", element="a, b", value=s)
    support_u = support_w = None
    if nb is not None:       # rows are translates of b: U_i through a_i, normal n_b
        support_u = np.concatenate([np.broadcast_to(nb, (len(a), 3)), -(v[:, 0] @ nb)[:, None]], axis=1)
    if na is not None:
        support_w = np.concatenate([np.broadcast_to(na, (len(b), 3)), -(v[0, :] @ na)[:, None]], axis=1)
    return with_face_image(QuadGrid(v, support_u=support_u, support_w=support_w))


@dataclass(frozen=True)
class TranslationalParams:
    """Two planar profiles; the surface is their translational sum."""

    a_points: list[list[float]] = param(doc="profile a in plane eps as 2D points (default eps = xz-plane: [x, z])",
                                        min_length=3)
    b_points: list[list[float]] = param(doc="profile b in plane phi as 2D points (default phi = yz-plane: [y, z])",
                                        min_length=3)
    common_point: list[float] = param([0.0, 0.0, 0.0], doc="p in x = a(s) + b(t) - p; the point where the profiles "
                                                           "meet makes the surface contain both", length=3)
    fit: str = param("interpolate", doc="'interpolate' or 'control' (B-spline control polygon)",
                     choices=("interpolate", "control"))
    faces_u: int = param(20, doc="faces along a", min=1, max=4000)
    faces_v: int = param(14, doc="faces along b", min=1, max=4000)
    eps_origin: list[float] = param([0.0, 0.0, 0.0], doc="a point of plane eps", length=3)
    eps_axes: list[list[float]] = param([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], doc="two in-plane axes of eps", length=2)
    phi_origin: list[float] = param([0.0, 0.0, 0.0], doc="a point of plane phi", length=3)
    phi_axes: list[list[float]] = param([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], doc="two in-plane axes of phi", length=2)

    def __post_init__(self):
        eps, phi = self.frames()
        s = float(np.linalg.norm(np.cross(eps.normal, phi.normal)))
        if s < np.sin(np.radians(1.0)):
            raise DesignError("phi_axes", f"planes eps and phi are parallel ({np.degrees(np.arcsin(min(s, 1))):.3g}°): "
                                          f"a translational surface needs two different profile planes")
        self.curves()

    def frames(self) -> tuple[Frame, Frame]:
        return (Frame.from_axes(self.eps_origin, self.eps_axes, "eps_axes"),
                Frame.from_axes(self.phi_origin, self.phi_axes, "phi_axes"))

    def curves(self) -> tuple[PlanarCurve, PlanarCurve]:
        eps, phi = self.frames()
        return (fit_planar_curve(self.a_points, eps, self.fit, "a_points", "a"),
                fit_planar_curve(self.b_points, phi, self.fit, "b_points", "b"))


def _samples(curve: PlanarCurve, count: int) -> np.ndarray:
    return curve.point(curve.param_at_length(np.linspace(0.0, curve.length, count)))


@construction("translational", TranslationalParams,
              "translational surface of two planar profiles (both support-plane families parallel)",
              section="§3.1 (special case)")
def build_translational(p: TranslationalParams) -> QuadGrid:
    a, b = p.curves()
    return translational_mesh(_samples(a, p.faces_u + 1), _samples(b, p.faces_v + 1), np.asarray(p.common_point))
