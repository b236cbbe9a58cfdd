"""The ISO 10303-21 (STEP Part 21) text level of :mod:`._step_text_read`: entity records ``#id = TYPE(…);`` across
lines, parameters with strings (``''`` escapes), references, enumerations, typed values, lists and complex
entities; the common geometric entities on a fast path.

Not a check (the leading underscore keeps it out of the registry).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import NamedTuple

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


def read_entities(data: bytes) -> dict[int, tuple[str, str]]:
    """``#id`` → (type name, the raw text of its parameters including the parentheses; a complex entity's type is
    ``''``) for every entity of the DATA section."""
    start = data.find(b"DATA;")
    end = data.rfind(b"ENDSEC;")
    if start < 0:
        raise StepTextError("no DATA section")
    if end < start:
        raise StepTextError("the DATA section does not end (no ENDSEC; after it): the file is cut short")
    out: dict[int, tuple[str, str]] = {}
    kinds: dict[str, str] = {}                    # one string per entity type (a million entities, a few dozen types)
    chunks = data[start + 5:end].decode("latin-1").split(";")
    k = 0
    while k < len(chunks):
        record = chunks[k]
        k += 1
        while record.count("'") % 2 and k < len(chunks):     # a ';' inside a string: join the pieces again
            record += ";" + chunks[k]
            k += 1
        record = record.strip()
        if not record:
            continue
        head, eq, body = record.partition("=")
        head, body = head.strip(), body.strip()
        if not eq or not head.startswith("#") or not head[1:].isdigit():
            raise StepTextError(f"cannot parse the entity {record[:60]!r}")
        p = body.find("(")
        if p < 0:
            raise StepTextError(f"{head}: no parameter list")
        kind = body[:p].strip()
        out[int(head[1:])] = (kinds.setdefault(kind, kind), body[p:])
    return out


_REFS = re.compile(r"#(\d+)")

_FAST = {"CARTESIAN_POINT", "DIRECTION", "VERTEX_POINT", "MANIFOLD_SOLID_BREP", "CLOSED_SHELL", "EDGE_LOOP",
         "FACE_BOUND", "FACE_OUTER_BOUND", "ORIENTED_EDGE", "EDGE_CURVE", "ADVANCED_FACE", "PLANE", "CIRCLE",
         "CYLINDRICAL_SURFACE", "AXIS2_PLACEMENT_3D"}


def fast_params(kind: str, text: str) -> list | None:
    """:func:`parse_params` of the B-rep entities whose names are empty, by their fixed layout (five times
    faster); ``None`` for any other entity, which the full parser reads."""
    if kind not in _FAST or text.count("'") != 2 * text.count("''"):
        return None
    if kind in ("CARTESIAN_POINT", "DIRECTION"):
        inner = text[text.index("(", 1) + 1:text.index(")")]
        return ["", [float(x) for x in inner.split(",")]]
    refs = [Ref(int(x)) for x in _REFS.findall(text)]
    flag = text.rstrip().endswith(".T.)")
    if kind in ("VERTEX_POINT", "MANIFOLD_SOLID_BREP", "PLANE") and len(refs) == 1:
        return ["", refs[0]]
    if kind in ("CLOSED_SHELL", "EDGE_LOOP"):
        return ["", refs]
    if kind in ("FACE_BOUND", "FACE_OUTER_BOUND") and len(refs) == 1:
        return ["", refs[0], flag]
    if kind == "ORIENTED_EDGE" and len(refs) == 1 and text.count("*") == 2:
        return ["", "*", "*", refs[0], flag]
    if kind == "EDGE_CURVE" and len(refs) == 3:
        return ["", refs[0], refs[1], refs[2], flag]
    if kind == "ADVANCED_FACE" and len(refs) >= 2:
        return ["", refs[:-1], refs[-1], flag]
    if kind in ("CIRCLE", "CYLINDRICAL_SURFACE") and len(refs) == 1:
        return ["", refs[0], float(text[text.rindex(",") + 1:text.rindex(")")])]
    if kind == "AXIS2_PLACEMENT_3D" and len(refs) == 3:
        return ["", refs[0], refs[1], refs[2]]
    return None
