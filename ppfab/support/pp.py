"""Support structure of a PP mesh: the node axis of a vertex is the line where its two polyline planes meet
(§3.1.1: ``U_i ∩ W_j`` on a regular patch), on any quad mesh whose polylines are planar.

On a regular patch that carries its construction's planes ``U_i``, ``W_j`` the axes are ``U_i ∩ W_j`` of
those planes.  On any other quad mesh — annuli, meshes with holes, jagged boundaries, singular vertices —
the polylines of :attr:`~ppfab.mesh.QuadMesh.polylines` of both families are the beams
(:func:`~ppfab.support.planar.planar_support`): each gets its plane (least squares; the plane through a
straight polyline that contains the surface normal), the polylines that cannot be planar beams are left out
(``[support] exclude``), and the axis of a vertex is

* the line of its two planes where two planes pass through it (every regular vertex: interior valence 4,
  boundary valence 3);
* the line closest to all of them (least squares, exact when they share a line) where more meet: a
  singular vertex of valence ``k`` where ``k`` polylines end, a re-entrant corner of a jagged boundary;
* where only one plane passes (a vertex on a polyline that was left out, or on 2-vertex polylines only):
  the direction in that plane (or, with none, any direction) that makes the edges of the left-out
  polylines torsion-free, as near the surface normal as that allows (:func:`~ppfab.support.axes.solve_axes`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np

from ppfab import planes as pl
from ppfab.errors import GeometryError
from ppfab.mesh import QuadGrid, QuadMesh

from .planar import planar_support
from .registry import support_method
from .structure import SupportStructure, _assemble, _orient_inward, as_quadmesh, vertex_normals

if TYPE_CHECKING:  # pragma: no cover
    from .params import BeamContext, SupportParams


def support_pp(mesh: QuadMesh | QuadGrid, flip: bool = False, exclude: Sequence[int | str] = ("auto",),
               max_normal_angle_deg: float = 30.0, planar_tolerance: float = 1e-6,
               beams: "BeamContext | None" = None) -> SupportStructure:
    """Support structure of a PP mesh (module docstring): both polyline families are beams in their planes.

    Parameters
    ----------
    mesh : quad mesh (a regular patch with construction planes ``support_u``/``support_w`` uses them)
    exclude : selectors of polylines left out of the planar families (``[support] exclude``)
    beams : beam depth and torsion tolerance (mesh units), for the axes that are solved for

    Raises :class:`GeometryError` where two planes of a patch's construction are (nearly) parallel.
    """
    qm = as_quadmesh(mesh)
    grid = qm.grid
    if grid is not None and grid.support_u is not None and grid.support_w is not None:
        return _construction_planes(qm, grid, flip)
    normals = vertex_normals(qm)
    candidates = np.array([len(p) >= 3 for p in qm.polylines], dtype=bool)
    return planar_support(qm, normals, candidates, tuple(exclude), "pp", (0, 1), flip=flip,
                          max_normal_angle_deg=max_normal_angle_deg, planar_tolerance=planar_tolerance,
                          beams=beams)


def _construction_planes(qm: QuadMesh, grid: QuadGrid, flip: bool) -> SupportStructure:
    """Axes ``U_i ∩ W_j`` of the planes a PP construction made (§3.1.1)."""
    assert grid.support_u is not None and grid.support_w is not None
    U, W = pl.normalize(grid.support_u), pl.normalize(grid.support_w)
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
    return _assemble(qm, axes, planes, planar, (0, 1), "pp", {"planes": "grid"})


@support_method("pp", "PP meshes: the axis of a vertex is the line where its two polyline planes meet")
def _build(mesh: QuadMesh, params: "SupportParams", family: int | None,
           beams: "BeamContext | None" = None) -> SupportStructure:
    return support_pp(mesh, flip=params.flip, exclude=params.exclude,
                      max_normal_angle_deg=params.max_normal_angle_deg,
                      planar_tolerance=params.planar_tolerance, beams=beams)
