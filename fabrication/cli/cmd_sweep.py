"""``ppfab sweep SWEEP.toml -o RESULTS`` — many variants of a design on a Dask cluster, into one results table
(``results.parquet``, ``results.csv``, ``index.html``); see docs/sweeps.md."""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    from ..sweep.spec import SweepSpec

NAME = "sweep"
HELP = "compute many variants of a design (a sweep file) on a Dask cluster into a results table with plots"
ORDER = 45


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("sweep", help="sweep file (TOML): base design, keys to vary, stage, figures, [cost]")
    p.add_argument("-o", "--out", required=True,
                   help="results folder (created; an existing one only if ppfab wrote it): rerun to continue")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                   help="a running Dask scheduler (`dask scheduler`); default: a local cluster on this machine")
    p.add_argument("--workers", type=int, metavar="N",
                   help="workers of the local cluster (default: one per core; not with --scheduler)")
    p.add_argument("--stage", choices=["geometry", "nesting", "files"],
                   help="run this stage instead of the sweep file's (e.g. geometry for a quick look)")
    p.add_argument("--pareto", nargs=2, metavar=("X", "Y"),
                   help="the two figures of the Pareto plot in index.html (instead of the sweep file's)")
    p.add_argument("--retry-failed", action="store_true", help="compute the variants that failed before again")
    p.add_argument("--best", metavar="FIGURE",
                   help="then write the design of the best variant by FIGURE (e.g. cost, glass_sheets)")
    p.add_argument("--best-out", metavar="FILE",
                   help="where --best writes (default RESULTS/best-FIGURE.toml; replaces only a ppfab file)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def run(args: argparse.Namespace) -> int:
    from ppfab.errors import DesignError

    from ..sweep.figures import FIGURES
    from ..sweep.spec import load_sweep

    if args.workers is not None and (args.workers < 1 or args.scheduler):
        raise DesignError("--workers", "give a whole number ≥ 1, and only without --scheduler (the cluster's "
                                       "workers are its own)")
    if args.best is not None and args.best not in FIGURES:
        raise DesignError("--best", f"unknown figure {args.best!r}; give one of {', '.join(FIGURES)}")
    if args.best_out is not None and args.best is None:
        raise DesignError("--best-out", "goes with --best FIGURE")
    if args.scheduler is not None and not args.scheduler.strip():
        raise DesignError("--scheduler", "give the scheduler's address, e.g. tcp://10.0.0.5:8786")
    spec = load_sweep(args.sweep)
    if args.stage is not None:
        spec = with_stage(spec, args.stage)
    if args.pareto is not None:
        spec = with_pareto(spec, args.pareto)
    from ..sweep.engine import run_sweep

    report = run_sweep(spec, args.out, scheduler=args.scheduler, workers=args.workers,
                       retry_failed=args.retry_failed, quiet=args.quiet)
    print(f"ppfab: sweep of {report.variants} variants: {report.computed} computed, {report.skipped} already "
          f"done, {report.failed} failed, {report.seconds:.1f} s; results in {args.out}", file=sys.stderr)
    if args.best is not None:
        from ..sweep.best import write_best

        best = write_best(args.out, args.best, args.best_out, among={r["variant"] for r in report.rows})
        print(f"ppfab: best by {args.best}: variant {best.row['variant']} ({args.best} = {best.row[args.best]:.6g})"
              f", design in {best.path}", file=sys.stderr)
    return 1 if report.variants and report.failed == report.variants else 0


def with_stage(spec: "SweepSpec", stage: str) -> "SweepSpec":
    """``spec`` run to ``stage``; Pareto figures that stage does not measure give way to its defaults."""
    import dataclasses

    from ..sweep.figures import FIGURES, STAGES
    from ..sweep.spec import DEFAULT_PARETO

    pareto = spec.pareto
    if any(STAGES.index(FIGURES[f].stage) > STAGES.index(stage) for f in pareto):
        pareto = DEFAULT_PARETO[stage]
    return dataclasses.replace(spec, stage=stage, pareto=pareto)


def with_pareto(spec: "SweepSpec", figures: list[str]) -> "SweepSpec":
    """``spec`` with the Pareto plot of ``figures`` (two figures the sweep's stage measures)."""
    import dataclasses

    from ppfab.errors import DesignError

    from ..sweep.figures import FIGURES, STAGES

    for f in figures:
        if f not in FIGURES:
            raise DesignError("--pareto", f"unknown figure {f!r}; give two of {', '.join(FIGURES)}")
        if STAGES.index(FIGURES[f].stage) > STAGES.index(spec.stage):
            raise DesignError("--pareto", f"{f} is measured from stage {FIGURES[f].stage!r} on; this sweep runs "
                                          f"stage {spec.stage!r}")
    return dataclasses.replace(spec, pareto=(figures[0], figures[1]))
