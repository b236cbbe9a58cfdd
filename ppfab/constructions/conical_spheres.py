"""Conical P meshes from a family of spheres — the channel-surface approach (paper §4.2.3, §4.2.4).

Step 1  Control spheres ``(x, y, z, r)`` → a B-spline family ``Z(t)`` sampled uniformly in
        tangential distance (eq. 2): spheres ``Z_0 … Z_N`` (:mod:`ppfab.spheres`).
Step 2  The cone ``C_i`` touches ``Z_i`` and ``Z_{i+1}``; consecutive cones meet in the planes
        ``W_i`` of eq. (16).
Step 3  Tangent planes ``T_{s,j}`` of one cone ``C_s`` (profile angle ``θ_j``) are carried to the next
        cone by the Minkowski reflection ``σ_i`` that fixes ``W_i`` point by point (Remark 4.4):
        ``T_{i,j} = σ_i(T_{i−1,j})``.  The vertex ``v_ij = T_{i,j−1} ∩ T_{i,j} ∩ W_i`` is shared by the
        strips on both sides of ``W_i``, so rows lie in ``W_i`` (P property) and all faces at ``v_ij``
        touch ``Z_i`` (conical).
Step 4  The circular profile in ``W_{k}`` is replaced by the polygon circumscribing a designer's
        convex profile curve with edges parallel to the original ones (each strip plane keeps its
        normal and moves to the profile's support line); propagated by the same ``σ_i`` the mesh
        stays parallel to the channel mesh, hence conical and P.  A profile with inflections
        (Remark 4.2) gets the polygon *inscribed* in it instead: its vertices on the curve at equal
        arclength, each edge in the tangent plane of the cone whose trace in ``W_k`` is parallel to it —
        the profile angles ``θ_j`` of the channel mesh then run forwards and, past an inflection,
        backwards (the source profile traversed to and fro), and the mesh is still parallel to a
        channel mesh, conical and P.

§4.2.4  With the sphere centres in a plane ``M`` and every sphere touching a plane ``T``, all cone
        vertices lie on ``M ∩ T``; every transverse polyline then lies in a plane through that line
        and the mesh is a conical PP mesh (method ``conical_spheres_pp``).

Grid layout: row ``i`` (vertices ``v[i, :]``) lies in ``W_i`` (``support_u``), ``i = 0 … N``; column ``j``
follows the spine at profile angle ``θ_j``.  With a closed profile the rows are closed loops.
Oriented contact is ``n·c + d + r = 0`` (:mod:`ppfab.laguerre`): for positive radii the face
normals point away from the spine.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike

from ppfab import planes as pl
from ..errors import DesignError, GeometryError
from ..folds import check_folds, orientation_sign
from ..mesh import QuadGrid
from ..schema import param
from ..frame import Frame
from ..curves import PlanarCurve, support_values, weak_curvature
from ppfab.conical.arcspline import ArcSpline
from ppfab.conical.cones import cone_axes
from ppfab.conical.spheres import SphereSpline, bisector_normals_extended, check_spacelike_pairs, reflections, w_planes
from .registry import construction


def cone_frame(Z0: np.ndarray, Z1: np.ndarray, up: ArrayLike) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
    """Axis ``a``, ``cos β`` and the profile frame ``b1, b2`` of the cone touching spheres ``Z0``, ``Z1``.

    Tangent planes have unit normals ``n(θ) = cos β a + sin β (cos θ b1 + sin θ b2)`` with
    ``n·(c1 − c0) = −(r1 − r0)``; ``b1`` is the direction of ``up`` orthogonal to ``a`` (``θ = 0`` is the crown).
    """
    dc = Z1[:3] - Z0[:3]
    length = float(np.linalg.norm(dc))
    a = dc / length
    cosb = -(Z1[3] - Z0[3]) / length
    up = np.asarray(up, dtype=float)
    b1 = up - (up @ a) * a
    if np.linalg.norm(b1) <= 1e-9 * np.linalg.norm(up):
        raise GeometryError("the 'up' direction is parallel to the spine at the profile plane; choose another up",
                            element="up")
    b1 = b1 / np.linalg.norm(b1)
    return a, float(cosb), b1, np.cross(a, b1)


def profile_angles(faces: int, angle_range: tuple[float, float], closed: bool) -> np.ndarray:
    """Face angles (radians) with ghosts: ``faces + 2`` values (open, ghosts half a step beyond the
    ends so the boundary vertices sit at the range ends) or ``faces + 1`` (closed, column ``b`` is face
    ``(b − 1) mod faces``)."""
    a0, a1 = np.radians(angle_range)
    if closed:
        step = 2 * np.pi / faces
        return a0 + step * ((np.arange(faces + 1) - 1) % faces)
    return a0 + (np.arange(-1, faces + 1) + 0.5) * (a1 - a0) / faces


def _trace_angle(theta: np.ndarray, cone: tuple[np.ndarray, float, np.ndarray, np.ndarray], w: np.ndarray,
                 frame: Frame) -> np.ndarray:
    """Angle in the profile frame of the in-plane normal ``ν`` (the tangent plane's normal projected into
    ``W_k``, normal ``w``) of the cone's tangent plane at profile angle ``θ`` (radians), ``(k,)``."""
    a, cosb, b1, b2 = cone
    sinb = np.sqrt(max(0.0, 1.0 - cosb * cosb))
    n = cosb * a + sinb * (np.cos(theta)[:, None] * b1 + np.sin(theta)[:, None] * b2)
    nu = n - (n @ w)[:, None] * w
    return np.arctan2(nu @ frame.ey, nu @ frame.ex)


def _chord_planes(profile: PlanarCurve, faces: int, closed: bool, frame: Frame, Wk: np.ndarray,
                  cone: tuple[np.ndarray, float, np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Step 4 for a profile with inflections (Remark 4.2): the polygon inscribed in ``profile`` at equal
    arclength (one point beyond each end for the ghost strips of an open profile), each edge in the tangent
    plane of the cone whose trace in ``W_k`` is parallel to it.

    Returns the strip planes ``T0`` (in the layout of :func:`profile_angles`) and their profile angles
    ``θ`` (radians, not monotone past an inflection).  Raises :class:`GeometryError` when the cone's traces
    do not turn through every direction once (the cone axis lies in ``W_k``) or two neighbouring points of
    the polygon coincide."""
    a, cosb, b1, b2 = cone
    w = pl.normalize(Wk)[:3]
    t_dense, s_dense = profile.arclength_table(8001)
    total = float(s_dense[-1])
    step = total / faces
    if closed:
        s = step * np.arange(faces + 1)
    else:
        s = step * np.arange(-1, faces + 2)                          # a ghost point beyond each end
    t = np.interp(np.clip(s, 0.0, total), s_dense, t_dense)
    if not closed:                                                    # beyond the ends: the speed there
        t[0] = profile.t0 - step / float(profile.speed(np.array([profile.t0]))[0])
        t[-1] = profile.t1 + step / float(profile.speed(np.array([profile.t1]))[0])
    q = profile(t)                                                    # (P, 2) points in the frame
    d = np.diff(q, axis=0)
    length = np.linalg.norm(d, axis=1)
    if np.any(length <= 1e-9 * total):
        k = int(np.argmin(length))
        raise GeometryError(f"profile points {k} and {k + 1} of the inscribed polygon coincide", element="profile")
    right = np.stack([d[:, 1], -d[:, 0]], axis=1) / length[:, None]   # chord normal to the right of travel
    crown = float(np.sign(right[:, 0].sum())) or 1.0                  # the side of the crown (frame e1)
    psi = np.unwrap(np.arctan2(crown * right[:, 1], crown * right[:, 0]))
    grid_t = np.linspace(-np.pi, np.pi, 4097)
    table = np.unwrap(_trace_angle(grid_t, cone, w, frame))
    slope = np.diff(table)
    if not (np.all(slope > 0) or np.all(slope < 0)):
        raise GeometryError("the cone's tangent planes do not meet the profile plane in every direction once: "
                            "its axis lies too near the plane; choose another profile_plane", element="profile")
    if slope[0] < 0:
        grid_t, table = grid_t[::-1], table[::-1]
    span = table[-1] - table[0]                                       # 2π
    wrap = np.floor((psi - table[0]) / span)
    theta = np.interp(psi - wrap * span, table, grid_t)
    n = cosb * a + np.sqrt(max(0.0, 1.0 - cosb * cosb)) * (np.cos(theta)[:, None] * b1
                                                          + np.sin(theta)[:, None] * b2)
    x = frame.origin + q[:-1, :1] * frame.ex + q[:-1, 1:] * frame.ey   # each chord's first point, in space
    T = np.concatenate([n, -np.einsum("ki,ki->k", n, x)[:, None]], axis=1)
    if closed:
        T = np.concatenate([T[-1:], T], axis=0)                       # column b is face (b − 1) mod faces
        theta = np.concatenate([theta[-1:], theta])
    return T, theta


def _propagate(T0: np.ndarray, s0: int, sigma: list) -> np.ndarray:
    """Strip planes ``T_a`` for ``a = −1 … N`` from strip ``s0`` by the reflections (Step 3) → ``(N+2, k, 4)``.

    ``T_a = σ_a(T_{a−1})`` for ``a > s0`` and ``T_a = σ_{a+1}(T_{a+1})`` for ``a < s0``: with the homogeneous
    matrices ``B_a`` of the reflections (:meth:`~ppfab.transforms.laguerre.LaguerreMap.plane_matrix`) strip
    ``a`` is ``C_a X_0``, ``C_a = B_a ⋯ B_{s0+1}`` (resp. ``B_{a+1} ⋯ B_{s0}``), applied to all planes of all
    strips in one product.
    """
    N = len(sigma) - 1
    B = np.stack([m.plane_matrix() for m in sigma])
    C = np.empty((N + 2, 5, 5))
    C[s0 + 1] = np.eye(5)
    for a in range(s0 + 1, N + 1):                # a = N is the ghost strip beyond W_N
        C[a + 1] = B[a] @ C[a]
    for a in range(s0 - 1, -2, -1):               # a = −1 is the ghost strip before W_0
        C[a + 1] = B[a + 1] @ C[a + 2]
    P = pl.normalize(T0)
    X = np.concatenate([P[:, :3], -np.ones((len(P), 1)), P[:, 3:]], axis=1)
    Y = np.einsum("aij,kj->aki", C, X)
    out = np.concatenate([Y[..., :3], Y[..., 4:]], axis=-1) / -Y[..., 3:4]
    out[s0 + 1] = T0
    return out


def channel_mesh(spheres: np.ndarray, faces_spine: int, faces_profile: int,
                 angle_range: tuple[float, float] = (-90.0, 90.0), closed: bool = False,
                 up: ArrayLike = (0.0, 0.0, 1.0), degree: int = 3, profile: PlanarCurve | None = None,
                 profile_plane: int | None = None, check: bool = True, arcs: ArcSpline | None = None) -> QuadGrid:
    """A conical P mesh from control spheres (Steps 1–4 of §4.2.3).

    Parameters
    ----------
    spheres : (k, 4) float — control spheres ``(x, y, z, r)`` (consecutive ones spacelike)
    faces_spine : ``N``, the number of cones (face rows); ``N + 1`` spheres are sampled
    faces_profile : faces around the profile
    angle_range : profile angles in degrees from the crown (``θ = 0``: the normal closest to ``up``)
    closed : the profile runs once around (``angle_range[0]`` is the start); rows become closed loops
    up : reference direction for ``θ = 0``
    degree : degree of the sphere B-spline
    profile : optional convex curve in the frame of ``W_{profile_plane}`` (Step 4); the frame is
        ``meta["profile_frame"]`` (origin at the foot of the sphere centre on the plane, ``e1`` towards the
        crown face); the unchanged profile polygon in that frame is ``meta["profile_reference"]``
    profile_plane : index ``k`` of the plane whose profile is designed (default ``N // 2``)
    check : raise :class:`~ppfab.errors.FoldError` when the mesh folds
    arcs : optional arc-spline profile (Remark 4.3, :class:`~ppfab.conical.arcspline.ArcSpline`) in the
        cross-section ``Π`` of the cone ``C_s`` of strip ``s = min(k, N − 1)``: the plane through the centre of
        sphere ``Z_s`` normal to the cone's axis, frame ``meta["arc_frame"]`` (``e1`` towards the crown), where
        the normal angle of a tangent plane's trace is its profile angle ``θ`` and the channel's profile is a
        circle of radius ``r_s / sin β`` about the origin.  Each arc's faces are the tangent planes of one cone
        (a strip is a union of cone patches); ``angle_range`` is not used (the arcs' normal angles are), the
        faces are shared among the arcs by how far each turns (``meta["arc_of_column"]``)

    Returns
    -------
    QuadGrid ``(N+1, faces_profile + 1)`` (``(N+1, faces_profile)`` closed) with ``support_u = W``,
    unit face planes as ``face_image``, ``extended_face_planes`` (ghosts included), the cone axes
    (:func:`ppfab.conical.cones.cone_axes`: through the sphere centres on the channel mesh, the same
    directions after Step 4), and ``meta`` with the sampled spheres ``Z``, their parameters and ``H``.
    """
    if faces_spine < 1 or faces_profile < (3 if closed else 1):
        raise GeometryError(f"need at least 1 face along the spine and {3 if closed else 1} around the profile")
    spline = SphereSpline(spheres, degree)
    Z, tz = spline.sample_uniform(faces_spine + 1)
    H = bisector_normals_extended(spline, tz)
    W = w_planes(Z, H)
    sigma = reflections(Z, H)
    N = faces_spine
    k0 = N // 2 if profile_plane is None else int(profile_plane)
    if not 0 <= k0 <= N:
        raise GeometryError(f"profile_plane must be in 0..{N}, got {k0}", element="profile_plane", value=float(k0))
    s0 = min(k0, N - 1)
    a, cosb, b1, b2 = cone_frame(Z[s0], Z[s0 + 1], up)
    sinb = np.sqrt(max(0.0, 1.0 - cosb * cosb))
    theta = profile_angles(faces_profile, angle_range, closed)
    frame = _profile_frame(W[k0], Z[k0], cosb * a + sinb * b1, k0)
    inscribed = profile is not None and has_inflection(profile)
    if inscribed:
        assert profile is not None
        chords, theta = _chord_planes(profile, faces_profile, closed, frame, W[k0], (a, cosb, b1, b2))
    arc_of = np.zeros(0, dtype=np.int64)
    if arcs is not None:
        if profile is not None:
            raise GeometryError("a profile curve and profile arcs were both given; give one", element="profile_arcs")
        if arcs.closed != closed:
            raise GeometryError("the arc-spline profile must be closed exactly when the mesh is",
                                element="profile_arcs")
        theta, arc_of = arcs.face_angles(faces_profile)
    for attempt in range(2):
        if arcs is not None:               # Remark 4.3: reversed, the columns keep their arcs
            order = np.arange(len(theta)) if attempt == 0 else (
                np.r_[1, np.arange(len(theta) - 1, 0, -1)] if closed else np.arange(len(theta))[::-1])
            th, arc_th = theta[order], arc_of[order]
        else:
            th = theta if attempt == 0 else (-theta if closed else theta[::-1])
        n = cosb * a + sinb * (np.cos(th)[:, None] * b1 + np.sin(th)[:, None] * b2)
        T0 = np.concatenate([n, (-n @ Z[s0, :3] - Z[s0, 3])[:, None]], axis=1)
        reference = None
        if arcs is not None:               # each face's trace in Π the support line of its arc
            reference = frame.to2d(_vertices(_propagate(T0, s0, sigma), W, closed)[k0])
            T0 = np.concatenate([n, (-n @ Z[s0, :3] - sinb * arcs.support(th, arc_th))[:, None]], axis=1)
        elif inscribed:                      # Remark 4.2: the polygon inscribed in a profile with inflections
            th = theta if attempt == 0 else (np.concatenate([theta[1:2], theta[1:][::-1]]) if closed
                                             else theta[::-1])              # closed: column 0 is the last face
            T0 = chords if attempt == 0 else (np.concatenate([chords[1:2], chords[1:][::-1]]) if closed
                                              else chords[::-1])
        elif profile is not None:
            reference = frame.to2d(_vertices(_propagate(T0, s0, sigma), W, closed)[k0])
            T0 = _profile_planes(T0, frame, W[k0], profile)
        E = _propagate(T0, s0, sigma)
        v = _vertices(E, W, closed)
        inner = E[1:-1, 1:] if closed else E[1:-1, 1:-1]
        grid = QuadGrid(v, closed=closed, support_u=W, face_image=inner, extended_face_planes=E)
        s = orientation_sign(grid, inner)
        if (s > 0).sum() >= (s < 0).sum():
            break
    # the cone axes of the faces at each vertex (ghosts included at the boundary), turned against the
    # normals; on the channel mesh they pass through the sphere centres, after Step 4 (a parallel mesh:
    # the same normals) they are the same directions at the moved vertices — not the lines to the centres
    assert grid is not None
    axes, _ = cone_axes(grid)
    degrees = np.degrees(th[1:] if closed else th[1:-1])
    strip_t = 0.5 * (tz[1:] + tz[:-1])
    meta = {"spheres": Z, "sphere_t": tz, "H": H, "profile_plane": k0,
            "theta_deg": degrees, "profile_frame": frame, "profile_reference": reference,
            "planar_families": ("rows",)}
    if arcs is not None:
        meta["arc_frame"] = Frame(Z[s0, :3], b1, b2)
        meta["arc_of_column"] = arc_th[1:] if closed else arc_th[1:-1]
    grid = replace(grid, axes=axes, extended_face_planes=E, meta=meta)
    if check:                              # past an inflection the faces touch their spheres from the other
        check_folds(grid, strip_t, degrees, reference=None if inscribed else inner,       # side: no reference
                    context="conical_spheres", names=("spine t", "profile angle"))
    return grid


def has_inflection(curve: PlanarCurve, samples: int = 4001) -> bool:
    """Whether the curvature of ``curve`` changes sign or vanishes on ``[t0, t1]`` (Remark 4.2)."""
    t = np.linspace(curve.t0, curve.t1, samples)
    return bool(np.any(weak_curvature(curve, t, curve(t))))


def _vertices(E: np.ndarray, W: np.ndarray, closed: bool) -> np.ndarray:
    """``v[i, j] = T_{i, j−1} ∩ T_{i, j} ∩ W_i`` (strip ``i`` = ``E[i+1]``) → ``(N+1, cols, 3)``."""
    strip = E[1:]
    Wb = np.broadcast_to(W[:, None, :], strip[:, :-1].shape)
    return pl.intersect_three(strip[:, :-1], strip[:, 1:], Wb)


def _profile_frame(Wk: np.ndarray, Zk: np.ndarray, crown: np.ndarray, k: int) -> Frame:
    w = pl.normalize(Wk)
    origin = Zk[:3] - (w[:3] @ Zk[:3] + w[3]) * w[:3]
    e1 = crown - (crown @ w[:3]) * w[:3]
    e1 = e1 / np.linalg.norm(e1)
    return Frame(origin, e1, np.cross(w[:3], e1))


def _profile_planes(T0: np.ndarray, frame: Frame, Wk: np.ndarray, profile: PlanarCurve) -> np.ndarray:
    """Step 4: strip planes with the normals of ``T0`` through the support lines of ``profile`` in ``W_k``."""
    w = pl.normalize(Wk)[:3]
    n = T0[:, :3]
    nu = n - (n @ w)[:, None] * w
    nu /= np.linalg.norm(nu, axis=1, keepdims=True)
    omega = np.stack([nu @ frame.ex, nu @ frame.ey], axis=1)
    omega /= np.linalg.norm(omega, axis=1, keepdims=True)
    h, _ = support_values(profile, omega)
    x = frame.origin + h[:, None] * nu
    return np.concatenate([n, -np.einsum("ki,ki->k", n, x)[:, None]], axis=1)


def pp_column_planes(grid: QuadGrid) -> tuple[np.ndarray, float]:
    """Least-squares planes of the columns and the largest distance of a column vertex from its plane."""
    P, res = pl.fit_plane(grid.cols())
    return P, float(res.max())


def touching_radii(centers: np.ndarray, plane: np.ndarray, key: str = "touch_plane") -> np.ndarray:
    """Radii that make spheres with the given ``centers (k, 3)`` touch ``plane`` (oriented so that ``r > 0``)."""
    P = np.asarray(plane, dtype=float)
    if P.shape != (4,) or np.linalg.norm(P[:3]) == 0:
        raise DesignError(key, "needs [nx, ny, nz, d] with a nonzero normal")
    P = P / np.linalg.norm(P[:3])
    s = np.asarray(centers, dtype=float) @ P[:3] + P[3]
    size = max(float(np.ptp(centers, axis=0).max()), 1e-300)
    if np.any(np.abs(s) <= 1e-9 * size) or (np.any(s > 0) and np.any(s < 0)):
        k = int(np.argmin(np.abs(s))) if np.any(np.abs(s) <= 1e-9 * size) else int(np.argmax(np.sign(s) != np.sign(s[0])))
        raise DesignError(key, f"control centre {k} lies on or across the plane (signed distance {s[k]:.6g}); "
                               f"all centres must lie strictly on one side")
    return np.abs(s)


def coplanarity(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Least-squares plane of ``points (k, 3)`` and the largest distance from it."""
    P, res = pl.fit_plane(np.asarray(points, dtype=float))
    return P, float(res)


# -- design-file methods ----------------------------------------------------------------------------

def _check_angles(p) -> None:
    a0, a1 = p.angle_range
    if not p.closed and not (a0 < a1 and a1 - a0 < 360.0):
        raise DesignError("angle_range", f"needs start < end and less than 360° apart, got [{a0}, {a1}]")
    if p.closed and p.faces_profile < 3:
        raise DesignError("faces_profile", "a closed profile needs at least 3 faces")


@dataclass(frozen=True)
class ConicalSpheresParams:
    """Conical P mesh from a B-spline family of spheres (channel surface, §4.2.3, Steps 1–4)."""

    spheres: list[list[float]] = param(doc="control spheres [x, y, z, r] of the B-spline family (Step 1)",
                                       min_length=2)
    degree: int = param(3, doc="degree of the sphere B-spline", min=1, max=5)
    faces_spine: int = param(16, doc="faces along the spine (cones; faces_spine + 1 sampled spheres)", min=1, max=4000)
    faces_profile: int = param(12, doc="faces around the profile", min=1, max=4000)
    angle_range: list[float] = param([-90.0, 90.0], doc="profile angles in degrees, 0 = crown (normal closest to up)",
                                     length=2)
    closed: bool = param(False, doc="the profile runs once around (a tube); rows are closed loops")
    up: list[float] = param([0.0, 0.0, 1.0], doc="direction of the crown (profile angle 0)", length=3)
    profile: list[list[float]] = param([], doc="Step 4: profile curve [p, q] in the frame of W_profile_plane (origin "
                                              "at the circle's centre, p towards the crown); a convex one gets the "
                                              "circumscribed polygon at the profile angles, one with inflections the "
                                              "inscribed polygon at equal arclength (Remark 4.2; angle_range is "
                                              "then not used); empty: circle")
    profile_curve: str = param("interpolate", doc="interpolate: spline through the profile points; bspline: control points",
                               choices=("interpolate", "bspline"))
    profile_closed: bool = param(False, doc="the profile curve is closed (defaults to true for a closed mesh)")
    profile_plane: int = param(-1, doc="index of the plane W_k carrying the designed profile (-1: the middle one)",
                               min=-1)
    profile_arcs: list[list[float]] = param([], doc="Step 4 with an arc-spline profile (Remark 4.3): arcs [radius, "
                                                    "from_deg, to_deg] joined with a common tangent, by the angles of "
                                                    "their outward normals (the profile angles) in the cone's cross-"
                                                    "section at the profile plane; each arc's faces are tangent "
                                                    "planes of one cone; angle_range is then not used; empty: none")
    profile_arcs_centre: list[float] = param([0.0, 0.0], doc="centre [p, q] of the first profile arc (origin: the "
                                                             "sphere's centre, p towards the crown)", length=2)

    def __post_init__(self):
        for k, s in enumerate(self.spheres):
            if len(s) != 4:
                raise DesignError(f"spheres[{k}]", f"needs [x, y, z, r], got {len(s)} values")
        check_spacelike_pairs(np.asarray(self.spheres, dtype=float))
        _check_angles(self)
        if self.profile_plane > self.faces_spine:
            raise DesignError("profile_plane", f"must be at most faces_spine = {self.faces_spine}")
        for k, q in enumerate(self.profile):
            if len(q) != 2:
                raise DesignError(f"profile[{k}]", f"needs [p, q], got {len(q)} values")
        if self.profile_arcs:
            if self.profile:
                raise DesignError("profile_arcs", "and profile are both given: a designed profile is a curve or "
                                                  "arcs, not both; remove one")
            ArcSpline.from_arcs(self.profile_arcs, self.profile_arcs_centre, self.closed).faces_per_arc(
                self.faces_profile)


def _profile_curve(p: ConicalSpheresParams) -> PlanarCurve | None:
    if not p.profile:
        return None
    closed = p.profile_closed or p.closed
    if p.profile_curve == "interpolate":
        return PlanarCurve.from_points(p.profile, closed=closed, name="profile")
    return PlanarCurve.from_control_points(p.profile, closed=closed, name="profile")


@construction("conical_spheres", ConicalSpheresParams,
              "conical P mesh from a B-spline family of spheres: channel surface, propagated tangent planes, "
              "optional designed profile", planar_families=("rows",), section="§4.2.3")
def build_conical_spheres(p: ConicalSpheresParams) -> QuadGrid:
    arcs = ArcSpline.from_arcs(p.profile_arcs, p.profile_arcs_centre, p.closed) if p.profile_arcs else None
    return channel_mesh(np.asarray(p.spheres, float), p.faces_spine, p.faces_profile,
                        (p.angle_range[0], p.angle_range[1]),
                        p.closed, np.asarray(p.up, float), p.degree, _profile_curve(p),
                        None if p.profile_plane < 0 else p.profile_plane, arcs=arcs)


@dataclass(frozen=True)
class ConicalSpheresPPParams:
    """Conical PP mesh from spheres with a planar spine that all touch one plane (§4.2.4)."""

    centers: list[list[float]] = param(doc="control sphere centres [x, y, z], all in one plane M", min_length=2)
    touch_plane: list[float] = param(doc="the plane T = [nx, ny, nz, d] (n·x + d = 0) every sphere touches; "
                                         "the radii follow from it", length=4)
    degree: int = param(3, doc="degree of the sphere B-spline", min=1, max=5)
    faces_spine: int = param(16, doc="faces along the spine", min=1, max=4000)
    faces_profile: int = param(12, doc="faces around the profile", min=1, max=4000)
    angle_range: list[float] = param([-90.0, 90.0], doc="profile angles in degrees, 0 = crown", length=2)
    closed: bool = param(False, doc="the profile runs once around")
    up: list[float] = param([0.0, 0.0, 1.0], doc="direction of the crown (profile angle 0)", length=3)

    def __post_init__(self):
        c = np.asarray(self.centers, dtype=float)
        if c.ndim != 2 or c.shape[1] != 3:
            raise DesignError("centers", "needs a list of [x, y, z] centres")
        _check_angles(self)
        if len(c) >= 3:
            _, dev = coplanarity(c)
            size = float(np.ptp(c, axis=0).max())
            if dev > 1e-9 * max(size, 1e-300):
                raise DesignError("centers", f"the centres are not coplanar (largest distance from their plane "
                                             f"{dev:.3g}); the PP special case needs a planar spine (§4.2.4)")
        r = touching_radii(c, np.asarray(self.touch_plane, dtype=float))
        check_spacelike_pairs(np.concatenate([c, r[:, None]], axis=1), "centers")


@construction("conical_spheres_pp", ConicalSpheresPPParams,
              "conical PP mesh from spheres on a planar spine touching a common plane (channel surface)",
              planar_families=("rows", "cols"), section="§4.2.4")
def build_conical_spheres_pp(p: ConicalSpheresPPParams) -> QuadGrid:
    c = np.asarray(p.centers, dtype=float)
    spheres = np.concatenate([c, touching_radii(c, np.asarray(p.touch_plane, float))[:, None]], axis=1)
    grid = channel_mesh(spheres, p.faces_spine, p.faces_profile, (p.angle_range[0], p.angle_range[1]), p.closed,
                        np.asarray(p.up, float), p.degree)
    Wc, _ = pp_column_planes(grid)
    return replace(grid, support_w=Wc, meta={**grid.meta, "planar_families": ("rows", "cols")})
