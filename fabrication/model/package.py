"""The whole of a finished build as typed records: :class:`Package`, and :func:`differences` between two.

``fabrication.open_build(folder)`` reads one from an output folder; ``fabrication.readers.package_of(build)``
makes one from a build in memory.  The files round some values (``welds.csv`` to 3–4 decimals, the cutting
outlines pass through the placement and back), so two packages of one build are compared with a tolerance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, is_dataclass
from typing import Any, Iterator, Mapping

from .mesh import MeshData
from .node import Node
from .part import Part
from .sheet import Sheet
from .weld import Weld


@dataclass(frozen=True)
class Package:
    """A build's parts (in ``parts.csv`` order), nodes (vertex order), welds (``welds.csv`` order), cutting sheets
    (glass, then plates), the mesh, the design name and the program that wrote it (``ppfab 0.1.0``)."""

    name: str
    generator: str
    parts: tuple[Part, ...]
    nodes: tuple[Node, ...]
    welds: tuple[Weld, ...]
    sheets: tuple[Sheet, ...]
    mesh: MeshData

    def part(self, part_id: str) -> Part:
        """The part with this id (``KeyError`` naming it when there is none)."""
        for p in self.parts:
            if p.part_id == part_id:
                return p
        raise KeyError(f"no part {part_id!r} in {self.name}")

    def of_kind(self, kind: str) -> tuple[Part, ...]:
        """The parts of one kind, in order."""
        return tuple(p for p in self.parts if p.kind == kind)

    @property
    def kinds(self) -> dict[str, int]:
        """Kind → number of parts, in order of first appearance."""
        out: dict[str, int] = {}
        for p in self.parts:
            out[p.kind] = out.get(p.kind, 0) + 1
        return out


ABS_TOL = 1e-3
"""Default absolute tolerance of :func:`differences` (mm, degrees, kg): the files round lengths to 3 decimals
(half a unit: 5e-4)."""

REL_TOL = 1e-9
"""Default relative tolerance of :func:`differences`: the cutting outlines mapped onto a sheet and back."""


def differences(a: Any, b: Any, abs_tol: float = ABS_TOL, rel_tol: float = REL_TOL, limit: int = 20) -> list[str]:
    """Where two records (packages, parts, …) differ, as ``path: a != b`` lines (at most ``limit``); numbers
    agree within ``abs_tol + rel_tol · max(|a|, |b|)``, ints and floats compare as numbers.

    >>> from fabrication.model.weld import Weld
    >>> differences(Weld(node=1, part="A", weld_length_mm=300.0), Weld(node=1, part="A", weld_length_mm=300.0004))
    []
    >>> differences(Weld(node=1, part="A"), Weld(node=2, part="A"))
    ['.node: 1 != 2']
    """
    out: list[str] = []
    for line in _diff(a, b, "", abs_tol, rel_tol):
        out.append(line)
        if len(out) >= limit:
            break
    return out


def _diff(a: Any, b: Any, path: str, abs_tol: float, rel_tol: float) -> Iterator[str]:
    if isinstance(a, bool) or isinstance(b, bool):
        if a != b:
            yield f"{path}: {a!r} != {b!r}"
        return
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        if not (math.isclose(a, b, rel_tol=rel_tol, abs_tol=abs_tol) or (math.isnan(a) and math.isnan(b))):
            yield f"{path}: {a!r} != {b!r}"
        return
    if is_dataclass(a) and is_dataclass(b) and not isinstance(a, type) and not isinstance(b, type):
        if type(a) is not type(b):
            yield f"{path}: {type(a).__name__} != {type(b).__name__}"
            return
        for f in fields(a):
            yield from _diff(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}", abs_tol, rel_tol)
        return
    if isinstance(a, Mapping) and isinstance(b, Mapping):
        for k in sorted(set(a) | set(b), key=str):
            if k not in a or k not in b:
                yield f"{path}[{k!r}]: {'missing' if k not in a else a[k]!r} != {'missing' if k not in b else b[k]!r}"
            else:
                yield from _diff(a[k], b[k], f"{path}[{k!r}]", abs_tol, rel_tol)
        return
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        if len(a) != len(b):
            yield f"{path}: {len(a)} items != {len(b)} items"
            return
        for k, (x, y) in enumerate(zip(a, b)):
            name = getattr(x, "part_id", None) or getattr(x, "node_id", None) or getattr(x, "file", None)
            yield from _diff(x, y, f"{path}[{name or k}]", abs_tol, rel_tol)
        return
    if a != b:
        yield f"{path}: {a!r} != {b!r}"
