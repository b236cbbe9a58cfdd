"""The studio's live-optimisation controls (viser): a *live* switch, the anchors, the closeness weight, one
gizmo per anchor and the thread that relaxes the mesh while the designer drags (:class:`.live.LiveSession`).

The thread takes the studio's lock for each frame: it applies the anchors' latest positions, relaxes for about
:data:`FRAME_SECONDS`, shows the mesh (figures without the support structure while it moves, with it once it
settles) and sleeps while the mesh is settled and nothing is dragged.  A drag's end records the anchors in
``[optimize] anchors`` (one undo step); undo and redo start the session again from the design they restore.
"""

from __future__ import annotations

import json
import logging
import threading
import time
from typing import TYPE_CHECKING, Any

import numpy as np

from .live import LiveSession, corner_cells, parse_cells

if TYPE_CHECKING:
    from .app import Studio

log = logging.getLogger("ppfab")

FRAME_SECONDS = 0.03
"""Solver time per live frame: shorter than one Levenberg–Marquardt step at 31 × 31 vertices (45–60 ms), so a
frame is one step and the redraw (about 17 ms): 8–9 updates per second while an anchor is dragged
(``benchmarks/live.py``)."""


PAUSE_SECONDS = 0.015
"""Pause of the live thread after each frame, for the server's event loop (see :meth:`LivePanel._run`)."""

IDLE_SECONDS = 0.03
"""Pause of the live thread while the mesh is settled and no anchor moves."""


class LivePanel:
    """The controls and the live thread of one studio (see the module docstring)."""

    def __init__(self, studio: "Studio"):
        gui: Any = studio.server.gui
        self.studio = studio
        model = studio.model
        shape = model.state.raw.vertices.shape[:2]
        weight = float(model.doc.get("optimize", {}).get("weight_close", 0.01))
        self.session: LiveSession | None = None
        self.gizmos: dict[str, Any] = {}
        self._stop = threading.Event()
        self.thread: threading.Thread | None = None
        self.toggle = gui.add_checkbox("live: drag anchors", False,
                                       hint="relax the mesh towards the [optimize] targets while anchors are dragged")
        self.cells = gui.add_text("anchors [row, column]", json.dumps([list(c) for c in corner_cells(shape)]),
                                  hint="vertices held by gizmos, as [[row, column], ...] of the mesh grid")
        self.weight = gui.add_number("closeness weight", weight, min=0.0, step=0.001,
                                     hint="λ_close of the live relaxation: higher keeps more of the mesh in place")
        self.message = gui.add_markdown("")
        self.toggle.on_update(lambda _: studio._guard(self._switch))
        self.cells.on_update(lambda _: studio._guard(self.restart, field=""))
        self.weight.on_update(lambda _: studio._guard(self.restart, field=""))

    @property
    def on(self) -> bool:
        return bool(self.toggle.value)

    def _switch(self) -> None:
        if self.on:
            self.restart()
        else:
            self.stop()
            self.message.content = "live: off"

    def restart(self) -> None:
        """(Re)start the session from the model's design with the anchors and weight now in the controls."""
        if not self.on:
            return
        self.stop()
        model = self.studio.model
        shape = model.state.raw.vertices.shape[:2]
        weight = float(self.weight.value)
        if not np.isfinite(weight) or weight < 0:
            raise ValueError(f"closeness weight {weight} is not a weight; type 0 or more")
        self.session = LiveSession(model.doc, model.base_dir, parse_cells(str(self.cells.value), shape), weight)
        self._draw_gizmos()
        self._stop = threading.Event()
        self.thread = threading.Thread(target=self._run, args=(self.session, self._stop), name="ppfab-studio-live",
                                       daemon=True)
        self.thread.start()

    def stop(self, join: bool = False) -> None:
        """Stop the session: its thread ends at its next frame.  ``join`` waits for it (only from a caller that
        does not hold the studio's lock, which the thread may be waiting for: the studio's own stop)."""
        self._stop.set()
        if join and self.thread is not None:
            self.thread.join(10.0)
        self.thread = None
        for g in self.gizmos.values():
            g.remove()
        self.gizmos = {}
        self.session = None

    def _draw_gizmos(self) -> None:
        scene: Any = self.studio.server.scene
        session = self.session
        assert session is not None
        v = self.studio.model.state.placed.vertices.reshape(-1, 3) / 1000.0
        size = 0.06 * float(np.linalg.norm(v.max(0) - v.min(0)))
        self.studio.handle_scale = size
        for key, position in session.positions().items():
            g = scene.add_transform_controls(f"/live/{key}", scale=size, position=tuple(position),
                                             disable_rotations=True, disable_sliders=True)
            g.on_update(self._gizmo_callback(key))
            self.gizmos[key] = g
            self.gizmos[f"{key}-label"] = scene.add_label(f"/live/{key}-label", f"anchor {key[1:].replace('_', ', ')}",
                                                          position=tuple(position))

    def _gizmo_callback(self, key: str) -> Any:
        async def on_gizmo(event: Any) -> None:
            session = self.session
            if session is None:
                return
            session.request(key, np.asarray(event.target.position, dtype=float))
            label = self.gizmos.get(f"{key}-label")
            if label is not None:
                label.position = tuple(event.target.position)
            if getattr(event, "phase", "update") == "end":
                self.studio._guard(lambda: self._record(session))
        return on_gizmo

    def _record(self, session: LiveSession) -> None:
        """A drag ended: its anchors go into the design (one undo step) with the mesh as it is now."""
        self.studio.model.set_anchors(session.anchor_points(), session.raw.with_vertices(
            session.relaxation.vertices.reshape(session.raw.vertices.shape)), session.families)

    def _run(self, session: LiveSession, stop: threading.Event) -> None:
        studio = self.studio
        while not stop.is_set():
            with studio.lock:
                if stop.is_set() or session is not self.session:
                    return
                try:
                    mesh = session.tick(FRAME_SECONDS)
                    if mesh is not None:
                        studio.model.adopt(mesh, session.families, support=session.settled)
                        studio.redraw(handles=False)
                    self.message.content = session.line()
                except Exception as exc:             # shown, never a traceback; the session stops
                    log.info("studio live: %s", exc, exc_info=True)
                    self.message.content = f"**live stopped:** {exc}"
                    return
            # outside the lock, a pause for the server's event loop: the factorisation holds Python's GIL for
            # tens of ms, and without a pause every socket call of the event loop waits for the next one (a
            # 30-move drag sent at 30 Hz took 6.6 s to arrive; with the pause see benchmarks/live.py)
            time.sleep(IDLE_SECONDS if mesh is None else PAUSE_SECONDS)

    def snapshot(self) -> dict:
        """For tests: the anchors' display positions, updates per second, frames so far, settled or not."""
        s = self.session
        if s is None:
            return {"on": False}
        return {"on": True, "anchors": s.positions(), "rate": s.rate(), "frames": len(s.frames),
                "settled": s.settled, "line": s.line()}
