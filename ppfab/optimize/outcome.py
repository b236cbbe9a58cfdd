"""What an optimisation run did to the mesh, and the one-line message that says it.

Measures of the returned mesh against the input (all in mesh units or degrees):

* distance to the input *surface* (the input quads split along a diagonal, :mod:`.reference`),
* creases created (dihedral angles, :func:`ppfab.metrics.crease_report`),
* the angle between the support planes and the panels they carry (§2.3.2: 90° is the ideal) and, where two
  support planes meet at a vertex (PP), the angle between their line — the node axis — and the vertex normal
  (on a P run, with one plane per vertex, the axes of the exact P support, :func:`p_axis_normal_angles`),

and :func:`message`, which names the stop reason, every target missed, the steps the guard refused by
reason, created creases by edge, a fallback to the best iterate or the input, and the advice to remesh when
the net is far from conjugate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import planes as pl
from ..errors import GeometryError
from ..mesh import QuadMesh
from ..metrics import CreaseReport
from ..topology import Polyline

CONJUGACY_ADVICE = 0.3
"""Above this :func:`ppfab.metrics.conjugacy_defect` a failed run is explained by the net not being conjugate."""


def support_panel_angles(v: np.ndarray, faces: np.ndarray, planes: np.ndarray,
                         owner: np.ndarray, face: np.ndarray) -> np.ndarray:
    """Deviation from 90° (degrees, ``(P,)``) of the angle between support plane ``owner`` and panel ``face``.

    planes : (S, 4) unit planes; owner, face : (P,) pairs from :func:`.terms.polyline_faces`
    """
    if not len(owner):
        return np.zeros(0)
    c = v[faces[face]]
    n = np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1])
    n = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    dot = np.abs(np.einsum("ij,ij->i", planes[owner, :3], n))
    return np.degrees(np.arcsin(np.clip(dot, 0.0, 1.0)))


def axis_normal_angles(v: np.ndarray, faces: np.ndarray, planes: np.ndarray, lines: list[Polyline]) -> np.ndarray:
    """Angle (degrees) between the node axis and the vertex normal at every vertex on two support planes.

    The node axis of a vertex on the planes ``U`` and ``W`` of two polylines is the line ``U ∩ W``,
    direction ``n_U × n_W``; the vertex normal is the normalised sum of the unit normals of its faces.
    Returns ``(M,)`` over the vertices that lie on exactly two selected polylines (empty for a P mesh).
    """
    if len(lines) < 2:
        return np.zeros(0)
    owner_of = np.concatenate([np.full(len(np.unique(p.vertices)), s) for s, p in enumerate(lines)])
    verts = np.concatenate([np.unique(p.vertices) for p in lines])
    order = np.argsort(verts, kind="stable")
    verts, owner_of = verts[order], owner_of[order]
    uniq, start, count = np.unique(verts, return_index=True, return_counts=True)
    two = count == 2
    if not two.any():
        return np.zeros(0)
    vid = uniq[two]
    s0, s1 = owner_of[start[two]], owner_of[start[two] + 1]
    axis = np.cross(planes[s0, :3], planes[s1, :3])
    c = v[faces]
    fn = np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1])
    fn = fn / np.maximum(np.linalg.norm(fn, axis=1, keepdims=True), 1e-300)
    vn = np.zeros_like(v)
    np.add.at(vn, faces.ravel(), np.repeat(fn, 4, axis=0))
    nv = vn[vid]
    return np.degrees(pl.line_angle(axis, nv))


NEAR_CONICAL = 1e-2
"""An input whose largest conical residual ``|α_0 − α_1 + α_2 − α_3|`` is below this (rad) counts as nearly
conical (published conical meshes stored as text: 5e-6 … 1e-3; a mesh that is not conical: 0.03 and up)."""


def conical_loss(before: float, after: float, keep_conical: bool) -> str:
    """A warning when a nearly conical input (max residual below :data:`NEAR_CONICAL`) is no longer conical
    after a run that did not ask to keep it (above ``NEAR_CONICAL`` and ten times the input's), else ``""``.
    The δ targets say nothing about it, so a run can meet them and lose the conical property unnoticed."""
    if keep_conical or not before <= NEAR_CONICAL or not after > max(NEAR_CONICAL, 10.0 * before):
        return ""
    return (f"warning: the input was nearly conical (max conical residual {before:.2e} rad) and is not any more "
            f"({after:.2e} rad): set keep_conical = true (ppfab optimize --keep-conical) to keep it")


TANGENT_DEG = 30.0
"""The default ``support.max_normal_angle_deg``: a polyline whose plane is further than this from the surface
normal at one of its vertices is left out of the planar beams by the support (rule ``tangent``)."""


def tangent_planes(mesh: QuadMesh, planar_index: np.ndarray, max_deg: float = TANGENT_DEG) -> str:
    """A warning when some of the polylines made planar have planes further than ``max_deg`` from the
    surface normal at one of their vertices (the support's rule ``tangent``): the P / PP support leaves
    them out of the planar beams, so the run made polylines planar that the structure will not use as
    such; ``""`` when there are none."""
    from ppfab.support.lines import polyline_planes
    from ppfab.support.structure import vertex_normals

    idx = np.asarray(planar_index, dtype=np.int64)
    if not len(idx):
        return ""
    tilt = np.nan_to_num(polyline_planes(mesh, vertex_normals(mesh)).tilt_deg[idx], nan=0.0)
    bad = tilt > max_deg
    if not bad.any():
        return ""
    return (f"warning: {int(bad.sum())} of the {len(idx)} polylines made planar have planes more than "
            f"{max_deg:g}° from the surface normal at a vertex (up to {tilt.max():.0f}°): the support leaves "
            "them out of the planar beams (support.max_normal_angle_deg, rule 'tangent') and cuts their "
            "edges into one-edge beams")


def p_axis_normal_angles(mesh: QuadMesh, planar_index: np.ndarray) -> np.ndarray:
    """Angle (degrees) between the node axis and the surface normal at every vertex of the planar polylines
    of a P run (no vertex on two of them), the axes of the P support on their planes
    (:func:`ppfab.support.planar.planar_support` with exact strips: one free angle per transverse strip,
    chosen to keep the axes near the normals; nothing left out).  ``(M,)``; empty when the support cannot
    be found (a degenerate strip)."""
    from ppfab.support.planar import planar_support
    from ppfab.support.structure import vertex_normals

    idx = np.asarray(planar_index, dtype=np.int64)
    if not len(idx):
        return np.zeros(0)
    cand = np.zeros(len(mesh.polylines), dtype=bool)
    cand[idx] = True
    families = tuple(sorted({int(mesh.polylines[int(k)].family) for k in idx}))
    try:
        s = planar_support(mesh, vertex_normals(mesh), cand, (), "p", families, strips=True)
    except GeometryError:
        return np.zeros(0)
    on = np.unique(np.concatenate([mesh.polylines[int(k)].vertices for k in idx]))
    return np.asarray(s.normal_angle_deg)[on]


@dataclass(frozen=True)
class Outcome:
    """The facts :func:`message` reports (see :class:`ppfab.optimize.OptimizeResult` for the fields)."""

    stopped_by: str
    targets_met: bool
    delta_f_max: float
    delta_p_max: float
    conical_max: float
    delta_f_input: float
    delta_p_input: float
    target_delta_f: float
    target_delta_p: float
    target_conical: float
    iterations: int
    max_iterations: int
    rejected: dict[str, int]
    returned: str                   # "last", "best" or "input"
    best_iteration: int
    creases: CreaseReport
    crease_input_max: float
    edges: np.ndarray
    conjugacy_defect: float | None
    rose: tuple[str, ...] = ()       # why the last iterate was worse than the input (SolverControl.rises)
    circular_max: float = 0.0
    target_circular: float = np.inf
    nodes_max: float = 0.0
    target_nodes: float = np.inf


def _fmt_rejected(rejected: dict[str, int]) -> str:
    return ", ".join(f"{k} {v}" for k, v in sorted(rejected.items(), key=lambda kv: -kv[1]))


UNMET_NEXT = ("the build goes on with the mesh as far as it got, and the stages after it judge whether that is "
              "buildable: a face corner further than panels.planarity_tolerance from its plane or a torsion above "
              "beams.max_torsion_mm stops it by name, a polyline further than beams.plane_tolerance from its beam "
              "plane too (or becomes one-edge plates where beams.fallback accepts them); raise "
              "optimize.max_iterations to go further, or loosen optimize.target_delta_f / target_delta_p when those "
              "checks pass")
"""What a build says after an optimisation that missed its targets: whether it matters and which keys change it."""


def message(o: Outcome) -> str:
    """One line saying how the run ended and what the caller should know (see module docstring)."""
    refused = sum(o.rejected.values())
    guard_refused = sum(v for k, v in o.rejected.items() if k != "energy")
    mostly_guard = o.iterations > 0 and guard_refused > 0.5 * o.iterations
    what = {"targets": "targets met", "stationary": "stationary point reached",
            "max_iterations": f"iteration limit {o.max_iterations} reached",
            "stuck": "no step lowers the energy without being refused"}[o.stopped_by]
    if o.stopped_by != "targets" and mostly_guard:
        what = (f"stopped: the fold/crease guard refused most steps ({guard_refused} of {o.iterations}: "
                f"{_fmt_rejected({k: v for k, v in o.rejected.items() if k != 'energy'})}) — the remaining "
                f"changes towards the targets would fold or crease the mesh")
    elif o.stopped_by == "targets" and not o.targets_met:
        what = "δ targets met but the result is refused"
    parts = [f"{what}: max δ_f {o.delta_f_max:.2e}, max δ_P {o.delta_p_max:.2e}"]
    if np.isfinite(o.target_conical):
        parts[0] += f", max conical residual {o.conical_max:.2e} rad"
    if np.isfinite(o.target_circular):
        parts[0] += f", max circular residual {o.circular_max:.2e} rad"
    if np.isfinite(o.target_nodes):
        parts[0] += f", max node cosine {o.nodes_max:.2e}"
    if not o.targets_met:
        miss = []
        if o.delta_f_max > o.target_delta_f:
            miss.append(f"max δ_f {o.delta_f_max:.2e} > {o.target_delta_f:.0e}")
        if o.delta_p_max > o.target_delta_p:
            miss.append(f"max δ_P {o.delta_p_max:.2e} > {o.target_delta_p:.0e}")
        if o.conical_max > o.target_conical:
            miss.append(f"conical residual {o.conical_max:.2e} > {o.target_conical:.0e} rad")
        if o.circular_max > o.target_circular:
            miss.append(f"circular residual {o.circular_max:.2e} > {o.target_circular:.0e} rad")
        if o.nodes_max > o.target_nodes:
            miss.append(f"node cosine {o.nodes_max:.2e} > {o.target_nodes:.0e}")
        if len(o.creases.created):
            miss.append("creases created")
        parts.append("targets NOT met (" + ", ".join(miss) + ")")
    if refused and not mostly_guard and guard_refused:
        parts.append(f"guard refused {guard_refused} step(s) ({_fmt_rejected({k: v for k, v in o.rejected.items() if k != 'energy'})})")
    if len(o.creases.created):
        worst = o.creases.created[:5]
        names = ", ".join(f"edge ({int(o.edges[e, 0])}, {int(o.edges[e, 1])}) {o.creases.angles[e]:.1f}°"
                          for e in worst)
        parts.append(f"{len(o.creases.created)} edge(s) creased beyond {o.creases.limit:.1f}° (input max "
                     f"{o.crease_input_max:.1f}°): {names}")
    elif o.rejected.get("crease") and not o.targets_met:
        c = o.creases
        k = int(np.nanargmax(np.where(np.isfinite(c.change), c.change, -np.inf)))
        parts.append(f"largest crease {c.max:.1f}° (limit {c.limit:.1f}° = input max {o.crease_input_max:.1f}° "
                     f"+ crease_limit); edge ({int(o.edges[k, 0])}, {int(o.edges[k, 1])}) grew by "
                     f"{c.change[k]:.1f}° to {c.angles[k]:.1f}°")
    why = f" ({', '.join(o.rose)})" if o.rose else ""
    if o.returned == "best":
        parts.append(f"the last iterate was worse than the input{why}, so the best iterate (iteration "
                     f"{o.best_iteration}) is returned")
    elif o.returned == "input":
        parts.append(f"no iterate was better than the input{' (the last: ' + why[2:] if why else ''}, so the "
                     "input is returned unchanged")
    if not o.targets_met and o.delta_f_max > max(o.delta_f_input, o.target_delta_f) * 1.0001:
        parts.append(f"max δ_f rose from {o.delta_f_input:.2e} (input)")
    if not o.targets_met and o.conjugacy_defect is not None and o.conjugacy_defect > CONJUGACY_ADVICE:
        parts.append(f"the polylines are far from a conjugate net (twist / normal curvature "
                     f"{o.conjugacy_defect:.2f}; a conjugate net has about 0): planar quads with planar "
                     f"polylines need other polylines — remesh along conjugate curves of the surface (e.g. "
                     f"principal curvature lines) and optimise that mesh")
    return "; ".join(parts)
