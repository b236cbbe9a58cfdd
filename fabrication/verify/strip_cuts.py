"""strip_cuts.csv: the glazing strips cut from stock bars, recomputed from the strips of parts.csv.

The strips' lengths are ``length_mm`` of the ``strip`` rows of ``parts.csv`` (which the bite check holds to the
solids of ``glazing.step``).  Every strip must have exactly one row, with that length and its beam, and the bar,
start and nest tag ``parts.csv`` gives it; the nest tag ``F<bar>-<k>`` names the row's bar.  On each bar the
strips lie end to end from ``glazing.bar_end_allowance`` with one ``glazing.saw_kerf`` after each (first-fit decreasing,
:func:`fabrication.glazing.cutlist.cut_bars`), so every start is recomputed as the sum of the lengths and kerfs
before it (the allowance is squared off each end of a bar as delivered); no strip may end within the allowance
of ``glazing.bar_length``, and the bars used must be as many as the build's own first-fit decreasing needs for
those lengths.  (Which of two strips of equal length lies on which bar is not compared: equal lengths are
ordered by their rounding.)
"""

from __future__ import annotations

import re

from ..glazing.cutlist import cut_bars
from . import Verification, check
from ._cells import CellReader

TOLERANCE_MM = 0.01
_TAG = re.compile(r"F(\d+)-(\d+)")


@check("strip_cuts")
def check_strip_cuts(v: Verification) -> None:
    m = v.manifest
    files = m.get("files", {})
    parts = v.parts
    if parts is None:
        return
    strips = {r["part_id"]: r for r in parts if r["kind"] == "strip" and r.get("length_mm", "") != ""}
    rel = files.get("strip_cuts_csv")
    if rel is None:
        if strips:
            v.error("manifest.json", "files.strip_cuts_csv", f"missing: parts.csv has {len(strips)} strips")
        return
    gl = m.get("fabrication", {}).get("glazing", {})
    bar_length, kerf = float(gl.get("bar_length", 0.0)), float(gl.get("saw_kerf", 0.0))
    allowance = float(gl.get("bar_end_allowance", 0.0))
    lengths = {pid: float(r["length_mm"]) for pid, r in strips.items()}
    try:
        cuts, _ = cut_bars(lengths, bar_length, kerf, allowance) if lengths else ([], 0)
    except ValueError as exc:
        v.error(rel, "", f"the strips cannot be cut from glazing.bar_length {bar_length:g} mm bars: {exc}")
        return
    rows = v.read_table(rel)
    if rows is None:
        return
    cells = CellReader(v, rel)
    seen: set[str] = set()
    on_bar: dict[int, list[tuple[float, int, str]]] = {}
    for n, r in enumerate(rows, start=1):
        pid = cells.text(n, r, "part_id")
        bar = cells.integer(n, r, "bar", low=1)
        start = cells.number(n, r, "start_mm")
        length = cells.number(n, r, "length_mm")
        if pid is None or bar is None or start is None or length is None:
            continue
        row = strips.get(pid)
        if row is None:
            v.error(rel, f"row {n} column part_id", f"{pid!r} is not a strip of parts.csv")
            continue
        if pid in seen:
            v.error(rel, f"row {n}", f"{pid} is cut a second time")
            continue
        seen.add(pid)
        on_bar.setdefault(bar, []).append((start, n, pid))
        if abs(length - lengths[pid]) > TOLERANCE_MM:
            v.error(rel, f"row {n} column length_mm", f"{pid}: {length:.3f} written, the strip is "
                                                      f"{lengths[pid]:.3f} mm (parts.csv, glazing.step)")
        tag = _TAG.fullmatch(r.get("nest_tag") or "")
        if tag is None or int(tag.group(1)) != bar:
            v.error(rel, f"row {n} column nest_tag", f"{pid}: {r.get('nest_tag')!r} does not name bar {bar}")
        for column, mine, theirs in (("bar", str(bar), row.get("bar", "")),
                                     ("start_mm", f"{start:.3f}", _mm(row.get("bar_start_mm", ""))),
                                     ("nest_tag", r.get("nest_tag"), row.get("nest_tag")),
                                     ("beam", r.get("beam"), row.get("beam"))):
            if mine != theirs:
                v.error(rel, f"row {n} column {column}", f"{pid}: {mine!r} written, parts.csv has {theirs!r}")
    for pid in [p for p in strips if p not in seen]:
        v.error(rel, pid, f"strip of parts.csv ({lengths[pid]:.3f} mm) is cut from no bar")
    for bar, pieces in sorted(on_bar.items()):
        at = allowance
        for start, n, pid in sorted(pieces):
            if abs(start - at) > TOLERANCE_MM:
                v.error(rel, f"row {n} column start_mm", f"{pid} on bar {bar}: {start:.3f} written, the strips "
                                                         f"before it and their kerfs end at {at:.3f} mm")
            at += lengths[pid] + kerf
        if at - kerf > bar_length - allowance + TOLERANCE_MM:
            v.error(rel, f"bar {bar}", f"its strips end at {at - kerf:.3f} mm, within glazing.bar_end_allowance "
                                       f"{allowance:g} mm of the end of the {bar_length:g} mm bar")
    bars = len({c.bar for c in cuts})
    if seen == set(strips) and len(on_bar) != bars:
        v.error(rel, "bar", f"{len(on_bar)} bars used, first-fit decreasing cuts these strips from {bars} "
                            f"(glazing.bar_length {bar_length:g} mm, saw_kerf {kerf:g} mm, bar_end_allowance "
                            f"{allowance:g} mm)")
    v.checked.append("strip_cuts")


def _mm(text: str) -> str:
    try:
        return f"{float(text):.3f}"
    except ValueError:
        return repr(text)
