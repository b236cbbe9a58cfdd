"""Support structure of a P mesh: node axes in the planes of one polyline family (§3.1), on any quad mesh.

The polylines of the planar family are the continuous beams; every axis lies in the plane of the family's
polyline through its vertex, and the edges of the other family (cut into one-edge beams between the
crossings) are torsion-free: each transverse polyline keeps one free parameter, its axes propagating from
vertex to vertex, which is chosen to keep the axes near the surface normals and from crossing within the
beam depth (:func:`~ppfab.support.axes.solve_axes`).  Polylines of the family that cannot be planar beams are
left out (``[support] exclude``, :mod:`ppfab.support.planar`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np

from ppfab import planes as pl
from ppfab.errors import GeometryError
from ppfab.mesh import QuadGrid, QuadMesh
from ppfab.topology import family_index

from .planar import planar_support
from .registry import support_method
from .structure import SupportStructure, as_quadmesh, vertex_normals

if TYPE_CHECKING:  # pragma: no cover
    from .params import BeamContext, SupportParams


def support_p(mesh: QuadMesh | QuadGrid, family: int | str = 0, planes: np.ndarray | None = None,
              flip: bool = False, max_normal_angle_deg: float = 30.0, exclude: Sequence[int | str] = ("auto",),
              planar_tolerance: float = 1e-6, beams: "BeamContext | None" = None) -> SupportStructure:
    """Support structure of a P mesh: axes in the planes of one polyline family.

    Parameters
    ----------
    mesh : quad mesh with planar faces whose polylines of ``family`` are planar
    family : 0 / ``"rows"`` or 1 / ``"cols"``
    planes : (L_f, 4) float, optional — the planes of that family's polylines in the order of
        ``mesh.family(family)``; least-squares planes when omitted
    exclude : selectors of polylines left out of the planar family (``[support] exclude``)
    beams : beam depth and torsion tolerance (mesh units)
    """
    fam = family_index(family, "support.family")
    qm = as_quadmesh(mesh)
    lines = np.array([k for k, p in enumerate(qm.polylines) if p.family == fam], dtype=np.int64)
    if len(lines) == 0:
        raise GeometryError(f"the mesh has no polylines of family {('rows', 'cols')[fam]}")
    all_planes = None
    if planes is not None:
        given = pl.as_planes(planes)
        if given.shape != (len(lines), 4):
            raise GeometryError(f"planes need shape ({len(lines)}, 4) for the {len(lines)} polylines of the family, "
                                f"got {given.shape}")
        all_planes = np.full((len(qm.polylines), 4), np.nan)
        all_planes[lines] = pl.normalize(given)
    candidates = np.zeros(len(qm.polylines), dtype=bool)
    candidates[lines] = True
    return planar_support(qm, vertex_normals(qm), candidates, tuple(exclude), "p", (fam,), flip=flip,
                          max_normal_angle_deg=max_normal_angle_deg, planar_tolerance=planar_tolerance,
                          beams=beams, planes=all_planes)


@support_method("p", "P meshes: axes in the planes of one family")
def _build(mesh: QuadMesh, params: "SupportParams", family: int | None,
           beams: "BeamContext | None" = None) -> SupportStructure:
    return support_p(mesh, 0 if family is None else family, flip=params.flip,
                     max_normal_angle_deg=params.max_normal_angle_deg, exclude=params.exclude,
                     planar_tolerance=params.planar_tolerance, beams=beams)
