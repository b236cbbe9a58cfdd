"""The record of one cutting sheet: :class:`Sheet`."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Sheet:
    """One stock sheet with parts nested on it: its file (relative to the build folder), 1-based number among
    the sheets of its kind (``panel`` glass, ``beam`` plate), the stock size ``(length, width)`` and usable area
    ``(x0, y0, x1, y1)`` in mm, the material and thickness written on it (distinct values joined by ``"; "``),
    and the part ids cut from it in the order they are drawn (by nest tag)."""

    file: str
    kind: str
    number: int
    size: tuple[float, float] | None
    usable: tuple[float, float, float, float] | None
    material: str
    thickness: str
    parts: tuple[str, ...]
