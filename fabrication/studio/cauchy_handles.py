"""The handles of the Cauchy construction (§3.1.2, Fig. 7): the initial vertices on their node axes and the
support planes.

The construction's side condition is that every initial vertex lies on its node axis: ``v_{i,0}`` on
``l_{i0} = U_i ∩ W_0`` and ``v_{0,j}`` on ``l_{0j} = U_0 ∩ W_j`` (``v_00`` on both).  Every handle keeps it exactly,
in closed form:

``boundary_u_i``, ``boundary_w_j`` (points)
    The initial vertex slides along its node axis ``(p, d)`` (``|d| = 1``): a drag to ``x`` puts it at the
    foot ``p + ((x − p)·d) d``, the nearest point of the line.  ``boundary_u_0`` is ``v_00`` and sets both
    ``boundary_u[0]`` and ``boundary_w[0]``.
``support_u_i``, ``support_w_j`` (turnable planes)
    Shown at the middle of the last edge of the row ``v[i, :]`` (resp. the column ``v[:, j]``), a point of the
    plane on the far side from the initial polylines.  Moved to ``p'`` and turned by ``R`` the plane becomes
    ``n' = R n``, ``d' = −n'·p'`` (``|n|`` kept, so the stored numbers keep their scale).  The node axes through
    the edited plane move with it, and each initial vertex on one of them is replaced by its foot on the new
    axis (for ``U_0`` every ``v_{0,j}``, for ``W_0`` every ``v_{i,0}``, ``v_00`` once for both lists).

The result is exact Cauchy data, so the propagated mesh is PP (its rows lie in ``U_i``, its columns in
``W_j``); what the construction still refuses (planes that meet at too small an angle, a propagation that breaks
down) is refused by the model with the construction's reason.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from .handle_base import Handle, HandleSet, Params

_POINT_COLOURS = {"boundary_u": (230, 90, 40), "boundary_w": (40, 110, 230)}
_PLANE_COLOURS = {"support_u": (240, 170, 60), "support_w": (90, 170, 240)}


def _split(key: str) -> tuple[str, int]:
    name, _, k = key.rpartition("_")
    if name not in (*_POINT_COLOURS, *_PLANE_COLOURS) or not k.isdigit():
        raise KeyError(key)
    return name, int(k)


def _axes(U: np.ndarray, W: np.ndarray, min_angle_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Node axes ``U_i ∩ W_j``: points and unit directions ``(m+1, n+1, 3)`` (the construction's own lines)."""
    from ppfab.constructions.cauchy import node_axes_lines

    return node_axes_lines(U, W, min_angle_deg)


def _foot(x: Any, p: np.ndarray, d: np.ndarray) -> list[float]:
    """The point of the line ``(p (3,), d (3,))``, ``|d| = 1``, nearest ``x (3,)``."""
    x = np.asarray(x, dtype=float)
    return [float(c) for c in p + float((x - p) @ d) * d]


class CauchyHandles(HandleSet):
    """Initial vertices on their node axes and turnable support planes (see the module docstring)."""

    def handles(self, params: Params, grid: Any) -> list[Handle]:
        U, W = np.asarray(params["support_u"], float), np.asarray(params["support_w"], float)
        P, D = _axes(U, W, float(params["min_angle_deg"]))
        out = []
        v00 = 0.5 * (np.asarray(_foot(params["boundary_u"][0], P[0, 0], D[0, 0]))
                     + np.asarray(_foot(params["boundary_w"][0], P[0, 0], D[0, 0])))
        out.append(Handle("boundary_u_0", v00, "v_00 on U_0 ∩ W_0", _POINT_COLOURS["boundary_u"]))
        for i, x in enumerate(params["boundary_u"][1:], 1):
            out.append(Handle(f"boundary_u_{i}", np.asarray(_foot(x, P[i, 0], D[i, 0])), f"v_{i},0 on U_{i} ∩ W_0",
                              _POINT_COLOURS["boundary_u"]))
        for j, x in enumerate(params["boundary_w"][1:], 1):
            out.append(Handle(f"boundary_w_{j}", np.asarray(_foot(x, P[0, j], D[0, j])), f"v_0,{j} on U_0 ∩ W_{j}",
                              _POINT_COLOURS["boundary_w"]))
        v = np.asarray(grid.vertices, dtype=float)
        for i in range(v.shape[0]):
            out.append(Handle(f"support_u_{i}", 0.5 * (v[i, -2] + v[i, -1]), f"plane U_{i}",
                              _PLANE_COLOURS["support_u"], rotatable=True, normal=U[i, :3]))
        for j in range(v.shape[1]):
            out.append(Handle(f"support_w_{j}", 0.5 * (v[-2, j] + v[-1, j]), f"plane W_{j}",
                              _PLANE_COLOURS["support_w"], rotatable=True, normal=W[j, :3]))
        return out

    def apply(self, params: Params, grid: Any, key: str, position: np.ndarray, rotation: np.ndarray) -> Params:
        name, k = _split(key)
        out = copy.deepcopy(params)
        x = np.asarray(position, dtype=float)
        U, W = np.asarray(params["support_u"], float), np.asarray(params["support_w"], float)
        if name == "boundary_w" and k == 0:
            raise KeyError(f"{key} (v_00 is the handle boundary_u_0)")
        if name in _POINT_COLOURS:
            if k >= len(params[name]):
                raise IndexError(f"{name} has {len(params[name])} vertices, no {k}")
            P, D = _axes(U, W, float(params["min_angle_deg"]))
            i, j = (k, 0) if name == "boundary_u" else (0, k)
            out[name][k] = _foot(x, P[i, j], D[i, j])
            if k == 0:
                out["boundary_w"][0] = list(out["boundary_u"][0])
            return out
        planes = U if name == "support_u" else W
        n = np.asarray(rotation, dtype=float) @ planes[k, :3]
        out[name][k] = [float(c) for c in n] + [-float(n @ x)]
        U2, W2 = np.asarray(out["support_u"], float), np.asarray(out["support_w"], float)
        P, D = _axes(U2, W2, float(params["min_angle_deg"]))
        # the initial vertices on the node axes through the edited plane, each onto its foot on the new axis
        if name == "support_u":
            first, second = [k], (list(range(len(W))) if k == 0 else [])      # v_k0; and every v_0j for U_0
        else:
            first, second = (list(range(len(U))) if k == 0 else []), [k]      # every v_i0 for W_0; and v_0k
        for i in first:
            if i:
                out["boundary_u"][i] = _foot(params["boundary_u"][i], P[i, 0], D[i, 0])
        for j in second:
            if j:
                out["boundary_w"][j] = _foot(params["boundary_w"][j], P[0, j], D[0, j])
        if 0 in first or 0 in second:
            mid = 0.5 * (np.asarray(params["boundary_u"][0], float) + np.asarray(params["boundary_w"][0], float))
            out["boundary_u"][0] = _foot(mid, P[0, 0], D[0, 0])
            out["boundary_w"][0] = list(out["boundary_u"][0])
        return out
