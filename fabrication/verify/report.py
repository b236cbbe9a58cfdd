"""report.html: the figures of the report regenerated from the files and compared, table by table.

The page's tables are read back with the standard library's HTML parser, and each figure is set against the
same figure from the files: the summary (:func:`~fabrication.verify.summary.recompute_summary`, the totals the
summary check holds the manifest to), the rows of the panel, beam plate and node tables (``parts.csv`` and
``nodes.csv``), the glass support tables (``bites.csv``), the weld preparations (``welds.csv``) and the list of
files (the manifest's ``files``).  A number shown rounded (``85.3 m²``, ``1,970.5``, ``3.963e-15``) matches
when the figure from the files rounds to it, within the rounding of the table it comes from.  Text the report
adds around the figures (headings, notes, the embedded figures and drawings) is not compared.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from html.parser import HTMLParser
from typing import Any, Callable

import numpy as np

from . import Verification, check, read_csv
from .summary import Figure, recompute_summary

REL = "report.html"


@dataclass
class Table:
    """One ``<table>`` of the page: the heading above it, its header cells and its rows of cell texts."""

    heading: str
    kv: bool
    header: list[str] = field(default_factory=list)
    rows: list[list[str]] = field(default_factory=list)


class _Tables(HTMLParser):
    """Collects the tables of a page with the last ``h2``/``h3`` heading before each."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tables: list[Table] = []
        self.heading = ""
        self._in_heading = False
        self._cell: list[str] | None = None
        self._row: list[str] | None = None
        self._head = False

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag in ("h2", "h3"):
            self._in_heading, self.heading = True, ""
        elif tag == "table":
            self.tables.append(Table(self.heading, ("class", "kv") in attrs))
        elif tag == "tr" and self.tables:
            self._row = []
        elif tag in ("td", "th") and self._row is not None:
            self._cell, self._head = [], tag == "th"

    def handle_endtag(self, tag: str) -> None:
        if tag in ("h2", "h3"):
            self._in_heading = False
        elif tag in ("td", "th") and self._cell is not None and self._row is not None:
            self._row.append("".join(self._cell).strip())
            self._cell = None
        elif tag == "tr" and self._row is not None and self.tables:
            t = self.tables[-1]
            if self._head and not t.rows:
                t.header = self._row
            else:
                t.rows.append(self._row)
            self._row = None

    def handle_data(self, data: str) -> None:
        if self._in_heading:
            self.heading += data
        elif self._cell is not None:
            self._cell.append(data)


def read_tables(text: str) -> list[Table]:
    """The tables of an HTML page (:class:`Table`)."""
    p = _Tables()
    p.feed(text)
    p.close()
    return p.tables


_NUMBER = re.compile(r"-?\d[\d,]*(?:\.\d+)?(?:e[-+]?\d+)?")


def shown(text: str) -> list[tuple[float, float]]:
    """Every number in a cell's text with how far it may be from what it shows: ``(value, half a unit of the
    last digit shown)`` (thousands separators read; ``1.2e-05`` by its mantissa's digits)."""
    out = []
    for tok in _NUMBER.findall(text):
        mant, _, exp = tok.replace(",", "").partition("e")
        decimals = len(mant.partition(".")[2])
        value = float(mant) * 10.0 ** int(exp or 0)
        out.append((value, 0.5 * 10.0 ** (int(exp or 0) - decimals)))
    return out


def fmt_step(value: float) -> float:
    """Half a unit of the last digit :func:`fabrication.htmlreport.fmt` keeps of a float (it trims trailing
    zeros, so the digits shown understate it): two decimals from 1 up, four significant digits below."""
    a = abs(value)
    if a == 0:
        return 0.0
    if a >= 1e5 or a < 1e-3:
        return 0.5 * 10.0 ** (math.floor(math.log10(a)) - 3)
    return 0.005 if a >= 1 else 0.5 * 10.0 ** (math.floor(math.log10(a)) - 3)


@dataclass
class _Compare:
    v: Verification

    def numbers(self, element: str, text: str, want: list[float], slack: list[float] | None = None,
                table_fmt: bool = False) -> None:
        """Name ``element`` when the numbers of ``text`` are not ``want`` as rounded for display."""
        got = shown(text)
        slack = slack or [0.0] * len(want)
        bad = len(got) != len(want)
        for (g, step), w, s in zip(got, want, slack):
            tol = (max(step, fmt_step(w)) if table_fmt else step) + s + 1e-9 * abs(w)
            bad = bad or not abs(g - w) <= tol
        if bad:
            self.v.error(REL, element, f"{text!r} in the report, {_show(want)} from the files")

    def text(self, element: str, got: str, want: str) -> None:
        if got != want:
            self.v.error(REL, element, f"{got!r} in the report, {want!r} from the files")


def _show(values: list[float]) -> str:
    return " / ".join(f"{x:.6g}" for x in values)


def _num(text: Any) -> float:
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


SUMMARY_ROWS: dict[str, Callable[[dict[str, Figure]], tuple[list[float], list[float]]]] = {
    "structure size (x × y × z)": lambda s: ([x / 1000 for x in s["extent_mm"].value], [1e-9] * 3),
    "panels / panel types": lambda s: ([s["panels"].value, s["panel_types"].value], [0, 0]),
    "beams / plates / plate types": lambda s: ([s["beams"].value, s["beam_plates"].value, s["beam_types"].value],
                                               [0, 0, 0]),
    "nodes": lambda s: ([s["nodes"].value], [0]),
    "glass area": lambda s: ([s["glass_area_m2"].value], [s["glass_area_m2"].tolerance]),
    "glass weight": lambda s: ([s["glass_weight_kg"].value / 1000], [s["glass_weight_kg"].tolerance / 1000]),
    "total beam length": lambda s: ([s["beam_length_m"].value], [s["beam_length_m"].tolerance]),
    "plate area / weight": lambda s: ([s["plate_area_m2"].value, s["beam_mass_kg"].value / 1000],
                                      [s["plate_area_m2"].tolerance, s["beam_mass_kg"].tolerance / 1000]),
    "steel take-off (plates, strips, cover plates)": lambda s: ([s["steel_mass_kg"].value / 1000],
                                                                [s["steel_mass_kg"].tolerance / 1000]),
    "weld length": lambda s: ([s["weld_length_m"].value], [s["weld_length_m"].tolerance]),
    "glass retention (blocks, stops, gaskets, plates, caps, screws)":
        lambda s: ([s["retention_mass_kg"].value], [s["retention_mass_kg"].tolerance]),
}
"""Summary rows of the report: label → (the figures it shows, each one's rounding in the files)."""


def _summary(c: _Compare, table: Table, figures: dict[str, Figure], manifest: dict[str, Any]) -> None:
    summary = manifest.get("summary", {}) if isinstance(manifest.get("summary"), dict) else {}
    for row in table.rows:
        if len(row) != 2:
            continue
        label, text = row
        make = SUMMARY_ROWS.get(label)
        if make is not None:
            try:
                want, slack = make(figures)
            except KeyError:
                continue
            c.numbers(f"Summary: {label}", text, want, slack)
            continue
        for prefix in ("glass", "plate"):
            if label == f"{prefix} sheets (utilisation; lower bound)" and f"{prefix}_utilisation" in figures:
                fig = figures[f"{prefix}_utilisation"]
                c.numbers(f"Summary: {label}", text, [figures[f"{prefix}_sheets"].value, 100 * fig.value,
                                                      _num(summary.get(f"{prefix}_lower_bound"))],
                          [0, 100 * fig.tolerance, 0])


def _rows_by_first(table: Table) -> dict[str, list[str]]:
    return {r[0]: r for r in table.rows if r}


def _parts_table(c: _Compare, table: Table, title: str, parts: dict[str, dict[str, str]],
                 columns: dict[str, tuple[str, float, float]], texts: dict[str, str]) -> None:
    """Rows of a parts table: ``columns`` report column → (parts.csv column, scale, rounding in parts.csv);
    ``texts`` report column → parts.csv column compared as text."""
    index = {h: k for k, h in enumerate(table.header)}
    seen = set()
    for row in table.rows:
        pid = row[0] if row else ""
        part = parts.get(pid)
        if part is None:
            c.v.error(REL, f"{title}: {pid}", "is not a part of that kind in parts.csv")
            continue
        seen.add(pid)
        for col, (src, scale, slack) in columns.items():
            k = index.get(col)
            if k is not None and k < len(row) and part.get(src, "") != "":
                c.numbers(f"{title}: {pid} column {col}", row[k], [_num(part[src]) * scale], [slack * scale],
                          table_fmt=True)
        for col, src in texts.items():
            k = index.get(col)
            if k is not None and k < len(row):
                c.text(f"{title}: {pid} column {col}", row[k], part.get(src, ""))
    for pid in sorted(set(parts) - seen):
        c.v.error(REL, f"{title}: {pid}", "row missing")


def _nodes_table(c: _Compare, table: Table, nodes: list[dict[str, str]]) -> None:
    by_id = {r["node_id"]: r for r in nodes}
    index = {h: k for k, h in enumerate(table.header)}
    for row in table.rows:
        node = by_id.get(row[0] if row else "")
        if node is None:
            c.v.error(REL, f"Nodes: {row[0] if row else ''}", "is not a node of nodes.csv")
            continue
        for col, src, slack in (("vertex", "vertex", 0.0), ("x [mm]", "x", 0.05), ("y [mm]", "y", 0.05),
                                ("z [mm]", "z", 0.05), ("torsion [°]", "torsion_deg", 5e-10),
                                ("torsion [mm]", "torsion_mm", 5e-7)):
            k = index.get(col)
            if k is not None and k < len(row):
                c.numbers(f"Nodes: {node['node_id']} column {col}", row[k], [_num(node[src])], [slack],
                          table_fmt=True)
        for col, want in (("beams", "; ".join(b for b in node["beams"].split(";") if b)),
                          ("joint", node.get("joint", ""))):
            k = index.get(col)
            if k is not None and k < len(row):
                c.text(f"Nodes: {node['node_id']} column {col}", row[k], want)


def _bites_tables(c: _Compare, tables: list[Table], bites: list[dict[str, str]], min_bite: float) -> None:
    values = np.array([_num(r["bite_mm"]) for r in bites])
    tilt = np.array([_num(r["tilt_deg"]) for r in bites])
    if not len(values) or not np.all(np.isfinite(values)):
        return
    for table in tables:
        if table.header[:1] == ["pane edges"] and table.rows:
            c.numbers("Glass support: pane edges", " ".join(table.rows[0]),
                      [len(values), float(values.min()), float(np.median(values)), min_bite, float(tilt.max())],
                      [0, 5e-4, 5e-4, 0, 5e-5])
        elif table.header[:1] == ["pane"]:
            worst = sorted(values)[:len(table.rows)]
            for k, (row, want) in enumerate(zip(table.rows, worst)):
                c.numbers(f"Glass support: row {k + 1} column bite [mm]", row[3] if len(row) > 3 else "",
                          [float(want)], [5e-4], table_fmt=True)


def _welds_table(c: _Compare, table: Table, welds: list[dict[str, str]]) -> None:
    kinds: dict[str, list[float]] = {}
    for w in welds:
        kinds.setdefault(w.get("preparation", ""), []).append(_num(w.get("weld_length_mm")))
    seen = set()
    for row in table.rows:
        prep = row[0] if row else ""
        seen.add(prep)
        if prep not in kinds:
            c.v.error(REL, f"Welds: {prep}", "no weld of welds.csv has this preparation")
            continue
        c.numbers(f"Welds: {prep}", " ".join(row[1:]), [len(kinds[prep]), sum(kinds[prep]) / 1000],
                  [0, 5e-4 * len(kinds[prep]) / 1000], table_fmt=True)
    for prep in sorted(set(kinds) - seen):
        c.v.error(REL, f"Welds: {prep}", f"row missing ({len(kinds[prep])} welds in welds.csv)")


def _files_table(c: _Compare, table: Table, files: dict[str, Any], rel: str) -> None:
    listed = {row[0] for row in table.rows if row}
    want = {p for value in files.values() for p in ([value] if isinstance(value, str) else value)}
    want.add("manifest.json")
    want.discard(rel)                                 # the report is listed once it is written
    for name in sorted(want - listed):
        c.v.error(REL, f"Files: {name}", "listed in the manifest but not in the report")
    for name in sorted(listed - want):
        c.v.error(REL, f"Files: {name}", "listed in the report but not in the manifest")


@check("report")
def check_report(v: Verification) -> None:
    m = v.manifest
    files = m.get("files", {})
    rel = files.get("report_html")
    if rel is None:
        return
    try:
        text = (v.folder / rel).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        v.error(rel, "", f"cannot be read ({exc})")
        return
    tables = read_tables(text)
    c = _Compare(v)
    parts = (v.parts or [])
    figures = recompute_summary(v)
    expected = {"Summary": True, "Panels": any(r["kind"] == "panel" for r in parts),
                "Beam plates": any(r["kind"] == "beam" for r in parts), "Nodes": bool(v.nodes),
                "Files": True}
    present = {t.heading for t in tables}
    for heading, wanted in expected.items():
        if wanted and heading not in present:
            v.error(rel, heading, "table missing (the build writes it)")
    for t in tables:
        if t.kv and t.heading == "Summary":
            _summary(c, t, figures, m)
        elif t.header[:1] == ["panel"] and t.heading == "Panels":
            _parts_table(c, t, "Panels", {r["part_id"]: r for r in parts if r["kind"] == "panel"},
                         {"face": ("face", 1.0, 0.0), "area [m²]": ("area_mm2", 1e-6, 5e-4),
                          "weight [kg]": ("weight_kg", 1.0, 5e-4), "sheet": ("sheet", 1.0, 0.0)},
                         {"type": "type_id", "nest tag": "nest_tag"})
        elif t.header[:1] == ["plate"] and t.heading == "Beam plates":
            _parts_table(c, t, "Beam plates", {r["part_id"]: r for r in parts if r["kind"] == "beam"},
                         {"length [m]": ("length_mm", 1e-3, 5e-4), "mass [kg]": ("mass_kg", 1.0, 5e-5),
                          "sheet": ("sheet", 1.0, 0.0)},
                         {"beam": "beam_id", "family": "family", "nest tag": "nest_tag"})
        elif t.header[:1] == ["node"] and t.heading == "Nodes" and v.nodes is not None:
            _nodes_table(c, t, v.nodes)
        elif t.header[:1] == ["weld preparation"] and files.get("welds_csv"):
            _welds_table(c, t, _read(v, files["welds_csv"]))
        elif t.header[:1] == ["file"] and t.heading == "Files":
            _files_table(c, t, files, rel)
    if files.get("bites_csv"):
        min_bite = _num(m.get("fabrication", {}).get("panels", {}).get("min_bite"))
        _bites_tables(c, [t for t in tables if t.heading == "Glass support"], _read(v, files["bites_csv"]), min_bite)
    v.checked.append("report")


def _read(v: Verification, rel: str) -> list[dict[str, str]]:
    try:
        return read_csv(v.folder / rel)
    except (OSError, UnicodeDecodeError, ValueError):
        return []                                     # named by the check that reads the table
