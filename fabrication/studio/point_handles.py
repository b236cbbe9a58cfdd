"""Point and plane handles of the constructions whose parameters are points or planes in space.

Every map from a moved handle to new parameters is closed form; where a construction has a side condition
that a single moved point would break, the map restores it exactly by a rigid translation of the *other*
input (never by changing the point the designer moved), so the construction's own guarantee (PP, or the
conical property) holds for every accepted edit.  An edit the construction still refuses (an inflection, a
fold, parallel planes) is refused by the model with the construction's one-line reason.

``translational`` (§3.1, special case)
    The points of profile ``a`` (in plane ε) and ``b`` (in plane φ), moved points projected into their plane
    (:meth:`~ppfab.frame.Frame.to2d` drops the normal component).  Any two planar profiles give a PP mesh.
``profile_curves`` (§3.2.1)
    The points of ``c`` (in ε) and ``d`` (in φ).  The curves must meet at a point of ``ε ∩ φ`` with a common
    normal along that line.  After a point of ``c`` moves, ``p`` is the point of the new ``c`` whose normal is
    along ``ε ∩ φ`` (``m(t)·n_φ = 0``, unique on a convex curve) and ``q`` the point where ``d`` crosses ε; the
    plane φ (and ``d`` with it) is translated by ``p − q``.  Both points lie in ε, so ε is unchanged, ``d`` now
    crosses ε at ``p`` with its old normal and φ passes through ``p``: the conditions hold again.  The same with
    the roles swapped for a point of ``d``.
``conical_sections`` (§4.1.2)
    The points of section A (shown in the plane ``y = y_crest``) and B (``x = x_crest``).  The sections must be
    horizontal at the same height; after a point of one section moves, the other is translated in ``z`` by the
    difference of their crest heights (the crest height of a translated curve moves by the translation).
``plane_splines`` (§3.2.2)
    One turnable handle per plane ``γ``, ``γ_{i,i+1}``, ``τ_i``: shown at the point of the plane nearest the
    mesh face at its knot, moved and turned it becomes the plane ``[p', R n]`` (stored as point and normal).
    With ``side_condition = "project"`` the construction turns ``γ_i`` and ``τ_i`` about the knot line into
    place; ``u_planes[0]`` is the common corner plane, so ``v_planes[0]`` follows it.  Default tangent planes
    are written out (the ones the construction used) when one of them is first moved.
``bisector`` (§3.1.3)
    The points (sphere centres) of the polylines ``g`` and ``h``; radii stay.  Any points give a PP mesh.
``conical_spheres_pp`` (§4.2.4)
    The sphere centres, a moved centre projected into the plane ``M`` of the others (the spine must stay
    planar; with fewer than three others any position is coplanar).
"""

from __future__ import annotations

import copy
import warnings
from typing import Any

import numpy as np

from ppfab.frame import Frame

from .handle_base import Handle, HandleSet, Params

_COLOURS = ((230, 90, 40), (40, 110, 230), (40, 170, 90), (150, 70, 200))


def _split(key: str) -> tuple[str, int]:
    """``"c_points_3"`` → ``("c_points", 3)``."""
    name, _, k = key.rpartition("_")
    if not name or not k.isdigit():
        raise KeyError(key)
    return name, int(k)


def _face_centres(grid: Any) -> np.ndarray:
    v = np.asarray(grid.vertices)
    return 0.25 * (v[:-1, :-1] + v[1:, :-1] + v[1:, 1:] + v[:-1, 1:])


class PlanarPointHandles(HandleSet):
    """Handles of point lists given as 2D coordinates in plane frames (subclasses name the lists, the frames
    and the repair of the side condition)."""

    lists: tuple[str, ...] = ()

    def frame(self, params: Params, grid: Any, name: str) -> Frame:
        raise NotImplementedError

    def rejoin(self, params: Params, grid: Any, name: str) -> Params:
        """Restore the construction's side condition after a point of ``name`` moved (default: none)."""
        return params

    def handles(self, params: Params, grid: Any) -> list[Handle]:
        out = []
        for colour, name in zip(_COLOURS, self.lists):
            pts = self.frame(params, grid, name).to3d(np.asarray(params[name], dtype=float))
            out += [Handle(f"{name}_{k}", p, f"{name}[{k}]", colour) for k, p in enumerate(pts)]
        return out

    def apply(self, params: Params, grid: Any, key: str, position: np.ndarray, rotation: np.ndarray) -> Params:
        name, k = _split(key)
        if name not in self.lists:
            raise KeyError(key)
        out = copy.deepcopy(params)
        out[name][k] = [float(x) for x in self.frame(params, grid, name).to2d(np.asarray(position, dtype=float))]
        return self.rejoin(out, grid, name)


class TranslationalHandles(PlanarPointHandles):
    lists = ("a_points", "b_points")

    def frame(self, params: Params, grid: Any, name: str) -> Frame:
        if name == "a_points":
            return Frame.from_axes(params["eps_origin"], params["eps_axes"], "eps_axes")
        return Frame.from_axes(params["phi_origin"], params["phi_axes"], "phi_axes")


class ProfileHandles(TranslationalHandles):
    lists = ("c_points", "d_points")

    def frame(self, params: Params, grid: Any, name: str) -> Frame:
        return super().frame(params, grid, "a_points" if name == "c_points" else "b_points")

    def rejoin(self, params: Params, grid: Any, name: str) -> Params:
        from ppfab.constructions.profile_curves import crossing
        from ppfab.curves import fit_planar_curve

        eps, phi = self.frame(params, grid, "c_points"), self.frame(params, grid, "d_points")
        moved, other = ("c_points", "d_points") if name == "c_points" else ("d_points", "c_points")
        f_moved, f_other = (eps, phi) if name == "c_points" else (phi, eps)
        curve = fit_planar_curve(params[moved], f_moved, params["fit"], moved, moved[0])
        p = _crest(curve, f_other.normal, moved)
        still = fit_planar_curve(params[other], f_other, params["fit"], other, other[0])
        size = max(curve.extent, still.extent)
        q = still.point(np.array([crossing(still, f_moved.origin, f_moved.normal, 1e-3 * size, other,
                                           "eps" if name == "c_points" else "phi")]))[0]
        origin = "phi_origin" if name == "c_points" else "eps_origin"
        out = copy.deepcopy(params)
        out[origin] = [float(x) for x in np.asarray(params[origin], dtype=float) + (p - q)]
        return out


def _crest(curve: Any, across: np.ndarray, key: str) -> np.ndarray:
    """The point of a planar ``curve`` whose unit normal is orthogonal to ``across (3,)``: the root of
    ``m(t)·across`` on ``[t0, t1]`` (it must be unique)."""
    from scipy.optimize import brentq

    from ppfab.errors import DesignError

    t = np.linspace(curve.t0, curve.t1, 2001)

    def s(x: Any) -> Any:
        return curve.unit_normal(np.atleast_1d(x)) @ across

    val = s(t)
    roots = [float(t[k]) for k in np.flatnonzero(val == 0)]
    roots += [brentq(lambda x: float(s(x)[0]), t[k], t[k + 1], xtol=1e-15 * (t[-1] - t[0]))
              for k in np.flatnonzero(val[:-1] * val[1:] < 0)]
    if len(roots) != 1:
        raise DesignError(key, f"the moved curve has {len(roots)} points where its normal lies along the line "
                               f"eps∩phi (it needs exactly one, where the two curves meet)")
    return curve.point(np.array(roots))[0]


class SectionHandles(PlanarPointHandles):
    lists = ("section_a", "section_b")

    def frame(self, params: Params, grid: Any, name: str) -> Frame:
        crest = np.asarray(getattr(grid, "meta", {}).get("crest", np.zeros(3)), dtype=float)
        if name == "section_a":
            return Frame.from_axes([0.0, crest[1], 0.0], [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], name)
        return Frame.from_axes([crest[0], 0.0, 0.0], [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], name)

    def rejoin(self, params: Params, grid: Any, name: str) -> Params:
        from ppfab.constructions.conical_sections import _prepare

        def height(which: str, pts: list) -> float:
            sec, _, _ = _prepare(pts, params["case"], which, params["curve"], int(params[f"faces_{which}"]),
                                 params["sampling"], float(params["d"]), int(params["degree"]))
            return -float(sec.support(np.array([sec.crest_t]))[0])

        other = "section_b" if name == "section_a" else "section_a"
        dz = height(name[-1], params[name]) - height(other[-1], params[other])
        out = copy.deepcopy(params)
        out[other] = [[float(p[0]), float(p[1]) + dz] for p in params[other]]
        return out


class PlaneSplineHandles(HandleSet):
    """Turnable plane handles of ``plane_splines`` (see the module docstring)."""

    def _planes(self, params: Params) -> dict[str, np.ndarray]:
        """List name → unit planes ``(k, 4)``; default tangents are the ones the construction uses."""
        from ppfab.constructions.plane_splines import plane_from_entry, plane_spline

        out = {}
        g0 = None
        for axis in ("u", "v"):
            out[f"{axis}_planes"] = np.stack([plane_from_entry(e, f"{axis}_planes[{k}]")
                                              for k, e in enumerate(params[f"{axis}_planes"])])
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                spline = plane_spline(params[f"{axis}_planes"], params.get(f"{axis}_tangents"),
                                      params["side_condition"], params["tolerance"], g0=g0, name=axis)
            g0 = spline.knots[0]
            given = params.get(f"{axis}_tangents")
            out[f"{axis}_tangents"] = spline.tangents if given is None else \
                np.stack([plane_from_entry(e, f"{axis}_tangents[{k}]") for k, e in enumerate(given)])
        return out

    @staticmethod
    def _anchor(centres: np.ndarray, name: str, k: int, count: int, plane: np.ndarray) -> np.ndarray:
        """The point of ``plane`` nearest the face centre at the knot (``γ``: ``t = k/2``, ``τ``: ``t = k``,
        segments ``(count − 1)/2`` resp. ``count − 1``), at the middle (``γ``) or a quarter (``τ``) of the
        other direction."""
        m, n = centres.shape[:2]
        tangent = name.endswith("tangents")
        segments = (count - 1) if tangent else (count - 1) / 2
        t = (k if tangent else k / 2) / max(segments, 1)
        across = 0.25 if tangent else 0.5
        if name[0] == "u":
            x = centres[int(round(t * (m - 1))), int(round(across * (n - 1)))]
        else:
            x = centres[int(round(across * (m - 1))), int(round(t * (n - 1)))]
        nrm = plane[:3]
        return x - (nrm @ x + plane[3]) * nrm

    def handles(self, params: Params, grid: Any) -> list[Handle]:
        centres = _face_centres(grid)
        out = []
        for colour, (name, planes) in zip(_COLOURS, self._planes(params).items()):
            for k, plane in enumerate(planes):
                if name == "v_planes" and k == 0:
                    continue                          # the common corner plane: the handle u_planes_0
                out.append(Handle(f"{name}_{k}", self._anchor(centres, name, k, len(planes), plane),
                                  f"{name}[{k}]", colour, rotatable=True, normal=np.asarray(plane[:3], dtype=float)))
        return out

    def apply(self, params: Params, grid: Any, key: str, position: np.ndarray, rotation: np.ndarray) -> Params:
        name, k = _split(key)
        planes = self._planes(params)
        if name not in planes or (name == "v_planes" and k == 0):
            raise KeyError(key)
        n = np.asarray(rotation, dtype=float) @ planes[name][k, :3]
        entry = [float(x) for x in np.r_[np.asarray(position, dtype=float), n]]
        out = copy.deepcopy(params)
        if out.get(name) is None:                     # default tangents: write out the ones in use
            out[name] = [[float(x) for x in p] for p in planes[name]]
        out[name][k] = entry
        if name == "u_planes" and k == 0:
            out["v_planes"][0] = list(entry)
        return out


class BisectorHandles(HandleSet):
    """The points of ``g`` and ``h`` (see the module docstring)."""

    def handles(self, params: Params, grid: Any) -> list[Handle]:
        return [Handle(f"{name}_{k}", np.asarray(p[:3], dtype=float), f"{name}[{k}]", colour)
                for colour, name in zip(_COLOURS, ("g", "h")) for k, p in enumerate(params[name])]

    def apply(self, params: Params, grid: Any, key: str, position: np.ndarray, rotation: np.ndarray) -> Params:
        name, k = _split(key)
        if name not in ("g", "h"):
            raise KeyError(key)
        out = copy.deepcopy(params)
        out[name][k] = [float(x) for x in position] + [float(x) for x in params[name][k][3:]]
        return out


class SpinePPHandles(HandleSet):
    """The sphere centres of ``conical_spheres_pp``, kept in the plane of the others."""

    def handles(self, params: Params, grid: Any) -> list[Handle]:
        return [Handle(f"centers_{k}", np.asarray(c, dtype=float), f"sphere {k} centre", (200, 60, 160))
                for k, c in enumerate(params["centers"])]

    def apply(self, params: Params, grid: Any, key: str, position: np.ndarray, rotation: np.ndarray) -> Params:
        name, k = _split(key)
        if name != "centers":
            raise KeyError(key)
        c = np.asarray(params["centers"], dtype=float)
        p = np.asarray(position, dtype=float)
        others = np.delete(c, k, axis=0)
        if len(others) >= 3:
            mean = others.mean(0)
            _, sv, vt = np.linalg.svd(others - mean)
            if sv[1] > 1e-9 * max(sv[0], 1e-300):     # the others span a plane M: project into it
                p = p - ((p - mean) @ vt[2]) * vt[2]
        out = copy.deepcopy(params)
        out["centers"][k] = [float(x) for x in p]
        return out
