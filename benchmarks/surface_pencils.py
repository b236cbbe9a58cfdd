"""Parallel section planes against a pencil of planes through a vertical axis, on real shell patches.

The three 10 m patches of the botanic-garden bubble (WWmore/DOS @ f15cff51,
objs/obj_equilibrium/botanic-garden-bubble-0.obj, in the shared data) that docs/remeshing.md uses, each
resampled into a triangle mesh whose edges do not follow the original net (``tests/surface_cases.py``).  For
each: the sections net with the default parallel planes, with the planes searched (``search_planes``), and with
a pencil through a vertical axis at 10–70 m from the patch's middle in 24 directions — reported: the pencil
whose edges stay nearest the spacing (``max |log(edge / spacing)|``) among those whose planes stay within 30° of
the surface normals (rows a P support keeps as planar beams), and the nearest of all.  Spacing 1500 mm, CPU
seconds of the whole search.

    OMP_NUM_THREADS=1 python benchmarks/surface_pencils.py
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))

PATCHES = {"bubble (8, 11), hole": dict(hole=(9.0, 11.5, 1.5), crop=(8.0, 11.0, 5.0)),
           "bubble (0, −3)": dict(crop=(0.0, -3.0, 5.0)),
           "bubble (8, 4)": dict(crop=(8.0, 4.0, 5.0))}
DISTANCES_MM = (10000.0, 15000.0, 20000.0, 30000.0, 45000.0, 70000.0)
TILT_DEG = 30.0


def main() -> None:
    from conftest import shared_file
    from surface_cases import resample_quad_mesh

    from fabrication.surfacefile import read_surface
    from ppfab.errors import GeometryError
    from ppfab.surface import SurfaceSpec, remesh

    def row(r) -> str:
        return (f"{int(r.net.grid_faces.sum())} | {r.panel_size_min:.2f}–{r.panel_size_max:.2f} | {r.fan_out:.2f} | "
                f"{r.tilt_max_deg:.0f}°")

    print("| patch | net | quads | edges / spacing | fan-out | tilt | CPU s |")
    print("|---|---|---:|---|---:|---:|---:|")
    tmp = Path(tempfile.mkdtemp())
    for name, kw in PATCHES.items():
        mesh = resample_quad_mesh(shared_file("DOS__botanic-garden-bubble-0.obj"), 1500, 3, **kw)
        path = tmp / "patch.ply"
        mesh.export(path)
        sf = read_surface(path, units="m")
        for label, extra in (("parallel, default", {}), ("parallel, searched", {"search_planes": True})):
            t = time.process_time()
            try:
                r = remesh(sf.samples, SurfaceSpec(path=str(path), spacing=1500.0, **extra))
                print(f"| {name} | {label} | {row(r)} | {time.process_time() - t:.1f} |")
            except GeometryError as exc:
                print(f"| {name} | {label} | refused: {str(exc)[:60]} | | | | |")
        cx, cy = kw["crop"][0] * 1000.0, kw["crop"][1] * 1000.0
        t = time.process_time()
        found = []
        for dist in DISTANCES_MM:
            for ang in range(0, 360, 15):
                a = np.radians(ang)
                axis = [cx + dist * np.cos(a), cy + dist * np.sin(a)]
                try:
                    r = remesh(sf.samples, SurfaceSpec(path=str(path), spacing=1500.0, pencil_axis=axis))
                except GeometryError:
                    continue
                if r.net.grid_faces.sum() >= 15:
                    worst = max(abs(np.log(r.panel_size_min)), abs(np.log(r.panel_size_max)))
                    found.append((worst, r.tilt_max_deg or 0.0, dist, ang, r))
        cpu = time.process_time() - t
        within = [f for f in found if f[1] <= TILT_DEG]
        for label, pool in ((f"pencil, best within {TILT_DEG:.0f}°", within), ("pencil, best of all", found)):
            if pool:
                worst, tilt, dist, ang, r = min(pool, key=lambda f: f[0])
                print(f"| {name} | {label} (axis {dist / 1000:.0f} m at {ang}°) | {row(r)} | {cpu:.1f} "
                      f"({len(found)} axes) |")


if __name__ == "__main__":
    main()
