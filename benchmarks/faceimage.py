"""Building a 500 × 500-face PP mesh from its face image: vectorised vs a per-vertex Python loop.

Both compute the same thing — the extended face image ``F = g_a + h_b − c`` (eq. 7), the support
planes ``U_i``, ``W_j`` as differences, and every vertex as ``F[i+1, j+1] ∩ U_i ∩ W_j`` — and the
script checks they agree before printing times.

    python benchmarks/faceimage.py [faces]
"""

from __future__ import annotations

import sys
import time

import numpy as np

from ppfab.faceimage import pp_from_face_image


def generators(m: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    s = np.linspace(-0.5, 0.5, m + 2)
    t = np.linspace(-0.5, 0.5, n + 2)
    g = np.stack([s, 0.1 * s ** 2, 0.5 + 0 * s, -0.5 * s ** 2 + 0.05 * s ** 3], axis=1)
    h = np.stack([0.1 * t ** 2, t, 0.5 + 0 * t, -0.5 * t ** 2 - 0.03 * t ** 3], axis=1)
    return g, h


def loop_version(g: np.ndarray, h: np.ndarray) -> np.ndarray:
    """The same construction, one vertex at a time (the baseline)."""
    m1, n1 = len(g) - 1, len(h) - 1
    out = np.empty((m1, n1, 3))
    for i in range(m1):
        u = g[i + 1] - g[i]
        for j in range(n1):
            w = h[j + 1] - h[j]
            f = g[i + 1] + h[j + 1]
            a = np.array([f[:3], u[:3], w[:3]])
            b = -np.array([f[3], u[3], w[3]])
            out[i, j] = np.linalg.solve(a, b)
    return out


def main(faces: int = 500) -> None:
    g, h = generators(faces, faces)
    t0 = time.perf_counter()
    grid = pp_from_face_image(g, h)
    t_vec = time.perf_counter() - t0
    t0 = time.perf_counter()
    v_loop = loop_version(g, h)
    t_loop = time.perf_counter() - t0
    err = np.abs(grid.vertices - v_loop).max()
    print(f"PP mesh from face image, {faces} x {faces} faces ({(faces + 1) ** 2} vertices)")
    print(f"{'method':<28}{'time [s]':>10}")
    print(f"{'ppfab (vectorised numpy)':<28}{t_vec:>10.3f}")
    print(f"{'per-vertex Python loop':<28}{t_loop:>10.3f}")
    print(f"speed-up {t_loop / t_vec:.1f}x; max |difference| {err:.2e}")
    if err > 1e-9:
        raise SystemExit("results differ")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 500)
