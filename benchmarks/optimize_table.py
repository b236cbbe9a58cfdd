"""The table of docs/optimisation.md: ppfab optimize on every mesh in ../shared/data and generated ones.

For each mesh and each of ``rows`` (P) and ``both`` (PP attempt), plus ``keep_conical`` runs on the conical
and nearly-PP meshes, it prints, in the form of the paper's §3.3 table, max/avg δ_P (over the polylines made
planar) and max/avg δ_f before and after, and then what the run did to the design:

* the conical residual ``|α1 − α2 + α3 − α4|`` (max, rad) before → after,
* the largest deviation of a corner angle from 90° (degrees) before → after,
* the largest dihedral angle between neighbouring faces (crease, degrees) before → after,
* the largest distance of a result vertex to the input surface (mesh units, and relative to the bounding-box
  diagonal),

the CPU time (``time.process_time``, single-threaded with ``OMP_NUM_THREADS=1``: on a shared machine it
does not count other jobs), the LM iterations, whether the targets (1e-6) were met and what the solver returned (the last
iterate, or the best / the input when the last was worse), and the folds of the result.  Default
parameters otherwise.  The generated 100 × 120 roof patch (12,000 vertices) shows the size the solver
handles.

Run:  python benchmarks/optimize_table.py [--families rows,both] [--max-iter 500] [--no-roof] > table.md
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
from ppfab.metrics import quality  # noqa: E402
from ppfab.optimize import build_problem, optimize  # noqa: E402

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
KEEP_CONICAL = {"DOS__conical1.obj": ("rows", "both"), "DOS__enneper2.obj": ("both",)}


def generated_mesh() -> tuple[str, QuadGrid]:
    """30 × 30 samples of the translational surface ``(x, y, 0.35 sin 1.7x + 0.25 cosh 1.3y)`` (exactly PP)
    with Gaussian noise of 3 % of the grid spacing."""
    rng = np.random.default_rng(0)
    x = np.linspace(-1.0, 1.0, 30)
    i, j = np.meshgrid(x, x, indexing="ij")
    v = np.stack([i, j, 0.35 * np.sin(1.7 * i) + 0.25 * np.cosh(1.3 * j)], axis=-1)
    return "generated: noisy translational 30×30", QuadGrid(v + rng.normal(scale=0.03 * 2 / 29, size=v.shape))


def roof_patch(m: int = 100, n: int = 120) -> tuple[str, QuadGrid]:
    """A 100 × 120-vertex roof patch with 1 m spacing (12,000 vertices): a shallow dome with a wave and a
    twist, sampled along x, y (not a conjugate net: the quads are not planar)."""
    x, y = np.meshgrid(np.arange(m, dtype=float), np.arange(n, dtype=float), indexing="ij")
    z = (8.0 - 0.0016 * ((x - 50) ** 2 + 0.7 * (y - 60) ** 2) + 0.6 * np.sin(x / 14.0) * np.sin(y / 19.0)
         + 0.0004 * (x - 50) * (y - 60))
    return "generated: roof patch 100×120 (1 m spacing)", QuadGrid(np.stack([x, y, z], axis=-1))


def meshes(roof: bool):
    for path in sorted(DATA.glob("*.obj")) + sorted(DATA.glob("*.off")):
        yield path.name, load_mesh(path)
    yield generated_mesh()
    if roof:
        yield roof_patch()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--families", default="rows,both")
    ap.add_argument("--max-iter", type=int, default=500)
    ap.add_argument("--no-roof", action="store_true")
    ap.add_argument("--only", default="", help="comma-separated substrings of mesh names to run")
    args = ap.parse_args(argv)
    print("| mesh | V / F | planar | δ_P max / avg before | **δ_P max** | **δ_P avg** | **δ_f max** | "
          "**δ_f avg** | δ_f max before | conical max before → after (rad) | corner dev. max before → after (°) | "
          "crease max before → after (°) | max dist. to input surface (rel. bbox diag) | CPU s | iter | met "
          "(returned) | folds |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    only = [s for s in args.only.split(",") if s]
    for name, mesh in meshes(not args.no_roof):
        if only and not any(s in name for s in only):
            continue
        qm = mesh.to_quadmesh() if isinstance(mesh, QuadGrid) else mesh
        v0 = np.asarray(qm.vertices)
        diag = float(np.linalg.norm(np.ptp(v0, axis=0)))
        runs = [(fam, {}) for fam in args.families.split(",")]
        runs += [(fam, {"keep_conical": True}) for fam in KEEP_CONICAL.get(name, ())]
        q0 = quality(mesh)
        for fam, kw in runs:
            prob = build_problem(mesh, families=fam)
            df0, _, dp0, dpa0 = prob.metrics(v0)
            t = time.process_time()
            res = optimize(mesh, families=fam, max_iterations=args.max_iter, **kw)
            dt = time.process_time() - t
            extra = f" ({len(res.excluded)} crossing left out)" if len(res.excluded) else ""
            label = f"{fam} + keep_conical" if kw else fam
            ret = "" if res.returned == "last" else f" ({res.returned})"
            print(f"| {name} | {len(v0)} / {len(qm.faces)} | {label}: {len(res.polylines)}{extra} | "
                  f"{dp0:.1e} / {dpa0:.1e} | {res.delta_p_max:.1e} | {res.delta_p_mean:.1e} | "
                  f"{res.delta_f_max:.1e} | {res.delta_f_mean:.1e} | {df0:.1e} | "
                  f"{q0.conical_max:.1e} → {res.conical_max:.1e} | "
                  f"{res.corner_deviation_max_input:.1f} → {res.corner_deviation_max:.1f} | "
                  f"{res.crease_max_input:.1f} → {res.crease_max:.1f} | "
                  f"{res.surface_distance_max:.3g} ({res.surface_distance_max / diag:.1e}) | {dt:.1f} | "
                  f"{res.iterations} | {'yes' if res.targets_met else 'no'}{ret} | "
                  f"{res.quality.flipped_edges} / {res.quality.nonconvex_faces} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
