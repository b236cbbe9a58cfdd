"""Live optimisation in the studio: how often the shown mesh updates while an anchor is dragged, against
re-running the optimiser from scratch for every drag event (what a tool without a live mode does).

Mesh: the Fig. 23 example (``DOS__enneper2.obj``, WWmore/DOS, 31 × 31 vertices = 30 × 30 faces; PP and conical
targets 1e-7).  Anchors: the four corners and the centre; the centre is dragged up by 1 m in 30 moves at 30
moves per second, as a hand would, through the calls a gizmo makes.

- **live** — a running studio (viser server, no browser attached): its live thread applies the latest anchor
  position, relaxes for ``FRAME_SECONDS`` and redraws the mesh with its figures.  Updates per second = redraws
  during the drag over the drag's wall time; CPU seconds of the whole process for the drag and the settling.
- **from scratch** — :func:`ppfab.optimize.optimize` of the design's mesh with the dragged anchor at each of 5
  positions of the drag (the projected plane solver: the fastest per step at this size), CPU seconds per run:
  one update per finished run is the best such a loop can show.

    OMP_NUM_THREADS=1 python benchmarks/live.py
"""

from __future__ import annotations

import asyncio
import os
import socket
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from fabrication.studio.app import Studio  # noqa: E402
from fabrication.studio.model import StudioModel  # noqa: E402
from ppfab.optimize import optimize  # noqa: E402

EXAMPLE = REPO / "examples" / "fig23_enneper_pp_to_conical.toml"


class _Event:
    def __init__(self, position, phase: str):
        self.target = type("Target", (), {"position": tuple(position)})()
        self.phase = phase


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def live() -> None:
    studio = Studio(StudioModel.load(EXAMPLE), port=_port())
    try:
        panel = studio.live
        panel.cells.value = "[[0, 0], [0, 30], [30, 0], [30, 30], [15, 15]]"
        panel.toggle.value = True
        studio._guard(panel._switch)
        deadline = time.monotonic() + 60
        while not panel.snapshot()["settled"] and time.monotonic() < deadline:
            time.sleep(0.05)
        start = np.asarray(panel.snapshot()["anchors"]["a15_15"])
        callback = panel._gizmo_callback("a15_15")
        redraws0, cpu0, t0 = studio.redraws, time.process_time(), time.monotonic()
        moves = 30
        for k in range(1, moves + 1):
            asyncio.run(callback(_Event(start + [0.0, 0.0, k / moves], "end" if k == moves else "update")))
            time.sleep(1.0 / 30)
        drag_wall, drag_redraws = time.monotonic() - t0, studio.redraws - redraws0
        while not panel.snapshot()["settled"] and time.monotonic() < t0 + 120:
            time.sleep(0.02)
        settle_wall, cpu = time.monotonic() - t0, time.process_time() - cpu0
        line = panel.snapshot()["line"]
        print(f"live       : {drag_redraws} redraws in the {drag_wall:.2f} s drag = {drag_redraws / drag_wall:.1f} "
              f"updates/s; settled {settle_wall - drag_wall:.2f} s after the last move; CPU {cpu:.2f} s for drag "
              f"and settling; {line}")
    finally:
        studio.stop()


def scratch(runs: int = 5) -> None:
    model = StudioModel.load(EXAMPLE)
    params = dict(model.doc["optimize"], plane_solver="projected")
    grid = model.state.raw
    centre = 15 * 31 + 15
    lift = 1000.0 / float(model.doc["geometry"]["scale"])
    cpus = []
    for k in range(1, runs + 1):
        point = grid.vertices.reshape(-1, 3)[centre] + [0.0, 0.0, lift * k / runs]
        anchors = [[v, *map(float, grid.vertices.reshape(-1, 3)[v])] for v in (0, 30, 930, 960)]
        c0 = time.process_time()
        res = optimize(grid, params, anchors=[*anchors, [centre, *map(float, point)]])
        cpus.append(time.process_time() - c0)
    print(f"scratch    : {runs} runs, CPU {min(cpus):.2f}–{max(cpus):.2f} s each (median "
          f"{float(np.median(cpus)):.2f} s) = at most {1 / float(np.median(cpus)):.2f} updates/s; last: "
          f"{res.iterations} iterations, targets met {res.targets_met}")


if __name__ == "__main__":
    print(f"OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', '(unset)')}")
    live()
    scratch()
