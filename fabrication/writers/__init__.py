"""The output writers: one module per output format, registered in a table.

A writer is a function ``write(build, out, files) -> str`` that writes its files into the (temporary) output
folder ``out`` and records each under a key of ``files`` (the manifest's ``files`` table, in writing
order); it returns a short note for the progress display.  Modules of this package register theirs with
:func:`writer`, with an ``order`` (mesh 10, STEP 20, DXF 30, R12/R2000 DXF 40, tables 50, IFC 60, Rhino 65,
glTF 70, report 80, manifest 90) and an
``enabled(design)`` predicate for optional files; :func:`write_all` runs them in order.  Adding an output
format is one new module.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from ppfab.registry import Registry

if TYPE_CHECKING:  # pragma: no cover
    from ..design import Design
    from ..pipeline.progress import Progress
    from ..pipeline.records import Build

Files = dict[str, "str | list[str]"]
"""The manifest's ``files`` table: key → a path or a list of paths relative to the output folder."""


@dataclass(frozen=True)
class Writer:
    """One entry of :data:`WRITERS`."""

    name: str
    order: int
    write: Callable[["Build", Path, Files], str]
    enabled: Callable[["Design"], bool]


_TABLE: Registry[Writer] = Registry("writer", "fabrication.writers")
WRITERS: dict[str, Writer] = _TABLE.entries


def writer(name: str, order: int, enabled: Callable[["Design"], bool] | None = None) -> Callable:
    """Decorator registering ``write(build, out, files) -> note`` as the writer ``name``."""
    def register(fn: Callable[["Build", Path, Files], str]) -> Callable[["Build", Path, Files], str]:
        _TABLE.add(name, Writer(name, order, fn, enabled or (lambda design: True)))
        return fn
    return register


def load_writers() -> list[Writer]:
    """Import every writer module of this package (once); the writers in their order."""
    return sorted(_TABLE.load().values(), key=lambda w: (w.order, w.name))


def write_all(build: "Build", out: Path, progress: "Progress") -> Files:
    """Run every enabled writer in order into ``out``; returns the ``files`` table."""
    files: Files = {}
    writers = [w for w in load_writers() if w.enabled(build.design)]
    progress.watch(out)                       # the status counts the files written so far
    try:
        for k, w in enumerate(writers):
            progress.start(w.name)
            progress.advance(k, None, f"file set {k + 1} of {len(writers)}")
            try:
                note = w.write(build, out, files)
            except BaseException:
                progress.fail()
                raise
            progress.done(note)
    finally:
        progress.watch(None)
    return files
