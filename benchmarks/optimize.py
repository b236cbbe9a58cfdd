"""Benchmark: ppfab's sparse Levenberg–Marquardt vs scipy.optimize.least_squares on identical residuals.

For noisy grids of about 30×30, 60×60 and 100×100 vertices (an exact PP translational surface
``(x, y, f(x) + g(y))`` plus Gaussian noise of 3 % of the spacing), both solvers minimise the same
residual vector (:class:`ppfab.optimize.residuals.Residuals`: E_P, E_f, E_1, E_fair, E_close and the
shape barrier, all of vertices, support normals and face normals as unknowns) with the same
regularisation continuation (fairness and closeness weights × 1, 0.1, 0.01, … down to 1e-6, one stage
after the other):

* ``ppfab``  — :func:`ppfab.optimize.optimize` (analytic sparse Jacobian, damped normal equations with the
  face normals eliminated, SuperLU on a block-ordered system; support normals exact or, for long
  polylines, by variable projection — ``plane_solver = "auto"``), stages switched adaptively;
* ``scipy``  — ``least_squares(method="trf", jac_sparsity=…)`` (finite-difference Jacobian with column
  grouping, LSMR trust-region steps), run to convergence at each stage until the targets are met.

Both stop when max δ_f <= 1e-6 and max δ_P <= 1e-6 (``ppfab.metrics``) or at their budget; scipy gets
``--scipy-budget`` seconds per grid (default 240) and is reported as not converged beyond it.

Run:  python benchmarks/optimize.py [--sizes 30,60,100] [--families both] [--scipy-budget 240]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from ppfab.mesh import QuadGrid  # noqa: E402
from ppfab.optimize import build_problem, optimize  # noqa: E402


def noisy_grid(n: int, noise: float = 0.03, seed: int = 0) -> QuadGrid:
    """An exact PP translational surface sampled on ``n × n`` vertices plus noise (fraction of the spacing)."""
    rng = np.random.default_rng(seed)
    x = np.linspace(-1.0, 1.0, n)
    i, j = np.meshgrid(x, x, indexing="ij")
    v = np.stack([i, j, 0.35 * np.sin(1.7 * i) + 0.25 * np.cosh(1.3 * j)], axis=-1)
    return QuadGrid(v + rng.normal(scale=noise * 2.0 / (n - 1), size=v.shape))


def run_ppfab(grid: QuadGrid, families: str) -> dict:
    t = time.perf_counter()
    res = optimize(grid, families=families, max_iterations=300)
    dt = time.perf_counter() - t
    return {"time": dt, "iters": res.iterations, "df": res.delta_f_max, "dp": res.delta_p_max,
            "met": res.targets_met, "disp": res.displacement_rel}


def run_scipy(grid: QuadGrid, families: str, budget: float) -> dict:
    """Same residuals (all normals unknown), same stages, scipy's trf with the Jacobian sparsity."""
    t = time.perf_counter()
    prob = build_problem(grid, families=families, plane_solver="exact")
    res, p = prob.residuals, prob.params
    z = prob.z0.copy()
    sparsity = res.sparsity()
    nfev = 0
    s = 1.0
    df = dp = np.inf
    while True:
        def fun(x, s=s):
            zz = z.copy()
            zz[res.free_index] = x
            return res.residual(zz, s)

        def stop(intermediate_result):
            """Stop at the targets (checked after every iteration, as ppfab does) or at the budget."""
            zz = z.copy()
            zz[res.free_index] = intermediate_result.x
            f_max, _, p_max, _ = prob.metrics(res.unpack(zz)[0])
            if (f_max <= p.target_delta_f and p_max <= p.target_delta_p) or time.perf_counter() - t > budget:
                raise StopIteration

        if time.perf_counter() - t > budget:
            break
        out = least_squares(fun, z[res.free_index], jac_sparsity=sparsity, method="trf", max_nfev=100,
                            callback=stop)
        nfev += out.nfev
        z[res.free_index] = out.x
        df, _, dp, _ = prob.metrics(res.unpack(z)[0])
        if out.status == -2 and time.perf_counter() - t > budget:
            break
        if (df <= p.target_delta_f and dp <= p.target_delta_p) or s <= p.reg_min:
            break
        s = max(s * p.reg_decay, p.reg_min)
    dt = time.perf_counter() - t
    v = res.unpack(z)[0] * prob.scale + prob.center
    v0 = np.asarray(prob.mesh.vertices)
    diag = np.linalg.norm(np.ptp(v0, axis=0))
    return {"time": dt, "iters": nfev, "df": df, "dp": dp,
            "met": bool(df <= p.target_delta_f and dp <= p.target_delta_p),
            "disp": float(np.linalg.norm(v - v0, axis=1).mean() / diag)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="30,60,100")
    ap.add_argument("--families", default="both", choices=["rows", "cols", "both", "none"])
    ap.add_argument("--scipy-budget", type=float, default=240.0)
    args = ap.parse_args(argv)
    head = (f"{'grid':>9} {'solver':>6} {'time s':>8} {'iter/nfev':>9} {'max δ_f':>9} {'max δ_P':>9} "
            f"{'met':>4} {'disp/diag':>9} {'scipy/ppfab':>11}")
    print(f"families = {args.families}; targets max δ_f, max δ_P <= 1e-6; noise 3 % of the spacing")
    print(head)
    print("-" * len(head))
    for n in (int(k) for k in args.sizes.split(",")):
        grid = noisy_grid(n)
        a = run_ppfab(grid, args.families)
        b = run_scipy(grid, args.families, args.scipy_budget)
        for name, r in (("ppfab", a), ("scipy", b)):
            bound = "" if b["met"] else ">"               # scipy stopped at its budget: a lower bound
            ratio = f"{bound}{b['time'] / a['time']:.1f}".rjust(11) if name == "scipy" else " " * 11
            more = "" if r["met"] or name == "ppfab" else "  (stopped at the time budget)"
            print(f"{n:>4}x{n:<4} {name:>6} {r['time']:8.2f} {r['iters']:9d} {r['df']:9.2e} {r['dp']:9.2e} "
                  f"{'yes' if r['met'] else 'no':>4} {r['disp']:9.2e} {ratio}{more}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
