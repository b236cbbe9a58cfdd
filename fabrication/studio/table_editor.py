"""Structured editors for the studio's nested-list parameters (a curve's coefficients per coordinate, spheres
``[x, y, z, r]``, planes ``[nx, ny, nz, d]``, control points): one line per inner list, its numbers in vector
fields of up to three (``[x, y, z, r]`` is a vector of three and a number), rows added or removed by buttons,
and the whole value as JSON text beneath for pasting.  Every change sends the whole new list to the studio's
``set`` (the construction checks it; a refused value is shown under the editor and the fields show the
model's value again).

The pure helpers (:func:`is_table`, :func:`row_chunks`, :func:`with_cells`, :func:`with_rows`) carry the
logic; :class:`TableEditor` draws them with viser's GUI.
"""

from __future__ import annotations

import copy
import json
from typing import Any, Callable


def is_table(value: Any) -> bool:
    """Whether ``value`` is a non-empty list of non-empty lists of numbers (the editors' domain)."""
    return (isinstance(value, list) and len(value) > 0 and all(
        isinstance(row, list) and len(row) > 0 and all(
            isinstance(x, (int, float)) and not isinstance(x, bool) for x in row) for row in value))


def row_chunks(length: int) -> list[tuple[int, int]]:
    """``[start, stop)`` slices of a row of ``length`` numbers, three at most each: 4 → ``[(0, 3), (3, 4)]``."""
    return [(s, min(s + 3, length)) for s in range(0, length, 3)]


def with_cells(value: list[list[float]], row: int, start: int, numbers: Any) -> list[list[float]]:
    """A copy of ``value`` with ``value[row][start:start + len(numbers)]`` replaced by ``numbers`` (floats)."""
    out = copy.deepcopy(value)
    items = [float(x) for x in (numbers if isinstance(numbers, (list, tuple)) else [numbers])]
    out[row][start:start + len(items)] = items
    return out


def with_rows(value: list[list[float]], change: int) -> list[list[float]]:
    """A copy with the last row repeated (``change = +1``) or removed (``change = -1``; one row always stays)."""
    out = copy.deepcopy(value)
    if change > 0:
        out.append(copy.deepcopy(out[-1]))
    elif change < 0 and len(out) > 1:
        out.pop()
    return out


def shape(value: Any) -> tuple[int, ...]:
    """The row lengths of a table (what decides the fields drawn)."""
    return tuple(len(row) for row in value) if is_table(value) else ()


class TableEditor:
    """The fields of one nested-list parameter ``key`` (see the module docstring); ``apply(make)`` is the
    studio's guarded setter (it sets the value ``make()`` returns; what ``make`` raises is shown as the
    refusal), ``syncing()`` says whether the studio is writing the model's values into the fields (their
    callbacks then do nothing)."""

    def __init__(self, gui: Any, key: str, value: list[list[float]], hint: str | None,
                 apply: Callable[[Callable[[], Any]], None], syncing: Callable[[], bool]):
        self.key = key
        self.value = copy.deepcopy(value)
        self.apply = apply
        self.syncing = syncing
        self.fields: list[tuple[int, int, Any]] = []          # (row, start, handle)
        self.folder = gui.add_folder(key)
        with self.folder:
            for r, row in enumerate(value):
                for start, stop in row_chunks(len(row)):
                    label = f"{key}[{r}]" if start == 0 else f"{key}[{r}][{start}]" if stop - start == 1 else \
                        f"{key}[{r}][{start}:{stop}]"
                    part = tuple(float(x) for x in row[start:stop])
                    if len(part) == 1:
                        h = gui.add_number(label, part[0], step=0.001, hint=hint)
                    elif len(part) == 2:
                        h = gui.add_vector2(label, part, step=0.001, hint=hint)
                    else:
                        h = gui.add_vector3(label, part, step=0.001, hint=hint)
                    h.on_update(lambda e, r=r, start=start: self._cells(r, start, e.target.value))
                    self.fields.append((r, start, h))
            add, drop = gui.add_button(f"{key}: add a row"), gui.add_button(f"{key}: remove the last row")
            add.on_click(lambda _: self._rows(+1))
            drop.on_click(lambda _: self._rows(-1))
            self.buttons = (add, drop)
            self.text = gui.add_text(f"{key} (JSON)", json.dumps(value), hint=hint)
            self.text.on_update(lambda e: self._json(str(e.target.value)))

    # -- what the studio asks of a control ---------------------------------------------------------------
    @property
    def order(self) -> float:
        return float(self.folder.order)

    def remove(self) -> None:
        self.folder.remove()

    def sync(self, value: Any) -> bool:
        """Show ``value`` (the model's); ``False`` when its shape differs and the editor must be drawn anew."""
        if shape(value) != shape(self.value):
            return False
        self.value = copy.deepcopy(value)
        for r, start, h in self.fields:
            part = value[r][start:start + (1 if isinstance(h.value, (int, float)) else len(h.value))]
            new: Any = float(part[0]) if isinstance(h.value, (int, float)) else tuple(float(x) for x in part)
            if h.value != new:
                h.value = new
        text = json.dumps(value)
        if self.text.value != text:
            self.text.value = text
        return True

    # -- edits ------------------------------------------------------------------------------------------
    def _cells(self, row: int, start: int, numbers: Any) -> None:
        if not self.syncing():
            self.apply(lambda: with_cells(self.value, row, start, numbers))

    def _rows(self, change: int) -> None:
        if not self.syncing():
            self.apply(lambda: with_rows(self.value, change))

    def _json(self, text: str) -> None:
        if self.syncing():
            return

        def parse() -> Any:
            try:
                return json.loads(text)
            except json.JSONDecodeError as exc:
                raise ValueError(f"{self.key}: not JSON ({exc.msg}); give a list such as [[0.0, 1.0], [2.0]]") \
                    from None
        self.apply(parse)
