"""The record of one output writer and the ``files`` table the writers fill (no imports of the writers)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable

if TYPE_CHECKING:  # pragma: no cover
    from ..design import Design
    from ..records import BuildRecord

Files = dict[str, "str | list[str]"]
"""The manifest's ``files`` table: key → a path or a list of paths relative to the output folder."""


@dataclass(frozen=True)
class Writer:
    """One entry of :data:`WRITERS`."""

    name: str
    order: int
    write: Callable[["BuildRecord", Path, Files], str]
    enabled: Callable[["Design"], bool]


