"""The studio's form values: a list typed into a field, a control's value for the model and for a message."""

from __future__ import annotations

import json
from typing import Any

import numpy as np


def parse_list(text: str, label: str) -> list:
    """The list of numbers typed into the field ``label`` (JSON), or :class:`ValueError` saying what is wrong."""
    try:
        value = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ValueError(f"{label}: not a list of numbers ({exc.msg} at character {exc.pos})") from None
    if not isinstance(value, list):
        raise ValueError(f"{label}: give a list such as [[0.0, 1.0], [2.0]]")
    return value


def plain(value: Any) -> Any:
    """A control's value as plain Python: tuples as lists of floats, numpy scalars as int or float."""
    if isinstance(value, tuple):
        return [float(x) for x in value]
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (np.floating,)):
        return float(value)
    return value


def field_value(value: Any) -> str:
    """A control's value as the message under it quotes it (``1000``, ``0.25``, ``(1, 2)``)."""
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)
