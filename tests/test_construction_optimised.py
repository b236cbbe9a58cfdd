"""A construction's mesh optimised by the design's ``[optimize]`` (it used to be ignored without a word): the
paper's Fig. 23 in its hard form, a PP translational vault — conjugate, not a curvature-line net — made conical
while it stays PP (examples/fig23_translational_pp_to_conical.toml).

Checked with formulas written here, not ppfab's metrics: the angle balance of a conical node
(α₁ + α₃ = α₂ + α₄, the four face angles at an interior vertex, §2.3) and each polyline's distance to its
least-squares plane (the smallest singular value direction of its centred points)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fabrication.design import load_design
from ppfab.geometry import build_geometry

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "fig23_translational_pp_to_conical.toml"


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The angle between vectors ``a`` and ``b`` (…, 3), radians."""
    c = np.einsum("...k,...k->...", a, b) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
    return np.arccos(np.clip(c, -1.0, 1.0))


def angle_balance(v: np.ndarray) -> np.ndarray:
    """``|α₁ − α₂ + α₃ − α₄|`` at every interior vertex of a grid ``v (m, n, 3)``: the four angles between
    consecutive edges around the vertex, in turn (0 at a conical node)."""
    c = v[1:-1, 1:-1]
    e = [v[2:, 1:-1] - c, v[1:-1, 2:] - c, v[:-2, 1:-1] - c, v[1:-1, :-2] - c]
    a = [_angle(e[k], e[(k + 1) % 4]) for k in range(4)]
    return np.abs(a[0] - a[1] + a[2] - a[3])


def off_plane(points: np.ndarray) -> float:
    """The largest distance of ``points (k, 3)`` from their least-squares plane."""
    centred = points - points.mean(axis=0)
    normal = np.linalg.svd(centred)[2][2]
    return float(np.abs(centred @ normal).max())


def test_a_pp_construction_is_made_conical_and_stays_pp():
    design = load_design(EXAMPLE)
    plain = build_geometry(design.geometry)                              # no [optimize]: the construction
    made = build_geometry(design.geometry, design.optimize)
    assert plain.optimize_result is None and made.optimize_result is not None
    before, after = plain.mesh.vertices, made.mesh.vertices              # placed in mm
    assert angle_balance(before).max() > 0.5                             # far from conical: 0.89 rad measured
    assert angle_balance(after).max() < 1e-5
    lines = [after[i] for i in range(after.shape[0])] + [after[:, j] for j in range(after.shape[1])]
    assert max(off_plane(line) for line in lines) < 1e-3                # mm, on a 30 m vault: still PP
    diagonal = np.linalg.norm(before.reshape(-1, 3).max(axis=0) - before.reshape(-1, 3).min(axis=0))
    moved = np.linalg.norm(after - before, axis=-1)
    # the shape has to change (a translational net is not principal), but stays the same vault
    assert 1e-3 * diagonal < moved.mean() < 2e-2 * diagonal
    assert made.planar_families == ("rows", "cols")


def test_an_optimisation_that_stops_short_says_whether_it_matters_and_which_keys_change_it(caplog):
    """Two iterations cannot make the translational net conical: the warning gives the residual, says the build
    goes on and which checks judge the result, and names the keys that change it."""
    from dataclasses import replace

    design = load_design(EXAMPLE)
    with caplog.at_level("WARNING", logger="ppfab"):
        g = build_geometry(design.geometry, replace(design.optimize, max_iterations=2))
    assert g.optimize_result is not None and not g.optimize_result.targets_met
    said = [r.getMessage() for r in caplog.records if "did not meet its targets" in r.getMessage()]
    assert len(said) == 1
    for key in ("panels.planarity_tolerance", "beams.max_torsion_mm", "optimize.max_iterations",
                "optimize.target_delta_f", "targets NOT met"):
        assert key in said[0], key
