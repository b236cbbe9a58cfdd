"""P / PP / planar-quad optimisation of quad meshes (paper §3.3).

:func:`optimize` takes any all-quad mesh (:class:`~ppfab.mesh.QuadMesh`, e.g.
from :func:`ppfab.io.load_mesh`, or a :class:`~ppfab.mesh.QuadGrid`) and moves
its vertices so that faces become planar (``E_f``) and the selected polylines
lie in planes (``E_P``), with unit-normal (``E_1``), fairness (``E_fair``) and
closeness terms (to the input surface by default), by a sparse
Levenberg–Marquardt method with an analytic Jacobian (:mod:`.residuals`,
:mod:`.linsolve`, :mod:`.solver`).  On request it keeps or makes the mesh
conical (``keep_conical``, ``E_conical``), keeps panels near-rectangular
(``E_orth``) and stands the support planes at right angles to the panels
(``E_axes``, node axes along the normals) — :mod:`.terms`.  The result says what
the run did to the design (:mod:`.outcome`): distance to the input surface,
creases, conical residual, corner angles, refused steps; it is never worse than
the input.

Examples
--------
>>> import numpy as np
>>> from ppfab.mesh import QuadGrid
>>> i, j = np.meshgrid(np.arange(8.0), np.arange(8.0), indexing="ij")
>>> v = np.stack([i, j, 0.05 * (i - 3.5) ** 2 + 0.03 * (j - 3.5) ** 2], axis=-1)
>>> v = v + np.random.default_rng(1).normal(scale=0.01, size=v.shape)
>>> res = optimize(QuadGrid(v), families="both")
>>> res.targets_met, res.history[-1].delta_p_max < 1e-6
(True, True)
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ppfab import planes as pl
from ..errors import DesignError, GeometryError
from ..mesh import QuadGrid, QuadMesh, as_quadmesh
from ..metrics import (CreaseReport, Quality, conjugacy_defect, crease_report, dihedral_angles, face_planarity,
                       quality)
from ..schema import as_plain, parse_params
from .guard import StepGuard
from .linsolve import resolve_solver
from .outcome import (Outcome, axis_normal_angles, conical_loss, message, p_axis_normal_angles,
                      support_panel_angles, tangent_planes)
from .params import OptimizeParams
from .reference import ReferenceSurface
from .residuals import Residuals, Weights
from .selection import Selection, free_vertices, select_polylines
from .solver import IterationRecord, LevenbergMarquardt, PlanarityMetrics, SolverControl
from .terms import conical_stars, node_pairs, polyline_faces

__all__ = ["optimize", "OptimizeParams", "OptimizeResult", "IterationRecord", "Problem", "build_problem"]

log = logging.getLogger("ppfab")

EXACT_PLANES_LIMIT = 150_000
"""``plane_solver = "auto"`` keeps support normals as unknowns while Σ (polyline length)² is at most this."""

CREASE_MARGIN = 5.0
"""The crease barrier ``E_crease`` acts from this many degrees below the crease limit of the step guard."""

AUTO_FAIRNESS_DELTA_F = 1e-3
"""``fairness = "auto"`` uses the paper's absolute E_fair when the input's max δ_f exceeds this."""


@dataclass
class OptimizeResult:
    """What :func:`optimize` returns.

    mesh : the optimised mesh, same type, vertex and face order as the input (a grid gets its support planes)
    converged : the solver stopped at the targets or at a stationary point (not by the iteration limit)
    targets_met : max δ_f <= target_delta_f and max δ_P (selected polylines) <= target_delta_p
    iterations : LM iterations (linear solves, rejected steps included)
    history : one :class:`IterationRecord` per iteration
    message : one line saying how the run ended
    displacement_mean : mean vertex displacement from the input, mesh units
    displacement_rel : ``displacement_mean`` / bounding-box diagonal of the input
    displacement_max : largest vertex displacement, mesh units
    planes : (S, 4) unit support planes ``n·x + d = 0`` of the selected polylines (mesh units)
    polylines : (S,) indices into ``mesh.polylines`` of the polylines made planar
    skipped : requested polylines with fewer than 3 vertices (planar anyway)
    quality : :class:`~ppfab.metrics.Quality` of the result
    time : wall time in seconds
    delta_f_max, delta_f_mean : face planarity δ_f of the result (§3.3)
    delta_p_max, delta_p_mean : δ_P of the result over the polylines made planar
    excluded : polylines of the requested families left out because they pass twice through a vertex
    polyline_delta_p : (S,) δ_P of each polyline made planar (same order as ``polylines``)
    fairness, plane_solver, linear_solver : the modes ``"auto"`` resolved to
    conical_max_input, conical_max : max conical residual ``|α1 − α2 + α3 − α4|`` (rad) before / after
    circular_max_input, circular_max : max circular residual ``|α1 − α2 + α3 − α4|`` over every panel's corner
        angles (rad) before / after (0 on a circular mesh with planar panels)
    node_angle_max_input, node_angle_max : with ``orthogonal_nodes``, the largest deviation from 90° (degrees) of
        the angle between the planes of the row and the column crossing at a node, before / after (0 otherwise)
    corner_deviation_max_input, corner_deviation_max : max ``|corner angle − 90°|`` (degrees) before / after
    surface_distance_max, surface_distance_mean : distance of the result's vertices to the input surface
        (the input quads), mesh units
    crease_max_input, crease_max : largest dihedral angle (degrees) before / after
    crease_change_max : largest increase of an edge's dihedral angle (degrees)
    crease_limit : the dihedral angle (degrees) beyond which an edge counts as a created crease
    creases : :class:`~ppfab.metrics.CreaseReport` (angles and change per edge of ``mesh.edges``)
    creased_edges : (k, 2) vertex pairs of the created creases, worst first (never with ``targets_met``)
    support_angle_max : largest deviation from 90° between a support plane and a panel along it, degrees
    axis_angle_max, axis_angle_mean : node axis vs vertex normal, degrees: where two planes meet (PP) the
        axis is ``U ∩ W``; on a P run the axis of the exact P support in the planes (one free angle per
        transverse strip, :func:`ppfab.optimize.outcome.p_axis_normal_angles`); 0 without planar polylines
    rejected : refused steps by reason (``energy``, ``fold``, ``crease``, ``flip``, ``nonconvex``, ``collapse``,
        ``nan``)
    returned : ``"last"`` (the final iterate), ``"best"`` (the final iterate was worse than the input; the
        best-scoring iterate is returned) or ``"input"`` (no iterate was better than the input)
    factorisations, cg_solves : how the linear systems were solved (``inexact_solves`` of the CG solves were
        inexact Newton steps on a new linearisation, :mod:`ppfab.optimize.linsolve`)
    conjugacy_defect : :func:`ppfab.metrics.conjugacy_defect` of the input
    warnings : what the targets do not say but the caller should know (also at the end of ``message`` and
        logged): a nearly conical input that lost its conicality (:func:`.outcome.conical_loss`), polylines
        made planar whose planes the support will leave out (:func:`.outcome.tangent_planes`)
    """

    mesh: QuadMesh | QuadGrid
    converged: bool
    targets_met: bool
    iterations: int
    history: list[IterationRecord]
    message: str
    displacement_mean: float
    displacement_rel: float
    displacement_max: float
    planes: np.ndarray
    polylines: np.ndarray
    skipped: int
    quality: Quality
    time: float
    delta_f_max: float = 0.0
    delta_f_mean: float = 0.0
    delta_p_max: float = 0.0
    delta_p_mean: float = 0.0
    excluded: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    polyline_delta_p: np.ndarray = field(default_factory=lambda: np.zeros(0))
    fairness: str = ""
    plane_solver: str = ""
    linear_solver: str = ""
    params: OptimizeParams = field(default_factory=OptimizeParams)
    conical_max_input: float = 0.0
    conical_max: float = 0.0
    circular_max_input: float = 0.0
    circular_max: float = 0.0
    node_angle_max_input: float = 0.0
    node_angle_max: float = 0.0
    corner_deviation_max_input: float = 0.0
    corner_deviation_max: float = 0.0
    surface_distance_max: float = 0.0
    surface_distance_mean: float = 0.0
    crease_max_input: float = 0.0
    crease_max: float = 0.0
    crease_change_max: float = 0.0
    crease_limit: float = 180.0
    creases: CreaseReport | None = None
    creased_edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64))
    support_angle_max: float = 0.0
    axis_angle_max: float = 0.0
    axis_angle_mean: float = 0.0
    rejected: dict[str, int] = field(default_factory=dict)
    returned: str = "last"
    factorisations: int = 0
    cg_solves: int = 0
    inexact_solves: int = 0
    conjugacy_defect: float = 0.0
    warnings: tuple[str, ...] = ()

    def summary(self) -> dict:
        """Plain-data summary (for ``--json`` and reports)."""
        last = self.history[-1] if self.history else None
        return {
            "converged": self.converged, "targets_met": self.targets_met, "iterations": self.iterations,
            "message": self.message, "time_s": self.time,
            "displacement_mean": self.displacement_mean, "displacement_rel": self.displacement_rel,
            "displacement_max": self.displacement_max,
            "planar_polylines": int(len(self.polylines)), "skipped_polylines": self.skipped,
            "final_energy": last.energy if last else None,
            "delta_f_max": self.delta_f_max, "delta_f_mean": self.delta_f_mean,
            "delta_p_max": self.delta_p_max, "delta_p_mean": self.delta_p_mean,
            "excluded_polylines": self.excluded.tolist(),
            "polylines": self.polylines.tolist(), "polyline_delta_p": self.polyline_delta_p.tolist(),
            "fairness": self.fairness, "plane_solver": self.plane_solver, "linear_solver": self.linear_solver,
            "quality": self.quality.as_dict(), "params": as_plain(self.params),
            "conical_max_input": self.conical_max_input, "conical_max": self.conical_max,
            "circular_max_input": self.circular_max_input, "circular_max": self.circular_max,
            "node_angle_max_input": self.node_angle_max_input, "node_angle_max": self.node_angle_max,
            "corner_deviation_max_input": self.corner_deviation_max_input,
            "corner_deviation_max": self.corner_deviation_max,
            "surface_distance_max": self.surface_distance_max, "surface_distance_mean": self.surface_distance_mean,
            "crease_max_input": self.crease_max_input, "crease_max": self.crease_max,
            "crease_change_max": self.crease_change_max, "crease_limit": self.crease_limit,
            "creased_edges": self.creased_edges.tolist(),
            "support_angle_max": self.support_angle_max, "axis_angle_max": self.axis_angle_max,
            "axis_angle_mean": self.axis_angle_mean, "rejected": dict(self.rejected), "returned": self.returned,
            "factorisations": self.factorisations, "cg_solves": self.cg_solves,
            "inexact_solves": self.inexact_solves,
            "conjugacy_defect": self.conjugacy_defect, "warnings": list(self.warnings),
        }


def solver_control(p: OptimizeParams, max_iterations: int | None = None) -> SolverControl:
    """The stopping rule of ``p``: its targets (``inf`` for what it does not ask: free faces, no conical or
    circular goal) and continuation settings; ``max_iterations`` overrides ``p.max_iterations``."""
    return SolverControl(p.target_delta_f if (p.planar_faces and p.weight_faces > 0) else np.inf,
                         p.target_delta_p, p.max_iterations if max_iterations is None else max_iterations,
                         p.reg_decay, p.reg_min, p.stall,
                         target_conical=p.target_conical if p.keep_conical else np.inf,
                         target_circular=p.target_circular if p.keep_circular else np.inf,
                         target_nodes=p.target_nodes if p.orthogonal_nodes else np.inf,
                         linear_solver=resolve_solver(p.linear_solver))


def _params(params: OptimizeParams | dict | None, kw: dict) -> OptimizeParams:
    if isinstance(params, OptimizeParams):
        base = as_plain(params)
    else:
        base = dict(params or {})
    base.update(kw)
    return parse_params(OptimizeParams, base, "optimize")


@dataclass
class Problem:
    """An optimisation problem in normalised coordinates (mean edge length 1, centroid at 0).

    ``to_mesh_units(v) = v · scale + center``.
    """

    mesh: QuadMesh
    params: OptimizeParams
    selection: Selection
    free: np.ndarray
    center: np.ndarray
    scale: float
    residuals: Residuals
    z0: np.ndarray
    metrics: PlanarityMetrics
    guard: StepGuard
    reference: ReferenceSurface | None
    fairness: str = "relative"            # the resolved E_fair mode
    plane_solver: str = "exact"           # the resolved support-normal treatment
    stars: np.ndarray = field(default_factory=lambda: np.zeros((0, 5), dtype=np.int64))  # conical stars
    axes_pairs: tuple = (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64))      # (polyline, face)
    crease0: np.ndarray = field(default_factory=lambda: np.zeros(0))   # input dihedral angles, degrees
    crease_limit: float = 180.0                                         # input max + params.crease_limit
    surface: ReferenceSurface | None = None                             # the input surface (normalised)
    held: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # (N, 3) mesh units: input, anchors moved

    def to_mesh_units(self, v: np.ndarray) -> np.ndarray:
        """``(N, 3)`` normalised vertices in mesh units, the fixed vertices exactly where they are held."""
        out = v * self.scale + self.center
        out[~self.free] = self.held[~self.free]
        return out

    def on_stage(self, z: np.ndarray) -> None:
        """A stage begins: update the shape barrier's face normals and the surface foot points."""
        v = self.residuals.unpack(z)[0]
        self.residuals.set_shape_reference(v)
        if self.reference is not None:
            self.residuals.set_reference(*self.reference.closest(v))


def _initial_normals(v: np.ndarray, faces: np.ndarray, lines) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals of least-squares planes of the faces ``(F, 3)`` and polylines ``(S, 3)``."""
    nf, _ = pl.fit_plane(v[faces])
    if lines:
        from ..metrics import pad_polylines

        pts, w = pad_polylines(v, lines)
        ns, _ = pl.fit_plane(pts, w)
    else:
        ns = np.zeros((0, 4))
    return nf[:, :3], ns[:, :3]


def build_problem(mesh: QuadMesh | QuadGrid, params: OptimizeParams | dict | None = None, *,
                  reference: tuple[np.ndarray, np.ndarray] | None = None, **kw) -> Problem:
    """Set up (but do not solve) the problem of :func:`optimize`; used by benchmarks and tests.

    ``reference`` : ``(vertices (R, 3), faces (G, 3 or 4))`` in mesh units — the surface to stay close to (a
    designer's surface the mesh was made from); the input mesh itself when omitted."""
    p = _params(params, kw)
    qm = as_quadmesh(mesh)                                 # refuses anything else (GeometryError)
    v = np.asarray(qm.vertices, dtype=float)
    faces = np.asarray(qm.faces, dtype=np.int64)
    lengths = qm.edge_lengths()
    scale = float(lengths.mean()) if len(lengths) else 0.0
    if not scale > 0:
        raise GeometryError("the mesh has no edge of positive length", element="edges", value=scale)
    short = np.flatnonzero(lengths <= 1e-9 * scale)
    if len(short):
        e = qm.edges[short[0]]
        raise GeometryError(f"edge ({int(e[0])}, {int(e[1])}) has zero length ({lengths[short[0]]:.3g}); "
                            f"{len(short)} degenerate edge(s)", element=f"edge ({int(e[0])}, {int(e[1])})",
                            value=float(lengths[short[0]]))
    center = v.mean(axis=0)
    vn = (v - center) / scale
    try:
        sel = select_polylines(qm, p.families, p.polylines, p.fair_families)
        free = free_vertices(qm, p.fix_boundary, p.fixed_vertices)
        held = anchored(v, p.anchors)
    except DesignError as exc:
        raise DesignError(f"optimize.{exc.key}", str(exc).split(": ", 1)[-1]) from None
    free[[int(a[0]) for a in p.anchors]] = False
    if not free.any():
        raise DesignError("optimize.fixed_vertices" if p.fixed_vertices else "optimize.fix_boundary",
                          f"all {len(free)} vertices are fixed: nothing can move")
    weights = Weights(p.weight_planarity, p.weight_faces, p.weight_unit, p.weight_fair, p.weight_close,
                      p.weight_shape, p.shape_ratio, p.weight_conical if p.keep_conical else 0.0,
                      p.weight_orthogonal, p.weight_axes, p.slide, p.weight_circular if p.keep_circular else 0.0,
                      p.weight_nodes if p.orthogonal_nodes else 0.0)
    topo = qm.topology
    stars = conical_stars(faces, len(v), ~topo.boundary_vertices) if p.keep_conical \
        else np.zeros((0, 5), dtype=np.int64)
    if p.keep_conical and not len(stars):
        raise DesignError("optimize.keep_conical", "the mesh has no interior vertex with four faces: there is "
                                                   "no conical condition to keep")
    circles = faces if p.keep_circular else np.zeros((0, 4), dtype=np.int64)
    nodes = node_pairs(sel.planar)[0] if p.orthogonal_nodes else np.zeros((0, 2), dtype=np.int64)
    if p.orthogonal_nodes and not len(nodes):
        raise DesignError("optimize.orthogonal_nodes", "no planar row crosses a planar column: there is no node "
                                                       "to make orthogonal")
    pairs = (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64))
    if p.weight_axes > 0:
        pairs = polyline_faces(sel.planar, qm.edges, topo.edge_faces)
    fairness = p.fairness
    if fairness == "auto":
        far = len(faces) and float(face_planarity(v[faces]).max()) > AUTO_FAIRNESS_DELTA_F
        fairness = "absolute" if far else "relative"
    exact = p.plane_solver == "exact" or p.orthogonal_nodes or (
        p.plane_solver == "auto" and sum(len(ln) ** 2 for ln in sel.planar) <= EXACT_PLANES_LIMIT)
    c0 = vn[faces]
    crease0 = dihedral_angles(np.cross(c0[:, 2] - c0[:, 0], c0[:, 3] - c0[:, 1]), topo.edge_faces)
    finite = crease0[np.isfinite(crease0)]
    limit = min(180.0, (float(finite.max()) if finite.size else 0.0) + p.crease_limit)
    start = np.radians(limit - min(CREASE_MARGIN, p.crease_limit / 3.0)) if limit < 180.0 else None
    res = Residuals(vn, faces, qm.edges, sel.planar, sel.fair, free, weights, fairness, p.closeness,
                    p.planar_faces, plane_unknowns=exact, stars=stars, orthogonality=p.orthogonality,
                    axes_pairs=pairs, edge_faces=topo.edge_faces, crease_start=start, circles=circles,
                    nodes=nodes)
    v_start = (held - center) / scale                      # the anchors where they are held, the rest as input
    nf, ns = _initial_normals(vn, faces, sel.planar)       # the planes of the input: an anchor moved far makes
    z0 = res.pack(v_start, ns, nf)                         # spikes whose own planes would keep them (nonconvex)
    metrics = PlanarityMetrics(faces, sel.planar, len(vn), stars, circles, nodes)
    guard = StepGuard(faces, qm.edges, vn, p.min_edge_ratio, topo.edge_faces, crease_limit=limit)
    surface = ReferenceSurface(vn, faces) if reference is None else \
        ReferenceSurface((np.asarray(reference[0], dtype=float) - center) / scale, reference[1])
    ref = surface if p.closeness == "surface" else None
    return Problem(qm, p, sel, free, center, scale, res, z0, metrics, guard, ref, fairness,
                   "exact" if exact else "projected", stars, pairs, crease0, limit, surface, held)


def anchored(vertices: np.ndarray, anchors: list[list[float]]) -> np.ndarray:
    """``(N, 3)`` copy of ``vertices`` with every anchor ``[vertex, x, y, z]`` moved to its point.

    Raises :class:`DesignError` (key ``anchors[k]``) for a vertex that does not exist or is anchored twice."""
    out = np.array(vertices, dtype=float)
    seen: set[int] = set()
    for k, a in enumerate(anchors):
        i = int(a[0])
        if not 0 <= i < len(out):
            raise DesignError(f"anchors[{k}]", f"vertex {i} does not exist (the mesh has {len(out)} vertices)")
        if i in seen:
            raise DesignError(f"anchors[{k}]", f"vertex {i} is anchored twice; keep one of its entries")
        seen.add(i)
        out[i] = [float(x) for x in a[1:4]]
    return out


def optimize(mesh: QuadMesh | QuadGrid, params: OptimizeParams | dict | None = None, *,
             callback: Callable[[IterationRecord], None] | None = None,
             reference: tuple[np.ndarray, np.ndarray] | None = None, **kw) -> OptimizeResult:
    """Make faces planar and polylines planar (P or PP) by the optimisation of §3.3.

    Parameters
    ----------
    mesh : :class:`QuadMesh` (any all-quad mesh) or :class:`QuadGrid`
    params : :class:`OptimizeParams` or a dict of its fields (the design file's ``[optimize]`` table)
    callback : called with each :class:`IterationRecord` (progress display)
    reference : ``(vertices, faces)`` of the surface to stay close to (triangles or quads, mesh units); the
        input mesh when omitted (see :func:`build_problem`)
    **kw : fields of :class:`OptimizeParams` overriding ``params``

    Returns
    -------
    :class:`OptimizeResult`; ``targets_met`` says whether max δ_f and max δ_P reached their targets.

    Raises
    ------
    DesignError : a parameter is out of range or names a polyline / vertex that does not exist
    GeometryError : degenerate input (zero-length edges)
    """
    t0 = time.perf_counter()
    prob = build_problem(mesh, params, reference=reference, **kw)
    p = prob.params
    control = solver_control(p)
    target_df, _, target_c, target_o, target_n = control.targets()
    lm = LevenbergMarquardt(prob.residuals, prob.z0, prob.metrics, prob.guard, control, prob.on_stage, callback)
    state = lm.run()
    v_last = prob.residuals.unpack(state.z)[0]
    m_last = prob.metrics(v_last)
    last = (m_last[0], m_last[2], *prob.metrics.goals(v_last))
    last_score = control.score(*last)
    rose = control.rises(last, state.start_metrics)
    returned = "last"
    z_out = state.z
    if (last_score > state.start_score or rose) and state.best_z is not None:   # never hand back something worse
        z_out = state.best_z
        returned = "input" if state.best_iteration == 0 else "best"
    v_n = prob.residuals.unpack(z_out)[0]
    v0 = np.asarray(prob.mesh.vertices)
    v = v0 + (v_n - prob.residuals.vertices0) * prob.scale         # unmoved vertices stay bit-identical
    v[~prob.free] = prob.held[~prob.free]
    if returned == "input":                                        # the input, with its anchors where held
        v = prob.held.copy()
        v_n = prob.residuals.unpack(prob.z0)[0]
    out_qm = prob.mesh.with_vertices(v)
    planes = _support_planes(v, prob.selection.planar)
    out = _as_input_type(mesh, out_qm, prob.selection, planes)
    disp = np.linalg.norm(v - v0, axis=1)
    diag = float(np.linalg.norm(v0.max(axis=0) - v0.min(axis=0)))
    dfm, dfa, dpm, dpa = prob.metrics(v)
    df0, _, dp0, _ = prob.metrics(v0)
    con, circ, node_cos = prob.metrics.goals(v)
    node_cos_in = prob.metrics.nodes_max(v0)
    c = v_n[np.asarray(prob.mesh.faces)]
    creases = crease_report(dihedral_angles(np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1]),
                                            prob.mesh.topology.edge_faces), prob.crease0, prob.crease_limit)
    met = bool(dfm <= target_df and dpm <= p.target_delta_p and con <= target_c and circ <= target_o
               and node_cos <= target_n and not len(creases.created))
    per_line = prob.metrics.per_polyline(v)
    q_in, q_out = quality(mesh), quality(out)
    foot, _ = prob.surface.closest(v_n) if prob.surface is not None else (v_n, None)
    dist = np.linalg.norm(v_n - foot, axis=1) * prob.scale
    faces = np.asarray(prob.mesh.faces, dtype=np.int64)
    sup = support_panel_angles(v, faces, planes, *_all_pairs(prob))
    axis = axis_normal_angles(v, faces, planes, prob.selection.planar)
    if not len(axis) and len(prob.selection.planar):          # P: one plane per vertex, axes of the P support
        axis = p_axis_normal_angles(out_qm, prob.selection.planar_index)
    defect = conjugacy_defect(prob.mesh) if not met else 0.0
    crease_in = float(np.nanmax(prob.crease0)) if np.isfinite(prob.crease0).any() else 0.0
    outcome = Outcome(state.stopped_by, met, dfm, dpm, con, df0, dp0, target_df, p.target_delta_p, target_c,
                      state.iterations, p.max_iterations, state.rejected, returned, state.best_iteration,
                      creases, crease_in, prob.mesh.edges, defect if not met else None,
                      rose if returned != "last" else (), circ, target_o, node_cos, target_n)
    warns = tuple(w for w in (conical_loss(q_in.conical_max, q_out.conical_max, p.keep_conical),
                              tangent_planes(out_qm, prob.selection.planar_index)) if w)
    msg = message(outcome) + _notes(p, prob, per_line) + "".join(f"; {w}" for w in warns)
    log.debug(msg)
    for w in warns:
        log.warning(w)
    return OptimizeResult(
        mesh=out, converged=state.stopped_by in ("targets", "stationary"), targets_met=met,
        iterations=state.iterations, history=state.history, message=msg,
        displacement_mean=float(disp.mean()), displacement_rel=float(disp.mean() / diag) if diag > 0 else 0.0,
        displacement_max=float(disp.max()), planes=planes, polylines=prob.selection.planar_index,
        skipped=prob.selection.skipped, quality=q_out, time=time.perf_counter() - t0,
        delta_f_max=dfm, delta_f_mean=dfa, delta_p_max=dpm, delta_p_mean=dpa,
        excluded=prob.selection.crossing, polyline_delta_p=per_line, fairness=prob.fairness,
        plane_solver=prob.plane_solver, linear_solver=lm.cache.solver, params=p,
        conical_max_input=q_in.conical_max, conical_max=q_out.conical_max,
        circular_max_input=q_in.circular_max, circular_max=q_out.circular_max,
        node_angle_max_input=_cos_to_deviation(node_cos_in), node_angle_max=_cos_to_deviation(node_cos),
        corner_deviation_max_input=q_in.corner_deviation_max, corner_deviation_max=q_out.corner_deviation_max,
        surface_distance_max=float(dist.max()) if len(dist) else 0.0,
        surface_distance_mean=float(dist.mean()) if len(dist) else 0.0,
        crease_max_input=crease_in, crease_max=creases.max, crease_change_max=creases.change_max,
        crease_limit=prob.crease_limit, creases=creases, creased_edges=prob.mesh.edges[creases.created],
        support_angle_max=float(sup.max()) if len(sup) else 0.0,
        axis_angle_max=float(axis.max()) if len(axis) else 0.0,
        axis_angle_mean=float(axis.mean()) if len(axis) else 0.0,
        rejected=state.rejected, returned=returned, factorisations=state.factorisations,
        cg_solves=state.cg_solves, inexact_solves=state.inexact_solves, conjugacy_defect=defect, warnings=warns)


def _cos_to_deviation(cos: float) -> float:
    """Deviation from 90° (degrees) of an angle whose ``|cos|`` is ``cos``."""
    return float(np.degrees(np.arcsin(min(1.0, abs(cos)))))


def _all_pairs(prob: Problem) -> tuple[np.ndarray, np.ndarray]:
    """(polyline, face) pairs of every planar polyline (those of E_axes, or computed for the report)."""
    if len(prob.axes_pairs[0]) or not prob.selection.planar:
        return prob.axes_pairs
    qm = prob.mesh
    return polyline_faces(prob.selection.planar, qm.edges, qm.topology.edge_faces)


def _support_planes(v: np.ndarray, lines) -> np.ndarray:
    """Least-squares unit planes ``(S, 4)`` of the planar polylines in mesh units."""
    if not lines:
        return np.zeros((0, 4))
    from ..metrics import pad_polylines

    pts, w = pad_polylines(v, lines)
    planes, _ = pl.fit_plane(pts, w)
    return planes


def _as_input_type(mesh, out_qm: QuadMesh, sel: Selection, planes: np.ndarray):
    if not isinstance(mesh, QuadGrid):
        return out_qm
    m1, n1 = mesh.shape
    fam = np.array([ln.family for ln in sel.planar], dtype=np.int64)
    support = {}
    if np.count_nonzero(fam == 0) == m1:
        support["support_u"] = planes[fam == 0]
    if np.count_nonzero(fam == 1) == n1:
        support["support_w"] = planes[fam == 1]
    return mesh.with_vertices(np.asarray(out_qm.vertices).reshape(m1, n1, 3), **support)


def _notes(p: OptimizeParams, prob: Problem, per_line: np.ndarray) -> str:
    """The worst polylines above the δ_P target, inconsistent families and polylines left out."""
    tail = ""
    bad = np.flatnonzero(per_line > p.target_delta_p)
    if len(bad):
        worst = bad[np.argsort(-per_line[bad])][:5]
        tail += (f"; {len(bad)} polyline(s) above the δ_P target, worst: "
                 + ", ".join(f"{int(prob.selection.planar_index[k])} ({per_line[k]:.1e})" for k in worst))
    if prob.mesh.grid is None and p.families != "none" and not prob.mesh.topology.families_consistent:
        tail += " (polyline families are not consistent on this mesh: family labels are per polyline)"
    if len(prob.selection.crossing):
        tail += (f"; left out {len(prob.selection.crossing)} polyline(s) that pass twice through a vertex: "
                 f"{', '.join(map(str, prob.selection.crossing.tolist()))} (list them in 'polylines' to force)")
    return tail
