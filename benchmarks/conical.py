"""Timings of the conical constructions and transforms against the plain PP construction of the same size.

Baseline (measured in the same run): :func:`ppfab.faceimage.pp_from_face_image` on generic generators
with the same number of faces — the vectorised core every PP construction uses.  Each row prints the
time and the ratio to that baseline, plus the largest conical residual of the result (a check that
the timed code did its job).

    python benchmarks/conical.py [faces ...]        (default: 20 60 150)
"""

from __future__ import annotations

import sys
import time

import numpy as np

from ppfab.conical.cones import laguerre_transform, conical_quality
from ppfab.conical.edit import edit_conical, mobius_of_laguerre
from ppfab.constructions.conical_pp import Series, conical_pp_grid
from ppfab.constructions.conical_sections import sections_grid
from ppfab.constructions.conical_spheres import channel_mesh
from ppfab.faceimage import pp_from_face_image
from ppfab.transforms.laguerre import LaguerreMap, boost
from ppfab.curves import PlanarCurve


def timed(fn, repeat: int = 3):
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def baseline(m: int, n: int):
    s, t = np.linspace(-0.5, 0.5, m + 2), np.linspace(-0.5, 0.5, n + 2)
    g = np.stack([s, 0.1 * s ** 2, 0.5 + 0 * s, -0.5 * s ** 2 + 0.05 * s ** 3], axis=1)
    h = np.stack([0.1 * t ** 2, t, 0.5 + 0 * t, -0.5 * t ** 2 - 0.03 * t ** 3], axis=1)
    return pp_from_face_image(g, h)


def main(sizes: list[int]) -> None:
    x = np.linspace(-15, 15, 9)
    y = np.linspace(-10, 10, 7)
    spheres = np.array([[0, 0, 2, 5.0], [8, 3, 3, 6], [16, -2, 2.5, 5.5], [24, 0, 2, 4.5], [30, 2, 3, 5]])
    ellipse = np.c_[6.5 * np.cos(np.linspace(0, 2 * np.pi, 24, endpoint=False)),
                    8.0 * np.sin(np.linspace(0, 2 * np.pi, 24, endpoint=False))]
    print(f"{'faces':>7}  {'what':<38} {'time [s]':>9} {'× baseline':>10} {'conical residual':>17}")
    for k in sizes:
        m, n = k, max(2, (2 * k) // 3)
        t_base, _ = timed(lambda: baseline(m, n))
        mesh_pp = None
        rows = []

        def pp():
            return conical_pp_grid(Series(cos=[-30.0, 1.2]), Series(cosh=[-60.0], poly=[0, 0, 5.0]),
                                   np.linspace(-.78, .78, m), np.linspace(-.66, .66, n), frame="z_up")
        t, mesh_pp = timed(pp)
        rows.append(("conical_pp case1 (eq. 11)", t, mesh_pp))
        t, g = timed(lambda: sections_grid(np.c_[x, 8 - x ** 2 / 30], np.c_[y, 8 - y ** 2 / 20], m, n, d=3.0))
        rows.append(("conical_sections (§4.1.2)", t, g))
        t, g = timed(lambda: channel_mesh(spheres, m, n, (-80, 80)))
        rows.append(("conical_spheres Steps 1-3", t, g))
        prof = PlanarCurve.from_points(ellipse, closed=True, name="profile")
        t, g = timed(lambda: channel_mesh(spheres, m, n, (-80, 80), profile=prof))
        rows.append(("conical_spheres + profile (Step 4)", t, g))
        L = LaguerreMap(boost([0.3, 0.2, 1.0], 0.2))
        t, g = timed(lambda: laguerre_transform(mesh_pp, L))
        rows.append(("Laguerre transform of the eq. 11 mesh", t, g))
        if m * n <= 20000:
            t, r = timed(lambda: edit_conical(mesh_pp, A=mobius_of_laguerre(L.A)), repeat=1)
            rows.append(("§4.3 exact edit, A fixed (sparse KKT)", t, r.grid))
        print(f"{m:>3}x{n:<3}  {'baseline pp_from_face_image':<38} {t_base:>9.4f} {1.0:>10.1f}")
        for name, t, g in rows:
            print(f"{'':>7}  {name:<38} {t:>9.4f} {t / t_base:>10.1f} {conical_quality(g).angle_max:>17.1e}")


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [20, 60, 150])
