"""The table of docs/optimisation.md: ppfab optimize on every mesh in ../shared/data and a generated one.

For each mesh and each of ``rows`` (P) and ``both`` (PP attempt) it prints, in the form of the paper's
§3.3 table, max/avg δ_P (over the polylines made planar) and max/avg δ_f before and after, the time,
the LM iterations, whether the targets (1e-6) were met, how many of the polylines reached δ_P <= 1e-6,
the folds of the result (flipped edges / non-convex faces, ``ppfab.metrics``),
and the mean vertex displacement from the
input in mesh units and relative to the bounding-box diagonal.  Default parameters otherwise.

Run:  python benchmarks/optimize_table.py [--families rows,both] [--max-iter 500] > table.md
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from ppfab.io import load_mesh  # noqa: E402
from ppfab.mesh import QuadGrid  # noqa: E402
from ppfab.optimize import build_problem, optimize  # noqa: E402

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def generated_mesh() -> tuple[str, QuadGrid]:
    """30 × 30 samples of the translational surface ``(x, y, 0.35 sin 1.7x + 0.25 cosh 1.3y)`` (exactly PP)
    with Gaussian noise of 3 % of the grid spacing."""
    rng = np.random.default_rng(0)
    x = np.linspace(-1.0, 1.0, 30)
    i, j = np.meshgrid(x, x, indexing="ij")
    v = np.stack([i, j, 0.35 * np.sin(1.7 * i) + 0.25 * np.cosh(1.3 * j)], axis=-1)
    return "generated: noisy translational 30×30", QuadGrid(v + rng.normal(scale=0.03 * 2 / 29, size=v.shape))


def meshes():
    for path in sorted(DATA.glob("*.obj")) + sorted(DATA.glob("*.off")):
        yield path.name, load_mesh(path)
    yield generated_mesh()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--families", default="rows,both")
    ap.add_argument("--max-iter", type=int, default=500)
    args = ap.parse_args(argv)
    print("| mesh | V / F | planar | δ_P max / avg before | **δ_P max** | **δ_P avg** | **δ_f max** | "
          "**δ_f avg** | δ_f max before | time s | iter | met | polylines ≤ 1e-6 | folds | "
          "displacement mean (rel. bbox diag) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, mesh in meshes():
        qm = mesh.to_quadmesh() if isinstance(mesh, QuadGrid) else mesh
        for fam in args.families.split(","):
            prob = build_problem(mesh, families=fam)
            df0, _, dp0, dpa0 = prob.metrics(np.asarray(qm.vertices))
            t = time.perf_counter()
            res = optimize(mesh, families=fam, max_iterations=args.max_iter)
            dt = time.perf_counter() - t
            extra = f" ({len(res.excluded)} crossing left out)" if len(res.excluded) else ""
            print(f"| {name} | {len(qm.vertices)} / {len(qm.faces)} | {fam}: {len(res.polylines)}{extra} | "
                  f"{dp0:.1e} / {dpa0:.1e} | {res.delta_p_max:.1e} | {res.delta_p_mean:.1e} | "
                  f"{res.delta_f_max:.1e} | {res.delta_f_mean:.1e} | {df0:.1e} | {dt:.1f} | {res.iterations} | "
                  f"{'yes' if res.targets_met else 'no'} | "
                  f"{int((res.polyline_delta_p <= 1e-6).sum())} / {len(res.polylines)} | "
                  f"{res.quality.flipped_edges} / {res.quality.nonconvex_faces} | {res.displacement_mean:.2e} "
                  f"({res.displacement_rel:.1e}) |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
