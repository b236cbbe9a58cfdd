r"""The text of ppfab's STEP files: product labels in ASCII, ISO 10303-21 strings, the header, the colours in
a canonical order (:func:`canonical_styles`).

The CAD kernel writes ``FILE_NAME(…, ('Author'), ('Open CASCADE'), …)`` and the wall-clock time; ppfab replaces
``FILE_DESCRIPTION`` and ``FILE_NAME`` with its own (:func:`step_header`): the design in the description, a fixed
time stamp, ppfab and its version as the originating system, the kernel's STEP processor as the preprocessor.
Header strings are encoded as ISO 10303-21 requires (``''`` for a quote, ``\\`` for a backslash,
``\X2\00E9\X0\`` for a character outside printable ASCII); product names (labels) are folded to ASCII, since the
kernel writes a label's UTF-8 bytes unencoded.
"""

from __future__ import annotations

import re
import unicodedata

from ppfab import __version__

from ..contract import FIXED_TIMESTAMP


def step_label(name: str) -> str:
    """A product name for a STEP file: ``name`` folded to printable ASCII.

    >>> step_label("Überdachung Süd")
    'Uberdachung Sud'
    """
    folded = unicodedata.normalize("NFKD", name).encode("ascii", "ignore").decode("ascii")
    return "".join(c for c in folded if c.isprintable()) or "ppfab"


def step_string(text: str) -> str:
    r"""``text`` as an ISO 10303-21 string literal.

    >>> print(step_string("Café 'A'"))
    'Caf\X2\00E9\X0\ ''A'''
    """
    out = []
    for ch in text:
        if ch == "'":
            out.append("''")
        elif ch == "\\":
            out.append("\\\\")
        elif " " <= ch <= "~":
            out.append(ch)
        else:
            out.append("\\X2\\" + ch.encode("utf-16-be").hex().upper() + "\\X0\\")
    return "'" + "".join(out) + "'"


def step_header(file_name: str, description: str, preprocessor: str) -> bytes:
    """``FILE_DESCRIPTION`` and ``FILE_NAME`` of a ppfab STEP file."""
    desc = f"ppfab {__version__}: {description}" if description else f"ppfab {__version__}"
    return (f"FILE_DESCRIPTION(({step_string(desc)}),'2;1');\n"
            f"FILE_NAME({step_string(file_name)},{step_string(FIXED_TIMESTAMP)},(''),(''),\n"
            f"  {step_string(preprocessor)},{step_string(f'ppfab {__version__}')},'');\n").encode("ascii")


_FILE_NAME = re.compile(rb"FILE_NAME\((?:\s*(?:'(?:[^']|'')*'|\([^)]*\))\s*,){4}\s*'((?:[^']|'')*)'", re.S)


def replace_header(head: bytes, file_name: str, description: str) -> bytes:
    """The header section ``head`` (up to the first ``ENDSEC;``) with ppfab's ``FILE_DESCRIPTION`` and
    ``FILE_NAME`` in place of the kernel's (its preprocessor version kept)."""
    found = _FILE_NAME.search(head)
    pre = found.group(1).decode("ascii", "replace").replace("''", "'") if found else "Open CASCADE"
    start, end = head.find(b"FILE_DESCRIPTION("), head.find(b"FILE_SCHEMA(")
    if start < 0 or end < start:
        raise ValueError("unexpected STEP header: no FILE_DESCRIPTION before FILE_SCHEMA")
    return head[:start] + step_header(file_name, description, pre) + head[end:]


# -- presentation styles in a canonical order -----------------------------------------------------------

_ENTITY = re.compile(rb"#(\d+)\s*=\s*(.*?);\s*(?=#\d+\s*=|\Z)", re.S)
_REF = re.compile(rb"#(\d+)")
_STYLE_START = re.compile(rb"#\d+\s*=\s*MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION\(")
_SHARED = {b"COLOUR_RGB", b"DRAUGHTING_PRE_DEFINED_CURVE_FONT", b"CURVE_STYLE", b"FILL_AREA_STYLE_COLOUR",
           b"FILL_AREA_STYLE", b"SURFACE_STYLE_FILL_AREA", b"SURFACE_SIDE_STYLE", b"SURFACE_STYLE_USAGE"}
"""Style entities that are values (no reference to geometry): identical ones are written once."""


def canonical_styles(body: bytes) -> bytes:
    """The DATA section ``body`` with its presentation styles (colours) in a canonical order.

    The kernel writes the colours last — one ``MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION`` per
    coloured shape with its styled items, style assignments and colours — in an order that follows memory
    addresses, and shares a colour entity between shapes or not depending on that order: two runs give
    different bytes for the same colours.  This rewrites that tail as a canonical graph: every entity keyed by its
    text with references into the tail replaced by their keys (a Merkle key; references to the geometry before
    the tail stay as they are), the value entities of :data:`_SHARED` written once per key, the rest once each,
    depth first from the presentation representations in the order of their keys, renumbered from the tail's
    first id.  Nothing before the tail refers into it (checked), so the geometry and the product tree are
    unchanged.
    """
    m = _STYLE_START.search(body)
    if m is None:
        return body
    head, tail = body[:m.start()], body[m.start():]
    ents: dict[int, tuple[bytes, bytes]] = {}
    for em in _ENTITY.finditer(tail):
        text = re.sub(rb"\s*\n\s*", b"", em.group(2))
        kind = text.split(b"(", 1)[0].strip()
        ents[int(em.group(1))] = (kind, text)
    if not ents or any(int(r) in ents for r in _REF.findall(head)):
        raise ValueError("unexpected STEP data: the geometry refers to the presentation styles")
    keys: dict[int, bytes] = {}

    def key(i: int) -> bytes:
        if i not in keys:
            kind, text = ents[i]
            keys[i] = _REF.sub(lambda r: b"{" + key(int(r.group(1))) + b"}" if int(r.group(1)) in ents
                               else r.group(0), text)
        return keys[i]

    referenced = {int(r) for _, text in ents.values() for r in _REF.findall(text)}
    roots = sorted((i for i in ents if i not in referenced), key=key)
    new_id: dict[object, int] = {}
    order: list[int] = []
    next_id = [min(ents)]

    def visit(i: int) -> int:
        kind, text = ents[i]
        slot: object = key(i) if kind in _SHARED else i
        if slot not in new_id:
            new_id[slot] = next_id[0]
            next_id[0] += 1
            order.append(i)
            for r in _REF.findall(text):
                if int(r) in ents:
                    visit(int(r))
        return new_id[slot]

    for root in roots:
        visit(root)

    def renumber(i: int) -> bytes:
        kind, text = ents[i]
        return _REF.sub(lambda r: b"#%d" % visit(int(r.group(1))) if int(r.group(1)) in ents else r.group(0), text)

    out = [b"#%d = %s;\n" % (visit(i), renumber(i)) for i in order]
    return head + b"".join(out)
