"""Readers of the tables of a build: ``parts.json`` (or ``parts.csv``), ``nodes.json`` (or ``nodes.csv``),
``welds.csv`` and ``manifest.json``.  Each returns plain rows (``(row number, columns)``) or records; a missing
file or a malformed row is a :class:`~fabrication.readers.errors.BuildReadError` naming the file, row and column."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

from ..model import ColumnError, Node, Weld
from ..model.values import csv_typed, words
from .errors import bad, missing

Row = tuple[int, dict[str, Any]]


def read_json(path: Path, what: str) -> Any:
    """The JSON document at ``path`` (``what``: why it is needed, for the error when it is missing)."""
    if not path.is_file():
        raise missing(path, what)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise bad(path, "not UTF-8 text") from None
    except json.JSONDecodeError as exc:
        raise bad(path, f"not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})") from None


def read_csv(path: Path, what: str, required: tuple[str, ...] = ()) -> list[Row]:
    """The rows of the CSV file at ``path`` with their cells typed (:func:`~fabrication.model.values.csv_typed`);
    ``required`` columns must be in the header."""
    if not path.is_file():
        raise missing(path, what)
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            reader = csv.reader(fh)
            header = next(reader, None)
            if not header:
                raise bad(path, "empty file: no header row")
            absent = [c for c in required if c not in header]
            if absent:
                raise bad(path, f"the header has no column {absent[0]!r} (columns: {', '.join(header)})")
            rows = []
            for n, cells in enumerate(reader, start=1):
                if not cells:
                    continue
                if len(cells) != len(header):
                    raise bad(path, f"{len(cells)} cells, the header has {len(header)}", row=n)
                typed = {}
                for name, cell in zip(header, cells):
                    try:
                        typed[name] = csv_typed(cell)
                    except ValueError as exc:
                        raise bad(path, str(exc), row=n, column=name) from None
                rows.append((n, typed))
            return rows
    except UnicodeDecodeError:
        raise bad(path, "not UTF-8 text") from None
    except csv.Error as exc:
        raise bad(path, f"not valid CSV: {exc}") from None


def read_parts(folder: Path) -> tuple[Path, list[Row]]:
    """The rows of ``parts.json`` (``parts.csv`` when the JSON is absent), in order, with the file read."""
    path = folder / "parts.json"
    if not path.is_file() and (folder / "parts.csv").is_file():
        csv_path = folder / "parts.csv"
        return csv_path, read_csv(csv_path, "the parts list", ("part_id", "kind"))
    rows = []
    for n, row in _json_tables(path, "the parts list", "parts"):
        for col in ("part_id", "kind"):
            if not isinstance(row.get(col), str) or not row[col]:
                raise bad(path, f"no {col}", row=n, column=col)
        rows.append((n, row))
    return path, rows


def _json_tables(path: Path, what: str, key: str) -> list[tuple[int, dict[str, Any]]]:
    """``(row number, table)`` of the list ``key`` at the top level of the JSON file ``path`` (``what`` it holds,
    for the error); a missing list or an entry that is not a table is a :func:`bad` error naming the row."""
    doc = read_json(path, what)
    entries = doc.get(key) if isinstance(doc, dict) else None
    if not isinstance(entries, list):
        raise bad(path, f"no list '{key}' at the top level")
    out = []
    for n, entry in enumerate(entries, start=1):
        if not isinstance(entry, dict):
            raise bad(path, f"expected a table of columns, got {type(entry).__name__}", row=n)
        out.append((n, entry))
    return out


def _csv_node(row: dict[str, Any]) -> dict[str, Any]:
    """A ``nodes.csv`` row as the ``nodes.json`` entry it abbreviates: no beam planes, per-panel angles, pairs or
    ``axis_normal_deg``; each ending plate's set-back (``trims_mm`` lists them in order) on its beam."""
    ids, roles = words(row.get("beams")), words(row.get("roles"))
    mins, trims = words(row.get("beam_panel_deg")), words(row.get("trims_mm"))
    if len(roles) != len(ids) or len(mins) not in (0, len(ids)):
        raise ColumnError("roles" if len(roles) != len(ids) else "beam_panel_deg",
                          f"{len(ids)} beams but {len(roles)} roles and {len(mins)} angles")
    ending = [k for k, r in enumerate(roles) if r != "through"]
    trim_of = dict(zip(ending, trims)) if len(trims) == len(ending) else {}
    beams: list[dict[str, Any]] = [
        {"part_id": pid, "role": role, "plane": None, "panel_angles_deg": [],
         "panel_angle_min_deg": mins[k] if mins else None, "trim_mm": trim_of.get(k)}
        for k, (pid, role) in enumerate(zip(ids, roles))]
    known = {"beams", "roles", "beam_panel_deg", "trims_mm", "i", "j", "x", "y", "z", "axis_x", "axis_y", "axis_z"}
    rec = {k: val for k, val in row.items() if k not in known}
    rec.update(grid=None if row.get("i") in (None, "") else [row["i"], row["j"]],
               position=[row.get(c) for c in "xyz"], axis=[row.get(f"axis_{c}") for c in "xyz"], beams=beams)
    if trims and not trim_of:
        rec["trims_mm"] = row["trims_mm"]                    # kept as written when it cannot be matched
    return rec


def read_nodes(folder: Path) -> tuple[Node, ...]:
    """The nodes of ``nodes.json`` (``nodes.csv`` when the JSON is absent), in vertex order."""
    path = folder / "nodes.json"
    if not path.is_file() and (folder / "nodes.csv").is_file():
        csv_path = folder / "nodes.csv"
        found = []
        for n, row in read_csv(csv_path, "the node table", ("node_id", "vertex", "x", "y", "z")):
            try:
                found.append(Node.from_record(_csv_node(row)))
            except ColumnError as exc:
                raise bad(csv_path, exc.reason, row=n, column=exc.column) from None
        return tuple(found)
    out = []
    for n, rec in _json_tables(path, "the node table", "nodes"):
        try:
            out.append(Node.from_record(rec))
        except ColumnError as exc:
            raise bad(path, exc.reason, row=n, column=exc.column) from None
    return tuple(out)


def read_welds(folder: Path, expected: bool) -> tuple[Weld, ...]:
    """The welds of ``welds.csv``; an absent file is no welds unless the manifest lists it (``expected``)."""
    path = folder / "welds.csv"
    if not path.is_file() and not expected:
        return ()
    out = []
    for n, row in read_csv(path, "the welds the manifest lists", ("node", "part", "to")):
        try:
            out.append(Weld.from_columns(row))
        except ColumnError as exc:
            raise bad(path, exc.reason, row=n, column=exc.column) from None
    return tuple(out)


def read_manifest(folder: Path) -> dict[str, Any]:
    """``manifest.json`` (every ppfab output folder has one)."""
    path = folder / "manifest.json"
    doc = read_json(path, "every ppfab output folder has a manifest")
    if not isinstance(doc, dict):
        raise bad(path, "expected a table at the top level")
    if not str(doc.get("generator", "")).startswith("ppfab"):
        raise bad(path, f"generator is {doc.get('generator')!r}, not ppfab: not a ppfab output folder",
                  column="generator")
    return doc
