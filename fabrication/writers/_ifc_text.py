r"""An IFC file written as ISO 10303-21 text by ppfab: :class:`IfcText`, the file ``model.ifc`` is built in.

IfcOpenShell's object model costs about 20 µs an entity to fill from Python and write (an instance made in its C++
file, then each attribute set through its Python wrapper, the file's transaction switched off and on around it),
and its file keeps every instance until the process ends; ``model.ifc`` of the bundled default at 44 × 30 faces has
about a million entities.  :class:`IfcText` takes the same calls the writer made of IfcOpenShell —
``create_entity(cls, **attributes)`` for an entity, ``create_entity(type, value)`` for a typed value, the header's
fields, :meth:`IfcText.write` — and turns each entity into its line of text as it is made, in the order it is
made, numbered from 1, as IfcOpenShell numbers a new file.  Only the text is kept (a byte per character) and the
few counts the writer reports (:meth:`IfcText.count`).

The schema is IfcOpenShell's (``ifcopenshell_wrapper.schema_by_name``): the order of each class's attributes (its
own after its supertypes'), which of them are derived (written ``*``), which are enumerations (written
``.VALUE.``) and which are real numbers (an integer given there is written as a real).  Values are written as
IfcOpenShell writes them, so the file is the one IfcOpenShell writes given the same calls, byte for byte
(``tests/test_ifc_text.py`` writes the whole file of two builds through both and compares):

* a real by :func:`real_text`: the shortest digits that read back as the same double, in plain or scientific
  notation, whichever is shorter (plain on a tie), with a decimal point always and a capital ``E``:
  ``0.``, ``1.5``, ``1.E-05``, ``1152921504606846976.``;
* a string by :func:`string_text`: ``''`` for a quote, ``\\`` for a backslash, a run of characters outside
  printable ASCII as ``\X2\…\X0\`` (four hex digits a character) or, in a string that holds a character beyond
  the Basic Multilingual Plane, every such run as ``\X4\…\X0\`` (eight hex digits a character);
* ``.T.``/``.F.`` for a boolean, ``$`` for an unset attribute, ``#n`` for an entity, ``(…)`` for a list, a typed
  value inline as ``IFCLABEL('…')``.

The header names ppfab (its version) as both the preprocessor and the originating system.

ISO 10303-21:2016 §6.4 (tokens), §7 (header) and §8 (data section); IFC4 ADD2 TC1 for the classes.
"""

from __future__ import annotations

import math
import re
from collections import Counter
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any, Sequence

import numpy as np

__all__ = ["IfcText", "Entity", "Typed", "real_text", "string_text"]

_CHUNK = 1 << 22
"""Bytes of text written to the file at a time."""


class Entity:
    """An entity of an :class:`IfcText` file: its number (``#id``) and class.  Its attributes are in the file's
    text, not here (they are written as the entity is made)."""

    __slots__ = ("id", "cls")

    def __init__(self, id: int, cls: str):
        self.id = id
        self.cls = cls

    def __repr__(self) -> str:
        return f"#{self.id}={self.cls}(…)"


class Typed:
    """A typed value written inline (``IFCLABEL('x')``, ``IFCBOOLEAN(.T.)``): a ``NominalValue`` of a select."""

    __slots__ = ("text",)

    def __init__(self, text: str):
        self.text = text

    def __repr__(self) -> str:
        return self.text


# -- values --------------------------------------------------------------------------------------------

def _digits(a: float) -> tuple[str, int]:
    """The significant digits of ``a`` > 0 as IfcOpenShell chooses them, and the decimal exponent of the first
    (``a = d1.d2d3… × 10^e``): the fewest digits, *correctly rounded*, that read back as ``a``.  That is Python's
    ``repr`` except at a power of two, where the doubles below lie twice as close as those above and ``repr`` may
    take a digit string that is not the nearest: 2⁻⁴⁴ is ``5.6843418860808015E-14`` in IfcOpenShell's files
    (``5.684341886080801e-14`` does not read back), ``5.684341886080802e-14`` in ``repr``."""
    mantissa, _, exp = repr(a).partition("e")
    whole, _, frac = mantissa.partition(".")
    digits = (whole + frac).lstrip("0").rstrip("0")
    e = (len(whole) - 1 if whole.strip("0") else -(len(frac) - len(frac.lstrip("0")) + 1)) + int(exp or 0)
    if len(digits) > 1 and math.frexp(a)[0] == 0.5:
        for p in range(len(digits), 18):
            text = f"{a:.{p - 1}e}"
            if float(text) == a:
                break
        m, _, x = text.partition("e")
        digits, e = m.replace(".", "").rstrip("0"), int(x)
    return digits, e


def real_text(x: float) -> str:
    """A real number as IfcOpenShell writes it: the shortest digits that read back as the same double
    (:func:`_digits`) in plain or scientific notation, whichever is shorter, plain on a tie (an integer with all
    its digits); a decimal point always, a capital ``E``.

    >>> [real_text(v) for v in (0.0, 1.5, 100.0, 1e5, 1e-5, 0.000123, 2.0 ** 60, -2.5e-7, 2.0 ** -44)]
    ['0.', '1.5', '100.', '1.E+05', '1.E-05', '0.000123', '1152921504606846976.', '-2.5E-07', '5.6843418860808015E-14']
    """
    r = repr(x)
    if "e" not in r:                       # Python writes 1e-4 <= |x| < 1e16 plainly
        if not r.endswith(".0"):
            if x >= 1e-3 or x <= -1e-3:    # a fraction: its plain form is shorter than any scientific one, and
                return r                   # a power of two in this range has at most 16 digits, exact
        elif x >= 1.0 and x < 1e4 or x <= -1.0 and x > -1e4:
            return r[:-1]                  # an integer of at most four digits: plain ("100.")
    if not math.isfinite(x):
        raise ValueError(f"{x!r} is not a number an IFC file can hold")
    sign = "-" if r.startswith("-") else ""
    if x == 0.0:
        return sign + "0."
    digits, e = _digits(abs(x))
    n = len(digits)
    if e >= 0:                             # an integer is written with all its digits, as exact as the double
        plain = str(int(abs(x))) if n <= e + 1 else digits[:e + 1] + "." + digits[e + 1:]
    else:
        plain = "0." + "0" * (-e - 1) + digits
    sci = digits[0] + ("." + digits[1:] if n > 1 else "") + ("e-" if e < 0 else "e+") + f"{abs(e):02d}"
    out = plain if len(plain) <= len(sci) else sci
    if "." not in out:
        out = out.replace("e", ".e") if "e" in out else out + "."
    return sign + out.upper()


_PLAIN = re.compile(r"[ -&(-\[\]-~]*")
"""Printable ASCII without the quote and the backslash: written as it is."""


def string_text(text: str) -> str:
    r"""``text`` as an ISO 10303-21 string, encoded as IfcOpenShell encodes it.

    >>> print(string_text("Café 'A' \\ éü"))
    'Caf\X2\00E9\X0\ ''A'' \\ \X2\00E900FC\X0\'
    """
    if _PLAIN.fullmatch(text):
        return "'" + text + "'"
    out: list[str] = []
    run: list[str] = []
    wide = any(ord(c) > 0xFFFF for c in text)

    def close() -> None:
        if run:
            if wide:
                out.append("\\X4\\" + "".join(f"{ord(c):08X}" for c in run) + "\\X0\\")
            else:
                out.append("\\X2\\" + "".join(f"{ord(c):04X}" for c in run) + "\\X0\\")
            run.clear()

    for ch in text:
        if " " <= ch <= "~":
            close()
            out.append("''" if ch == "'" else "\\\\" if ch == "\\" else ch)
        else:
            run.append(ch)
    close()
    return "'" + "".join(out) + "'"


_REAL, _ENUM, _OTHER = 1, 2, 0


def _value_text(v: Any, kind: int) -> str:
    """One attribute value (``kind``: what the schema declares there, for an aggregate its elements)."""
    if v is None:
        return "$"
    if isinstance(v, Entity):
        return f"#{v.id}"
    if type(v) is float:
        return real_text(v)
    if isinstance(v, str):
        return f".{v}." if kind == _ENUM else string_text(v)
    if isinstance(v, Typed):
        return v.text
    if isinstance(v, (bool, np.bool_)):
        return ".T." if v else ".F."
    if isinstance(v, (int, np.integer)):
        return real_text(float(v)) if kind == _REAL else str(int(v))
    if isinstance(v, (list, tuple)):
        if v and all(type(x) is float for x in v):          # coordinates, direction ratios
            return "(" + ",".join([real_text(x) for x in v]) + ")"
        if v and all(type(x) is Entity for x in v):         # references
            return "(" + ",".join([f"#{x.id}" for x in v]) + ")"
        return "(" + ",".join([_value_text(x, kind) for x in v]) + ")"
    if isinstance(v, (float, np.floating)):
        return real_text(float(v))
    raise TypeError(f"{type(v).__name__} {v!r} cannot be written to an IFC file")


# -- the schema ----------------------------------------------------------------------------------------

@dataclass(frozen=True)
class _Class:
    """What the writer needs of a class of the schema: its name as written, each attribute's position and kind,
    which attributes are derived, and the classes it is a subtype of (itself included)."""

    upper: str
    index: dict[str, int]
    kinds: tuple[int, ...]
    derived: tuple[bool, ...]
    ancestors: frozenset[str]


def _kind(t: Any) -> int:
    """``_REAL``, ``_ENUM`` or ``_OTHER`` for an attribute's declared type (an aggregate: its elements')."""
    import ifcopenshell.ifcopenshell_wrapper as w

    while True:
        if isinstance(t, w.aggregation_type):
            t = t.type_of_element()
        elif isinstance(t, w.named_type):
            t = t.declared_type()
        elif isinstance(t, w.type_declaration):
            t = t.declared_type()
        elif isinstance(t, w.enumeration_type):
            return _ENUM
        elif isinstance(t, w.simple_type):
            return _REAL if t.declared_type() == "real" else _OTHER
        else:
            return _OTHER


@lru_cache(maxsize=None)
def _schema(name: str) -> Any:
    import ifcopenshell.ifcopenshell_wrapper as w

    return w.schema_by_name(name)


@lru_cache(maxsize=None)
def _class(schema: str, cls: str) -> _Class:
    decl = _schema(schema).declaration_by_name(cls)
    attrs = decl.all_attributes()
    ancestors, up = set(), decl
    while up is not None:
        ancestors.add(up.name().upper())
        up = up.supertype()
    return _Class(decl.name().upper(), {a.name(): k for k, a in enumerate(attrs)},
                  tuple(_kind(a.type_of_attribute()) for a in attrs), tuple(bool(d) for d in decl.derived()),
                  frozenset(ancestors))


@lru_cache(maxsize=None)
def _typed_kind(schema: str, cls: str) -> tuple[str, int] | None:
    """The name as written and the kind of a defined type (``IfcLabel``, ``IfcBoolean``, …); ``None`` for an
    entity class."""
    import ifcopenshell.ifcopenshell_wrapper as w

    decl = _schema(schema).declaration_by_name(cls)
    return (decl.name().upper(), _kind(decl)) if isinstance(decl, w.type_declaration) else None


# -- the header ----------------------------------------------------------------------------------------

@dataclass
class FileDescription:
    description: tuple[str, ...] = ("ViewDefinition [CoordinationView]",)
    implementation_level: str = "2;1"


@dataclass
class FileName:
    name: str = ""
    time_stamp: str = ""
    author: tuple[str, ...] = ("",)
    organization: tuple[str, ...] = ("",)
    preprocessor_version: str = ""
    originating_system: str = ""
    authorization: str = ""


@dataclass
class Header:
    file_description: FileDescription = field(default_factory=FileDescription)
    file_name: FileName = field(default_factory=FileName)


def _strings(values: Sequence[str]) -> str:
    return "(" + ",".join(string_text(v) for v in values) + ")"


# -- the file ------------------------------------------------------------------------------------------

class IfcText:
    """An IFC file being written: entities made by :meth:`create_entity` become lines of text at once.

    The subset of ``ifcopenshell.file`` that ``model.ifc``'s writer uses (``header``, ``create_entity``,
    ``write``), and :meth:`count` of the entities of a class and its subclasses."""

    def __init__(self, schema: str = "IFC4"):
        self.schema = schema
        self.header = Header()
        self._data = bytearray()
        self._next = 1
        self._made: Counter[str] = Counter()

    def create_entity(self, cls: str, *args: Any, **attributes: Any) -> Any:
        """A new entity of class ``cls`` with ``attributes`` (by name; positional ``args`` first), numbered next;
        for a defined type (``IfcLabel``, ``IfcBoolean``, …) its typed value ``args[0]``, written inline where
        it is used.  An attribute the class does not have raises ``ValueError``, as IfcOpenShell does."""
        if len(args) == 1 and not attributes and (typed := _typed_kind(self.schema, cls)) is not None:
            return Typed(f"{typed[0]}({_value_text(args[0], typed[1])})")
        c = _class(self.schema, cls)
        if len(args) > len(c.kinds):
            raise ValueError(f"entity instance of type '{cls}' has only {len(c.kinds)} attributes but {len(args)} "
                             "attributes were provided.")
        values: list[Any] = [None] * len(c.kinds)
        values[:len(args)] = args
        for name, value in attributes.items():
            k = c.index.get(name)
            if k is None:
                raise ValueError(f"entity instance of type '{cls}' doesn't have the following attributes: {name}.")
            values[k] = value
        text = ",".join(["*" if derived else _value_text(v, kind)
                         for v, kind, derived in zip(values, c.kinds, c.derived)])
        entity = Entity(self._next, cls)
        self._data += f"#{self._next}={c.upper}({text});\n".encode("ascii")
        self._next += 1
        self._made[cls] += 1
        return entity

    def count(self, cls: str) -> int:
        """How many entities of ``cls`` or a subclass of it the file has (``len(file.by_type(cls))``)."""
        upper = cls.upper()
        return sum(n for made, n in self._made.items() if upper in _class(self.schema, made).ancestors)

    def head(self) -> bytes:
        """The file's text up to ``DATA;``."""
        d, n = self.header.file_description, self.header.file_name
        return ("ISO-10303-21;\nHEADER;\n"
                f"FILE_DESCRIPTION({_strings(d.description)},{string_text(d.implementation_level)});\n"
                f"FILE_NAME({string_text(n.name)},{string_text(n.time_stamp)},{_strings(n.author)},"
                f"{_strings(n.organization)},{string_text(n.preprocessor_version)},"
                f"{string_text(n.originating_system)},{string_text(n.authorization)});\n"
                f"FILE_SCHEMA(('{self.schema}'));\nENDSEC;\nDATA;\n").encode("ascii")

    def write(self, path: str | Path) -> None:
        """Write the file to ``path``."""
        data = memoryview(self._data)
        with open(path, "wb") as out:
            out.write(self.head())
            for start in range(0, len(data), _CHUNK):
                out.write(data[start:start + _CHUNK])
            out.write(b"ENDSEC;\nEND-ISO-10303-21;\n")
        data.release()
