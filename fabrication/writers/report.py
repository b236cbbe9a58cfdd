"""``report.html``: one self-contained page (inline CSS, figures as data URIs, sheets as inline SVG)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from . import Files, writer

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord


@writer("report", order=80, declare=lambda build: {"report_html": "report.html"},
        enabled=lambda design: design.output.report)
def write_report(build: "BuildRecord", out: Path, files: Files) -> str:
    from ..report import build_report

    drawings = {}
    for key in ("drawings", "node_sheets"):
        for rel in files.get(key, []):
            drawings[str(rel)] = (out / str(rel)).read_text(encoding="utf-8")
    others = {k: v for k, v in files.items() if k != "report_html"}     # the page lists the other files
    html = build_report(build, others, list(build.parts), drawings)
    (out / "report.html").write_text(html, encoding="utf-8")
    return f"{len(html) / 1e6:.1f} MB"
