"""Panel sizes of the sections net held to the spacing by re-seeding (ppfab.surface.balance), and the honest
report of what re-seeding cannot do: a strip whose conjugate curves fan apart keeps its range (no T-junctions
in a quad net)."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import shared_file
from surface_cases import resample_quad_mesh


def test_each_strip_straddles_the_spacing():
    """Random dense edge lengths on 5 lanes: between consecutive positions the strip widths (summed here from
    the lengths, fractional ends interpolated) have min·max = spacing² on every complete strip."""
    from ppfab.surface.balance import strip_positions

    rng = np.random.default_rng(4)
    L = rng.uniform(50.0, 400.0, size=(80, 5))
    t = strip_positions(L, np.ones(L.shape, dtype=bool), 37.5, 1500.0)
    assert 37.5 in t.tolist() and np.all(np.diff(t) > 0) and t[0] >= 0 and t[-1] <= 80
    C = np.vstack([np.zeros(5), np.cumsum(L, axis=0)])
    width = np.stack([np.interp(t, np.arange(81), C[:, k]) for k in range(5)], axis=1)
    w = np.diff(width, axis=0)                                   # (strips, lanes)
    assert np.sqrt(w.min(axis=1) * w.max(axis=1)) == pytest.approx(1500.0, rel=1e-9)
    # what is left at either end is less than a strip
    for end in (0, 80):
        rest = np.abs(C[end] - np.array([np.interp(t[0 if end == 0 else -1], np.arange(81), C[:, k])
                                         for k in range(5)]))
        assert np.sqrt(rest.min() * rest.max()) < 1500.0


def test_lanes_outside_the_outline_do_not_count():
    from ppfab.surface.balance import strip_positions

    L = np.full((40, 2), 100.0)
    L[:, 1] = 1000.0                                             # a lane of long edges, outside the outline
    ins = np.ones(L.shape, dtype=bool)
    ins[:, 1] = False
    t = strip_positions(L, ins, 20.0, 1500.0)
    assert np.diff(t) == pytest.approx(15.0)                     # 15 edges of 100 mm on the inside lane


@pytest.fixture(scope="module")
def shell_patch(tmp_path_factory):
    """A 10 m patch of the botanic-garden bubble (WWmore/DOS), resampled into a triangle mesh (m)."""
    from fabrication.surfacefile import read_surface

    mesh = resample_quad_mesh(shared_file("DOS__botanic-garden-bubble-0.obj"), 1500, 3, crop=(0.0, -3.0, 5.0))
    out = tmp_path_factory.mktemp("patch") / "patch.ply"
    mesh.export(out)
    return read_surface(out, units="m").samples


def _section_edges_by_strip(net) -> dict[int, np.ndarray]:
    """Edges along the rows of the kept faces, grouped by strip, measured from the mesh's own vertices and
    their (row, column) of the full grid."""
    v = np.asarray(net.mesh.vertices).reshape(-1, 3)
    key = {(int(i), int(j)): k for k, (i, j) in enumerate(zip(net.row_of_vertex, net.col_of_vertex))}
    out: dict[int, list[float]] = {}
    for i, j in np.argwhere(net.grid_faces):
        for r in (i, i + 1):
            out.setdefault(int(j), []).append(float(np.linalg.norm(v[key[(r, j + 1)]] - v[key[(r, j)]])))
    return {j: np.array(e) for j, e in out.items()}


def test_strip_seeding_narrows_a_fanning_net(shell_patch):
    """On the real shell patch the uniform seeds leave an edge at 0.08 × spacing where conjugate curves
    converge; seeds chosen strip by strip make the worst edge at least 1.5 times nearer the spacing."""
    from ppfab.surface.heightfield import fit_height_field
    from ppfab.surface.plan import plan_frame
    from ppfab.surface.sections import sections_net

    fr = plan_frame(shell_patch.points)
    hf = fit_height_field(fr.to_local(shell_patch.points), 1500.0 / 8, 1500.0)
    loops = [fr.to_local(b)[:, :2] for b in shell_patch.boundary]
    worst = {}
    for bal in (False, True):
        net = sections_net(hf, fr, loops, 1500.0, 0.25, balance=bal)
        e = np.concatenate(list(_section_edges_by_strip(net).values())) / 1500.0
        worst[bal] = float(np.abs(np.log(e)).max())
    assert worst[False] > np.log(1 / 0.1) and worst[True] < worst[False] - np.log(1.5)


def test_remesh_reports_the_fan_out_it_could_not_remove(shell_patch):
    from ppfab.surface import SurfaceSpec, remesh

    r = remesh(shell_patch, SurfaceSpec(path="patch.ply", spacing=1500.0))
    strips = _section_edges_by_strip(r.net)
    fan = max(float(e.max() / e.min()) for e in strips.values())
    assert r.fan_out == pytest.approx(fan, rel=1e-9)
    assert r.panel_size_max / r.panel_size_min >= r.fan_out - 1e-9
    assert r.summary()["seeding"] in ("uniform", "scaled", "strips")
