"""``ppfab sweep --best FIGURE``: the design file of the best variant, ready for ``ppfab build``."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..pipeline.overwrite import OutputFileError, check_output_file, write_output_text, written_by_ppfab
from .figures import FIGURES
from .pareto import best_row
from .store import ResultsFolder, strip_stamp


@dataclass(frozen=True)
class Best:
    """The best variant's row and the design file written for it."""

    row: dict[str, Any]
    path: Path


def write_best(out: str | os.PathLike, figure: str, target: str | os.PathLike | None = None,
               among: "set[str] | None" = None) -> Best:
    """Write the design of the successful variant of the results folder ``out`` with the best ``figure``
    (smallest or largest, :data:`~fabrication.sweep.figures.FIGURES`) to ``target`` (default
    ``out/best-<figure>.toml``); ``among``: only these variant keys (the current sweep's; default every row).
    An existing target is replaced only when ppfab wrote it."""
    if not (Path(out) / "results.parquet").is_file():
        raise OutputFileError(f"{out} holds no sweep results (results.parquet); run the sweep first")
    folder = ResultsFolder.open(out)
    row = best_row([r for r in folder.read_table() if among is None or r["variant"] in among], figure)
    source = folder.root / row["design"]
    if not written_by_ppfab(source):
        raise OutputFileError(f"{source} was not written by ppfab or was changed since; run the sweep again to "
                              "write it anew")
    f = FIGURES[figure]
    head = (f"# best variant by {figure} ({f.better}imum {row[figure]:.6g}{' ' + f.unit if f.unit else ''}): "
            f"{row['variant']}\n")
    text = head + strip_stamp(source.read_text(encoding="utf-8"))
    path = Path(target) if target is not None else folder.root / f"best-{figure}.toml"
    t = check_output_file(path, inputs=[source], force=True)
    write_output_text(t, text)
    return Best(row, t.path)
