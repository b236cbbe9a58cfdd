"""Support structure of a P mesh: node axes in the planes of one polyline family (§3.1)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ppfab import planes as pl
from ppfab.errors import GeometryError
from ppfab.topology import family_index
from ppfab.mesh import QuadGrid, QuadMesh
from ppfab.metrics import polyline_fit

from .parallel import _planar_constraints, _solve_axes
from .registry import support_method
from .structure import SupportStructure, _assemble, as_quadmesh, vertex_normals

if TYPE_CHECKING:  # pragma: no cover
    from .params import SupportParams


def support_p(mesh: QuadMesh | QuadGrid, family: int | str = 0, planes: np.ndarray | None = None,
              flip: bool = False, max_normal_angle_deg: float = 30.0) -> SupportStructure:
    """Support structure of a P mesh: axes in the planes of one polyline family.

    Parameters
    ----------
    mesh : quad mesh with planar faces whose polylines of ``family`` are planar
    family : 0 / ``"rows"`` or 1 / ``"cols"``
    planes : (L_f, 4) float, optional — the planes of that family's polylines in the order of
        ``mesh.family(family)``; least-squares planes when omitted

    The axes lie in the planes ``U`` of the family (so each such polyline with its
    axes is one planar beam); the transverse support planes pass through the edge and
    both end axes.  Found as the parallel mesh nearest to the normal offset whose
    offsets lie in the planes (:func:`parallel_offsets`).
    """
    fam = family_index(family, "support.family")
    qm = as_quadmesh(mesh)
    normals = vertex_normals(qm)
    fit, dev = polyline_fit(qm)
    lines = np.array([k for k, p in enumerate(qm.polylines) if p.family == fam], dtype=np.int64)
    if len(lines) == 0:
        raise GeometryError(f"the mesh has no polylines of family {('rows', 'cols')[fam]}")
    all_planes = fit.copy()
    if planes is not None:
        given = pl.as_planes(planes)
        if given.shape != (len(lines), 4):
            raise GeometryError(f"planes need shape ({len(lines)}, 4) for the {len(lines)} polylines of the family, "
                                f"got {given.shape}")
        all_planes[lines] = pl.normalize(given)
    use = lines[np.all(np.isfinite(all_planes[lines]), axis=1)]
    constraints, per_vertex = _planar_constraints(qm, use, all_planes)
    axes, meta = _solve_axes(qm, normals, constraints, per_vertex, flip, max_normal_angle_deg)
    planar = np.zeros(len(all_planes), dtype=bool)
    planar[use] = True
    return _assemble(qm, axes, all_planes, planar, (fam,), "p", meta)


@support_method("p", "P meshes: axes in the planes of one family")
def _build(mesh: QuadMesh, params: "SupportParams", family: int | None) -> SupportStructure:
    return support_p(mesh, 0 if family is None else family, flip=params.flip,
                     max_normal_angle_deg=params.max_normal_angle_deg)
