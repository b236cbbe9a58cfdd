"""Live relaxation with anchors (``ppfab.optimize.live``): the studio's drag-a-vertex optimisation.

Checked on a real 31 × 31 mesh (``DOS__enneper2.obj``: WWmore/DOS, objs/obj_anet/enneper2.obj) and a real mesh far
from planar (``DOS__heart.obj``).  Planarity is measured here by SVD plane fits (not ``ppfab.metrics``): the
largest distance of a face's or a polyline's vertices from their least-squares plane over its bounding-box
diagonal (δ_f, δ_P of §3.3).
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import shared_file
from ppfab.errors import DesignError
from ppfab.io import load_mesh
from ppfab.optimize import optimize
from ppfab.optimize.live import LiveRelaxation


def _grid(name: str):
    mesh = load_mesh(shared_file(name))
    assert mesh.grid is not None, f"{name} is read as a regular grid"
    return mesh.grid


def _flatness(points: np.ndarray) -> float:
    c = points - points.mean(0)
    normal = np.linalg.svd(c, full_matrices=False)[2][-1]
    return float(np.abs(c @ normal).max() / np.linalg.norm(points.max(0) - points.min(0)))


def _delta_f(v: np.ndarray) -> float:
    quads = np.stack([v[:-1, :-1], v[:-1, 1:], v[1:, 1:], v[1:, :-1]], axis=2).reshape(-1, 4, 3)
    return max(_flatness(q) for q in quads)


def _delta_p(v: np.ndarray, families: str) -> float:
    lines = ([*v] if families in ("rows", "both") else []) + ([*np.swapaxes(v, 0, 1)] if families in ("cols", "both")
                                                            else [])
    return max(_flatness(line) for line in lines)


def test_a_dragged_anchor_is_held_exactly_and_the_mesh_settles_pp_around_it():
    grid = _grid("DOS__enneper2.obj")
    m, n = grid.vertices.shape[:2]
    centre, corners = (m // 2) * n + n // 2, [0, n - 1, (m - 1) * n, m * n - 1]
    live = LiveRelaxation(grid, {"families": "both"}, anchors=corners + [centre])
    start = live.vertices.copy()
    size = float(np.linalg.norm(start.max(0) - start.min(0)))
    target = start[centre] + [0.0, 0.0, 0.05 * size]
    for k in range(1, 6):                                       # a drag: five moves, a frame after each
        live.move(centre, start[centre] + k / 5 * (target - start[centre]))
        frame = live.relax(seconds=0.05)
        assert frame.steps >= 1
    frame = live.relax(seconds=120.0, max_steps=2000)          # let go
    assert frame.settled
    v = frame.vertices
    assert np.array_equal(v[centre], target)                   # held exactly where it was put
    assert np.array_equal(v[corners], start[corners])
    g = v.reshape(m, n, 3)
    assert _delta_f(g) <= 1e-6 and _delta_p(g, "both") <= 1e-6
    assert np.linalg.norm(v[centre + n] - start[centre + n]) > 0.01 * size     # the neighbourhood followed


def test_a_higher_closeness_weight_keeps_the_mesh_nearer_its_input_away_from_the_anchor():
    grid = _grid("DOS__enneper2.obj")
    m, n = grid.vertices.shape[:2]
    anchor = (m // 2) * n + n // 2
    moved = {}
    for weight in (0.01, 1.0):
        def equilibrium(lift: float) -> np.ndarray:             # no continuation: the regularised equilibrium
            live = LiveRelaxation(grid, {"families": "rows", "reg_decay": 1.0}, anchors=[anchor], weight_close=weight)
            v0 = live.vertices
            live.move(anchor, v0[anchor] + [0.0, 0.0, lift])
            frame = live.relax(seconds=120.0, max_steps=2000)
            assert frame.settled and frame.reg == 1.0
            return frame.vertices
        v = grid.vertices.reshape(-1, 3)
        size = float(np.linalg.norm(v.max(0) - v.min(0)))
        far = np.linalg.norm(v - v[anchor], axis=1) > 0.25 * size
        moved[weight] = float(np.linalg.norm(equilibrium(0.05 * size) - equilibrium(0.0), axis=1)[far].mean())
    assert moved[1.0] < 0.5 * moved[0.01], moved


def test_the_build_optimiser_holds_the_anchors_the_live_session_hands_over():
    grid = _grid("DOS__enneper2.obj")
    m, n = grid.vertices.shape[:2]
    anchor = (m // 3) * n + n // 3
    live = LiveRelaxation(grid, {"families": "rows"}, anchors=[anchor])
    v0 = live.vertices
    live.move(anchor, v0[anchor] + [0.0, 0.0, 0.03 * float(np.linalg.norm(v0.max(0) - v0.min(0)))])
    points = live.anchor_points()
    assert points[0][0] == anchor
    result = optimize(grid, {"families": "rows", "anchors": points})
    v = result.mesh.vertices.reshape(-1, 3)
    assert np.array_equal(v[anchor], np.asarray(points[0][1:]))
    assert result.targets_met, result.message
    assert _delta_f(result.mesh.vertices) <= 1e-6 and _delta_p(result.mesh.vertices, "rows") <= 1e-6


@pytest.mark.parametrize("anchors, key", [([[5000, 0.0, 0.0, 0.0]], "optimize.anchors[0]"),
                                          ([[3, 0.0, 0.0]], "optimize.anchors[0]"),
                                          ([[2.5, 0.0, 0.0, 0.0]], "optimize.anchors[0]"),
                                          ([[3, 0.0, 0.0, 1.0], [3, 1.0, 0.0, 0.0]], "optimize.anchors[1]")])
def test_bad_anchors_are_named(anchors, key):
    grid = _grid("DOS__heart.obj")
    with pytest.raises(DesignError) as err:
        optimize(grid, {"families": "rows", "anchors": anchors, "max_iterations": 1})
    assert err.value.key == key


def test_moving_a_vertex_that_is_not_an_anchor_is_refused():
    live = LiveRelaxation(_grid("DOS__heart.obj"), {"families": "rows"}, anchors=[0])
    with pytest.raises(DesignError, match="vertex 5 is not an anchor"):
        live.move(5, [0.0, 0.0, 0.0])
    with pytest.raises(DesignError, match="does not exist"):
        LiveRelaxation(_grid("DOS__heart.obj"), {"families": "rows"}, anchors=[10 ** 6])
