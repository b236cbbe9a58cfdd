"""JSON text as every writer writes it: indented, keys in insertion order, numpy values as plain numbers."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from ..contract import json_safe


def json_text(obj: Any) -> str:
    """``obj`` as indented JSON with a final newline (arrays become lists, paths strings, NaN and ±inf
    ``null``: JSON has no such numbers)."""
    return json.dumps(json_safe(obj), indent=2, sort_keys=False, default=_plain, allow_nan=False) + "\n"


def _plain(o: Any) -> Any:
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")
