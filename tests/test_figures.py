"""Figures are deterministic and never read memory they did not write: plates of different vertex counts
(mplot3d pads such lists with uninitialised memory and used to scale its axes by it)."""

from __future__ import annotations

import numpy as np

from fabrication.figures import histogram, mesh_figure, padded_polygons, save


def _scene(seed: int = 0):
    rng = np.random.default_rng(seed)
    quads = rng.uniform(0, 10, size=(6, 4, 3))
    plates = [rng.uniform(-5, 15, size=(k, 3)) for k in (4, 7, 12, 5)]
    return quads, plates


def test_padded_polygons_repeat_the_last_vertex():
    _, plates = _scene()
    out = padded_polygons(plates)
    assert out.shape == (4, 12, 3)
    for k, p in enumerate(plates):
        assert np.array_equal(out[k, :len(p)], p) and np.all(out[k, len(p):] == p[-1])


def test_axis_limits_come_from_the_data_only():
    quads, plates = _scene()
    fig = mesh_figure(quads, plates=plates)
    ax = fig.axes[0]
    pts = np.concatenate([quads.reshape(-1, 3)] + plates)
    lo = pts.min(axis=0)
    assert np.allclose([ax.get_xlim()[0], ax.get_ylim()[0], ax.get_zlim()[0]], lo)
    assert np.allclose(ax.get_xlim()[1] - ax.get_xlim()[0], np.ptp(pts[:, 0]))
    a = save(fig)
    b = save(mesh_figure(quads, plates=plates))
    assert a == b and a[:8] == b"\x89PNG\r\n\x1a\n"


def test_histogram_of_equal_values_draws():
    for values in (np.full(12, 90.0) + np.arange(12) * 1e-13, np.array([3.0]), np.array([])):
        png = save(histogram(values, "t", "x"))
        assert png[:4] == b"\x89PNG"
