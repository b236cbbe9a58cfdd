"""Levenberg–Marquardt for the energies of §3.3, with regularisation continuation.

The loop is Madsen, Nielsen & Tingleff, *Methods for non-linear least squares
problems* (2004), Algorithm 3.16: solve ``(JᵀJ + μI) h = −Jᵀr``
(:class:`~ppfab.optimize.linsolve.DampedSystem`), accept the step when the
gain ratio ``ρ = (E(x) − E(x + h)) / (L(0) − L(h))`` is positive and the
:class:`~ppfab.optimize.guard.StepGuard` finds no fold or collapse, then
``μ ← μ·max(1/3, 1 − (2ρ − 1)³)``; otherwise the step is undone and
``μ ← μν, ν ← 2ν``.  Within a stage the energy therefore never increases.

Stages: the paper's energy (stage 0, regularisation factor ``s = 1``) has its
minimum where the fairness and closeness terms still pull the vertices a
little off the constraints.  When an accepted step lowers the energy by less
than ``stall`` (relative), the fairness and closeness weights are multiplied by
``reg_decay`` (down to ``reg_min``) and a new stage starts from the current
state, so the constraints E_P, E_f, E_1 are driven to zero while the mesh stays
where the regularised problem put it.  The run stops when the targets on
``max δ_f`` and ``max δ_P`` are met (measured with :mod:`ppfab.metrics` after
every accepted step), at a stationary point, or after ``max_iterations`` solves.

On large systems the first solve of a new linearisation may be an inexact Newton step (CG preconditioned with
an earlier factor, :mod:`ppfab.optimize.linsolve`); a rejected inexact step turns them off until the next stage.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..metrics import circular_residual, face_planarity, pad_polylines, polyline_planarity
from ..planes import fit_plane
from ..topology import Polyline
from .guard import StepGuard
from .linsolve import INEXACT_MIN_UNKNOWNS, DampedSystem, FactorCache
from .residuals import Residuals
from .terms import angle_balance


@dataclass(frozen=True)
class IterationRecord:
    """One Levenberg–Marquardt iteration (one linear solve).

    Energies are of the state after the iteration (unchanged when the step was
    rejected); ``energy`` is the weighted total at the stage's regularisation
    factor ``reg``; δ values are of the current state (§3.3 metrics).
    """

    iteration: int
    stage: int
    reg: float
    accepted: bool
    rejected_by: str
    mu: float
    step: float
    energy: float
    E_P: float
    E_f: float
    E_1: float
    E_fair: float
    E_close: float
    delta_f_max: float
    delta_f_mean: float
    delta_p_max: float
    delta_p_mean: float
    time: float
    conical_max: float = 0.0
    E_conical: float = 0.0
    E_orth: float = 0.0
    E_axes: float = 0.0
    circular_max: float = 0.0
    nodes_max: float = 0.0

    def line(self) -> str:
        """One line for progress output."""
        mark = "+" if self.accepted else f"x {self.rejected_by}"
        return (f"it {self.iteration:4d} st {self.stage} s={self.reg:.0e} E={self.energy:.3e} "
                f"E_P={self.E_P:.2e} E_f={self.E_f:.2e} dF={self.delta_f_max:.2e}/{self.delta_f_mean:.2e} "
                f"dP={self.delta_p_max:.2e}/{self.delta_p_mean:.2e}"
                + (f" con={self.conical_max:.2e}" if self.conical_max else "")
                + (f" circ={self.circular_max:.2e}" if self.circular_max else "")
                + (f" nodes={self.nodes_max:.2e}" if self.nodes_max else "") + f" mu={self.mu:.1e} {mark}")


class PlanarityMetrics:
    """``δ_f`` of all faces and ``δ_P`` of the selected polylines (§3.3), from vertices ``(N, 3)``; the conical
    residual of ``stars (K, 5)``, the circular residual of ``circles (C, 4)`` and the orthogonal-node measure of
    ``nodes (K, 2)`` (positions in ``polylines`` of the row and column crossing at a node) when given."""

    def __init__(self, faces: np.ndarray, polylines: list[Polyline], n_vertices: int,
                 stars: np.ndarray | None = None, circles: np.ndarray | None = None,
                 nodes: np.ndarray | None = None):
        self.faces = np.asarray(faces, dtype=np.int64)
        self.stars = np.zeros((0, 5), dtype=np.int64) if stars is None else np.asarray(stars, dtype=np.int64)
        self.circles = np.zeros((0, 4), dtype=np.int64) if circles is None else \
            np.asarray(circles, dtype=np.int64).reshape(-1, 4)
        self.nodes = np.zeros((0, 2), dtype=np.int64) if nodes is None else \
            np.asarray(nodes, dtype=np.int64).reshape(-1, 2)
        self.has_lines = bool(polylines)
        if polylines:
            idx, self.weights = pad_polylines(np.arange(n_vertices, dtype=float)[:, None], polylines)
            self.index = idx[..., 0].astype(np.int64)

    def per_polyline(self, vertices: np.ndarray) -> np.ndarray:
        """``δ_P (S,)`` of every selected polyline."""
        if not self.has_lines:
            return np.zeros(0)
        return polyline_planarity(vertices[self.index], self.weights)

    def __call__(self, vertices: np.ndarray) -> tuple[float, float, float, float]:
        """``(δ_f max, δ_f mean, δ_P max, δ_P mean)``."""
        df = face_planarity(vertices[self.faces]) if len(self.faces) else np.zeros(1)
        dp = polyline_planarity(vertices[self.index], self.weights) if self.has_lines else np.zeros(1)
        return float(df.max()), float(df.mean()), float(dp.max()), float(dp.mean())

    def conical_max(self, vertices: np.ndarray) -> float:
        """Largest conical residual ``|α_0 − α_1 + α_2 − α_3|`` (rad) over the stars (0 without stars)."""
        if not len(self.stars):
            return 0.0
        return float(np.abs(angle_balance(vertices, self.stars)[0]).max())

    def circular_max(self, vertices: np.ndarray) -> float:
        """Largest circular residual ``|α_0 − α_1 + α_2 − α_3|`` (rad, corner angles) over the circles (0 without)."""
        if not len(self.circles):
            return 0.0
        return float(circular_residual(vertices[self.circles]).max())

    def nodes_max(self, vertices: np.ndarray) -> float:
        """Largest ``|cos|`` of the angle between the least-squares planes of the row and the column crossing at a
        node (0: orthogonal nodes, §2.3.4; 0 without nodes)."""
        if not len(self.nodes) or not self.has_lines:
            return 0.0
        planes, _ = fit_plane(vertices[self.index], self.weights)
        n = planes[:, :3]
        return float(np.abs(np.einsum("ij,ij->i", n[self.nodes[:, 0]], n[self.nodes[:, 1]])).max())

    def goals(self, vertices: np.ndarray) -> tuple[float, float, float]:
        """``(conical_max, circular_max, nodes_max)`` of ``vertices``: the measures of the geometric goals."""
        return self.conical_max(vertices), self.circular_max(vertices), self.nodes_max(vertices)


RISE = 1.0001
"""Relative rise of a measure above its input value (and its target) that makes an iterate worse than the
input (:meth:`SolverControl.rises`)."""


@dataclass
class SolverControl:
    """Stopping and continuation settings (see module docstring), and the sparse solver of the normal equations
    (``"superlu"`` or ``"pardiso"``, :func:`~ppfab.optimize.linsolve.resolve_solver`)."""

    target_delta_f: float = 1e-6
    target_delta_p: float = 1e-6
    max_iterations: int = 500
    reg_decay: float = 0.1
    reg_min: float = 1e-6
    stall: float = 0.05
    tau: float = 1e-4
    max_rejections: int = 40
    target_conical: float = np.inf
    target_circular: float = np.inf
    target_nodes: float = np.inf
    linear_solver: str = "superlu"
    inexact_min_unknowns: int = INEXACT_MIN_UNKNOWNS      # systems this large may take inexact Newton steps

    def rises(self, now: tuple[float, ...], start: tuple[float, ...]) -> tuple[str, ...]:
        """The targeted measures — max δ_f, max δ_P, max conical and circular residual, max node cosine — of an iterate ``now`` that are
        above both their target and their value at the ``start`` (by more than :data:`RISE`), each as
        ``"max δ_f 8.09e-03 > input 4.06e-05"``: an iterate with any is worse than the input, whatever its
        score."""
        out = []
        for name, x, x0, t in zip(("max δ_f", "max δ_P", "max conical residual", "max circular residual",
                                   "max node cosine"), now, start, self.targets()):
            if np.isfinite(t) and x > max(x0 * RISE, t):
                out.append(f"{name} {x:.2e} > input {x0:.2e}")
        return tuple(out)

    def targets(self) -> tuple[float, float, float, float, float]:
        """The targets of max δ_f, max δ_P, max conical and max circular residual and max node cosine (``inf``:
        not targeted)."""
        return (self.target_delta_f, self.target_delta_p, self.target_conical, self.target_circular,
                self.target_nodes)

    def score(self, dfm: float, dpm: float, conical: float, circular: float = 0.0, nodes: float = 0.0) -> float:
        """Worst target ratio of an iterate (``<= 1``: every target met)."""
        ratios = [x / t for x, t in zip((dfm, dpm, conical, circular, nodes), self.targets()) if np.isfinite(t)]
        return float(max(ratios, default=0.0))


@dataclass
class SolverState:
    """What a run ended with."""

    z: np.ndarray
    iterations: int
    stopped_by: str           # "targets", "stationary", "max_iterations", "stuck"
    history: list[IterationRecord] = field(default_factory=list)
    best_z: np.ndarray | None = None            # the best-scoring state seen that is nowhere worse than the
                                                # start (SolverControl.rises; the start included)
    best_iteration: int = 0                     # its iteration (0 = the start)
    best_score: float = np.inf
    start_score: float = np.inf
    rejected: dict[str, int] = field(default_factory=dict)   # refused steps by reason
    factorisations: int = 0
    cg_solves: int = 0
    start_metrics: tuple[float, ...] = (np.inf,) * 5   # max δ_f, max δ_P, conical, circular, node cosine
    inexact_solves: int = 0                             # CG solves of a new linearisation (inexact Newton)


class LevenbergMarquardt:
    """Stateful LM solver over a :class:`Residuals` problem (call :meth:`step` or :meth:`run`).

    Parameters
    ----------
    problem : the residuals and Jacobian
    z0 : (n_full,) initial state
    metrics : maps vertices ``(N, 3)`` to ``(δ_f max, δ_f mean, δ_P max, δ_P mean)``
    guard : step guard, or ``None``
    control : :class:`SolverControl`
    on_stage : called with the state ``z`` when a new stage begins (e.g. to update foot points)
    callback : called with every :class:`IterationRecord`
    """

    def __init__(self, problem: Residuals, z0: np.ndarray, metrics: PlanarityMetrics,
                 guard: StepGuard | None = None, control: SolverControl | None = None,
                 on_stage: Callable[[np.ndarray], None] | None = None,
                 callback: Callable[[IterationRecord], None] | None = None):
        self.p = problem
        self.z = problem.project_normals(np.array(z0, dtype=float))
        self.metrics = metrics
        self.guard = guard
        self.c = control or SolverControl()
        self.on_stage = on_stage
        self.callback = callback
        self.reg = 1.0
        self.stage = 0
        self.mu = 0.0                            # set from the first linearisation (Madsen et al. τ)
        self.nu = 2.0
        self.rejections = 0
        self.iteration = 0
        self.history: list[IterationRecord] = []
        self.t0 = time.perf_counter()
        self.cache = FactorCache(last=3 * problem.n_planes if problem.plane_unknowns else 0,
                                 solver=self.c.linear_solver, inexact_min=self.c.inexact_min_unknowns)
        if on_stage is not None:
            on_stage(self.z)
        self._linearise()
        self.current_metrics = metrics(self.vertices)
        self.current_conical, self.current_circular, self.current_nodes = metrics.goals(self.vertices)
        self.start_score = self.best_score = self.score()
        self.start_metrics = self._measures()
        self.best_z = self.z.copy()
        self.best_iteration = 0
        self.rejected: dict[str, int] = {}

    @property
    def vertices(self) -> np.ndarray:
        return self.p.unpack(self.z)[0]

    def _linearise(self) -> None:
        self.r = self.p.residual(self.z, self.reg)
        self.energy = float(self.r @ self.r)
        self.system = DampedSystem(self.p.jacobian(self.z, self.reg), self.r, self.p.n_face_unknowns,
                                   self.cache)
        if self.mu == 0.0:
            self.mu = self.c.tau * max(self.system.diag_max, 1e-12)

    def _measures(self) -> tuple[float, float, float, float, float]:
        return (self.current_metrics[0], self.current_metrics[2], self.current_conical, self.current_circular,
                self.current_nodes)

    def score(self) -> float:
        """Worst target ratio of the current state (:meth:`SolverControl.score`)."""
        return self.c.score(*self._measures())

    def targets_met(self) -> bool:
        return all(x <= t for x, t in zip(self._measures(), self.c.targets()))

    def _record(self, accepted: bool, reason: str, step: float) -> IterationRecord:
        e = self.p.energies(self.z, self.reg)
        m = self.current_metrics
        rec = IterationRecord(self.iteration, self.stage, self.reg, accepted, reason, float(self.mu), step,
                              e["total"], e["E_P"], e["E_f"], e["E_1"], e["E_fair"], e["E_close"],
                              m[0], m[1], m[2], m[3], time.perf_counter() - self.t0, self.current_conical,
                              e["E_conical"], e["E_orth"], e["E_axes"], self.current_circular, self.current_nodes)
        self.history.append(rec)
        if self.callback is not None:
            self.callback(rec)
        return rec

    def step(self) -> str:
        """One LM iteration; returns ``''`` to go on or the reason to stop."""
        self.iteration += 1
        inexact_before = self.cache.inexact_solves
        h = self.system.solve(self.mu)
        inexact = self.cache.inexact_solves > inexact_before
        z_new = self.z.copy()
        z_new[self.p.free_index] += h
        z_new = self.p.project_normals(z_new)
        v_old, v_new = self.vertices, self.p.unpack(z_new)[0]
        reason = self.guard.check(v_old, v_new) if self.guard is not None else ""
        step_norm = float(np.linalg.norm(h))
        if not reason:
            r_new = self.p.residual(z_new, self.reg)
            e_new = float(r_new @ r_new)
            pred = self.system.predicted_decrease(h, self.mu)
            rho = (self.energy - e_new) / pred if pred > 0 else -1.0
            if not (rho > 0 and np.isfinite(e_new)):
                reason = "energy"
        if reason:                       # undo: state, energy and linearisation stay as they were
            if inexact:
                self.cache.inexact_ok = False          # the stale factor misled: exact steps until a new stage
            self.mu *= self.nu
            self.nu *= 2.0
            self.rejections += 1
            self.rejected[reason] = self.rejected.get(reason, 0) + 1
            self._record(False, reason, step_norm)
            if self.rejections >= self.c.max_rejections:
                return "stuck"
            return "max_iterations" if self.iteration >= self.c.max_iterations else ""
        self.rejections = 0
        old_energy = self.energy
        self.z = z_new
        self.mu *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
        self.nu = 2.0
        self.current_metrics = self.metrics(self.vertices)
        self.current_conical, self.current_circular, self.current_nodes = self.metrics.goals(self.vertices)
        score = self.score()
        if score < self.best_score and not self.c.rises(self._measures(), self.start_metrics):
            self.best_score, self.best_z, self.best_iteration = score, self.z.copy(), self.iteration
        self._record(True, "", step_norm)
        if self.targets_met():
            return "targets"
        decrease = (old_energy - e_new) / old_energy if old_energy > 0 else 0.0
        tiny = step_norm <= 1e-13 * (np.linalg.norm(self.z) + 1e-13) or decrease < 1e-13
        if decrease < self.c.stall and self.reg > self.c.reg_min and self.c.reg_decay < 1.0:
            self.reg = max(self.reg * self.c.reg_decay, self.c.reg_min)
            self.stage += 1
            self.cache.inexact_ok = True
            if self.on_stage is not None:
                self.on_stage(self.z)
        elif tiny:
            return "stationary"
        if self.iteration >= self.c.max_iterations:
            return "max_iterations"
        self._linearise()
        return ""

    def restart(self, z: np.ndarray) -> None:
        """Go on from state ``z`` changed outside the solver (a fixed vertex moved: a live anchor): the
        continuation starts again at stage 0 (``s = 1``), the damping from the new linearisation, the iteration
        count from 0; the best state and the start's measures are those of ``z``."""
        self.z = self.p.project_normals(np.array(z, dtype=float))
        self.reg, self.stage, self.iteration, self.rejections, self.nu, self.mu = 1.0, 0, 0, 0, 2.0, 0.0
        self.cache.inexact_ok = True
        if self.on_stage is not None:
            self.on_stage(self.z)
        self._linearise()
        self.current_metrics = self.metrics(self.vertices)
        self.current_conical, self.current_circular, self.current_nodes = self.metrics.goals(self.vertices)
        self.start_score = self.best_score = self.score()
        self.start_metrics = self._measures()
        self.best_z, self.best_iteration = self.z.copy(), 0

    def run(self) -> SolverState:
        """Iterate until a stop criterion (see module docstring)."""
        reason = "targets" if self.targets_met() else ""
        while not reason:
            reason = self.step()
        return SolverState(self.z, self.iteration, reason, self.history, self.best_z, self.best_iteration,
                           self.best_score, self.start_score, dict(self.rejected), self.cache.factorisations,
                           self.cache.cg_solves, self.start_metrics, self.cache.inexact_solves)
