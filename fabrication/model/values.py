"""Cell values of the tables as typed values: the converters the records use, shared by every reader.

A cell arrives as JSON (``parts.json``, ``nodes.json``: numbers, text, lists, ``null``) or as CSV text
(``parts.csv``, ``welds.csv``: everything a string, ``""`` for an empty cell).  Each converter takes either and
raises :class:`ValueError` with a short reason; the readers add the file, row and column.
"""

from __future__ import annotations

import ast
import json
import re
from typing import Any

_INT = re.compile(r"^[+-]?\d+$")
_FLOAT = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")


def empty(value: Any) -> bool:
    """An empty cell: ``None`` or ``""``."""
    return value is None or value == ""


def opt_float(value: Any) -> float | None:
    """A number, or ``None`` for an empty cell."""
    if empty(value):
        return None
    if isinstance(value, bool):
        raise ValueError(f"expected a number, got {value!r}")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ValueError(f"expected a number, got {value!r}") from None


def opt_int(value: Any) -> int | None:
    """A whole number, or ``None`` for an empty cell."""
    if empty(value):
        return None
    if isinstance(value, float) and value.is_integer():
        return int(value)
    if isinstance(value, int) and not isinstance(value, bool):
        return value
    if isinstance(value, str) and _INT.match(value.strip()):
        return int(value)
    raise ValueError(f"expected a whole number, got {value!r}")


def text(value: Any) -> str:
    """Text (``""`` for an empty cell)."""
    return "" if value is None else str(value)


def flag(value: Any) -> bool:
    """A yes/no cell: ``true``/``false``, ``1``/``0``, ``yes``/``no`` (empty: ``False``)."""
    if empty(value):
        return False
    if isinstance(value, bool):
        return value
    s = str(value).strip().lower()
    if s in ("1", "true", "yes"):
        return True
    if s in ("0", "false", "no"):
        return False
    raise ValueError(f"expected 0/1, got {value!r}")


def words(value: Any) -> tuple[str, ...]:
    """A ``;``-separated list of ids or words (or a JSON list): ``"B-U01;B-W02"`` → ``("B-U01", "B-W02")``."""
    if empty(value):
        return ()
    if isinstance(value, (list, tuple)):
        return tuple(str(v) for v in value)
    return tuple(s for s in str(value).split(";") if s != "")


def whole_numbers(value: Any) -> tuple[int, ...]:
    """A list of whole numbers: a JSON list or ``;``-separated text (``"0;1"``)."""
    items = structured(value) if isinstance(value, str) and value.startswith("[") else value
    out = []
    for v in (items if isinstance(items, (list, tuple)) else words(items)):
        n = opt_int(v)
        if n is None:
            raise ValueError(f"expected whole numbers, got {value!r}")
        out.append(n)
    return tuple(out)


def float_list(value: Any) -> tuple[float, ...]:
    """Numbers separated by ``;`` (``"125;375.5"``), a JSON list, or one number; ``()`` for an empty cell."""
    if empty(value):
        return ()
    if isinstance(value, bool):
        raise ValueError(f"expected numbers separated by ';', got {value!r}")
    if isinstance(value, (int, float)):
        return (float(value),)
    items = value if isinstance(value, (list, tuple)) else words(value)
    out = []
    for x in items:
        n = opt_float(x)
        if n is None:
            raise ValueError(f"expected numbers separated by ';', got {value!r}")
        out.append(n)
    return tuple(out)


def numbers(value: Any, count: int | None = None) -> tuple[float, ...] | None:
    """A list of numbers (``count`` of them when given), or ``None`` for an empty cell."""
    if empty(value):
        return None
    items = structured(value) if isinstance(value, str) else value
    if not isinstance(items, (list, tuple)):
        raise ValueError(f"expected a list of numbers, got {value!r}")
    out = tuple(float(v) if not isinstance(v, bool) and isinstance(v, (int, float)) else _bad(value) for v in items)
    if count is not None and len(out) != count:
        raise ValueError(f"expected {count} numbers, got {len(out)}")
    return out


def _bad(value: Any) -> float:
    raise ValueError(f"expected a list of numbers, got {value!r}")


def structured(cell: str) -> Any:
    """A structured cell (a list or a table): JSON, or a Python literal as builds before 0.2 wrote them
    (docs/migration.md)."""
    try:
        return json.loads(cell)
    except ValueError:
        pass
    try:
        return ast.literal_eval(cell)
    except (ValueError, SyntaxError):
        raise ValueError(f"expected a JSON value, got {cell[:40]!r}") from None


def csv_typed(cell: str) -> Any:
    """A CSV cell as the value ``parts.json`` holds for it: ``""`` stays ``""``, a whole number becomes an
    ``int``, a decimal number a ``float``, a list or table its value, anything else text (a leading ``'`` that
    protected a formula character removed)."""
    s = cell
    if s == "":
        return ""
    if _INT.match(s):
        return int(s)
    if _FLOAT.match(s):
        return float(s)
    if s[0] in "[{":
        return structured(s)
    if len(s) > 1 and s[0] == "'" and s[1] in "=+-@\t\r":
        return s[1:]
    return s
