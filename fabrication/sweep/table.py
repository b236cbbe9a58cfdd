"""The results table: one row per variant, as Parquet (pyarrow) and CSV bytes.

Columns, in order: ``index``, ``variant`` (the key), ``status`` (``ok`` / ``failed``), ``reason``, ``stage``,
the varied design keys (dotted), every figure of :data:`~fabrication.sweep.figures.FIGURES`, ``worker``,
``finished`` (UTC, ISO 8601), ``design`` and ``report`` (paths relative to the results folder).
"""

from __future__ import annotations

import datetime as dt
import json
from typing import Any

from .figures import FIGURES
from .variants import Variant
from .worker import VariantResult

HEAD = ("index", "variant", "status", "reason", "stage")
TAIL = ("worker", "finished", "design", "report")
INTEGER_FIGURES = frozenset({"panels", "panel_types", "glass_sheets", "plate_sheets", "node_types"})


def _scalar(v: Any) -> Any:
    """A varied value as a table cell: numbers, text and booleans as they are, lists and tables as JSON."""
    return v if isinstance(v, (bool, int, float, str)) or v is None else json.dumps(v, sort_keys=True)


def make_row(variant: Variant, result: VariantResult, stage: str) -> dict[str, Any]:
    """The table row of a finished variant."""
    row: dict[str, Any] = {"index": variant.index, "variant": variant.key, "status": result.status,
                           "reason": result.reason, "stage": stage}
    row.update({k: _scalar(v) for k, v in variant.values.items()})
    for name in FIGURES:
        v = result.figures.get(name)
        row[name] = None if v is None else (int(v) if name in INTEGER_FIGURES else float(v))
    row.update({"worker": result.worker,
                "finished": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
                "design": f"designs/{variant.key}.toml",
                "report": f"builds/{variant.key}/report.html" if result.built else ""})
    return row


def columns(rows: list[dict[str, Any]]) -> list[str]:
    """The column order of ``rows``: the fixed head, the varied keys in order of appearance, the figures,
    the fixed tail."""
    fixed = set(HEAD) | set(TAIL) | set(FIGURES)
    varied: list[str] = []
    for r in rows:
        varied += [k for k in r if k not in fixed and k not in varied]
    return list(HEAD) + varied + list(FIGURES) + list(TAIL)


def _column_type(name: str, values: list[Any]) -> Any:
    import pyarrow as pa

    if name in ("index",) or name in INTEGER_FIGURES:
        return pa.int64()
    if name in FIGURES:
        return pa.float64()
    seen = [v for v in values if v is not None]
    if seen and all(isinstance(v, bool) for v in seen):
        return pa.bool_()
    if seen and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in seen):
        return pa.int64() if all(isinstance(v, int) for v in seen) else pa.float64()
    return pa.string()


def to_arrow(rows: list[dict[str, Any]]) -> Any:
    """``rows`` (sorted by ``index``, then key) as a :class:`pyarrow.Table` with one type per column."""
    import pyarrow as pa

    rows = sorted(rows, key=lambda r: (r.get("index", 0), r.get("variant", "")))
    arrays, names = [], []
    for name in columns(rows):
        values = [r.get(name) for r in rows]
        t = _column_type(name, values)
        if t == pa.string():
            values = [None if v is None else (v if isinstance(v, str) else json.dumps(v)) for v in values]
        elif t == pa.float64():
            values = [None if v is None else float(v) for v in values]
        arrays.append(pa.array(values, type=t))
        names.append(name)
    return pa.Table.from_arrays(arrays, names=names)


def table_bytes(rows: list[dict[str, Any]]) -> dict[str, bytes]:
    """``results.parquet`` and ``results.csv`` of ``rows``."""
    import pyarrow as pa
    import pyarrow.csv as pcsv
    import pyarrow.parquet as pq

    table = to_arrow(rows)
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink)
    csv = pa.BufferOutputStream()
    pcsv.write_csv(table, csv)
    return {"results.parquet": sink.getvalue().to_pybytes(), "results.csv": csv.getvalue().to_pybytes()}
