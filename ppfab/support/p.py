"""Support structure of a P mesh: node axes in the planes of one polyline family (§3.1), on any quad mesh.

The polylines of the planar family are the continuous beams; every axis lies in the plane of the family's
polyline through its vertex, and the edges of the other family (cut into one-edge beams between the
crossings) are torsion-free: each transverse polyline keeps one free parameter, its axes propagating from
vertex to vertex, which is chosen to keep the axes near the surface normals and from crossing within the
beam depth.  Every strip that is a tree or a single cycle of such vertices is solved exactly by that
propagation (:mod:`ppfab.support.strips`: torsion-free to rounding); only what the combinatorics leave (a
vertex on no plane of the family, a strip joining two fixed axes) goes to the penalty solve of
:func:`~ppfab.support.axes.solve_axes`.  Polylines of the family that cannot be planar beams are left out
(``[support] exclude``, :mod:`ppfab.support.planar`).  With ``beams`` given, a structure whose torsion
exceeds ``beams.max_torsion`` on some edge is refused (:class:`GeometryError` naming the worst edge), never
returned.
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
    beams : beam depth and torsion tolerance (mesh units); when given, torsion beyond the tolerance raises

    Raises
    ------
    GeometryError
        the family has no polylines, ``planes`` has the wrong shape, or (with ``beams``) the torsion of some
        edge at beam depth exceeds ``beams.max_torsion`` (the message names the worst edge and its value)
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
    s = planar_support(qm, vertex_normals(qm), candidates, tuple(exclude), "p", (fam,), flip=flip,
                       max_normal_angle_deg=max_normal_angle_deg, planar_tolerance=planar_tolerance,
                       beams=beams, planes=all_planes, strips=True)
    if beams is not None:
        check_torsion(s, beams)
    return s


def check_torsion(s: SupportStructure, beams: "BeamContext") -> None:
    """Refuse a P structure whose torsion at beam depth exceeds ``beams.max_torsion`` on some edge: one line
    naming the worst edge, its value, how many edges are over and how many strips were left to the penalty
    solve."""
    if not len(s.edges):
        return
    off = s.torsion_offset(beams.depth)
    over = np.flatnonzero(~(off <= beams.max_torsion))
    if not len(over):
        return
    k = int(over[np.argmax(off[over])])
    i, j = (int(x) for x in s.edges[k])
    forced = int(s.meta.get("penalty_strips", 0))
    raise GeometryError(f"P support: edge N{i:04d}-N{j:04d} has torsion {off[k]:.3g} mm at beam depth "
                        f"{beams.depth:g} mm > beams.max_torsion_mm = {beams.max_torsion:g} mm ({len(over)} edge(s) "
                        f"over; {forced} strip(s) not solvable exactly, left to the penalty solve); leave out the "
                        "polylines there (support.exclude), optimise the mesh to P ([optimize] families), or "
                        "raise beams.max_torsion_mm", element=f"edge N{i:04d}-N{j:04d}", value=float(off[k]))


@support_method("p", "P meshes: axes in the planes of one family")
def _build(mesh: QuadMesh, params: "SupportParams", family: int | None,
           beams: "BeamContext | None" = None) -> SupportStructure:
    return support_p(mesh, 0 if family is None else family, flip=params.flip,
                     max_normal_angle_deg=params.max_normal_angle_deg, exclude=params.exclude,
                     planar_tolerance=params.planar_tolerance, beams=beams)
