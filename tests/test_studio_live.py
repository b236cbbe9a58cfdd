"""The studio's live optimisation without a browser: a running studio (viser server on a free loopback port) on
the Fig. 23 example (the real mesh ``DOS__enneper2.obj``, WWmore/DOS, 31 × 31 vertices), its live switch on,
anchors dragged through the same calls a gizmo makes.  Planarity is measured by SVD plane fits here."""

from __future__ import annotations

import socket
import time

import numpy as np
import pytest

from conftest import REPO, wait_for

pytest.importorskip("viser", reason="the studio extra is not installed (pip install '.[studio]')")

from fabrication.studio.app import Studio  # noqa: E402
from fabrication.studio.live import parse_cells  # noqa: E402
from fabrication.studio.model import StudioModel  # noqa: E402

ENNEPER = REPO / "examples" / "fig23_enneper_pp_to_conical.toml"


def _flatness(points: np.ndarray) -> float:
    c = points - points.mean(0)
    return float(np.abs(c @ np.linalg.svd(c, full_matrices=False)[2][-1]).max()
                 / np.linalg.norm(points.max(0) - points.min(0)))


@pytest.fixture
def studio():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    server = Studio(StudioModel.load(ENNEPER), port=port)
    yield server
    server.stop()


class _Event:
    """What a transform gizmo's callback receives: the target's position and the drag's phase."""

    def __init__(self, position, phase: str):
        self.target = type("Target", (), {"position": tuple(position)})()
        self.phase = phase


def _drag(studio: Studio, key: str, lift: float, steps: int = 6, pause: float = 0.1) -> None:
    import asyncio

    panel = studio.live
    start = np.asarray(panel.snapshot()["anchors"][key])
    callback = panel._gizmo_callback(key)
    for k in range(1, steps + 1):
        phase = "end" if k == steps else "update"
        asyncio.run(callback(_Event(start + [0.0, 0.0, lift * k / steps], phase)))
        time.sleep(pause)


def test_live_anchors_drag_the_mesh_which_settles_pp_and_the_drag_is_one_undo_step(studio):
    panel = studio.live
    assert panel is not None and not panel.on
    before = studio.snapshot()["vertices"].copy()
    panel.cells.value = "[[0, 0], [0, 30], [30, 0], [30, 30], [15, 15]]"
    panel.toggle.value = True
    studio._guard(panel._switch)
    assert studio.model.error == ""
    snap = panel.snapshot()
    assert snap["on"] and set(snap["anchors"]) == {"a0_0", "a0_30", "a30_0", "a30_30", "a15_15"}
    undo_before = len(studio.model.history.undo)
    _drag(studio, "a15_15", 1.0)                                  # one metre up, in six moves
    wait_for(lambda: panel.snapshot()["settled"], 120.0, "the mesh to settle", poll=0.05)
    time.sleep(0.3)                                               # the settled frame shown
    with studio.lock:
        after = studio.snapshot()
    v = after["vertices"]                                          # placed, mm
    assert abs((v[15, 15, 2] - before[15, 15, 2]) - 1000.0) < 1e-6  # the anchor where it was dragged
    assert np.array_equal(v[0, 0], before[0, 0]) and np.array_equal(v[30, 30], before[30, 30])
    assert abs(v[16, 15, 2] - before[16, 15, 2]) > 50.0            # its neighbours followed
    quads = np.stack([v[:-1, :-1], v[:-1, 1:], v[1:, 1:], v[1:, :-1]], axis=2).reshape(-1, 4, 3)
    assert max(_flatness(q) for q in quads) <= 1e-6              # the [optimize] targets (1e-7 δ, + rounding)
    assert max(_flatness(line) for line in [*v, *np.swapaxes(v, 0, 1)]) <= 1e-6
    # the drag is recorded in the design (one undo step); undo takes it back and the session starts again
    recorded = studio.model.doc["optimize"]["anchors"]
    assert len(studio.model.history.undo) == undo_before + 1
    assert [a[0] for a in recorded] == [0, 30, 15 * 31 + 15, 930, 960]
    studio._guard(lambda: studio._history(studio.model.undo))
    assert "anchors" not in studio.model.doc["optimize"]
    wait_for(lambda: panel.snapshot().get("frames", 0) == 0 or panel.snapshot()["settled"], 120.0, "the restart",
             poll=0.05)
    assert np.allclose(panel.snapshot()["anchors"]["a15_15"], before[15, 15] / 1000.0, atol=1e-12)


def test_live_refuses_anchors_off_the_mesh_and_a_negative_weight_in_one_line(studio):
    panel = studio.live
    panel.toggle.value = True
    panel.cells.value = "[[0, 0], [31, 2]]"
    studio._guard(panel._switch)
    assert studio.model.error == "anchors: vertex [31, 2] is not on the mesh (rows 0 to 30, columns 0 to 30)"
    assert "\n" not in studio.model.error
    panel.cells.value = "[[0, 0]]"
    panel.weight.value = -1.0
    studio._guard(panel.restart)
    assert studio.model.error.startswith("closeness weight -1.0 is not a weight")
    with pytest.raises(ValueError, match="not JSON"):
        parse_cells("[[0, 0]", (4, 4))
    with pytest.raises(ValueError, match="pairs of whole numbers"):
        parse_cells("[[0.5, 0]]", (4, 4))
