"""Design-space sweeps: many variants of one design, computed on a Dask cluster, into one results table.

From Python::

    import fabrication.sweep
    report = fabrication.sweep("sweep.toml", "results")      # or fabrication.sweep.sweep(...)
    report.computed, report.failed, report.rows[0]["glass_sheets"]

The command line is ``ppfab sweep SWEEP.toml -o RESULTS`` (docs/sweeps.md).  Modules: :mod:`.spec` (the sweep
file), :mod:`.variants` (the designs and their keys), :mod:`.worker` (one variant, on a worker),
:mod:`.figures` (what is measured, the cost model), :mod:`.store` (the results folder), :mod:`.table` (Parquet
and CSV), :mod:`.engine` (Dask), :mod:`.htmlpage` (index.html), :mod:`.pareto` (front and best variant).
"""

from __future__ import annotations

import os
import sys
import types
from typing import Any

from .spec import SweepSpec, load_sweep, parse_sweep

__all__ = ["SweepSpec", "load_sweep", "parse_sweep", "sweep", "write_best"]


def sweep(spec: "SweepSpec | str | os.PathLike", out: str | os.PathLike, scheduler: str | None = None,
          workers: int | None = None, processes: bool = True, retry_failed: bool = False,
          quiet: bool = True) -> Any:
    """Run a sweep (a :class:`SweepSpec` or the path of a sweep file) into the folder ``out``; returns the
    :class:`~fabrication.sweep.engine.SweepReport`.

    ``scheduler``: ``tcp://HOST:PORT`` of a running Dask scheduler (default: a LocalCluster of ``workers``
    single-threaded workers, one per core; ``processes=False`` runs them as threads of this process).
    ``retry_failed``: compute the variants that failed before again.
    """
    from .engine import run_sweep

    s = spec if isinstance(spec, SweepSpec) else load_sweep(spec)
    return run_sweep(s, out, scheduler=scheduler, workers=workers, processes=processes,
                     retry_failed=retry_failed, quiet=quiet)


def write_best(out: str | os.PathLike, figure: str, target: str | os.PathLike | None = None) -> Any:
    """Write the design of the best variant by ``figure`` in the results folder ``out`` (see
    :func:`fabrication.sweep.best.write_best`)."""
    from .best import write_best as _write_best

    return _write_best(out, figure, target)


class _CallableModule(types.ModuleType):
    """``fabrication.sweep(...)`` is :func:`sweep`."""

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return sweep(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
