"""The record of one output writer and the ``files`` table the writers fill (no imports of the writers)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable

if TYPE_CHECKING:  # pragma: no cover
    from ..design import Design
    from ..progress import Progress
    from ..records import BuildRecord

Files = dict[str, "str | list[str]"]
"""The manifest's ``files`` table: key → a path or a list of paths relative to the output folder."""


def listed_files(files: Files) -> list[str]:
    """Every path in the ``files`` table, sorted, each once."""
    out: list[str] = []
    for value in files.values():
        if isinstance(value, str):
            out.append(value)
        else:
            out.extend(v for v in value if isinstance(v, str))
    return sorted(set(out))


@dataclass(frozen=True)
class Writer:
    """One entry of :data:`WRITERS`: ``declare(build)`` names every file ``write(build, out, files)`` will
    write (its entries of the ``files`` table, before any file is written); ``write`` writes exactly those,
    reading the build and the whole declared table (never a file another writer wrote)."""

    name: str
    order: int
    write: Callable[["BuildRecord", Path, Files], str]
    enabled: Callable[["Design"], bool]
    declare: Callable[["BuildRecord"], Files] = lambda build: {}




def run_writer(w: Writer, build: "BuildRecord", out: Path, files: Files, progress: "Progress",
               place: tuple[int, int] | None = None) -> None:
    """Run one writer as a stage of the progress display (``place``: its index and the count of file sets, shown
    as "file set k of n"); a failure marks the stage failed and propagates."""
    progress.start(w.name)
    if place is not None:
        progress.advance(place[0], None, f"file set {place[0] + 1} of {place[1]}")
    try:
        note = w.write(build, out, files)
    except BaseException:
        progress.fail()
        raise
    progress.done(note)
