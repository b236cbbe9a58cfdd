"""Arc-spline profiles (Remark 4.3): a channel surface whose profile is a chain of circular arcs is made of cone
patches.  Checked here apart from the construction: faces and rows by SVD, the conical property by the vertex
angles, the cone patches by a least-squares common point of each arc's face planes (fitted to the vertices), the
apex in the designed strip by its closed form from the two spheres."""

from __future__ import annotations

import numpy as np
import pytest

from ppfab.constructions import build_construction
from ppfab.constructions.conical_spheres import channel_mesh
from ppfab.errors import DesignError

from test_conical_spheres import WAVY, angle_balance_of

TOL = 1e-9


def quads_of(grid) -> np.ndarray:
    """``(rows − 1, faces, 4, 3)`` corners of every face, the closing column included."""
    v = grid.vertices
    q = np.stack([v[:-1, :-1], v[1:, :-1], v[1:, 1:], v[:-1, 1:]], axis=2)
    if grid.closed:
        wrap = np.stack([v[:-1, -1], v[1:, -1], v[1:, 0], v[:-1, 0]], axis=1)[:, None]
        q = np.concatenate([q, wrap], axis=1)
    return q


def face_planes(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Unit normals ``(…, 3)``, offsets ``n·x`` and the largest corner distance of each face's SVD plane."""
    c = q.mean(axis=-2)
    _, s, vt = np.linalg.svd(q - c[..., None, :])
    n = vt[..., 2, :]
    return n, np.einsum("...i,...i->...", n, c), float(s[..., 2].max())


def common_point(n: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, float]:
    """The least-squares point ``P`` of ``n_i·P = d_i`` and the largest misfit (mm)."""
    p = np.linalg.lstsq(n, d, rcond=None)[0]
    return p, float(np.abs(n @ p - d).max())


def cone_of(z0: np.ndarray, z1: np.ndarray) -> tuple[np.ndarray, float, float]:
    """Axis, cos β and sin β of the cone touching spheres ``(x, y, z, r)`` ``z0``, ``z1`` (oriented contact)."""
    dc = z1[:3] - z0[:3]
    length = np.linalg.norm(dc)
    cosb = -(z1[3] - z0[3]) / length
    return dc / length, cosb, np.sqrt(1 - cosb ** 2)


ARCS_OPEN = [[3.0, -80.0, -30.0], [8.0, -30.0, 20.0], [4.5, 20.0, 80.0]]


def test_arc_spline_faces_are_tangent_planes_of_one_cone_per_arc_in_every_strip():
    params = {"spheres": WAVY.tolist(), "faces_spine": 12, "faces_profile": 16, "profile_arcs": ARCS_OPEN,
              "profile_arcs_centre": [1.5, 0.5]}
    grid = build_construction("conical_spheres", params)
    q = quads_of(grid)
    n, d, flat = face_planes(q)
    size = np.ptp(grid.vertices.reshape(-1, 3), axis=0).max()
    assert flat < TOL * size                                           # planar faces
    for row in grid.vertices:                                          # rows in planes (P)
        assert np.linalg.svd(row - row.mean(axis=0), compute_uv=False)[2] < TOL * size
    assert angle_balance_of(grid.vertices).max() < TOL                 # conical
    arc_of = grid.meta["arc_of_column"]
    assert [int((arc_of == k).sum()) for k in range(3)] == [5, 5, 6]   # faces shared by how far each arc turns
    # every strip: the faces of one arc pass through one point (a cone patch); three different apexes
    for i in range(q.shape[0]):
        apexes = []
        for k in range(3):
            p, misfit = common_point(n[i, arc_of == k], d[i, arc_of == k])
            assert misfit < 1e-8 * size, (i, k, misfit)
            apexes.append(p)
        assert min(np.linalg.norm(apexes[0] - apexes[1]), np.linalg.norm(apexes[1] - apexes[2])) > 1e-3 * size
    # the designed strip's apexes in closed form: z0 + c_k + ρ_k tan β a (c_k from the G1 junctions)
    s = min(grid.meta["profile_plane"], len(grid.vertices) - 2)
    z = grid.meta["spheres"]
    a, cosb, sinb = cone_of(z[s], z[s + 1])
    frame = grid.meta["arc_frame"]
    assert np.allclose(frame.origin, z[s, :3]) and abs(frame.ex @ a) < 1e-12 and abs(frame.ey @ a) < 1e-12
    u = lambda deg: np.array([np.cos(np.radians(deg)), np.sin(np.radians(deg))])   # noqa: E731
    centres = [np.array([1.5, 0.5])]
    for (r0, _, _), (r1, t1, _) in zip(ARCS_OPEN[:-1], ARCS_OPEN[1:]):
        centres.append(centres[-1] + (r0 - r1) * u(t1))
    for k, ((r, _, _), c) in enumerate(zip(ARCS_OPEN, centres)):
        expect = frame.origin + c[0] * frame.ex + c[1] * frame.ey + r * sinb / cosb * a
        p, _ = common_point(n[s, arc_of == k], d[s, arc_of == k])
        assert np.linalg.norm(p - expect) < 1e-7 * size, (k, p, expect)


def test_one_arc_of_the_cone_radius_is_the_channel_mesh():
    base = dict(spheres=WAVY, faces_spine=10, faces_profile=12, angle_range=(-70.0, 70.0))
    channel = channel_mesh(**base)
    z = channel.meta["spheres"]
    s = min(channel.meta["profile_plane"], 9)
    _, _, sinb = cone_of(z[s], z[s + 1])
    arcs = {"profile_arcs": [[z[s, 3] / sinb, -70.0, 70.0]]}
    grid = build_construction("conical_spheres", {"spheres": WAVY.tolist(), "faces_spine": 10, "faces_profile": 12,
                                                  **arcs})
    assert np.abs(grid.vertices - channel.vertices).max() < 1e-9 * np.ptp(channel.vertices)


def test_a_closed_arc_spline_tube():
    """Four arcs, radii 7 and 4 alternating over quarter turns: G1 and closing (c_0 + (7 − 4)(u90 − u180 + u270 − u0)
    = c_0)."""
    arcs = [[7.0, -45.0, 45.0], [4.0, 45.0, 135.0], [7.0, 135.0, 225.0], [4.0, 225.0, 315.0]]
    params = {"spheres": WAVY.tolist(), "faces_spine": 10, "faces_profile": 24, "closed": True, "profile_arcs": arcs}
    grid = build_construction("conical_spheres", params)
    q = quads_of(grid)
    n, d, flat = face_planes(q)
    size = np.ptp(grid.vertices.reshape(-1, 3), axis=0).max()
    assert flat < TOL * size
    v = grid.vertices
    assert angle_balance_of(np.concatenate([v[:, -1:], v, v[:, :1]], axis=1)).max() < TOL
    arc_of = grid.meta["arc_of_column"]
    assert len(arc_of) == 24 and all(int((arc_of == k).sum()) == 6 for k in range(4))
    for i in range(q.shape[0]):
        for k in range(4):
            assert common_point(n[i, arc_of == k], d[i, arc_of == k])[1] < 1e-8 * size


@pytest.mark.parametrize("arcs, closed, words", [
    ([[3.0, -80.0, -30.0], [8.0, -20.0, 20.0]], False, "profile_arcs[1]: starts at -20° where arc 0 ended at -30°"),
    ([[-3.0, -80.0, -30.0]], False, "profile_arcs[0]: radius must be positive"),
    ([[3.0, 30.0, -30.0]], False, "from_deg < to_deg"),
    ([[7.0, -45.0, 45.0], [4.0, 45.0, 315.0]], True, "the arcs do not close: the last arc ends 4.24264 mm"),
    ([[7.0, 0.0, 300.0]], True, "turns once around (360°), these arcs turn 300°"),
])
def test_bad_arcs_are_named_in_one_line(arcs, closed, words):
    params = {"spheres": WAVY.tolist(), "faces_spine": 8, "faces_profile": 12, "closed": closed, "profile_arcs": arcs}
    with pytest.raises(DesignError) as err:
        build_construction("conical_spheres", params)
    assert words in str(err.value) and "\n" not in str(err.value)


def test_arcs_and_a_profile_curve_are_not_both_taken():
    params = {"spheres": WAVY.tolist(), "profile_arcs": ARCS_OPEN, "profile": [[6, -5], [6.5, 0], [6, 5]]}
    with pytest.raises(DesignError, match="profile_arcs: and profile are both given"):
        build_construction("conical_spheres", params)
    with pytest.raises(DesignError, match="fewer than the 3 arcs"):
        build_construction("conical_spheres", {"spheres": WAVY.tolist(), "faces_profile": 2, "profile_arcs": ARCS_OPEN})
