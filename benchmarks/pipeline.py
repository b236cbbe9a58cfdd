"""Time each stage of ``ppfab build`` on the bundled default (or a given design).

    python benchmarks/pipeline.py [DESIGN.toml]

Prints the seconds per stage (compute stages, then one line per writer) and the total, and — as the
baseline measured in the same run — the time of the geometry alone, so the cost of fabrication is visible
as a ratio.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path


def main(argv: list[str]) -> None:
    from fabrication import build, load_design
    from fabrication.pipeline.progress import Progress
    from ppfab.geometry import build_geometry

    design = load_design(argv[0] if argv else None)
    t0 = time.perf_counter()
    build_geometry(design.geometry, design.optimize, design.base_dir)
    t_geo = time.perf_counter() - t0
    progress = Progress(quiet=True)
    result = build(design, progress=progress)
    with tempfile.TemporaryDirectory() as tmp:
        result.write(Path(tmp) / "out", progress=progress)
    times = progress.times
    total = sum(times.values())
    print(f"ppfab build — {design.info.name}")
    print(f"{'stage':<12}{'seconds':>10}{'share':>8}")
    for name, t in times.items():
        print(f"{name:<12}{t:>10.2f}{100 * t / total:>7.1f}%")
    print(f"{'total':<12}{total:>10.2f}")
    print(f"baseline: geometry alone {t_geo:.3f} s; the whole build is {total / max(t_geo, 1e-9):.0f}x that")


if __name__ == "__main__":
    main(sys.argv[1:])
