"""Support structure of a circular mesh: the node axes of its vertex offset (§2.3.3, Remark 2.1).

A quad mesh with planar faces is *circular* when the corners of every face lie on a circle.  Such a mesh has
a parallel mesh of unit vectors ``u_i`` — its discrete Gauss image, inscribed in the unit sphere — so that
``v_i + d u_i`` is an offset at the constant vertex distance ``d`` [Pottmann et al. 2007].  Along an edge
``e = v_j − v_i`` the vector ``u_j`` is the mirror image of ``u_i`` in the plane normal to ``e``::

    u_j = H_e u_i,     H_e = I − 2 ê êᵀ                                          (reflection)

so ``u_j − u_i ∥ e``: the lines ``v_i + t u_i`` of the two ends of every edge lie in one plane — a
torsion-free support structure whose node axes have the same length ``d`` between the mesh and its offset
at every node (beam ends of one height).  Around a planar quad the four reflections compose to a rotation
about the face normal by twice ``α_0 − α_1 + α_2 − α_3`` (the corner angles), the identity exactly when the
quad is inscribed in a circle: the propagation closes on a circular mesh and on no other.

:func:`vertex_offset` propagates ``u`` along a breadth-first spanning tree of the edges from a unit seed
``u_0`` chosen to keep the axes nearest to the vertex normals (``u_i = R_i u_0`` with ``R_i`` the product of
the reflections on the path: ``u_0 = normalize(Σ_i R_iᵀ n_i)`` maximises ``Σ_i u_i · n_i``), and measures
how far the four reflections of every face are from closing (the spectral norm of ``H_3 H_2 H_1 H_0 − I``,
the rotation angle).  :func:`support_circular` refuses a mesh with a face that does not close and otherwise
makes the axes exactly torsion-free with the parallel mesh nearest to the propagated vectors (over long
loops a mesh circular to rounding accumulates the faces' small rotations; the solve spreads them).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import breadth_first_order, connected_components

from ppfab.errors import GeometryError
from ppfab.mesh import QuadGrid, QuadMesh
from ppfab.metrics import polyline_fit

from .parallel import parallel_offsets
from .registry import support_method
from .structure import SupportStructure, _assemble, _edge_frames, _orient_inward, as_quadmesh, vertex_normals

if TYPE_CHECKING:  # pragma: no cover
    from .params import BeamContext, SupportParams

CLOSURE_TOLERANCE = 1e-5
"""Largest rotation (radians) of a face's four edge reflections for :func:`support_circular` to accept a mesh
as circular.  An optimised circular mesh (``[optimize] keep_circular``, target 1e-6 rad on the corner angles)
closes to a few 1e-6; a planar-quad mesh that is not circular to 1e-2 and more."""


@dataclass(frozen=True)
class VertexOffset:
    """The unit vertex offset of a quad mesh (the propagated Gauss image).

    unit : (N, 3) unit vectors ``u_i`` (``u_j = H_e u_i`` along the spanning tree)
    closure : (F,) rotation angle of each face's four edge reflections, ``‖H_3 H_2 H_1 H_0 − I‖₂`` (0 on a
        circular quad), radians
    """

    unit: np.ndarray
    closure: np.ndarray

    @property
    def closure_max(self) -> float:
        return float(self.closure.max(initial=0.0))


def vertex_offset(mesh: QuadMesh | QuadGrid) -> VertexOffset:
    """Propagate unit offset vectors by the edge reflections (module docstring) and measure their closure."""
    qm = as_quadmesh(mesh)
    n = len(qm.vertices)
    edges, _ = _edge_frames(qm)                                 # (refuses a zero-length edge)
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n)).tocsr()
    parts, label = connected_components(graph, directed=False)
    if parts > 1:
        raise GeometryError(f"the mesh falls into {parts} separate pieces; the vertex offset of a circular mesh "
                            "is propagated over one connected mesh (build the pieces one by one)",
                            element="mesh", value=float(parts))
    _, pred = breadth_first_order(graph, 0, directed=False, return_predecessors=True)
    depth = np.zeros(n, dtype=np.int64)                         # tree depth, by pointer jumping
    up = pred.copy()
    while np.any(up >= 0):
        depth += up >= 0
        up = np.where(up >= 0, pred[np.maximum(up, 0)], -1)
    child = np.flatnonzero(pred >= 0)
    par = pred[child]
    e = qm.vertices[child] - qm.vertices[par]                   # the tree edge from parent to child
    e = e / np.linalg.norm(e, axis=1, keepdims=True)
    step = np.zeros((n, 3))
    step[child] = e
    R = np.repeat(np.eye(3)[None], n, axis=0)
    for level in range(1, int(depth.max(initial=0)) + 1):      # one vectorised step per level of the tree
        i = np.flatnonzero(depth == level)
        p, u = pred[i], step[i]
        R[i] = R[p] - 2.0 * u[:, :, None] * np.einsum("kj,kjl->kl", u, R[p])[:, None, :]   # H_e R_p
    normals = vertex_normals(qm)
    seed = np.einsum("nji,nj->i", R, normals)                   # Σ R_iᵀ n_i
    length = float(np.linalg.norm(seed))
    if not length > 1e-12:
        raise GeometryError("the reflected vertex normals cancel: no vertex offset follows the surface here",
                            element="mesh", value=length)
    u = R @ (seed / length)
    c = qm.face_corners
    loop = np.repeat(np.eye(3)[None], len(c), axis=0)
    for k in range(4):
        e = c[:, (k + 1) % 4] - c[:, k]
        e /= np.linalg.norm(e, axis=1, keepdims=True)
        loop = loop - 2.0 * e[:, :, None] * np.einsum("fj,fjk->fk", e, loop)[:, None, :]   # H_e · loop
    return VertexOffset(u, np.linalg.norm(loop - np.eye(3), ord=2, axis=(1, 2)))


def support_circular(mesh: QuadMesh | QuadGrid, flip: bool = False,
                     tolerance: float = CLOSURE_TOLERANCE) -> SupportStructure:
    """Support structure of a circular mesh: the node axes of its unit vertex offset (module docstring).

    The propagated unit vectors are the target of the parallel mesh solve
    (:func:`~ppfab.support.parallel.parallel_offsets`), which makes every edge's two axes coplanar to the
    solver's tolerance; on a circular mesh they already are, and the offset lengths stay 1 (``meta``
    ``offset_length_spread``: largest ``|‖u_i‖ − 1|``).

    Raises :class:`GeometryError` naming the face whose reflections do not close when the mesh is not
    circular (rotation above ``tolerance`` radians).
    """
    qm = as_quadmesh(mesh)
    off = vertex_offset(qm)
    if off.closure_max > tolerance:
        k = int(np.argmax(off.closure))
        bad = int(np.count_nonzero(off.closure > tolerance))
        raise GeometryError(f"the mesh is not circular: the corners of face {k} are not on a circle (its edge "
                            f"reflections turn by {off.closure_max:.2e} rad > {tolerance:g}; {bad} face(s) like "
                            "it); make it circular first ([optimize] keep_circular = true) or use [support] "
                            "method = \"parallel\"", element=f"face {k}", value=off.closure_max)
    u, info = parallel_offsets(qm, off.unit)
    length = np.linalg.norm(u, axis=1)
    if np.any(length < 0.5):
        k = int(np.argmin(length))
        raise GeometryError(f"vertex {k}: the parallel mesh through the unit offset collapses there (offset "
                            f"{length[k]:.2e})", element=f"vertex {k}", value=float(length[k]))
    axes = _orient_inward(u, vertex_normals(qm), flip)
    meta = {"iterations": info["iterations"], "constraint_residual": info["residual"],
            "closure_max": off.closure_max, "offset_length_spread": float(np.abs(length - 1.0).max())}
    planes, _ = polyline_fit(qm)
    return _assemble(qm, axes, planes, np.zeros(len(planes), dtype=bool), (), "circular", meta)


@support_method("circular", "circular meshes: the axes of the unit vertex offset")
def _build(mesh: QuadMesh, params: "SupportParams", family: int | None,
           beams: "BeamContext | None" = None) -> SupportStructure:
    return support_circular(mesh, flip=params.flip)
