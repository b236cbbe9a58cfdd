"""Sweep benchmark: 24 variants of a small vault computed up to the nesting, by ``ppfab sweep`` on a Dask
LocalCluster of 1 and of 2 worker processes, against a plain sequential loop in one process.

Columns: wall seconds of the whole run (cluster start-up included), CPU seconds (this process, and the
workers' CPU of the variants as they report it), and the speed-up over the loop.  Below the table:

* the cluster's start-up (a LocalCluster of that many workers started and closed on its own),
* the scheduler's overhead per task: 200 tasks that do nothing, submitted and gathered the same way
  (``client.submit`` and ``as_completed``), wall time divided by the count,
* the sweep's own overhead per variant: wall of the sweep, less start-up, less the variants' wall on the
  workers (divided by the workers), per variant — scheduling plus writing the row (Parquet, CSV, ledger,
  design file, each flushed to disk).

Usage::

    python benchmarks/sweep.py                 # 24 variants, about a minute of CPU
    python benchmarks/sweep.py --variants 8    # a quick look
"""

from __future__ import annotations

import argparse
import logging
import tempfile
import time
from pathlib import Path

BASE = """
[design]
name = "bench vault"
[geometry]
method = "face_image_curves"
scale = 1000.0
[geometry.params]
g = [[0.0, 0.025], [0.0, 0.0, 0.0001], [0.5], [0.0, 0.0, -0.0125]]
h = [[0.0, 0.0, 0.0001], [0.0, 0.0333333], [0.5], [-8.0, 0.0, -0.0166667]]
u_range = [-4.5, 4.5]
v_range = [-3.0, 3.0]
faces_u = 6
faces_v = 4
[beams]
depth = 150.0
max_length = 3000.0
[nesting]
time_budget = 0.3
[beam_nesting]
time_budget = 0.3
"""


def sweep_file(folder: Path, n: int) -> Path:
    gaps = [10.0 + 2.0 * i for i in range(max(1, n // 3 + (n % 3 > 0)))]
    (folder / "base.toml").write_text(BASE)
    p = folder / "sweep.toml"
    p.write_text(f"""[sweep]
base = "base.toml"
stage = "nesting"
sample = "grid"
[vary]
"panels.gap" = {gaps}
"beams.depth" = [140.0, 150.0, 160.0]
""")
    return p


def sequential(spec) -> tuple[float, float, int]:
    """The plain loop: every variant computed in this process, one after the other."""
    from fabrication.sweep.variants import make_variants
    from fabrication.sweep.worker import VariantTask, run_variant

    vs = make_variants(spec)
    base_dir = str(spec.base.resolve().parent)
    c, w = time.process_time(), time.perf_counter()
    failed = 0
    for v in vs:
        r = run_variant(VariantTask(v.key, v.index, v.doc, spec.stage, base_dir))
        failed += r.status != "ok"
    return time.perf_counter() - w, time.process_time() - c, failed


def startup(workers: int) -> float:
    from distributed import Client, LocalCluster

    t = time.perf_counter()
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                           silence_logs=logging.ERROR)
    client = Client(cluster)
    client.wait_for_workers(workers)
    s = time.perf_counter() - t
    client.close()
    cluster.close()
    return s


def noop(x: int) -> int:
    return x


def scheduler_overhead(workers: int, n: int = 200) -> float:
    """Seconds per task of ``n`` tasks that do nothing, on a running LocalCluster."""
    from distributed import Client, LocalCluster, as_completed

    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                           silence_logs=logging.ERROR)
    client = Client(cluster)
    client.wait_for_workers(workers)
    try:
        t = time.perf_counter()
        futures = [client.submit(noop, i, pure=False) for i in range(n)]
        for f in as_completed(futures):
            f.result()
        return (time.perf_counter() - t) / n
    finally:
        client.close()
        cluster.close()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variants", type=int, default=24)
    args = ap.parse_args()
    for name in ("distributed", "tornado"):
        logging.getLogger(name).setLevel(logging.ERROR)
    from fabrication.sweep.engine import run_sweep
    from fabrication.sweep.spec import load_sweep

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        spec = load_sweep(sweep_file(root, args.variants))
        from fabrication.sweep.variants import make_variants

        n = len(make_variants(spec))
        rows: list[tuple[str, float, float, float | None, int, float]] = []
        wall, cpu, failed = sequential(spec)
        rows.append(("sequential loop", wall, cpu, None, failed, wall))
        base = wall
        extra = []
        for workers in (1, 2):
            c, t = time.process_time(), time.perf_counter()
            report = run_sweep(spec, root / f"res{workers}", workers=workers, quiet=True)
            w = time.perf_counter() - t
            task_cpu = sum(r["cpu_s"] or 0.0 for r in report.rows)
            task_wall = sum(r["wall_s"] or 0.0 for r in report.rows)
            rows.append((f"ppfab sweep, {workers} worker(s)", w, time.process_time() - c, task_cpu, report.failed,
                         base))
            s = startup(workers)
            per = (w - s - task_wall / workers) / n
            extra.append(f"{workers} worker(s): cluster start-up {s:.1f} s; the sweep's overhead per variant "
                         f"{1000 * per:.0f} ms (scheduling and writing the row)")
        print(f"{n} variants of a 6 x 4-face vault, stage nesting (budgets 0.3 s)\n")
        print(f"{'run':<26} {'wall s':>8} {'CPU s (this)':>13} {'CPU s (variants)':>17} {'failed':>7} {'speed-up':>9}")
        for name, w, c, tc, f, b in rows:
            tcs = "" if tc is None else f"{tc:.1f}"
            print(f"{name:<26} {w:>8.1f} {c:>13.1f} {tcs:>17} {f:>7} {base / w:>8.2f}x")
        print()
        for line in extra:
            print(line)
        for workers in (1, 2):
            print(f"scheduler overhead per task ({workers} worker(s), 200 empty tasks): "
                  f"{1000 * scheduler_overhead(workers):.1f} ms")


if __name__ == "__main__":
    main()
