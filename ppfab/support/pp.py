"""Support structure of a PP mesh: the node axis of ``v_ij`` is ``U_i ∩ W_j`` (§3.1.1)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ppfab import planes as pl
from ppfab.errors import GeometryError
from ppfab.mesh import QuadGrid, QuadMesh
from ppfab.topology import recover_grid

from .registry import support_method
from .structure import SupportStructure, _assemble, _orient_inward, as_quadmesh, vertex_normals

if TYPE_CHECKING:  # pragma: no cover
    from .params import SupportParams


def support_pp(mesh: QuadMesh | QuadGrid, flip: bool = False) -> SupportStructure:
    """Support structure of a PP patch: axis of ``v_ij`` along ``U_i ∩ W_j`` (§3.1.1).

    The planes are the grid's own ``support_u``/``support_w`` when it carries them,
    otherwise least-squares planes of the rows ``v[i, :]`` and columns ``v[:, j]``.
    Every row edge is supported by its ``U_i``, every column edge by its ``W_j``.

    Raises :class:`GeometryError` where ``U_i`` and ``W_j`` are (nearly) parallel.
    """
    qm = as_quadmesh(mesh)
    grid = qm.grid
    if grid is None:
        why = recover_grid(qm.topology)
        reason = why if isinstance(why, str) else "no grid recorded"
        raise GeometryError(f"support method 'pp' needs a regular patch (rows v[i, :] and columns v[:, j]); "
                            f"this mesh is not a regular grid: {reason}")
    U = grid.support_u if grid.support_u is not None else pl.fit_plane(grid.rows())[0]
    W = grid.support_w if grid.support_w is not None else pl.fit_plane(grid.cols())[0]
    U, W = pl.normalize(U), pl.normalize(W)
    ax = np.cross(U[:, None, :3], W[None, :, :3])
    s = np.linalg.norm(ax, axis=-1)
    if np.any(s < 1e-9):
        i, j = (int(k) for k in np.argwhere(s < 1e-9)[0])
        raise GeometryError(f"vertex ({i}, {j}): support planes U_{i} and W_{j} are parallel "
                            f"(sine {s[i, j]:.1e}), no node axis", element=f"vertex {i},{j}", value=float(s[i, j]))
    axes = np.zeros_like(qm.vertices)
    assert qm.grid_ids is not None, "a mesh with a grid carries its grid ids"
    axes[qm.grid_ids.ravel()] = (ax / s[..., None]).reshape(-1, 3)
    axes = _orient_inward(axes, vertex_normals(qm), flip)
    planes = np.concatenate([U, W], axis=0)            # grid polylines: rows, then columns
    planar = np.ones(len(planes), dtype=bool)
    return _assemble(qm, axes, planes, planar, (0, 1), "pp", {"planes": "grid" if grid.support_u is not None
                                                              else "least squares"})


@support_method("pp", "PP meshes: the axis of v_ij is U_i ∩ W_j")
def _build(mesh: QuadMesh, params: "SupportParams", family: int | None) -> SupportStructure:
    return support_pp(mesh, flip=params.flip)
