"""What a Dask worker runs for one variant: :func:`run_variant` (a plain function of a :class:`VariantTask`).

It never raises for a design that cannot be built: the error becomes a ``failed`` :class:`VariantResult`
with its one-line reason, so one bad variant never stops a sweep.  It imports only ppfab (installed on every
worker) and touches no file except, for stage ``files``, the variant's own build folder.
"""

from __future__ import annotations

import os
import socket
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .figures import cost, measure_build, measure_geometry


@dataclass(frozen=True)
class VariantTask:
    """Everything a worker needs for one variant (pickled to it)."""

    key: str
    index: int
    doc: dict
    stage: str
    base_dir: str
    prices: dict[str, float] = field(default_factory=dict)
    build_dir: str | None = None


@dataclass(frozen=True)
class VariantResult:
    """The outcome of one variant: ``status`` ``"ok"`` or ``"failed"`` (with ``reason``, one line), the
    figures measured, and where it ran."""

    key: str
    status: str
    reason: str = ""
    figures: dict[str, Any] = field(default_factory=dict)
    worker: str = ""
    built: bool = False


def one_line(exc: BaseException) -> str:
    """An exception as one line: ppfab's own errors by their message, anything else with its type name.

    >>> one_line(ValueError("bad\\nvalue"))
    'ValueError: bad value'
    """
    from ppfab.errors import PpfabError

    text = " ".join(str(exc).split())
    return text if isinstance(exc, PpfabError) and text else f"{type(exc).__name__}: {text}"


def compute(task: VariantTask) -> dict[str, Any]:
    """The figures of ``task`` (raises what the design or the build raises)."""
    from ..design import parse_design
    from ..pipeline import stages
    from ..progress import Progress
    from ..pipeline.records import PanelSet

    design = parse_design(task.doc, source=f"variant {task.key}", base_dir=Path(task.base_dir))
    p = Progress(quiet=True)
    if task.stage == "geometry":
        geometry = stages.stage_geometry(design, p, False)
        quality = stages.stage_quality(geometry, p)
        support = stages.stage_support(design, geometry, p)
        panels: PanelSet = stages.stage_panels(design, geometry, p, quality)
        return measure_geometry(design, geometry, quality, support, panels)
    result = stages.build(design, progress=p)
    if task.stage == "files" and task.build_dir is not None:
        before = os.environ.get("PPFAB_PARALLEL_WRITERS")
        os.environ["PPFAB_PARALLEL_WRITERS"] = "0"        # a worker is one core of the sweep already
        try:
            result.write(task.build_dir, force=True)
        finally:
            if before is None:
                os.environ.pop("PPFAB_PARALLEL_WRITERS", None)
            else:
                os.environ["PPFAB_PARALLEL_WRITERS"] = before
    return measure_build(result)


def run_variant(task: VariantTask) -> VariantResult:
    """Compute one variant; any error is returned as a failed result (never raised)."""
    import logging

    logging.getLogger("ppfab").setLevel(logging.ERROR)
    where = f"{socket.gethostname()}:{os.getpid()}"
    cpu, wall = time.thread_time(), time.perf_counter()
    try:
        figures = compute(task)
    except Exception as exc:       # one variant's failure is its own row, never the sweep's
        return VariantResult(task.key, "failed", one_line(exc), {"cpu_s": time.thread_time() - cpu,
                                                                 "wall_s": time.perf_counter() - wall}, where)
    figures["cost"] = cost(figures, task.prices)
    figures["cpu_s"] = time.thread_time() - cpu
    figures["wall_s"] = time.perf_counter() - wall
    return VariantResult(task.key, "ok", "", figures, where, built=task.stage == "files")
