"""``ppfab check MESH`` — print the quality metrics of a mesh file and test them against a tolerance."""

from __future__ import annotations

import argparse
import json

NAME = "check"
HELP = "print quality metrics (δ_f, δ_P of rows and columns, deviation, conical residual, folds) of a mesh"
ORDER = 20


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("mesh", help="quad mesh file (.obj or .off)")
    p.add_argument("--tol", type=float, default=None,
                   help="fail (exit 1) when max δ_f or max δ_P of a planar family exceeds this")
    p.add_argument("--families", choices=["rows", "cols", "both", "none"], default="both",
                   help="which polyline families --tol applies to (default both)")
    p.add_argument("--json", action="store_true", help="print the metrics as JSON")


def run(args: argparse.Namespace) -> int:
    from ppfab.io import load_mesh
    from ppfab.metrics import quality

    mesh = load_mesh(args.mesh)
    q = quality(mesh)
    if args.json:
        print(json.dumps(q.as_dict(), indent=2))
    else:
        print(f"{args.mesh}")
        print(q.table())
    if args.tol is None:
        return 0
    worst = {"delta_f": q.delta_f_max}
    if args.families in ("rows", "both"):
        worst["delta_P rows"] = q.delta_p_rows_max
    if args.families in ("cols", "both"):
        worst["delta_P cols"] = q.delta_p_cols_max
    failed = {k: v for k, v in worst.items() if v > args.tol}
    if failed:
        msg = ", ".join(f"{k} {v:.3e}" for k, v in failed.items())
        print(f"ppfab: check failed: {msg} > tol {args.tol:g}")
        return 1
    return 0
