"""``drawings/drawings.pdf``: the drawing set as one PDF, a page per sheet at its paper size, in the order of
the sheet register (key plan, elevations, erection drawing, node sheets); manifest key ``drawings_pdf``.

Each page is drawn with matplotlib's PDF backend from the SVG sheet written before it (the subset of SVG the
drawings use: nested ``<svg>`` views, ``rect``, ``polygon``, ``polyline`` and ``text``), so the PDF shows what
the SVG files say; text stays text (TrueType subsets, ``pdf.fonttype`` 42), so it can be searched.  The file is
reproducible: no creation date, fonts embedded as subsets in a fixed order."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from . import Files, writer

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord

DRAWINGS_PDF = "drawings/drawings.pdf"
_NS = "{http://www.w3.org/2000/svg}"
PT_PER_MM = 72.0 / 25.4


def _floats(text: str) -> np.ndarray:
    return np.array([[float(c) for c in p.split(",")] for p in text.split()])


def _colour(value: str | None) -> str:
    return "none" if value in (None, "none") else str(value)


def draw_sheet(ax, root: ET.Element) -> None:
    """Draw the SVG sheet ``root`` (paper mm) onto the matplotlib axes ``ax`` (limits set to the paper).

    Consecutive shapes of one style (fill, stroke, width, opacity, open or closed) go into one
    ``PolyCollection``, drawn in the sheet's order: a patch per shape cost matplotlib a transform and a limit
    update each (most of a page's time on the large views); texts are drawn above the shapes either way."""
    from matplotlib.collections import PolyCollection

    run: list[np.ndarray] = []
    style: tuple = ()

    def flush() -> None:
        if run:
            fill, stroke, lw, alpha, closed = style
            ax.add_collection(PolyCollection(list(run), closed=closed, facecolors=fill, edgecolors=stroke,
                                             linewidths=lw, alpha=alpha, joinstyle="miter", capstyle="butt"),
                              autolim=False)
            run.clear()

    def walk(el: ET.Element, origin: np.ndarray, scale: float) -> None:
        nonlocal style
        for child in el:
            tag = child.tag.removeprefix(_NS)
            if tag == "svg":
                _, _, w, _ = (float(t) for t in child.get("viewBox", "0 0 1 1").split())
                s = float(child.get("width", "1").removesuffix("mm")) / w
                at = origin + scale * np.array([float(child.get("x", 0)), float(child.get("y", 0))])
                walk(child, at, scale * s)
            elif tag == "g":
                walk(child, origin, scale)
            elif tag in ("polygon", "polyline", "rect"):
                if tag == "rect":
                    x, y = float(child.get("x", 0)), float(child.get("y", 0))
                    w, h = float(child.get("width", 0)), float(child.get("height", 0))
                    pts = np.array([[x, y], [x + w, y], [x + w, y + h], [x, y + h]])
                else:
                    pts = _floats(child.get("points", ""))
                fill = _colour(child.get("fill")) if tag != "polyline" else "none"
                stroke = _colour(child.get("stroke"))
                lw = float(child.get("stroke-width", 0)) * scale * PT_PER_MM if stroke != "none" else 0.0
                key = (fill, stroke, lw, float(child.get("fill-opacity", 1.0)) if fill != "none" else None,
                       tag != "polyline")
                if key != style:
                    flush()
                    style = key
                run.append(origin + scale * pts)
            elif tag == "text" and child.text:
                rot = re.findall(r"rotate\(([-0-9.e]+)", child.get("transform", ""))
                x, y = origin + scale * np.array([float(child.get("x", 0)), float(child.get("y", 0))])
                ax.text(x, y, child.text, fontsize=float(child.get("font-size", 1)) * scale * PT_PER_MM,
                        family="DejaVu Sans Mono", color=child.get("fill", "#000000"),
                        rotation=-float(rot[0]) if rot else 0.0, rotation_mode="anchor",
                        ha={"start": "left", "end": "right"}.get(child.get("text-anchor", "start"), "center"),
                        va="center")

    walk(root, np.zeros(2), 1.0)
    flush()


def write_pdf(sheets: list[Path], path: Path) -> None:
    """One PDF page per SVG sheet, each at the sheet's paper size (its ``viewBox`` in mm)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.backends.backend_pdf import PdfPages

    with matplotlib.rc_context({"pdf.fonttype": 42}), \
            PdfPages(path, metadata={"Creator": "ppfab", "CreationDate": None, "ModDate": None}) as pdf:
        for sheet in sheets:
            root = ET.parse(sheet).getroot()
            _, _, w, h = (float(t) for t in root.get("viewBox", "0 0 1 1").split())
            fig = plt.figure(figsize=(w / 25.4, h / 25.4))
            ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
            ax.set_xlim(0.0, w)
            ax.set_ylim(h, 0.0)
            ax.set_axis_off()
            draw_sheet(ax, root)
            pdf.savefig(fig)
            plt.close(fig)


@writer("drawings_pdf", order=78, declare=lambda build: {"drawings_pdf": DRAWINGS_PDF})
def write_drawings_pdf(build: "BuildRecord", out: Path, files: Files) -> str:
    """The drawing set as ``drawings/drawings.pdf`` (every sheet the drawing and erection writers wrote)."""
    from .drawings import sheet_register

    sheets = [rel for rel in sheet_register(build) if (out / rel).is_file()]
    write_pdf([out / rel for rel in sheets], out / DRAWINGS_PDF)
    return f"{len(sheets)} pages"
