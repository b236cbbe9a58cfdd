"""The designer's handles of each construction: points in the construction's own coordinates that edit its
parameters, as the paper's design methods use them.

A :class:`HandleSet` lists the handles of one parameter record (:meth:`HandleSet.handles`) and maps a moved
handle back to new parameters (:meth:`HandleSet.apply`).  Every map is closed form and exact, so the edited
parameters are plain numbers that a design file stores and that reproduce the mesh.

``face_image_curves`` (Prop. 3.1, eq. 8: ``f(u, v) = g(u) + h(v) − c``)
    Each curve ``g`` (resp. ``h``) of polynomial degree ``D`` is fixed by its values at ``D + 1`` nodes
    ``u_0 … u_D`` spread over ``u_range``.  The handle of node ``u_k`` is the face plane
    ``F_k = g(u_k) + h(v̄) − c`` (``v̄`` the middle of ``v_range``), shown at the point of that plane nearest
    the mesh face at ``(u_k, v̄)``.  Moving the handle by ``t`` and turning it by ``R`` makes the plane
    ``n' = R n``, ``d' = −n'·p'`` (``p' = p + t``, ``n·p + d = 0``): a new tangent plane of the roof there.  Then
    ``g(u_k) = F'_k − h(v̄) + c`` and every component of ``g`` is re-interpolated through the ``D + 1`` node
    values (a Vandermonde solve, exact for degree ``D``).  The mesh stays PP: every face image of the form (8) is.
``conical_spheres`` (§4.2.3, Steps 1 and 4)
    The centres of the control spheres ``(x, y, z, r)`` (the radii are number inputs) and, with a Step 4
    profile, its control points in the frame of ``W_k`` (moved points are projected into that plane).
``translational``, ``profile_curves``, ``conical_sections``, ``plane_splines``, ``bisector``,
``conical_spheres_pp``
    Point and plane handles, see :mod:`fabrication.studio.point_handles`.
``cauchy`` (§3.1.2, Fig. 7)
    The initial vertices, each sliding on its node axis, and the turnable support planes, see
    :mod:`fabrication.studio.cauchy_handles` (``conical_pp`` is edited with the controls alone: its parameters
    are series coefficients).
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from .cauchy_handles import CauchyHandles
from .handle_base import Handle, HandleSet, Params, Scalar
from .point_handles import (BisectorHandles, PlaneSplineHandles, ProfileHandles, SectionHandles,
                            SpinePPHandles, TranslationalHandles)


def _rot_z(deg: float) -> np.ndarray:
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


# ----------------------------------------------------------------------------------------------------------
# face_image_curves


def _polyval(coeffs: list[list[float]], t: np.ndarray) -> np.ndarray:
    """``(len(t), 4)``: one polynomial per coordinate, coefficients lowest degree first."""
    return np.stack([np.polynomial.polynomial.polyval(t, np.asarray(c, dtype=float)) for c in coeffs], axis=-1)


def curve_nodes(coeffs: list[list[float]], span: list[float]) -> np.ndarray:
    """``D + 1`` uniform nodes over ``span`` for a curve of largest degree ``D`` (at least 2 nodes)."""
    degree = max(1, max(len(c) for c in coeffs) - 1)
    return np.linspace(float(span[0]), float(span[1]), degree + 1)


def interpolate(nodes: np.ndarray, values: np.ndarray) -> list[list[float]]:
    """Coefficients (lowest degree first, one list per coordinate) of the polynomial curve of degree
    ``len(nodes) − 1`` through ``values (len(nodes), 4)`` at ``nodes``: the Vandermonde system ``V a = y``."""
    V = np.vander(nodes, len(nodes), increasing=True)
    a = np.linalg.solve(V, values)
    return [[float(x) for x in a[:, c]] for c in range(values.shape[1])]


class FaceImageHandles(HandleSet):
    """Tangent-plane handles at the nodes of ``g`` and ``h`` (see the module docstring)."""

    def _planes(self, params: Params) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """Curve name → (nodes (D+1,), node values (D+1, 4), face planes F_k (D+1, 4))."""
        c = np.asarray(params.get("c", [0.0, 0.0, 0.0, 0.0]), dtype=float)
        ur, vr = params.get("u_range", [0.0, 1.0]), params.get("v_range", [0.0, 1.0])
        um, vm = 0.5 * (ur[0] + ur[1]), 0.5 * (vr[0] + vr[1])
        out = {}
        for name, span, other, at in (("g", ur, "h", vm), ("h", vr, "g", um)):
            nodes = curve_nodes(params[name], span)
            values = _polyval(params[name], nodes)
            rest = _polyval(params[other], np.array([at]))[0]
            out[name] = (nodes, values, values + rest - c)
        return out

    def _anchor(self, params: Params, grid: Any, name: str, t: float, plane: np.ndarray) -> np.ndarray:
        """The point of ``plane`` nearest the centre of the mesh face at parameter ``t`` (and the middle of the
        other parameter)."""
        v = np.asarray(grid.vertices)
        centres = 0.25 * (v[:-1, :-1] + v[1:, :-1] + v[1:, 1:] + v[:-1, 1:])
        span = params["u_range" if name == "g" else "v_range"]
        m, n = centres.shape[:2]
        s = (t - span[0]) / (span[1] - span[0])
        if name == "g":
            x = centres[int(round(s * (m - 1))), n // 2]
        else:
            x = centres[m // 2, int(round(s * (n - 1)))]
        nrm = plane[:3]
        return x - (nrm @ x + plane[3]) / (nrm @ nrm) * nrm

    def handles(self, params: Params, grid: Any) -> list[Handle]:
        out = []
        for name, (nodes, _, planes) in self._planes(params).items():
            colour = (230, 90, 40) if name == "g" else (40, 110, 230)
            for k, (t, plane) in enumerate(zip(nodes, planes)):
                out.append(Handle(f"{name}{k}", self._anchor(params, grid, name, float(t), plane),
                                  f"{name}({t:.3g}): tangent plane", colour, rotatable=True,
                                  normal=np.asarray(plane[:3], dtype=float)))
        return out

    def apply(self, params: Params, grid: Any, key: str, position: np.ndarray, rotation: np.ndarray) -> Params:
        name, k = key[0], int(key[1:])
        if name not in ("g", "h"):
            raise KeyError(key)
        planes = self._planes(params)
        nodes, values, F = planes[name]
        n = np.asarray(rotation, dtype=float) @ F[k, :3]
        new_plane = np.r_[n, -float(n @ np.asarray(position, dtype=float))]
        values = values.copy()
        values[k] = values[k] + (new_plane - F[k])
        out = copy.deepcopy(params)
        out[name] = interpolate(nodes, values)
        return out


# ----------------------------------------------------------------------------------------------------------
# conical_spheres


class SphereHandles(HandleSet):
    """Centres of the control spheres and the Step 4 profile's control points (see the module docstring)."""

    def handles(self, params: Params, grid: Any) -> list[Handle]:
        out = [Handle(f"s{k}", np.asarray(s[:3], dtype=float), f"sphere {k} centre", (200, 60, 160))
               for k, s in enumerate(params["spheres"])]
        frame = getattr(grid, "meta", {}).get("profile_frame")
        if params.get("profile") and frame is not None:
            pts = frame.to3d(np.asarray(params["profile"], dtype=float))
            out += [Handle(f"p{k}", p, f"profile point {k}", (40, 170, 90)) for k, p in enumerate(pts)]
        return out

    def apply(self, params: Params, grid: Any, key: str, position: np.ndarray, rotation: np.ndarray) -> Params:
        out = copy.deepcopy(params)
        k = int(key[1:])
        if key[0] == "s":
            out["spheres"][k] = [float(x) for x in position] + [float(out["spheres"][k][3])]
        elif key[0] == "p":
            frame = grid.meta["profile_frame"]
            out["profile"][k] = [float(x) for x in frame.to2d(np.asarray(position, dtype=float))]
        else:
            raise KeyError(key)
        return out

    def scalars(self, params: Params) -> list[Scalar]:
        def radius(k: int) -> Scalar:
            def set_r(p: Params, value: float) -> Params:
                q = copy.deepcopy(p)
                q["spheres"][k][3] = float(value)
                return q
            return Scalar(f"sphere {k} radius", lambda p: float(p["spheres"][k][3]), set_r)
        return [radius(k) for k in range(len(params["spheres"]))]


HANDLE_SETS: dict[str, HandleSet] = {
    "face_image_curves": FaceImageHandles(),
    "conical_spheres": SphereHandles(),
    "translational": TranslationalHandles(),
    "profile_curves": ProfileHandles(),
    "conical_sections": SectionHandles(),
    "plane_splines": PlaneSplineHandles(),
    "bisector": BisectorHandles(),
    "conical_spheres_pp": SpinePPHandles(),
    "cauchy": CauchyHandles(),
}
"""Construction name → its handles; constructions not named here are edited with the sliders alone."""


def handle_set(method: str | None) -> HandleSet:
    return HANDLE_SETS.get(method or "", HandleSet())


def placement(geometry: Params) -> tuple[float, np.ndarray, np.ndarray]:
    """``(s, R (3, 3), t (3,))`` of ``[geometry]``'s placement ``x' = s R_z x + t`` (mm)."""
    return (float(geometry.get("scale", 1.0)), _rot_z(float(geometry.get("rotate_z_deg", 0.0))),
            np.asarray(geometry.get("translate", [0.0, 0.0, 0.0]), dtype=float))
