"""The output writers: one module per output format, registered in a table.

A writer is a function ``write(build, out, files) -> str`` that writes its files into the (temporary) output
folder ``out`` and records each under a key of ``files`` (the manifest's ``files`` table, in writing
order); it returns a short note for the progress display.  Modules of this package register theirs with
:func:`writer`, with an ``order`` (mesh 10, STEP 20, DXF sheets 30, per-type DXF 35, R12/R2000 DXF 40, tables 50, IFC 60, Rhino 65,
glTF 70, report 80, manifest 90) and an
``enabled(design)`` predicate for optional files; :func:`write_all` runs them in order.  Adding an output
format is one new module.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Callable

from ppfab.registry import Registry

from .base import Files, Writer

if TYPE_CHECKING:  # pragma: no cover
    from ..design import Design
    from ..progress import Progress
    from ..records import BuildRecord

_TABLE: Registry[Writer] = Registry("writer", "fabrication.writers")
WRITERS: dict[str, Writer] = _TABLE.entries


def writer(name: str, order: int, enabled: Callable[["Design"], bool] | None = None) -> Callable:
    """Decorator registering ``write(build, out, files) -> note`` as the writer ``name``."""
    def register(fn: Callable[["BuildRecord", Path, Files], str]) -> Callable[["BuildRecord", Path, Files], str]:
        _TABLE.add(name, Writer(name, order, fn, enabled or (lambda design: True)))
        return fn
    return register


def load_writers() -> list[Writer]:
    """Import every writer module of this package (once); the writers in their order."""
    return sorted(_TABLE.load().values(), key=lambda w: (w.order, w.name))


def write_all(build: "BuildRecord", out: Path, progress: "Progress", parallel: bool | None = None) -> Files:
    """Run every enabled writer in order into ``out``; returns the ``files`` table.

    With ``parallel`` (default: :func:`~fabrication.writers._parallel.parallel_enabled`, on with two cores) the
    per-type DXFs are written in a second process beside the others (:mod:`fabrication.writers._parallel`); the files
    and the table are the same either way.  An optional file that fails stops the build with an error naming the
    file, the part and the ``[output]`` key that skips it (:mod:`fabrication.writers._failures`).
    """
    from ._failures import guarded
    from ._parallel import SECOND_PROCESS, parallel_enabled, write_split

    enabled = [guarded(w) for w in load_writers() if w.enabled(build.design)]
    if parallel is None:
        parallel = parallel_enabled()
    if parallel and any(w.name in SECOND_PROCESS for w in enabled):
        return write_split(build, out, progress, enabled)
    files: Files = {}
    progress.watch(out)                       # the status counts the files written so far
    try:
        for k, w in enumerate(enabled):
            progress.start(w.name)
            progress.advance(k, None, f"file set {k + 1} of {len(enabled)}")
            try:
                note = w.write(build, out, files)
            except BaseException:
                progress.fail()
                raise
            progress.done(note)
    finally:
        progress.watch(None)
    return files
