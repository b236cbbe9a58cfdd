"""Benchmark: ppfab's sparse Levenberg–Marquardt vs scipy.optimize.least_squares, fairly.

For noisy grids of 30², 60², 100² and 200² vertices (an exact PP translational surface
``(x, y, 0.35 sin 1.7x + 0.25 cosh 1.3y)`` plus Gaussian noise of 3 % of the spacing), both solvers
minimise the same residual vector from the same start (:class:`ppfab.optimize.residuals.Residuals` of
:func:`ppfab.optimize.build_problem` with the default parameters: E_P, E_f, E_1, E_fair, E_close towards
the input surface, the shape barrier), with the same analytic sparse Jacobian
(:meth:`Residuals.jacobian`) and the same continuation and stage rule:

* a stage has a regularisation factor ``s`` (1, 0.1, 0.01, … down to 1e-6) on the fairness and closeness
  weights; it ends when an accepted step lowers the energy by less than 5 % (``stall``), and the next stage
  starts from where it ended (foot points on the input surface updated);
* the run stops when max δ_f <= 1e-6 and max δ_P <= 1e-6 (measured with ``ppfab.metrics`` after every
  accepted step), or at the budget.

Solvers:

* ``ppfab`` — :func:`ppfab.optimize.optimize` as a user calls it (damped normal equations with the face
  normals eliminated; MKL PARDISO when pypardiso is installed, else SuperLU with ppfab's nested-dissection
  ordering, ``linear_solver = "auto"``; support normals exact on 30², by variable projection above,
  ``plane_solver = "auto"``; guard and result report included in the time); with PARDISO a second row gives
  the same run with SuperLU;
* ``scipy`` — ``least_squares(method="trf", jac=<the analytic sparse Jacobian>, tr_solver="lsmr")`` with
  every normal an unknown (its natural form of the same residual vector), restarted per stage from a
  ``callback`` that applies the stage rule and the targets after every iteration.  Both ``x_scale=1`` and
  ``x_scale="jac"`` are run on the grids up to ``--scipy-variants-up-to`` and the faster one is reported
  (the baseline at its best); above that the variant that won on the largest grid compared is used.

Each solver (and each variant) first solves an 8 × 8 grid untimed, so that no timing includes the imports and
library loads a first call pays (MKL's, scipy's).

Printed per grid: CPU time of the process (``time.process_time``: on a shared machine it does not count the
time other jobs take; both solvers run single-threaded with ``OMP_NUM_THREADS=1``) and wall time, iterations (ppfab: LM iterations = linear solves; scipy: trf iterations, with
Jacobian evaluations), achieved max δ_f and δ_P, whether both targets were met, and scipy time / ppfab time.
Set ``OMP_NUM_THREADS=1`` for comparable timings.

``--sizes`` may also name ``roof``: the generated 100 × 120-vertex roof patch of ``benchmarks/optimize_table.py``
(12,000 vertices, a real-size P problem: rows made planar, ``families = "rows"``).

Run:  python benchmarks/optimize.py [--sizes 30,60,100,200,roof] [--scipy-budget 900]
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

TARGET = 1e-6


def noisy_grid(n: int, noise: float = 0.03, seed: int = 0) -> QuadGrid:
    """An exact PP translational surface sampled on ``n × n`` vertices plus noise (fraction of the spacing)."""
    rng = np.random.default_rng(seed)
    x = np.linspace(-1.0, 1.0, n)
    i, j = np.meshgrid(x, x, indexing="ij")
    v = np.stack([i, j, 0.35 * np.sin(1.7 * i) + 0.25 * np.cosh(1.3 * j)], axis=-1)
    return QuadGrid(v + rng.normal(scale=noise * 2.0 / (n - 1), size=v.shape))


def run_ppfab(grid: QuadGrid, families: str, linear_solver: str = "auto") -> dict:
    t, c = time.perf_counter(), time.process_time()
    res = optimize(grid, families=families, max_iterations=300, target_delta_f=TARGET, target_delta_p=TARGET,
                   linear_solver=linear_solver)
    dt, cpu = time.perf_counter() - t, time.process_time() - c
    return {"time": cpu, "wall": dt, "iters": res.iterations, "evals": res.factorisations, "df": res.delta_f_max,
            "dp": res.delta_p_max, "met": res.targets_met, "variant": f"{res.plane_solver}/{res.linear_solver}"}


class _Stop(Exception):
    pass


def run_scipy(grid: QuadGrid, families: str, budget: float, x_scale, tol: float = 1e-8,
              max_nfev: int = 1000) -> dict:
    """The same residuals and Jacobian with every normal an unknown, the same stages, scipy's trf."""
    t, c = time.perf_counter(), time.process_time()
    prob = build_problem(grid, families=families, plane_solver="exact")
    res, p = prob.residuals, prob.params
    z = res.project_normals(prob.z0.copy())
    s = 1.0
    iters = njev = 0
    df = dp = np.inf
    prob.on_stage(z)
    while True:
        state = {"cost": None, "stage_end": False, "met": False}

        def full(x: np.ndarray) -> np.ndarray:
            zz = z.copy()
            zz[res.free_index] = x
            return zz

        def fun(x, s=s):
            return res.residual(full(x), s)

        def jac(x, s=s):
            nonlocal njev
            njev += 1
            return res.jacobian(full(x), s)

        def callback(intermediate_result):
            """After every trf iteration: the targets, then ppfab's stage rule (decrease < stall)."""
            nonlocal iters
            iters += 1
            cost = 2.0 * float(intermediate_result.cost)                 # scipy's cost is ½‖r‖²
            v = res.unpack(full(intermediate_result.x))[0]
            f_max, _, p_max, _ = prob.metrics(v)
            if f_max <= TARGET and p_max <= TARGET:
                state["met"] = True
                raise StopIteration
            if state["cost"] is not None and cost < state["cost"]:
                if (state["cost"] - cost) / state["cost"] < p.stall and s > p.reg_min:
                    state["stage_end"] = True
                    raise StopIteration
            state["cost"] = cost
            if time.process_time() - c > budget:
                raise StopIteration

        out = least_squares(fun, z[res.free_index], jac=jac, method="trf", tr_solver="lsmr", x_scale=x_scale,
                            max_nfev=max_nfev, callback=callback, ftol=tol, xtol=tol, gtol=tol)
        z[res.free_index] = out.x
        df, _, dp, _ = prob.metrics(res.unpack(z)[0])
        if state["met"] or (df <= TARGET and dp <= TARGET) or time.process_time() - c > budget:
            break
        if s <= p.reg_min and not state["stage_end"]:
            break                                                        # last stage converged by scipy's rule
        s = max(s * p.reg_decay, p.reg_min)
        prob.on_stage(z)
    dt, cpu = time.perf_counter() - t, time.process_time() - c
    return {"time": cpu, "wall": dt, "iters": iters, "evals": njev, "df": df, "dp": dp,
            "met": bool(df <= TARGET and dp <= TARGET),
            "variant": f"x_scale={x_scale}" + ("" if tol == 1e-8 else f" tol={tol:.0e}")}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="30,60,100,200")
    ap.add_argument("--families", default="both", choices=["rows", "cols", "both", "none"])
    ap.add_argument("--scipy-budget", type=float, default=900.0, help="CPU seconds per scipy run")
    ap.add_argument("--scipy-tol", type=float, default=1e-8,
                    help="scipy's ftol, xtol and gtol (default 1e-8, its own): a smaller one lets a stage that trf "
                         "calls converged go on towards the targets")
    ap.add_argument("--scipy-max-nfev", type=int, default=1000, help="scipy's function evaluations per stage")
    ap.add_argument("--scipy-scale", default="", help="skip the variant comparison: x_scale for scipy (1 or jac)")
    ap.add_argument("--scipy-variants-up-to", type=int, default=10 ** 9,
                    help="run both x_scale variants of scipy up to this grid size and keep the faster (default: at "
                         "every size — the faster variant at 60² was the slower one at 100² and 200², 13.9 against "
                         "12.8 s and 80.7 against 68.0 s)")
    args = ap.parse_args(argv)
    head = (f"{'grid':>9} {'solver':>6} {'variant':>18} {'CPU s':>8} {'wall s':>8} {'iter':>5} {'jac/fact':>8} "
            f"{'max δ_f':>9} {'max δ_P':>9} {'met':>4} {'scipy/ppfab':>11}")
    roof = " (the roof patch: rows)" if "roof" in args.sizes.split(",") else ""
    print(f"families = {args.families}{roof}; targets max δ_f, max δ_P <= {TARGET:.0e}; noise 3 % of the spacing; "
          f"same residuals, start, analytic Jacobian and stage rule; time = CPU seconds")
    print(head)
    print("-" * len(head))
    best_scale: object = {"": 1.0, "1": 1.0, "jac": "jac"}[args.scipy_scale]
    warm = noisy_grid(8)                   # untimed: imports and library loads (MKL) are paid before any timing
    run_ppfab(warm, args.families)
    run_ppfab(warm, args.families, "superlu")
    for xs in (1.0, "jac"):
        run_scipy(warm, args.families, args.scipy_budget, xs)
    for size in args.sizes.split(","):
        if size == "roof":
            from optimize_table import roof_patch
            # n: its size for --scipy-variants-up-to, √12,000 vertices ≈ 110
            grid, families, n, label = roof_patch()[1], "rows", 110, "roof 100x120 P"
        else:
            n = int(size)
            grid, families, label = noisy_grid(n), args.families, f"{n:>4}x{n:<4}"
        a = run_ppfab(grid, families)
        plain = [run_ppfab(grid, families, "superlu")] if a["variant"].endswith("pardiso") else []
        if n <= args.scipy_variants_up_to and not args.scipy_scale:
            runs = [run_scipy(grid, families, args.scipy_budget, xs, args.scipy_tol, args.scipy_max_nfev)
                    for xs in (1.0, "jac")]
            met = [r for r in runs if r["met"]] or runs
            b = min(met, key=lambda r: r["time"])
            best_scale = 1.0 if b is runs[0] else "jac"
            others = [r for r in runs if r is not b]
        else:
            b = run_scipy(grid, families, args.scipy_budget, best_scale, args.scipy_tol, args.scipy_max_nfev)
            others = []
        for name, r in [("ppfab", a)] + [("ppfab", q) for q in plain] + [("scipy", b)] + [("scipy", o) for o in others]:
            bound = "" if b["met"] else ">"
            ratio = f"{bound}{r['time'] / a['time']:.1f}" if name == "scipy" else ""
            note = ("  (slower variant)" if name == "scipy" and r is not b
                    else f"  (scipy/this {b['time'] / r['time']:.1f})" if name == "ppfab" and r is not a else "")
            print(f"{label:>9} {name:>6} {r['variant']:>18} {r['time']:8.2f} {r['wall']:8.2f} {r['iters']:5d} "
                  f"{r['evals']:8d} "
                  f"{r['df']:9.2e} {r['dp']:9.2e} {'yes' if r['met'] else 'no':>4} {ratio:>11}{note}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
