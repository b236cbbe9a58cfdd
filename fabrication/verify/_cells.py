"""Typed reads of table cells and manifest values for the verify checks: a bad cell is a finding, never an error.

A CSV cell is named ``row N column C`` (``N`` the 1-based data row, the header not counted) and a manifest
value by its dotted key path (``files.glass_sheets``).  Each reader returns the value, or ``None`` after
recording a :class:`~fabrication.verify.Finding` that names the file, the element and what is wrong.

Not a check (the leading underscore keeps it out of the registry).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from . import Verification


def cell_element(row_no: int, column: str) -> str:
    """The element name of a CSV cell: ``row 3 column face``."""
    return f"row {row_no} column {column}"


def _short(text: Any) -> str:
    s = repr(text)
    return s if len(s) <= 60 else s[:57] + "..."


@dataclass(frozen=True)
class CellReader:
    """Typed cells of one CSV table ``file`` of a verification; every bad cell becomes one finding.

    ``empty_ok``: an empty cell reads as ``None`` without a finding (columns that apply to some kinds of row
    only); otherwise an empty cell is a finding too."""

    v: Verification
    file: str

    def _bad(self, row_no: int, column: str, text: Any, what: str) -> None:
        self.v.error(self.file, cell_element(row_no, column), f"{_short(text)} is not {what}")

    def text(self, row_no: int, row: Mapping[str, Any], column: str) -> str | None:
        """The cell as text; a missing cell (a short row) is a finding."""
        value = row.get(column)
        if value is None:
            self.v.error(self.file, cell_element(row_no, column), "cell is missing (the row is short)")
            return None
        return str(value)

    def number(self, row_no: int, row: Mapping[str, Any], column: str, empty_ok: bool = False) -> float | None:
        """A finite float."""
        text = self.text(row_no, row, column)
        if text is None or (empty_ok and text == ""):
            return None
        try:
            x = float(text)
        except ValueError:
            x = math.nan
        if not math.isfinite(x):
            self._bad(row_no, column, text, "a finite number")
            return None
        return x

    def integer(self, row_no: int, row: Mapping[str, Any], column: str, empty_ok: bool = False,
                low: int | None = None, high: int | None = None) -> int | None:
        """An integer in ``[low, high)`` when given."""
        text = self.text(row_no, row, column)
        if text is None or (empty_ok and text == ""):
            return None
        try:
            k = int(text)
        except ValueError:
            self._bad(row_no, column, text, "an integer")
            return None
        if (low is not None and k < low) or (high is not None and k >= high):
            rng = f"{low if low is not None else '…'} to {high - 1 if high is not None else '…'}"
            self.v.error(self.file, cell_element(row_no, column), f"{k} is out of range ({rng})")
            return None
        return k

    def json(self, row_no: int, row: Mapping[str, Any], column: str, empty_ok: bool = False,
             shape: Callable[[Any], str | None] | None = None) -> Any:
        """A JSON value (or a Python literal, as builds before 0.2 wrote it); ``shape(value)`` may return what
        it should have been (a finding) or ``None`` (fine)."""
        from ._shapes import literal

        text = self.text(row_no, row, column)
        if text is None or (empty_ok and text == ""):
            return None
        value = literal(text)
        if value is None:
            self._bad(row_no, column, text, "JSON")
            return None
        wrong = shape(value) if shape is not None else None
        if wrong is not None:
            self._bad(row_no, column, text, wrong)
            return None
        return value

    def vector(self, row_no: int, row: Mapping[str, Any], columns: Sequence[str]) -> np.ndarray | None:
        """``(len(columns),)`` finite floats from one cell per coordinate (``x, y, z``); ``None`` if any is bad."""
        out = [self.number(row_no, row, c) for c in columns]
        return None if any(x is None for x in out) else np.array(out, dtype=float)

    def id_list(self, row_no: int, row: Mapping[str, Any], column: str, count: int | None = None,
                empty_ok: bool = True) -> list[int] | None:
        """``a;b;…`` integers (``count`` of them when given)."""
        text = self.text(row_no, row, column)
        if text is None or (empty_ok and text == ""):
            return None
        try:
            out = [int(x) for x in text.split(";")]
        except ValueError:
            out = []
        if not out or (count is not None and len(out) != count):
            self._bad(row_no, column, text, f"{count or 'some'} integers separated by ';'")
            return None
        return out


def numbers_shape(n: int) -> Callable[[Any], str | None]:
    """A :meth:`CellReader.json` shape: a list of ``n`` finite numbers."""
    def test(value: Any) -> str | None:
        return None if is_vector(value, n) else f"a list of {n} numbers"
    return test


def plane_shape(value: Any) -> str | None:
    """A :meth:`CellReader.json` shape: a plane ``[a, b, c, d]`` (``a x + b y + c z + d = 0``) whose normal is
    not zero."""
    ok = is_vector(value, 4) and any(float(x) != 0.0 for x in value[:3])
    return None if ok else "a plane [a, b, c, d] with a normal (a, b, c) that is not zero"


def ints_shape(value: Any) -> str | None:
    """A :meth:`CellReader.json` shape: a list of integers."""
    ok = isinstance(value, list) and all(isinstance(x, int) and not isinstance(x, bool) for x in value)
    return None if ok else "a list of integers"


FRAME_KEYS = ("origin", "x_dir", "y_dir", "normal")


def frame_shape(value: Any) -> str | None:
    """A :meth:`CellReader.json` shape: a plate frame, an object of ``origin, x_dir, y_dir, normal`` points."""
    ok = isinstance(value, dict) and all(is_vector(value.get(k), 3) for k in FRAME_KEYS)
    return None if ok else f"a frame (an object of 3-vectors {', '.join(FRAME_KEYS)})"


def is_vector(value: Any, n: int) -> bool:
    """Whether ``value`` is a list of ``n`` finite numbers (not booleans)."""
    return (isinstance(value, list) and len(value) == n
            and all(is_number(x) for x in value))


def is_number(value: Any) -> bool:
    """A finite int or float that is not a bool."""
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


# -- manifest values -------------------------------------------------------------------------------------

def value_at(doc: Any, path: str) -> tuple[bool, Any]:
    """``(found, value)`` of the dotted key ``path`` in nested objects."""
    cur = doc
    for key in path.split("."):
        if not isinstance(cur, dict) or key not in cur:
            return False, None
        cur = cur[key]
    return True, cur


def number_at(v: Verification, file: str, doc: Any, path: str, required: bool = False) -> float | None:
    """The number at ``path`` of a JSON document (``None``, with a finding when it is not a number or, if
    ``required``, missing)."""
    found, value = value_at(doc, path)
    if not found or value is None:
        if required:
            v.error(file, path, "missing")
        return None
    if not is_number(value):
        v.error(file, path, f"{_short(value)} is not a number")
        return None
    return float(value)


def file_list(files: Any, key: str) -> list[str]:
    """The file names of ``files[key]`` (a name or a list of names); ``[]`` when it is neither (the manifest
    check reports that)."""
    if not isinstance(files, dict):
        return []
    value = files.get(key)
    if isinstance(value, str):
        return [value]
    if isinstance(value, list) and all(isinstance(x, str) for x in value):
        return list(value)
    return []
