"""The output writers: one module per output format, registered in a table.

A writer is two functions: ``declare(build) -> Files`` names the files it will write, under keys of the
manifest's ``files`` table, from the build alone; ``write(build, out, files) -> str`` writes exactly those
files into the (temporary) output folder ``out`` and returns a short note for the progress display.  The
table ``files`` it gets is every writer's declaration, made before any file is written, so a writer reads
only the build and names (the manifest lists and digests every file, the report links them), never what
another writer computed.  Modules of this package register theirs with :func:`writer`, with an ``order``
(mesh 10, STEP 20, glazing 25, bolts 26, DXF sheets 30, per-type DXF 35, R12/R2000 DXF 40, tables 50, IFC 60,
Rhino 65, glTF 70, drawings 75, erection 77, PDF 78, report 80, manifest 90) and an ``enabled(design)``
predicate for optional files; :func:`write_all` runs them in order and holds every writer to its
declaration.  Adding an output format is one new module.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Callable

from ppfab.registry import Registry

from .base import Files, Writer, listed_files, run_writer

if TYPE_CHECKING:  # pragma: no cover
    from ..design import Design
    from ..progress import Progress
    from ..records import BuildRecord

_TABLE: Registry[Writer] = Registry("writer", "fabrication.writers")
WRITERS: dict[str, Writer] = _TABLE.entries


def writer(name: str, order: int, declare: Callable[["BuildRecord"], Files],
           enabled: Callable[["Design"], bool] | None = None) -> Callable:
    """Decorator registering ``write(build, out, files) -> note`` as the writer ``name``, which writes the files
    ``declare(build)`` names."""
    def register(fn: Callable[["BuildRecord", Path, Files], str]) -> Callable[["BuildRecord", Path, Files], str]:
        _TABLE.add(name, Writer(name, order, fn, enabled or (lambda design: True), declare))
        return fn
    return register


def declared_files(build: "BuildRecord", writers: list[Writer]) -> Files:
    """The ``files`` table of a build: every writer's declaration, in writer order."""
    files: Files = {}
    for w in writers:
        files.update(w.declare(build))
    return files


def check_declared(out: Path, files: Files, writers: list[Writer]) -> None:
    """Raise :class:`~ppfab.errors.FabricationError` unless the folder ``out`` holds exactly the declared files
    (and ``manifest.json``): a writer that wrote less or more than it declared is a bug of ppfab's."""
    from ppfab.errors import FabricationError

    from ..contract import PARTIAL_MARKER

    wanted = set(listed_files(files)) | {"manifest.json"}
    written = {p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file() and p.name != PARTIAL_MARKER}
    missing, extra = sorted(wanted - written), sorted(written - wanted)
    if missing or extra:
        raise FabricationError(f"the writers ({', '.join(w.name for w in writers)}) did not write what they "
                               f"declared: missing {missing[:5]}, not declared {extra[:5]} (a bug of ppfab: "
                               "please report it with the design)")


def load_writers() -> list[Writer]:
    """Import every writer module of this package (once); the writers in their order."""
    return sorted(_TABLE.load().values(), key=lambda w: (w.order, w.name))


def write_all(build: "BuildRecord", out: Path, progress: "Progress", parallel: bool | None = None) -> Files:
    """Run every enabled writer in order into ``out``; returns the ``files`` table.

    With ``parallel`` (default: :func:`~fabrication.writers._parallel.parallel_enabled`, on with two cores) the
    per-type DXFs, the IFC and the 3dm file are written in a second process beside the others
    (:mod:`fabrication.writers._parallel`); the glTF file (and without a second process the IFC and the 3dm file
    too) is written in a forked process of its own (:data:`~fabrication.writers._parallel.CONFINED`: what they
    allocate stays with the process).  The
    files and the table are the same either way.  An optional file that fails stops the build with an error naming the
    file, the part and the ``[output]`` key that skips it (:mod:`fabrication.writers._failures`).
    """
    from ._failures import guarded
    from ._parallel import CONFINED, SECOND_PROCESS, confined, parallel_enabled, write_split

    enabled = [guarded(w) for w in load_writers() if w.enabled(build.design)]
    files = declared_files(build, enabled)
    if parallel is None:
        parallel = parallel_enabled()
    if parallel and any(w.name in SECOND_PROCESS for w in enabled):
        write_split(build, out, progress, enabled, files)
    else:
        progress.watch(out)                       # the status counts the files written so far
        try:
            for k, w in enumerate(enabled):
                run_writer(confined(w) if w.name in CONFINED else w, build, out, files, progress, (k, len(enabled)))
        finally:
            progress.watch(None)
    check_declared(out, files, enabled)
    return files
