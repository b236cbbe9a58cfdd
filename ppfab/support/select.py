"""Choosing the support method: :func:`support_structure` (``[support] method``, ``auto`` included)."""

from __future__ import annotations

import numpy as np

from ppfab.errors import GeometryError
from ppfab.mesh import QuadGrid, QuadMesh
from ppfab.metrics import face_planarity, polyline_fit, relative_deviation
from ppfab.topology import family_index

from ppfab.conical.cones import cone_axes

from .conical import conical_axis_residual
from .params import BeamContext, SupportParams
from .registry import get_support_method
from .structure import SupportStructure, as_quadmesh


def support_structure(mesh: QuadMesh | QuadGrid, params: SupportParams | None = None,
                      planar_families: tuple | list | None = None,
                      beams: BeamContext | None = None) -> SupportStructure:
    """The support structure chosen by ``params.method``.

    ``auto``: when ``planar_families`` names the families a construction keeps planar
    (``"rows"``/``"cols"`` or 0/1) — both → :func:`~ppfab.support.pp.support_pp`, one →
    :func:`~ppfab.support.p.support_p` with that family.  Otherwise: a patch carrying ``U_i``/``W_j`` or a mesh
    with both families planar (δ_P ≤ ``planar_tolerance``) → :func:`~ppfab.support.pp.support_pp`; one family
    planar → :func:`~ppfab.support.p.support_p`; a conical planar-quad mesh (residual ≤ 1e-6 rad) →
    :func:`~ppfab.support.conical.support_conical`; otherwise :func:`~ppfab.support.parallel.support_parallel`.
    ``beams``: the beam depth and torsion tolerance, in the mesh's units.
    """
    p = params or SupportParams()
    qm = as_quadmesh(mesh)
    method = p.method
    fam = None
    if method == "auto" and planar_families:
        fams = sorted({family_index(f) for f in planar_families})
        if len(fams) == 2:
            method = "pp"
        elif len(fams) == 1:
            method, fam = "p", fams[0]
    if method == "auto":
        method = _auto_method(qm, p.planar_tolerance)
    if method == "p" and fam is None:
        fam = _auto_family(qm) if p.method == "auto" else family_index(p.family, "support.family")
    return get_support_method(method).build(qm, p, fam, beams)


def _family_planarity(mesh: QuadMesh) -> dict[int, float]:
    planes, dev = polyline_fit(mesh)
    rel = relative_deviation(dev, mesh)
    out = {}
    for fam in (0, 1):
        ks = [k for k, p in enumerate(mesh.polylines) if p.family == fam and len(p) >= 3]
        out[fam] = float(max(rel[ks])) if ks else np.inf
    return out


def _auto_family(mesh: QuadMesh) -> int:
    fp = _family_planarity(mesh)
    return 0 if fp[0] <= fp[1] else 1


def _auto_method(mesh: QuadMesh, tol: float) -> str:
    grid = mesh.grid
    if grid is not None and grid.support_u is not None and grid.support_w is not None:
        return "pp"
    fp = _family_planarity(mesh)
    planar = [f for f in (0, 1) if fp[f] <= tol]
    if len(planar) == 2:
        return "pp"
    if planar:
        return "p"
    if float(face_planarity(mesh.face_corners).max()) <= 1e-3:
        try:
            a, cos = cone_axes(mesh)
        except GeometryError:                   # some vertex has no cone: not a conical mesh
            return "parallel"
        res = conical_axis_residual(mesh, a)
        if np.any(np.isfinite(cos)) and float(np.nanmax(res)) <= 1e-6:
            return "conical"
    return "parallel"
