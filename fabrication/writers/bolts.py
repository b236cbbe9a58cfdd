"""``bolts.csv``: the bolt sets of every bolted splice (:mod:`fabrication.glazing.bolts`), listed in the
manifest as ``files.bolts_csv``; nothing is written when the build has no bolted splice."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ..contract import BOLTS_CSV
from ..contract import BOLTS_COLUMNS
from ..glazing.bolts import splice_bolts, total_bolts
from ..parts import csv_text
from . import Files, writer

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord


def bolts_files(build: "BuildRecord") -> Files:
    """bolts.csv when the build has splices."""
    g = build.glazing
    return {"bolts_csv": BOLTS_CSV} if g is not None and g.splices else {}


@writer("bolts", order=26, declare=bolts_files)
def write_bolts(build: "BuildRecord", out: Path, files: Files) -> str:
    """One row per bolted splice: its bolt sets (size, grade, length from the grip, washers, nut, category)."""
    g = build.glazing
    if g is None or not g.splices:
        return "no bolted splices"
    sets = splice_bolts(g.splices, g.splice_params)
    (out / BOLTS_CSV).write_text(csv_text([s.row() for s in sets], BOLTS_COLUMNS), encoding="utf-8")
    return f"{total_bolts(sets)} bolt sets in {len(sets)} splices"
