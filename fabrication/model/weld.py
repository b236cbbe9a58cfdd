"""The record of one weld as ``welds.csv`` holds it: :class:`Weld`."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Mapping

from . import values as v
from .part import column, fill


@dataclass(frozen=True)
class Weld:
    """One weld: the node (``None`` for a welded splice, which has none), the plate welded and the one it is
    welded to, the angle between them, the weld length (mm), preparation, throat (mm) and the joint: ``T``,
    ``halflap``, ``corner`` or ``splice``.  Builds before ``welds.csv`` had ``joint`` listed only T joints
    (docs/migration.md): a row without it reads as ``T``.  Other columns are kept in ``extra``."""

    node: int | None = column("node", v.opt_int)
    part: str = column("part", v.text, "")
    to: str = column("to", v.text, "")
    dihedral_deg: float | None = column("dihedral_deg", v.opt_float)
    weld_length_mm: float | None = column("weld_length_mm", v.opt_float)
    preparation: str = column("preparation", v.text, "")
    throat_mm: float | None = column("throat_mm", v.opt_float)
    joint: str = column("joint", v.text, "T")
    extra: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def from_columns(cls, cols: Mapping[str, Any]) -> "Weld":
        """From one row (CSV text or values); raises :class:`~fabrication.model.part.ColumnError`."""
        weld, used = fill(cls, cols)
        extra = {k: val for k, val in cols.items() if k not in used and not v.empty(val)}
        return replace(weld, extra=extra) if extra else weld
