"""PP design methods and face-image transforms at size, against baselines measured in the same run.

1. Cauchy propagation (Fig. 7): the anti-diagonal wavefront (one numpy step per diagonal) against a
   per-vertex Python loop computing the same intersections; the script checks they agree.
2. Every design method at ``faces × faces`` faces, and every transform of the result, against the bare
   face-image construction :func:`~ppfab.faceimage.pp_from_face_image` of the same size (ratio column).

    python benchmarks/pp_constructions.py [faces]
"""

from __future__ import annotations

import sys
import time

import numpy as np

from ppfab.transforms import pp as tf
from ppfab.constructions.bisector import bisector_mesh
from ppfab.constructions.cauchy import cauchy_pp_mesh, node_axes_lines
from ppfab.constructions.plane_splines import plane_spline, plane_spline_mesh
from ppfab.constructions.profile_curves import profile_surface
from ppfab.constructions.translational import translational_mesh
from ppfab.faceimage import pp_from_face_image


def dome_data(m: int, n: int, z0: float = 40.0):
    xi, yj = np.linspace(-15, 15, m + 1), np.linspace(-10, 10, n + 1)
    U = np.array([[z0, 0, x, -z0 * x] for x in xi])
    W = np.array([[0, z0, y, -z0 * y] for y in yj])
    on = lambda x, y, z: [(z0 - z) / z0 * x, (z0 - z) / z0 * y, z]        # noqa: E731
    col = np.array([on(x, yj[0], 3 + 4 * (1 - (x / 15) ** 2)) for x in xi])
    row = np.array([on(xi[0], y, 3 + 3 * (1 - (y / 10) ** 2)) for y in yj])
    return U, W, col, row


def cauchy_loop(U, W, col, row) -> np.ndarray:
    """Baseline: the same propagation one vertex at a time."""
    P, D = node_axes_lines(U, W)
    v = np.zeros((len(U), len(W), 3))
    v[:, 0], v[0, :] = col, row
    for i in range(1, len(U)):
        for j in range(1, len(W)):
            a, b, c = v[i - 1, j - 1], v[i, j - 1], v[i - 1, j]
            n = np.cross(b - a, c - a)
            t = n @ (a - P[i, j]) / (n @ D[i, j])
            v[i, j] = P[i, j] + t * D[i, j]
    return v


def timed(fn, *args, repeat: int = 3, **kw):
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn(*args, **kw)
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(faces: int = 200) -> None:
    m, n = faces, int(faces * 2 / 3)
    U, W, col, row = dome_data(m, n)
    t_vec, grid = timed(cauchy_pp_mesh, U, W, col, row)
    t_loop, v_loop = timed(cauchy_loop, U, W, col, row, repeat=1)
    err = np.abs(grid.vertices - v_loop).max()
    print(f"Cauchy propagation, {m} x {n} faces")
    print(f"{'method':<34}{'time [s]':>10}")
    print(f"{'anti-diagonal wavefront (ppfab)':<34}{t_vec:>10.4f}")
    print(f"{'per-vertex Python loop':<34}{t_loop:>10.4f}")
    print(f"speed-up {t_loop / t_vec:.1f}x; max |difference| {err:.2e}\n")
    if err > 1e-9 * np.ptp(v_loop):
        raise SystemExit("results differ")

    s = np.linspace(-0.5, 0.5, m + 2)
    t = np.linspace(-0.5, 0.5, n + 2)
    g = np.stack([s, 0.1 * s ** 2, 0.5 + 0 * s, -0.5 * s ** 2], 1)
    h = np.stack([0.1 * t ** 2, t, 0.5 + 0 * t, -0.5 * t ** 2], 1)
    t_base, base = timed(pp_from_face_image, g, h)
    xs, ys = np.linspace(-15, 15, 9), np.linspace(-10, 10, 9)
    S = profile_surface([[x, 8 - x ** 2 / 45] for x in xs], [[y, 8 - y ** 2 / 22] for y in ys])
    up = [[x, -10.0, 8 - x * x / 50 - 10 / 3] + [x / 25, -2 / 3, 1.0] for x in (-15, -5, 5, 15)]
    inner = []
    for k in range(3):
        p, q = np.array(up[k][:3]), np.array(up[k + 1][:3])
        nn = np.cross(q - p, [0, 1, 2 / 3])
        inner.append(list(p) + list(nn * np.sign(nn[2])))
    u_planes = [up[0], inner[0], up[1], inner[1], up[2], inner[2], up[3]]
    vp = [[-15.0, y, 8 - 4.5 - y * y / 30] + [-0.6, y / 15, 1.0] for y in (-10, -10 / 3, 10 / 3, 10)]
    vin = []
    for k in range(3):
        p, q = np.array(vp[k][:3]), np.array(vp[k + 1][:3])
        nn = np.cross(q - p, [1, 0, 0.6])
        vin.append(list(p) + list(nn * np.sign(nn[2])))
    v_planes = [vp[0], vin[0], vp[1], vin[1], vp[2], vin[2], vp[3]]
    gs = plane_spline(u_planes)
    hs = plane_spline(v_planes, g0=gs.knots[0], name="v")
    a = np.stack([np.linspace(-15, 15, m + 1), 0 * np.linspace(0, 1, m + 1),
                  8 - np.linspace(-15, 15, m + 1) ** 2 / 50], 1)
    b = np.stack([0 * np.linspace(0, 1, n + 1), np.linspace(-10, 10, n + 1),
                  -np.linspace(-10, 10, n + 1) ** 2 / 30], 1)
    gp = np.stack([np.linspace(-15, 15, m + 2), 0 * s, 14 + 0 * s], 1)
    hp = np.stack([0 * t, np.linspace(-10, 10, n + 2), -14 + 0 * t], 1)
    rows = [
        ("pp_from_face_image (baseline)", t_base),
        ("cauchy", t_vec),
        ("bisector", timed(bisector_mesh, gp, hp)[0]),
        ("profile_curves", timed(S.mesh, m, n)[0]),
        ("plane_splines", timed(plane_spline_mesh, gs, hs, m, n)[0]),
        ("translational", timed(translational_mesh, a, b)[0]),
        ("transform: parallel_mesh", timed(tf.parallel_mesh, base, 0.01)[0]),
        ("transform: offset (f_transform)", timed(tf.offset_along_axes, base, 0.01, mode="f_transform")[0]),
        ("transform: projective_map", timed(tf.projective_map, base, np.eye(5) + 0.01)[0]),
        ("transform: multinet 2 x 2", timed(tf.multinet, base, 2, 2)[0]),
        ("transform: grid w/o face image", timed(tf.f_transform, type(base)(base.vertices), np.zeros(4))[0]),
    ]
    print(f"Design methods and transforms, {m} x {n} faces")
    print(f"{'method':<34}{'time [s]':>10}{'x baseline':>12}")
    for name, sec in rows:
        print(f"{name:<34}{sec:>10.4f}{sec / t_base:>12.1f}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 200)
