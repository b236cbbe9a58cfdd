"""Support structure of a conical mesh: the node axes are the cone axes (§2.3.3)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ppfab import planes as pl
from ppfab.conical.cones import cone_axes, vertex_face_normals
from ppfab.errors import GeometryError
from ppfab.mesh import QuadGrid, QuadMesh
from ppfab.metrics import polyline_fit

from .parallel import _axes_from_offsets, parallel_offsets
from .registry import support_method
from .structure import SupportStructure, _assemble, as_quadmesh, vertex_normals

if TYPE_CHECKING:  # pragma: no cover
    from .params import BeamContext, SupportParams


def support_conical(mesh: QuadMesh | QuadGrid, flip: bool = False) -> SupportStructure:
    """Support structure of a conical mesh: node axes are the cone axes (§2.3.3).

    At vertices with 3 or more faces the axis makes equal angles with the adjacent
    unit face normals (:func:`ppfab.conical.cones.cone_axes`).  Those vertices are offset along their
    axes so that every face moves by the same distance (the constant-distance
    offset, a parallel mesh of a conical mesh); boundary vertices (1 or 2 faces)
    get the parallel-mesh offsets nearest to that same face offset.
    """
    qm = as_quadmesh(mesh)
    normals = vertex_normals(qm)
    a, cos = cone_axes(qm)
    determined = np.isfinite(cos)
    if np.any(determined & (cos < 1e-3)):
        k = int(np.flatnonzero(determined & (cos < 1e-3))[0])
        raise GeometryError(f"vertex {k}: the cone axis is (nearly) tangent to the faces "
                            f"(cos {cos[k]:.1e}); the faces there do not touch a cone", element=f"vertex {k}")
    fn, mask = vertex_face_normals(qm)
    target = np.zeros_like(qm.vertices)
    target[determined] = a[determined] / cos[determined, None]
    # boundary: the minimum-norm offset moving each of its faces inward by 1 (n_k · u = −1):
    # −n_1 at a corner, −(n_1 + n_2)/(1 + n_1·n_2) between two faces
    one = mask.sum(axis=1) == 1
    two = mask.sum(axis=1) == 2
    target[one] = -fn[one, 0]
    s2 = fn[two, 0] + fn[two, 1]
    target[two] = -s2 / (1.0 + np.einsum("ij,ij->i", fn[two, 0], fn[two, 1]))[:, None]
    u, info = parallel_offsets(qm, target, fixed=determined)
    axes = _axes_from_offsets(qm, u, normals, False)
    axes[determined] = a[determined]
    if flip:
        axes = -axes
    resid = conical_axis_residual(qm, axes)
    meta = {"iterations": info["iterations"], "constraint_residual": info["residual"],
            "equal_angle_residual_max": float(np.nanmax(resid)) if np.any(np.isfinite(resid)) else 0.0}
    planes, dev = polyline_fit(qm)
    planar = np.zeros(len(planes), dtype=bool)
    return _assemble(qm, axes, planes, planar, (), "conical", meta)


def conical_axis_residual(mesh: QuadMesh, axes: np.ndarray) -> np.ndarray:
    """``(N,)`` spread ``max_k − min_k`` of the angles between the axis and the adjacent unit face
    normals, radians; ``nan`` at vertices with fewer than 3 faces.  Zero for cone axes of a conical mesh."""
    fn, mask = vertex_face_normals(mesh)
    ang = pl.line_angle(fn, np.asarray(axes, dtype=float)[:, None, :])
    hi = np.where(mask, ang, -np.inf).max(axis=1)
    lo = np.where(mask, ang, np.inf).min(axis=1)
    out = hi - lo
    out[mask.sum(axis=1) < 3] = np.nan
    return out


@support_method("conical", "conical meshes: the cone axes")
def _build(mesh: QuadMesh, params: "SupportParams", family: int | None,
           beams: "BeamContext | None" = None) -> SupportStructure:
    return support_conical(mesh, flip=params.flip)
