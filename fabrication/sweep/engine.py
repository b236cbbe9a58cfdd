"""Running a sweep on Dask distributed: a :class:`~distributed.LocalCluster` sized to this machine by
default, or an existing cluster given by its scheduler address (``tcp://HOST:PORT``).

Every variant not yet in the results table is one task (:func:`~fabrication.sweep.worker.run_variant`).
As each finishes, its row goes into the table at once (:class:`~fabrication.sweep.store.ResultsFolder`).
A worker that dies while running a task is replaced by the scheduler, which runs the task again elsewhere
(up to ``distributed.scheduler.allowed-failures`` times; then the variant is recorded as failed).  Ctrl-C
cancels what is left; every row written before it stays, and a rerun computes only what is missing.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import logging
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from ppfab.errors import PpfabError

from .spec import SweepSpec
from .store import ResultsFolder
from .table import make_row, table_bytes
from .variants import Variant, design_text, make_variants
from .worker import VariantResult, VariantTask, run_variant


class SchedulerError(PpfabError):
    """The Dask scheduler given cannot be reached."""

    exit_code = 2


class SweepSetupError(PpfabError):
    """A library a sweep needs is not installed."""


@dataclass(frozen=True)
class SweepReport:
    """What a sweep did: variants in the sweep, computed now, skipped (already in the table), failed (of the
    sweep's variants), seconds, where the results are, and the rows of the sweep's variants (the table may
    hold more: variants of earlier sweeps into the same folder)."""

    variants: int
    computed: int
    skipped: int
    failed: int
    seconds: float
    out: Path
    rows: list[dict[str, Any]] = field(default_factory=list, repr=False)


def require() -> None:
    """Refuse in one line when the libraries of the ``sweep`` extra are missing."""
    import importlib.util

    missing = [m for m in ("distributed", "pyarrow", "plotly") if importlib.util.find_spec(m) is None]
    if missing:
        raise SweepSetupError(f"ppfab sweep needs {', '.join(missing)}: install them with "
                              "pip install 'ppfab[sweep]'")


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):       # pragma: no cover - not Linux
        return os.cpu_count() or 1


CONNECT_TIMEOUT_S = 20.0
"""How long a client tries to reach a scheduler given by ``--scheduler`` before giving up."""


def _client(scheduler: str | None, workers: int | None, processes: bool,
            timeout: float = CONNECT_TIMEOUT_S) -> tuple[Any, Any]:
    """``(client, cluster)``: a client of the scheduler at ``scheduler``, or of a new LocalCluster of
    ``workers`` single-threaded workers (``cluster`` is ``None`` for an existing scheduler)."""
    from distributed import Client, LocalCluster

    if logging.getLogger().getEffectiveLevel() > logging.INFO:      # the cluster's own log only with --verbose
        for name in ("distributed", "bokeh", "tornado"):
            logging.getLogger(name).setLevel(logging.ERROR)
    if scheduler:
        try:
            return Client(scheduler, timeout=f"{timeout}s"), None
        except (OSError, TimeoutError) as exc:
            raise SchedulerError(f"cannot reach the Dask scheduler at {scheduler} ({' '.join(str(exc).split())}); "
                                 "start one with `dask scheduler` and workers with `dask worker ADDRESS`") from None
    n = workers or cores()
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=processes, dashboard_address=None,
                           silence_logs=logging.ERROR)
    return Client(cluster), cluster


def _lost(exc: BaseException, key: str) -> VariantResult:
    """A task that produced no result (its worker died too often, it was cancelled) as a failed result."""
    from .worker import one_line

    name = type(exc).__name__
    if name == "KilledWorker":
        reason = ("the worker running it died each time it was tried (distributed.scheduler.allowed-failures); "
                  "too little memory?")
    else:
        reason = one_line(exc)
    return VariantResult(key, "failed", reason)


def run_sweep(spec: SweepSpec, out: str | os.PathLike, scheduler: str | None = None, workers: int | None = None,
              processes: bool = True, retry_failed: bool = False, quiet: bool = False,
              on_row: Callable[[dict[str, Any]], None] | None = None,
              connect_timeout: float = CONNECT_TIMEOUT_S) -> SweepReport:
    """Run every variant of ``spec`` not yet in ``out``'s table and write the results (see the module
    docstring); returns a :class:`SweepReport`.  ``on_row`` is called with each new row once it is written.
    A second sweep into the same folder at the same time is refused (:class:`~fabrication.pipeline.lock.OutputLock`)."""
    from ..pipeline.lock import OutputLock

    require()
    t0 = time.perf_counter()
    variants = make_variants(spec)
    with OutputLock(out):                      # one sweep at a time per results folder
        return _run_locked(spec, out, variants, t0, scheduler, workers, processes, retry_failed, quiet, on_row,
                           connect_timeout)


def _run_locked(spec: SweepSpec, out: str | os.PathLike, variants: list[Variant], t0: float,
                scheduler: str | None, workers: int | None, processes: bool, retry_failed: bool, quiet: bool,
                on_row: Callable[[dict[str, Any]], None] | None, connect_timeout: float) -> SweepReport:
    from .htmlpage import index_html

    folder = ResultsFolder.open(out, inputs=[spec.source, spec.base])
    rows = {r["variant"]: r for r in folder.read_table()}
    todo = [v for v in variants if v.key not in rows
            or (retry_failed and rows[v.key].get("status") != "ok")]
    build_root = Path(out).resolve() / "builds"
    if spec.stage == "files" and todo:
        build_root.mkdir(exist_ok=True)
    base_dir = str(spec.base.resolve().parent)
    computed = 0
    if todo:
        computed = _compute(spec, todo, folder, rows, (scheduler, workers, processes, connect_timeout), quiet,
                            base_dir, build_root, on_row)
    keys = {v.key for v in variants}
    mine = [r for r in rows.values() if r["variant"] in keys]
    title = f"Sweep {spec.source.name}: {len(variants)} variants of {spec.base.name}"
    page = index_html(mine, title, spec.pareto, earlier=len(rows) - len(mine)).encode("utf-8")
    old = folder.root / "index.html"
    if not old.is_file() or old.read_bytes() != page:        # a rerun that changes nothing writes nothing
        folder.commit({"index.html": page})
    return SweepReport(variants=len(variants), computed=computed, skipped=len(variants) - len(todo),
                       failed=sum(1 for r in mine if r["status"] != "ok"), seconds=time.perf_counter() - t0,
                       out=folder.root, rows=mine)


def _compute(spec: SweepSpec, todo: list[Variant], folder: ResultsFolder, rows: dict[str, dict[str, Any]],
             cluster_args: tuple[str | None, int | None, bool, float], quiet: bool, base_dir: str,
             build_root: Path, on_row: Callable[[dict[str, Any]], None] | None) -> int:
    """Submit ``todo`` to the cluster (``cluster_args``: scheduler, workers, processes, connect timeout) and
    write each row as its task finishes; returns how many finished."""
    from distributed import as_completed
    from tqdm import tqdm

    client, cluster = _client(*cluster_args)
    bar = tqdm(total=len(todo), desc="sweep", unit="variant", disable=quiet, file=sys.stderr,
               dynamic_ncols=True)
    failed = done = 0
    futures: list[Any] = []
    try:
        by_key = {v.key: v for v in todo}
        for v in todo:
            task = VariantTask(key=v.key, index=v.index, doc=v.doc, stage=spec.stage, base_dir=base_dir,
                               prices=spec.prices,
                               build_dir=str(build_root / v.key) if spec.stage == "files" else None)
            futures.append(client.submit(run_variant, task, key=f"ppfab-variant-{v.key}", pure=False))
        for fut in as_completed(futures):
            key = str(fut.key).removeprefix("ppfab-variant-")
            try:
                result = fut.result()
            except (Exception, asyncio.CancelledError, concurrent.futures.CancelledError) as exc:
                result = _lost(exc, key)     # the task itself never raises: this is the cluster's doing
            variant = by_key[result.key]
            folder.write_design(variant.key, design_text(variant.doc, _comment(spec, variant)))
            row = make_row(variant, result, spec.stage)
            rows[variant.key] = row
            folder.commit(table_bytes(list(rows.values())))
            done += 1
            failed += row["status"] != "ok"
            bar.set_postfix_str(f"failed {failed}", refresh=False)
            bar.update(1)
            if on_row is not None:
                on_row(row)
    finally:
        bar.close()
        for f in futures:
            if not f.done():
                f.cancel()
        client.close()
        if cluster is not None:
            cluster.close()
    return done


def _comment(spec: SweepSpec, v: Variant) -> str:
    values = ", ".join(f"{k} = {val!r}" for k, val in v.values.items())
    return (f"variant {v.key} (#{v.index}) of the sweep {spec.source.name} on {spec.base.name}: {values}\n"
            "build it with: ppfab build THIS_FILE -o OUT")
