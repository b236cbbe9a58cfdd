"""The rows of the parts list of a build, made once: :class:`PartsTable`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterator

Row = dict[str, Any]
"""One row of ``parts.csv``: column name → cell (str, int or float; ``""`` for a blank)."""


@dataclass(frozen=True)
class PartsTable:
    """Every part of a build as a row of ``parts.csv`` / ``parts.json``, in the order written: glass panels,
    beam plates, glazing strips, splice cover plates, retention parts.

    Made once per build by the pipeline (:func:`fabrication.parts.parts_table`), before any file is written;
    every writer that lists parts (the tables, the report, IFC, Rhino, glTF) reads it here.  The columns are
    named in :mod:`fabrication.contract` (``PARTS_CONTRACT_COLUMNS``, ``PARTS_KNOWN_COLUMNS``).  A reader must
    not change a row: take ``dict(row)`` to add cells of its own.
    """

    rows: tuple[Row, ...] = ()

    def __iter__(self) -> Iterator[Row]:
        return iter(self.rows)

    def __len__(self) -> int:
        return len(self.rows)

    def by_id(self) -> dict[str, Row]:
        """Part id → row."""
        return {str(r["part_id"]): r for r in self.rows}
