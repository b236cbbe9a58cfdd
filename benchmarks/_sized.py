"""The design the benchmarks build: the bundled default (or another design file) cut into ``faces_u x faces_v``
faces, with both nesting budgets set (the budget buys a fixed work count, so nesting costs the same at every
size), shared by ``pipeline.py`` and ``ifc_writer.py``."""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any


def sized_design(size: str, budget: float, design: Path | None = None, paper: str | None = None) -> Any:
    """The parsed design ``design`` (the bundled default when ``None``) at ``size`` faces (``"44x30"``), both
    nesting budgets ``budget`` s, and ``[output] paper`` when given."""
    from fabrication import parse_design
    from fabrication.design import DEFAULT_DESIGN

    path = design or DEFAULT_DESIGN
    fu, fv = (int(x) for x in size.split("x"))
    doc = tomllib.loads(path.read_text(encoding="utf-8"))
    doc["geometry"].setdefault("params", {}).update(faces_u=fu, faces_v=fv)
    for section in ("nesting", "beam_nesting"):
        doc.setdefault(section, {})["time_budget"] = budget
    if paper:
        doc.setdefault("output", {})["paper"] = paper
    return parse_design(doc, str(path), "", path.resolve().parent)
