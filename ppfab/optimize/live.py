"""Live P / PP relaxation with anchors: the optimisation of §3.3 run a few steps at a time while a designer
drags vertices (the interaction of Kangaroo's anchors and goals, on the paper's energies).

:class:`LiveRelaxation` sets the problem up once (:func:`~ppfab.optimize.build_problem`) with the anchors among
the fixed vertices and closeness to the input's vertices (``E_close``, weight ``weight_close``), fairness relative
to the input's second differences.  :meth:`LiveRelaxation.move` puts an anchor where the designer dragged it (a
fixed vertex is a constant of the residuals ``r(z)``: only its entries of the state ``z`` change) and starts the
continuation again at the full regularisation; :meth:`LiveRelaxation.relax` runs Levenberg–Marquardt steps
(:class:`~ppfab.optimize.solver.LevenbergMarquardt`) for at most a time budget and returns a :class:`LiveFrame`.
Left alone, the relaxation goes on through its stages (fairness and closeness fading by ``reg_decay``) until the
targets on max δ_f and max δ_P are met — the same stopping rule as :func:`~ppfab.optimize.optimize` — so the mesh
a designer lets go of becomes P or PP to the design's targets where the anchors hold it.

Examples
--------
>>> import numpy as np
>>> from ppfab.mesh import QuadGrid
>>> i, j = np.meshgrid(np.arange(8.0), np.arange(8.0), indexing="ij")
>>> grid = QuadGrid(np.stack([i, j, 0.05 * (i - 3.5) ** 2 + 0.03 * (j - 3.5) ** 2], axis=-1))
>>> live = LiveRelaxation(grid, {"families": "both"}, anchors=[0, 63])
>>> live.move(63, live.vertices[63] + [0.0, 0.0, 0.5])
>>> frame = live.relax(seconds=5.0)
>>> bool(np.allclose(frame.vertices[63], [7.0, 7.0, 0.5 + 0.05 * 3.5 ** 2 + 0.03 * 3.5 ** 2]))
True
>>> frame.settled, frame.delta_f_max < 1e-6, frame.delta_p_max < 1e-6
(True, True, True)
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..errors import DesignError
from ..mesh import QuadGrid, QuadMesh, as_quadmesh
from .params import OptimizeParams
from .solver import LevenbergMarquardt

LIVE_ITERATIONS = 100_000
"""The solver's iteration limit in a live session (its count restarts at every anchor move)."""

STALL_STEPS, STALL_GAIN = 30, 0.01
"""At the smallest regularisation, a relaxation whose worst target ratio improves by less than ``STALL_GAIN``
(relative) over ``STALL_STEPS`` steps stops as ``"stalled"`` (measured on the Fig. 23 Enneper example with an
anchor lifted by 1 m: max δ_f crept from 1.8457e-7 to 1.8386e-7 over 900 steps against its target 1e-7)."""


@dataclass(frozen=True)
class LiveFrame:
    """The state after one :meth:`LiveRelaxation.relax`: ``vertices (N, 3)`` in the mesh's units (anchors exactly
    where they were put), max δ_f and max δ_P (§3.3) of the faces and the selected polylines, the solver steps
    taken in this call, whether the relaxation has stopped (:attr:`LiveRelaxation.stopped`: targets met,
    stationary, stalled or stuck; no step is taken until an anchor moves), the regularisation factor reached and the wall time of the call (s)."""

    vertices: np.ndarray
    delta_f_max: float
    delta_p_max: float
    steps: int
    settled: bool
    reg: float
    seconds: float
    reason: str = ""          # why it stopped: "targets", "stationary", "stalled" or "stuck" ("" while relaxing)


class LiveRelaxation:
    """A mesh relaxing towards planar faces and planar polylines (P: ``families = "rows"``/``"cols"``, PP:
    ``"both"``) while anchors are moved.

    Parameters
    ----------
    mesh : :class:`QuadMesh` or :class:`QuadGrid` (its vertex order: :meth:`QuadGrid.to_quadmesh`)
    params : the design's ``[optimize]`` (:class:`OptimizeParams` or its dict); its families, weights, targets and
        ``reg_decay`` are used; closeness is always to the input's vertices and fairness relative to the input
    anchors : indices of the vertices the designer holds and moves, held where they are (added to
        ``params.anchors``, whose vertices are held at their points)
    weight_close : λ_close of the closeness to the input (higher: the mesh stays nearer its input around the
        anchors; lower: a dragged anchor moves more of the mesh)
    """

    def __init__(self, mesh: QuadMesh | QuadGrid, params: OptimizeParams | dict | None = None,
                 anchors: Sequence[int] = (), weight_close: float | None = None):
        from . import _params, build_problem, solver_control

        p = _params(params, {})
        qm = as_quadmesh(mesh)
        v_in = np.asarray(qm.vertices, dtype=float)
        held = {int(a[0]): [float(x) for x in a[1:4]] for a in p.anchors}
        for a in anchors:
            if not 0 <= int(a) < len(v_in):
                raise DesignError("anchors", f"vertex {int(a)} does not exist: the mesh has {len(v_in)} vertices "
                                             f"(0 to {len(v_in) - 1})")
            held.setdefault(int(a), v_in[int(a)].tolist())
        self.anchors = tuple(sorted(held))
        # support normals projected out unless the design says otherwise: as sparse as the mesh, the cheapest step
        solver = "projected" if p.plane_solver == "auto" else p.plane_solver
        p = dataclasses.replace(p, anchors=[[i, *held[i]] for i in self.anchors],
                                closeness="vertices", fairness="relative", plane_solver=solver,
                                max_iterations=LIVE_ITERATIONS,
                                weight_close=p.weight_close if weight_close is None else float(weight_close))
        self.params = p
        self.problem = prob = build_problem(qm, p)
        self.control = solver_control(p, LIVE_ITERATIONS)
        self.solver = LevenbergMarquardt(prob.residuals, prob.z0, prob.metrics, prob.guard, self.control,
                                         prob.on_stage)
        self.stopped = "targets" if self.solver.targets_met() else ""
        self._watch: tuple[int, float] | None = None        # (steps, score) when the stall watch began
        self._steps = 0

    @property
    def vertices(self) -> np.ndarray:
        """``(N, 3)`` current vertices in the mesh's units (anchors and other fixed vertices exactly as held)."""
        return self.problem.to_mesh_units(self.solver.vertices)

    def anchor_points(self) -> list[list[float]]:
        """The anchors as ``[vertex, x, y, z]`` (mesh units): the value of ``[optimize] anchors`` that makes
        :func:`~ppfab.optimize.optimize` hold them where they are now."""
        return [[i, *map(float, self.problem.held[i])] for i in self.anchors]

    def move(self, anchor: int, position: Sequence[float] | np.ndarray) -> None:
        """Put ``anchor`` at ``position (3,)`` (mesh units) and restart the continuation at the full
        regularisation: the mesh follows on the next :meth:`relax`."""
        if int(anchor) not in self.anchors:
            raise DesignError("anchors", f"vertex {int(anchor)} is not an anchor; anchors are "
                                         f"{', '.join(map(str, self.anchors)) or 'none'}")
        x = np.asarray(position, dtype=float).reshape(3)
        if not np.isfinite(x).all():
            raise DesignError("anchors", f"anchor {int(anchor)}: position {x.tolist()} is not a point")
        prob, lm = self.problem, self.solver
        prob.held[int(anchor)] = x
        z = lm.z.copy()
        z[3 * int(anchor): 3 * int(anchor) + 3] = (x - prob.center) / prob.scale
        lm.restart(z)
        self.stopped, self._watch = "", None

    def relax(self, seconds: float = 0.1, max_steps: int = 50) -> LiveFrame:
        """Take solver steps for about ``seconds`` (at least one while not settled, at most ``max_steps``)."""
        t0 = time.perf_counter()
        lm = self.solver
        steps = 0
        while not self.stopped and steps < max_steps:
            reason = lm.step()
            steps += 1
            if reason in ("targets", "stationary", "stuck"):
                self.stopped = reason
            elif reason == "max_iterations":
                lm.iteration = 0
            self._steps += 1
            if not self.stopped and self._stalled():
                self.stopped = "stalled"
            if time.perf_counter() - t0 >= seconds:
                break
        dfm, _, dpm, _ = lm.current_metrics
        return LiveFrame(self.vertices, dfm, dpm, steps, bool(self.stopped), lm.reg, time.perf_counter() - t0,
                         self.stopped)

    def _stalled(self) -> bool:
        """Whether the relaxation has stopped improving at the smallest regularisation (:data:`STALL_STEPS`)."""
        lm = self.solver
        if lm.reg > self.control.reg_min * (1.0 + 1e-9):
            return False
        score = lm.score()
        if self._watch is None or score < (1.0 - STALL_GAIN) * self._watch[1]:
            self._watch = (self._steps, score)
            return False
        return self._steps - self._watch[0] >= STALL_STEPS
