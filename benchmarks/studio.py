"""Re-solve latency of the studio per construction at 30×30 and 60×60 faces.

For every bundled example whose construction has two resolution parameters, the resolution is set to
``N × N`` faces and the studio's whole re-solve (:func:`fabrication.studio.model.solve`: the closed-form
construction through :func:`ppfab.geometry.build_geometry`, placement, δ_P of the planar families, the live
figures and the fold marks) is timed, median of ``repeat`` runs after one warm-up; the construction alone is
the ``construct`` column, so the rest is the studio's overhead.  The goal is 100 ms at 30×30.

    OMP_NUM_THREADS=1 python benchmarks/studio.py [repeat]
"""

from __future__ import annotations

import copy
import statistics
import sys
import time
import tomllib
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from fabrication.studio.model import solve  # noqa: E402
from ppfab.constructions import get_construction  # noqa: E402
from ppfab.schema import parse_params  # noqa: E402

RESOLUTION = {
    "face_image_curves": ("faces_u", "faces_v"), "translational": ("faces_u", "faces_v"),
    "plane_splines": ("faces_u", "faces_v"), "profile_curves": ("faces_u", "faces_v"),
    "conical_pp": ("faces_u", "faces_v"), "conical_sections": ("faces_a", "faces_b"),
    "conical_spheres": ("faces_spine", "faces_profile"), "conical_spheres_pp": ("faces_spine", "faces_profile"),
}


def _median(fn, repeat: int) -> float:
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main(repeat: int = 5) -> None:
    seen: set[str] = set()
    print(f"{'example':34s} {'method':20s} {'faces':>7s} {'construct ms':>13s} {'re-solve ms':>12s} {'max δ_P':>9s}")
    for path in sorted((REPO / "examples").glob("*.toml")):
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
        method = doc.get("geometry", {}).get("method")
        if method not in RESOLUTION or method in seen and method != "conical_pp":
            continue
        seen.add(method)
        for n in (30, 60):
            d = copy.deepcopy(doc)
            for key in RESOLUTION[method]:
                d["geometry"]["params"][key] = n
            c = get_construction(method)
            record = parse_params(c.params, d["geometry"]["params"], "geometry.params")
            try:
                construct = _median(lambda: c.build(record), repeat)
                state = solve(d, path.parent)
                full = _median(lambda: solve(d, path.parent), repeat)
            except Exception as exc:                      # report, do not hide, a size the example cannot take
                print(f"{path.name:34s} {method:20s} {n:>3d}x{n:<3d} failed: {str(exc)[:70]}")
                continue
            print(f"{path.name:34s} {method:20s} {n:>3d}x{n:<3d} {1000 * construct:13.1f} {1000 * full:12.1f} "
                  f"{state.delta_p_max:9.1e}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5)
