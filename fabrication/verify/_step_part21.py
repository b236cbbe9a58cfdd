"""The ISO 10303-21 (STEP Part 21) text level of :mod:`._step_text_read`: entity records ``#id = TYPE(…);`` across
lines, parameters with strings (``''`` escapes), references, enumerations, typed values, lists and complex
entities; the common geometric entities on a fast path.

Not a check (the leading underscore keeps it out of the registry).
"""

from __future__ import annotations

import re
from array import array
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

_TOKEN = re.compile(r"\s*(?:'((?:[^']|'')*)'|#(\d+)|(\.[A-Z_0-9]*\.)|([-+0-9.][0-9.Ee+-]*)|([A-Za-z_][A-Za-z_0-9]*)"
                    r"|(\()|(\))|(,)|(\$)|(\*))")


class StepTextError(ValueError):
    """A STEP file the text-level reader cannot read (a syntax error, a missing entity, an unsupported one)."""


class Ref(NamedTuple):
    """A reference ``#id`` to another entity (a named tuple: a million are made for a large file)."""

    id: int


@dataclass(frozen=True)
class Typed:
    """A typed parameter ``NAME(args)`` (``LENGTH_MEASURE(1.E-07)``) or one part of a complex entity."""

    name: str
    args: list


def parse_params(text: str) -> list:
    """The parameter list of an entity, ``('a',#3,(1.,2.),.T.,$)`` → ``['a', Ref(3), [1.0, 2.0], True, None]``;
    a complex entity ``( A(…) B(…) )`` → a list of :class:`Typed`.  Enumerations other than ``.T.``/``.F.`` stay
    strings with their dots; ``*`` is ``'*'``."""
    pos = 0
    stack: list[list] = [[]]
    pending: str | None = None
    while True:
        m = _TOKEN.match(text, pos)
        if m is None:
            if text[pos:].strip():
                raise StepTextError(f"cannot parse {text[pos:pos + 40]!r}")
            break
        pos = m.end()
        s, ref, enum, num, word, opn, cls, _comma, dollar, star = m.groups()
        top = stack[-1]
        if s is not None:
            top.append(s.replace("''", "'"))
        elif ref is not None:
            top.append(Ref(int(ref)))
        elif enum is not None:
            top.append(True if enum == ".T." else False if enum == ".F." else enum)
        elif num is not None:
            top.append(float(num))
        elif word is not None:
            pending = word
        elif opn is not None:
            new: list = []
            top.append(Typed(pending, new) if pending is not None else new)
            pending = None
            stack.append(new)
        elif cls is not None:
            stack.pop()
            if not stack:
                raise StepTextError(f"unbalanced parentheses in {text[:60]!r}")
        elif dollar is not None:
            top.append(None)
        elif star is not None:
            top.append("*")
    if len(stack) != 1 or len(stack[0]) != 1:
        raise StepTextError(f"unbalanced parentheses in {text[:60]!r}")
    out = stack[0][0]
    if isinstance(out, Typed):           # a simple entity: its arguments
        return out.args
    return out                           # a complex entity: its parts


_RECORD = re.compile(r"\s*#(\d+)\s*=\s*([A-Za-z_][A-Za-z_0-9]*)?\s*(\((?:[^;']++|'(?:[^']|'')*+')*+);")
"""One entity record ``#id = TYPE(…);`` (a complex entity ``#id = ( A(…) B(…) );`` has no type before its
parameters); a ``;`` inside a string does not end it."""

_RECORD_BYTES = re.compile(_RECORD.pattern.encode("ascii"))
""":data:`_RECORD` on the file's bytes (ASCII, as ISO 10303-21 writes the DATA section)."""


class Entities(Mapping[int, tuple[str, str]]):
    """The entities of a DATA section, ``#id`` → (type name, the raw text of its parameters including the
    parentheses; a complex entity's type is ``''``), kept compactly: the file's bytes once and, per entity, its
    id, type and where its parameters stand in the bytes (a million entities of a large file as a few arrays,
    where a dictionary of strings held ten times the file's size).  A record is sliced from the bytes and
    decoded (Latin-1) when asked for."""

    def __init__(self, data: bytes, ids: np.ndarray, kinds: np.ndarray, starts: np.ndarray, stops: np.ndarray,
                 names: list[str]):
        self._data, self.ids, self.kinds, self._starts, self._stops = data, ids, kinds, starts, stops
        self.names = names                      # type code → type name
        self._codes = {n: k for k, n in enumerate(names)}
        self._sorted: np.ndarray | None = None
        self._nul: bool | None = None
        top = int(ids.max()) if len(ids) else -1
        self._dense = top < 4 * len(ids) + 1024  # ids 1 … n, as every writer numbers them: an array lookup
        if self._dense:
            self._row = np.full(top + 1, -1, dtype=np.int32 if len(ids) < 2**31 else np.int64)
            self._row[ids] = np.arange(len(ids))
        else:
            self._rows = {int(i): k for k, i in enumerate(ids.tolist())}

    def row(self, i: int) -> int:
        """Where ``#i`` stands among :attr:`ids`, -1 when it is not defined."""
        if self._dense:
            return int(self._row[i]) if 0 <= i < len(self._row) else -1
        return self._rows.get(i, -1)

    def kind(self, i: int) -> str:
        """The type name of ``#i`` (``''`` for a complex entity); raises ``KeyError`` when it is not defined."""
        k = self.row(i)
        if k < 0:
            raise KeyError(i)
        return self.names[self.kinds[k]]

    def __getitem__(self, i: int) -> tuple[str, str]:
        k = self.row(i)
        if k < 0:
            raise KeyError(i)
        return self.names[self.kinds[k]], self._data[self._starts[k]:self._stops[k]].decode("latin-1")

    def __contains__(self, i: object) -> bool:
        return isinstance(i, (int, np.integer)) and self.row(int(i)) >= 0

    def __iter__(self) -> Iterator[int]:
        return iter(self.ids.tolist())

    def __len__(self) -> int:
        return len(self.ids)

    def code(self, kind: str) -> int:
        """The code of the type name ``kind`` in :attr:`kinds`, -1 when no entity has it."""
        return self._codes.get(kind, -1)

    def rows(self, ids: np.ndarray) -> np.ndarray:
        """Where each of the ids stands among :attr:`ids` (:meth:`row` of many at once), -1 for one not defined."""
        ids = np.asarray(ids, dtype=np.int64)
        if self._dense:
            out = np.full(len(ids), -1, dtype=np.int64)
            inside = (ids >= 0) & (ids < len(self._row))
            out[inside] = self._row[ids[inside]]
            return out
        if self._sorted is None:
            self._sorted = np.argsort(self.ids, kind="stable")
        order = self._sorted
        if not len(order):
            return np.full(len(ids), -1, dtype=np.int64)
        at = np.clip(np.searchsorted(self.ids[order], ids), 0, len(order) - 1)
        return np.where(self.ids[order][at] == ids, order[at], -1)

    def texts(self, rows: np.ndarray) -> list[bytes]:
        """The parameter texts of the entities at ``rows`` (positions in :attr:`ids`), as bytes."""
        data = self._data
        return [data[a:b] for a, b in zip(self._starts[rows].tolist(), self._stops[rows].tolist())]

    def joined(self, rows: np.ndarray, sep: bytes) -> bytes:
        """The parameter texts of the entities at ``rows`` joined by ``sep`` (each slice a small copy: four times
        cheaper to make than a memoryview of it)."""
        return sep.join(self.texts(rows))

    @property
    def has_nul(self) -> bool:
        """Whether the file holds a NUL byte (which :meth:`joined` text uses as a separator)."""
        if self._nul is None:
            self._nul = b"\x00" in self._data
        return self._nul

    def of_kind(self, *kinds: str) -> np.ndarray:
        """The ids of the entities of these types, in file order."""
        codes = [self._codes[k] for k in kinds if k in self._codes]
        return self.ids[np.isin(self.kinds, codes)] if codes else self.ids[:0]

    def not_of_kind(self, kinds: "frozenset[str] | set[str]") -> np.ndarray:
        """The ids of the entities of any type but these, in file order."""
        codes = [self._codes[k] for k in kinds if k in self._codes]
        return self.ids[~np.isin(self.kinds, codes)]


def read_entities(data: bytes) -> Entities:
    """Every entity of the DATA section (:class:`Entities`), found in the file's bytes as they are (each record
    is decoded when asked for): a decoded copy of the section would be as large as the file again, 291 MB for
    glazing.step at 88 × 60 faces."""
    start = data.find(b"DATA;")
    end = data.rfind(b"ENDSEC;")
    if start < 0:
        raise StepTextError("no DATA section")
    if end < start:
        raise StepTextError("the DATA section does not end (no ENDSEC; after it): the file is cut short")
    ids, kinds = array("q"), array("i")         # 8 and 4 bytes an entity where a list of ints takes 36
    starts, stops = array("q"), array("q")
    codes: dict[bytes, int] = {}
    names: list[str] = []
    pos = start + 5
    match = _RECORD_BYTES.match
    blank = b" \t\r\n"
    while True:
        m = match(data, pos, end)
        if m is None:
            rest = data[pos:end].strip()
            if rest:
                raise StepTextError(f"cannot parse the entity {rest[:60].decode('latin-1')!r}")
            break
        kind = m.group(2) or b""
        code = codes.get(kind)
        if code is None:
            code = codes[kind] = len(names)
            names.append(kind.decode("latin-1"))
        ids.append(int(m.group(1)))
        kinds.append(code)
        a, b = m.span(3)
        while b > a and data[b - 1] in blank:
            b -= 1
        starts.append(a)
        stops.append(b)
        pos = m.end()
        if pos >= end:
            break
    offsets = np.uint32 if len(data) < 2**32 else np.int64
    return Entities(data, narrow_ids(np.frombuffer(ids, dtype=np.int64)), np.frombuffer(kinds, dtype=np.int32),
                    np.frombuffer(starts, dtype=np.int64).astype(offsets),
                    np.frombuffer(stops, dtype=np.int64).astype(offsets), names)


def narrow_ids(ids: np.ndarray) -> np.ndarray:
    """Entity ids as 32-bit integers when they fit (a file numbered from 1), else as they are.  With the offsets
    of a file under 4 GB 32-bit too, an entity takes 20 bytes of :class:`Entities` ' arrays, not 36: at 88 × 60
    faces glazing.step has 5.9 million entities (its read's peak 1,396 → 1,307 MB).  The B-rep tables' references
    too (:mod:`._step_breps`)."""
    return ids.astype(np.int32) if not len(ids) or int(np.abs(ids).max()) < 2**31 else ids


_FLAT_TOKEN = r"\s*(?:'[^',()]*'|#\d+|\$|\*|\.[A-Z_0-9]*\.|[-+0-9.][0-9.Ee+-]*)\s*"
_FLAT = re.compile(r"\(" + _FLAT_TOKEN + r"(?:," + _FLAT_TOKEN + r")*\)")
"""A flat parameter list: strings without commas, parentheses or quotes, references, ``$``, ``*``,
enumerations and numbers (a product's, an occurrence's, a placement's record): split at its commas."""


def flat_params(text: str) -> list | None:
    """:func:`parse_params` of a flat parameter list (:data:`_FLAT`: a product's, an occurrence's, a placement's
    record; three times faster), ``None`` for any other, which the full parser reads."""
    if _FLAT.fullmatch(text) is None:
        return None
    out: list = []
    for token in text[1:-1].split(","):
        t = token.strip()
        head = t[0]
        if head == "'":
            out.append(t[1:-1])
        elif head == "#":
            out.append(Ref(int(t[1:])))
        elif head == "$":
            out.append(None)
        elif head == "*":
            out.append("*")
        elif head == "." and t[-1] == "." and len(t) > 1 and not t[1].isdigit():
            out.append(True if t == ".T." else False if t == ".F." else t)
        else:
            out.append(float(t))
    return out
