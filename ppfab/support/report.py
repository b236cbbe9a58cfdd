"""Which polylines of a mesh can be planar beams, for ``ppfab check``: one record per polyline.

:func:`polyline_report` runs the PP support structure's choice of planar beams (:mod:`ppfab.support.planar`,
``[support] exclude = ["auto"]``) on a mesh as it is and records, per polyline, its family, size, ``δ_P``,
tilt (how far its plane is from the surface normals), whether its plane was chosen by the straight-line rule,
and whether it stays a planar beam — with the reason when not.  The check does not know the beams: it
assumes the default design's ratio of beam depth to edge length (200 mm to 1.5 m) and torsion tolerance
(0.5 mm at 200 mm depth); the torsion test is a ratio, so only the crossing term depends on that guess.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ppfab.mesh import QuadGrid, QuadMesh

from .lines import polyline_planes, select_polylines
from .params import BeamContext
from .pp import support_pp
from .structure import as_quadmesh, vertex_normals

DEPTH_PER_EDGE = 200.0 / 1500.0
TORSION_PER_DEPTH = 0.5 / 200.0


@dataclass(frozen=True)
class PolylineRecord:
    """One polyline: ``id`` (index into ``mesh.polylines``), ``family`` (0 rows, 1 cols), ``vertices``,
    ``closed``, ``delta_p`` (relative, §3.3), ``tilt_deg`` (largest angle between its plane and a vertex normal),
    ``straight`` (plane by the straight-line rule), ``planar_beam`` and, when not, ``reason``."""

    id: int
    family: int
    vertices: int
    closed: bool
    delta_p: float | None
    tilt_deg: float | None
    straight: bool
    planar_beam: bool
    reason: str

    def as_dict(self) -> dict:
        return asdict(self)


def tangent_polylines(mesh: QuadMesh | QuadGrid, max_normal_angle_deg: float = 30.0) -> list[int]:
    """Ids of the polylines whose plane is further than ``max_normal_angle_deg`` from a vertex normal (cheap)."""
    qm = as_quadmesh(mesh)
    planes = polyline_planes(qm, vertex_normals(qm))
    return [int(k) for k in np.flatnonzero(select_polylines(qm, ["tangent"], "check", planes, max_normal_angle_deg))]


def polyline_report(mesh: QuadMesh | QuadGrid, max_normal_angle_deg: float = 30.0) -> list[PolylineRecord]:
    """One :class:`PolylineRecord` per polyline (module docstring)."""
    qm = as_quadmesh(mesh)
    normals = vertex_normals(qm)
    planes = polyline_planes(qm, normals)
    edge = float(np.mean(qm.edge_lengths())) if len(qm.edges) else 1.0
    depth = DEPTH_PER_EDGE * edge
    s = support_pp(QuadMesh(qm.vertices, qm.faces), max_normal_angle_deg=max_normal_angle_deg,
                   beams=BeamContext(depth, TORSION_PER_DEPTH * depth))
    why = dict(s.left_out)
    planar = s.polyline_planar
    assert planar is not None
    out = []
    for k, p in enumerate(qm.polylines):
        short = len(p) < 3
        reason = "2 vertices: one edge, its plane is the support plane of the edge" if short else why.get(k, "")
        out.append(PolylineRecord(k, int(p.family), int(len(p)), bool(p.closed),
                                  None if short else float(planes.relative[k]),
                                  None if short else float(planes.tilt_deg[k]), bool(planes.straight[k]),
                                  bool(planar[k]), reason))
    return out
