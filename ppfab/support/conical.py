"""Support structure of a conical mesh: the node axes are the cone axes (§2.3.3)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ppfab import planes as pl
from ppfab.errors import GeometryError
from ppfab.mesh import QuadGrid, QuadMesh
from ppfab.metrics import polyline_fit

from .parallel import _axes_from_offsets, parallel_offsets
from .registry import support_method
from .structure import SupportStructure, _assemble, as_quadmesh, vertex_normals

if TYPE_CHECKING:  # pragma: no cover
    from .params import SupportParams


def _vertex_face_normals(mesh: QuadMesh) -> tuple[np.ndarray, np.ndarray]:
    """Padded unit normals of the faces at each vertex, ``(N, k, 3)``, and a mask ``(N, k)``."""
    f = mesh.faces.ravel()
    fid = np.repeat(np.arange(len(mesh.faces)), 4)
    order = np.argsort(f, kind="stable")
    f, fid = f[order], fid[order]
    counts = np.bincount(f, minlength=len(mesh.vertices))
    start = np.r_[0, np.cumsum(counts)[:-1]]
    slot = np.arange(len(f)) - start[f]
    k = int(counts.max())
    normals = np.zeros((len(mesh.vertices), k, 3))
    mask = np.zeros((len(mesh.vertices), k), dtype=bool)
    normals[f, slot] = pl.normalize(mesh.face_planes)[fid, :3]
    mask[f, slot] = True
    return normals, mask


def cone_axes(mesh: QuadMesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cone axes at vertices with at least 3 faces (§2.3.3).

    The axis ``a`` makes equal angles with the unit face normals ``n_k``:
    ``(n_k − n̄)·a = 0`` for all ``k``, solved in the least-squares sense as the
    eigenvector of the smallest eigenvalue of ``Σ (n_k − n̄)(n_k − n̄)ᵀ``.

    Returns
    -------
    axes : (N, 3) unit, pointing against the mean normal (inward); rows with fewer than 3 faces are 0
    cos_angle : (N,) mean ``−a·n_k`` (cosine of the cone's half opening angle complement)
    determined : (N,) bool, vertex has at least 3 faces
    """
    normals, mask = _vertex_face_normals(mesh)
    w = mask.astype(float)
    count = w.sum(axis=1)
    mean = np.einsum("nk,nki->ni", w, normals) / count[:, None]
    dev = (normals - mean[:, None, :]) * w[..., None]
    cov = np.einsum("nki,nkj->nij", dev, dev)
    _, vecs = np.linalg.eigh(cov)
    a = vecs[:, :, 0]
    a = np.where((np.einsum("ni,ni->n", a, mean) > 0)[:, None], -a, a)
    cos = -np.einsum("nki,ni,nk->n", normals, a, w) / count
    determined = count >= 3
    a[~determined] = 0.0
    return a, cos, determined


def support_conical(mesh: QuadMesh | QuadGrid, flip: bool = False) -> SupportStructure:
    """Support structure of a conical mesh: node axes are the cone axes (§2.3.3).

    At vertices with 3 or more faces the axis makes equal angles with the adjacent
    unit face normals (:func:`cone_axes`).  Those vertices are offset along their
    axes so that every face moves by the same distance (the constant-distance
    offset, a parallel mesh of a conical mesh); boundary vertices (1 or 2 faces)
    get the parallel-mesh offsets nearest to that same face offset.
    """
    qm = as_quadmesh(mesh)
    normals = vertex_normals(qm)
    a, cos, determined = cone_axes(qm)
    if np.any(determined & (cos < 1e-3)):
        k = int(np.flatnonzero(determined & (cos < 1e-3))[0])
        raise GeometryError(f"vertex {k}: the cone axis is (nearly) tangent to the faces "
                            f"(cos {cos[k]:.1e}); the faces there do not touch a cone", element=f"vertex {k}")
    fn, mask = _vertex_face_normals(qm)
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
    fn, mask = _vertex_face_normals(mesh)
    c = np.einsum("nki,ni->nk", fn, np.asarray(axes, dtype=float))
    ang = np.arccos(np.clip(np.abs(c), 0.0, 1.0))
    hi = np.where(mask, ang, -np.inf).max(axis=1)
    lo = np.where(mask, ang, np.inf).min(axis=1)
    out = hi - lo
    out[mask.sum(axis=1) < 3] = np.nan
    return out


@support_method("conical", "conical meshes: the cone axes")
def _build(mesh: QuadMesh, params: "SupportParams", family: int | None) -> SupportStructure:
    return support_conical(mesh, flip=params.flip)
