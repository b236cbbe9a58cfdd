"""Live optimisation in the studio, free of any user interface: anchors a designer drags while the mesh of a
mesh-file design relaxes towards P or PP (:class:`ppfab.optimize.live.LiveRelaxation`, the energies of §3.3).

:class:`LiveSession` starts from the design's mesh as read (its ``[optimize]`` and the anchors it already
records), takes the anchors as grid cells ``(row, column)`` of vertices, and is driven by two calls: :meth:`
LiveSession.request` (from a gizmo's callback: where an anchor is dragged to, display metres) and :meth:`
LiveSession.tick` (from the studio's live thread: apply the latest requests, relax for a time budget, hand back
the mesh to show).  :meth:`LiveSession.anchor_points` is the ``[optimize] anchors`` value that records the drag.
"""

from __future__ import annotations

import json
import threading
import time
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .handles import placement


@dataclass(frozen=True)
class LiveAnchor:
    """An anchor: its key (``"a<row>_<column>"``), grid cell and vertex index (row-major)."""

    key: str
    row: int
    col: int
    vertex: int


def corner_cells(shape: tuple[int, int]) -> list[tuple[int, int]]:
    """The four corner vertices ``(row, column)`` of a grid of ``shape = (rows, columns)`` vertices."""
    m, n = shape
    return [(0, 0), (0, n - 1), (m - 1, 0), (m - 1, n - 1)]


def parse_cells(text: str, shape: tuple[int, int]) -> list[tuple[int, int]]:
    """Anchors typed as JSON ``[[row, column], …]``; a one-line :class:`ValueError` says what is wrong."""
    m, n = shape
    try:
        value = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ValueError(f"anchors: not JSON ({exc.msg}); give [[row, column], ...] such as [[0, 0], [{m - 1}, "
                         f"{n - 1}]]") from None
    if not isinstance(value, list) or not all(isinstance(c, list) and len(c) == 2 and all(
            isinstance(x, int) and not isinstance(x, bool) for x in c) for c in value):
        raise ValueError("anchors: give a list of [row, column] pairs of whole numbers, such as [[0, 0], [3, 4]]")
    cells = []
    for r, c in value:
        if not (0 <= r < m and 0 <= c < n):
            raise ValueError(f"anchors: vertex [{r}, {c}] is not on the mesh (rows 0 to {m - 1}, columns 0 to "
                             f"{n - 1})")
        if (r, c) not in cells:
            cells.append((r, c))
    return cells


class LiveSession:
    """A live relaxation of ``doc``'s mesh (see the module docstring).

    Parameters
    ----------
    doc : the design document (a mesh-file design with ``[optimize]``)
    base_dir : the folder its relative mesh path is taken from
    cells : anchors ``(row, column)``; the anchors ``doc`` records in ``[optimize] anchors`` are added
    weight_close : λ_close of the relaxation (``None``: the design's ``weight_close``)
    """

    def __init__(self, doc: dict, base_dir: Path, cells: list[tuple[int, int]], weight_close: float | None = None):
        from ppfab.optimize.live import LiveRelaxation
        from ppfab.optimize.params import OptimizeParams
        from ppfab.schema import parse_params
        from ppfab.topology import families_of

        from .model import solve

        self.raw = solve(doc, base_dir).raw                  # the design's mesh as read: closeness is to it
        params = parse_params(OptimizeParams, dict(doc.get("optimize", {})), "optimize")
        self.families = tuple(families_of(params.families))
        m, n = self.raw.vertices.shape[:2]
        recorded = [(int(a[0]) // n, int(a[0]) % n) for a in params.anchors]
        self.anchors = tuple(LiveAnchor(f"a{r}_{c}", r, c, r * n + c) for r, c in dict.fromkeys([*recorded, *cells]))
        self.relaxation = LiveRelaxation(self.raw, params, [a.vertex for a in self.anchors], weight_close)
        self.scale, self.R, self.t = placement(doc.get("geometry", {}))
        self._lock = threading.Lock()
        self._pending: dict[int, np.ndarray] = {}
        self.frames: deque[tuple[float, Any]] = deque(maxlen=200)     # (time.monotonic(), LiveFrame)

    # -- coordinates: display metres <-> mesh units ---------------------------------------------------
    def to_display(self, point: np.ndarray) -> np.ndarray:
        return (self.scale * self.R @ np.asarray(point, dtype=float) + self.t) / 1000.0

    def from_display(self, point: np.ndarray) -> np.ndarray:
        return self.R.T @ ((np.asarray(point, dtype=float) * 1000.0 - self.t) / self.scale)

    def positions(self) -> dict[str, np.ndarray]:
        """Every anchor's position in display metres, by key."""
        v = self.relaxation.vertices
        return {a.key: self.to_display(v[a.vertex]) for a in self.anchors}

    # -- driving ----------------------------------------------------------------------------------------
    def request(self, key: str, display_position: Any) -> None:
        """Ask for anchor ``key`` at ``display_position (3,)`` (applied by the next :meth:`tick`; thread-safe)."""
        anchor = next((a for a in self.anchors if a.key == key), None)
        if anchor is None:
            raise ValueError(f"no live anchor {key}")
        point = self.from_display(np.asarray(display_position, dtype=float))
        with self._lock:
            self._pending[anchor.vertex] = point

    def tick(self, seconds: float = 0.08) -> Any:
        """Apply the requested anchor moves, relax for about ``seconds``; the mesh to show (a
        :class:`~ppfab.mesh.QuadGrid` in mesh units), or ``None`` when nothing changed (settled, no request)."""
        with self._lock:
            pending, self._pending = self._pending, {}
        for vertex, point in pending.items():
            self.relaxation.move(vertex, point)
        if self.relaxation.stopped and not pending:
            return None
        frame = self.relaxation.relax(seconds)
        self.frames.append((time.monotonic(), frame))
        return self.raw.with_vertices(frame.vertices.reshape(self.raw.vertices.shape))

    @property
    def settled(self) -> bool:
        return bool(self.relaxation.stopped)

    def anchor_points(self) -> list[list[float]]:
        """``[optimize] anchors`` for the anchors where they are now or are asked to be by a :meth:`request` not
        yet applied (``[vertex, x, y, z]``, mesh units): a drag's last move is recorded, not the one before."""
        with self._lock:
            pending = dict(self._pending)
        out = []
        for point in self.relaxation.anchor_points():
            vertex = int(point[0])
            out.append([vertex, *map(float, pending[vertex])] if vertex in pending else point)
        return out

    def rate(self, window: float = 2.0) -> float:
        """Updates per second over the last ``window`` seconds of frames (0 with fewer than two)."""
        now = time.monotonic()
        times = [t for t, _ in self.frames if now - t <= window]
        return (len(times) - 1) / (times[-1] - times[0]) if len(times) >= 2 and times[-1] > times[0] else 0.0

    def line(self) -> str:
        """One line for the panel: updates per second, max δ_f and δ_P now, settled or not."""
        if not self.frames:
            return f"live: {len(self.anchors)} anchors; drag one"
        frame = self.frames[-1][1]
        figures = f"max δ_f {frame.delta_f_max:.1e} · max δ_P {frame.delta_p_max:.1e}"
        if not self.settled:
            return f"live: relaxing (s = {frame.reg:.0e}), {self.rate():.1f} updates/s · {figures}"
        met = "targets met" if frame.reason == "targets" else f"{frame.reason}, targets not met"
        return f"live: settled ({met}) · {figures}"
