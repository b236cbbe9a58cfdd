"""A reader of STEP files (ISO 10303-21) at the text level, independent of the CAD kernel and of ppfab's writer.

Every solid ppfab writes is a prism of a planar polygon, some with round holes: a closed shell of planar faces
bounded by straight edges and circles, and cylindrical faces for the holes.  This module parses the entities
(``#id = TYPE(…);`` across lines, strings with ``''`` escapes, lists, complex entities), follows the product
tree (PRODUCT_DEFINITION → SHAPE_DEFINITION_REPRESENTATION, NEXT_ASSEMBLY_USAGE_OCCURRENCE with the
CONTEXT_DEPENDENT_SHAPE_REPRESENTATION whose ITEM_DEFINED_TRANSFORMATION places the child), the B-rep of each
solid (MANIFOLD_SOLID_BREP → CLOSED_SHELL → ADVANCED_FACE → FACE_BOUND → EDGE_LOOP → ORIENTED_EDGE →
EDGE_CURVE → VERTEX_POINT → CARTESIAN_POINT, on PLANE or CYLINDRICAL_SURFACE, edges on LINE or CIRCLE) and the
colours (STYLED_ITEM → … → COLOUR_RGB), and returns one light :class:`TextSolid` per placed solid: name,
assembly path, colour, placed vertices and faces.  Volume (divergence theorem, exact for circular arcs and
cylinder bands), face areas and a topological validity check are computed with numpy.

The B-reps are read all at once, type by type into tables (:mod:`._step_breps`), and measured all at once
(:mod:`._step_brep_facts`); this module walks the product tree and the styles, record by record.

Anything else in a B-rep (a B-spline surface, an ellipse) is refused with :class:`StepTextError` naming the
entity; ``ppfab verify --kernel`` reads such a file with the CAD kernel.

Not a check (the leading underscore keeps it out of the registry).
"""

from __future__ import annotations

import math
import os
import sys
from dataclasses import dataclass, field
from typing import NoReturn

import numpy as np

from ._shapes import cross3
from ._step_brep_facts import BrepFacts, facts_of
from ._step_breps import Tables, read_breps
from ._step_part21 import Entities, Ref, StepTextError, Typed, flat_params, parse_params, read_entities
from ._step_shell import Arc, Face, Loop, ShellCode

__all__ = ["Arc", "Entities", "Face", "Loop", "ShellCode", "StepModel", "StepTextError", "TextSolid",
           "read_entities", "read_text_solids", "solids_of"]


@dataclass(slots=True)
class TextSolid:
    """One placed solid of a STEP file as the text-level reader sees it: its product name, the names of the
    assemblies above it (root first), its colour ``(r, g, b, a)`` or ``None``, its vertices placed in the
    file's model space ``points (n, 3)`` mm, its faces (placed), the solid's vertices in its own representation
    ``local (n, 3)`` and the placement ``transform (4, 4)`` taking them into model space, and the id of its
    MANIFOLD_SOLID_BREP."""

    name: str
    path: tuple[str, ...]
    colour: tuple[float, float, float, float] | None
    points: np.ndarray
    code: ShellCode
    local: np.ndarray
    transform: np.ndarray
    brep: int
    shared: "dict[int, BrepFacts] | None" = field(default=None, repr=False)
    _facts: "BrepFacts | None" = field(default=None, repr=False)

    @property
    def shell(self) -> list[Face]:
        """The faces of the closed shell, placed: :attr:`code` (the faces in the B-rep's own coordinates, packed,
        shared by every solid placing it) unpacked and moved by :attr:`transform`.  Made anew at each call and
        not kept (a check reading a solid's faces takes them once): two calls give equal faces but not the same
        objects, so a face is told from another by its :attr:`Face.index`, never by identity."""
        if np.array_equal(self.transform, np.eye(4)):
            return self.code.faces()
        return self.code.faces(self.transform[:3, :3], self.transform[:3, 3])

    def faces(self) -> list[Face]:
        """The faces of the closed shell."""
        return self.shell

    @property
    def volume(self) -> float:
        """mm³ by the divergence theorem: ⅓ Σ over faces of ∫ x·n dA (exact for straight and circular edges and
        for cylinder bands)."""
        return self.facts().volume

    def facts(self) -> BrepFacts:
        """What a rigid motion does not change (:func:`~._step_brep_facts.facts_of`): the reader works it out for
        all B-reps of a file at once and keeps it per B-rep in :attr:`shared` (an instanced shape's solids share
        their B-rep); a solid made otherwise works out its own."""
        if self._facts is None:
            got = self.shared.get(self.brep) if self.shared is not None else None
            if got is None:
                got = facts_of([(self.local, self.code)])[0]
                if self.shared is not None:
                    self.shared[self.brep] = got
            self._facts = got
        return self._facts

    def face_area(self, face: Face) -> float:
        """Area of a planar face of :attr:`shell`, mm² (its loops' signed areas about its normal summed, outer
        less holes; 0 for a cylinder): :attr:`BrepFacts.face_areas` at the face's :attr:`Face.index`."""
        return self.facts().face_areas[face.index]

    def outer_loop(self, face: Face) -> Loop:
        """The loop of a planar face enclosing the largest area (its outer boundary;
        :attr:`BrepFacts.loop_areas`)."""
        if len(face.loops) == 1:
            return face.loops[0]
        first = int(self.code.face_loops[face.index])
        areas = self.facts().loop_areas
        return max(zip(face.loops, range(first, first + len(face.loops))), key=lambda x: abs(areas[x[1]]))[0]

    def ring(self, loop: Loop, arc_points: int = 0) -> np.ndarray:
        """``(k, 3)`` the loop's points in order: its vertices, with ``arc_points - 1`` more along each circular
        edge when ``arc_points`` > 0."""
        out = []
        for k, i in enumerate(loop.vertices.tolist()):
            out.append(self.points[i])
            arc = loop.arcs[k]
            if arc is not None and arc_points > 0:
                e1 = self.points[i] - arc.centre
                e2 = cross3(arc.axis, e1)
                for t in np.linspace(0.0, arc.sweep, arc_points + 1)[1:-1]:
                    out.append(arc.centre + e1 * math.cos(t) + e2 * math.sin(t))
        return np.array(out, dtype=float).reshape(-1, 3)

    def face_outline(self, normal: np.ndarray) -> np.ndarray | None:
        """The outer boundary (vertices in order) of the planar face facing ``normal`` (either sense), or
        ``None``."""
        n = np.asarray(normal, dtype=float)
        for f in self.shell:
            if f.surface == "plane" and abs(float(f.normal @ n)) >= 1.0 - 1e-9:
                return self.ring(self.outer_loop(f))
        return None

    def circle_centres(self) -> np.ndarray:
        """``(c, 3)`` the centres of the circular edges (each edge once)."""
        seen: dict[int, np.ndarray] = {}
        for f in self.shell:
            for lp in f.loops:
                for e, arc in zip(lp.edges, lp.arcs):
                    if arc is not None:
                        seen.setdefault(e, arc.centre)
        return np.array(list(seen.values()), dtype=float).reshape(-1, 3)

    def problems(self, tol: float = 1e-6) -> list[str]:
        """What makes the solid invalid at the text level (empty when none): an edge not used exactly twice in
        opposite senses (the shell is not closed and oriented), a vertex off its face's plane or cylinder or a
        circle's end off its circle by more than ``tol`` (relative to the solid's size), a volume not above 0."""
        facts = self.facts()
        out: list[str] = []
        if facts.bad_edges:
            out.append(f"{facts.bad_edges} edge(s) not shared by exactly two faces in opposite senses "
                       f"(#{facts.first_bad_edge})")
        scale = max(1.0, float(np.abs(self.points).max()) if len(self.points) else 1.0)
        if facts.off_surface > tol * scale:
            out.append(f"a vertex is {facts.off_surface:.3g} mm off its face's surface or its edge's circle")
        if not self.volume > 0:
            out.append(f"volume {self.volume:.6g} mm³ is not positive (faces turned inside out)")
        return out

    @property
    def is_valid(self) -> bool:
        """No :meth:`problems`."""
        return not self.problems()

    def shape_key(self) -> tuple:
        """What kind of solid this is, whatever its size and place: per face its surface and the edge counts and
        arcs of its loops, sorted.  Solids of one key are read by the CAD kernel once (one instance each)."""
        return (len(self.points), self.code.key())


class StepModel:
    """The entities of one file and the readers of the records the solids are made of."""

    def __init__(self, entities: Entities):
        self.raw = entities
        self.cache: dict[int, list] = {}
        self.breps: dict[int, tuple[np.ndarray, ShellCode]] = {}
        self.tables = Tables(entities)
        self.facts: dict[int, BrepFacts] = {}
        self.by_kind: dict[str, list[int]] = {}

    def kind(self, i: int) -> str:
        try:
            return self.raw.kind(i)
        except KeyError:
            raise StepTextError(f"#{i} is referenced but not defined") from None

    def args(self, i: int) -> list:
        """The parameters of ``#i`` parsed (:meth:`read`), kept: the records the product tree and the styles
        read more than once (a product's, a representation's, a style's; a B-rep's are read into
        :attr:`tables`, never one by one)."""
        got = self.cache.get(i)
        if got is None:
            got = self.cache[i] = self.read(i)
        return got

    def read(self, i: int) -> list:
        """The parameters of ``#i`` parsed (:func:`~._step_part21.parse_params`), not kept: the records read once
        (an occurrence, its placement and relations).  At 88 × 60 faces 632,000 records of glazing.step's product
        tree and styles were kept, now 149,000: 0.2 GB less at the end of the read (1,578 → 1,365 MB)."""
        try:
            _, text = self.raw[i]
        except KeyError:
            self._missing(i)
        got = flat_params(text)
        return parse_params(text) if got is None else got

    @staticmethod
    def _missing(i: int) -> NoReturn:
        raise StepTextError(f"#{i} is referenced but not defined")

    def ids(self, kind: str) -> list[int]:
        """The ids of the entities of type ``kind``, in file order."""
        got = self.by_kind.get(kind)
        if got is None:
            got = self.by_kind[kind] = self.raw.of_kind(kind).tolist()
        return got


def _name(args: list) -> str:
    """A PRODUCT's name, else its id."""
    return str(args[1] or args[0]) if len(args) > 1 else str(args[0])


def _colours(model: StepModel) -> dict[int, tuple[float, float, float, float]]:
    """Styled item (a B-rep or any other entity) → its colour, an overriding style winning over a plain one;
    alpha 1 less a SURFACE_STYLE_TRANSPARENT's transparency."""
    out: dict[int, tuple[float, float, float, float]] = {}
    for kind in ("STYLED_ITEM", "OVER_RIDING_STYLED_ITEM"):
        for i in model.ids(kind):
            a = model.read(i)
            item = a[2]
            if not isinstance(item, Ref):
                continue
            rgb: list[float] | None = None
            alpha = 1.0
            stack = list(a[1])
            seen: set[int] = set()
            while stack:
                x = stack.pop()
                if isinstance(x, list):
                    stack.extend(x)
                    continue
                if isinstance(x, Typed):
                    stack.extend(x.args)
                    continue
                if not isinstance(x, Ref) or x.id in seen:
                    continue
                seen.add(x.id)
                k = model.kind(x.id)
                if k == "COLOUR_RGB":
                    rgb = [float(c) for c in model.args(x.id)[1:4]]
                elif k == "SURFACE_STYLE_TRANSPARENT":
                    alpha = 1.0 - float(model.args(x.id)[0])
                elif k in ("PRESENTATION_STYLE_ASSIGNMENT", "PRESENTATION_STYLE_BY_CONTEXT", "SURFACE_STYLE_USAGE",
                           "SURFACE_SIDE_STYLE", "SURFACE_STYLE_FILL_AREA", "FILL_AREA_STYLE",
                           "FILL_AREA_STYLE_COLOUR", "SURFACE_STYLE_RENDERING_WITH_PROPERTIES"):
                    stack.extend(model.args(x.id)[:2] if k == "PRESENTATION_STYLE_BY_CONTEXT"
                                 else model.args(x.id))
            if rgb is not None:
                out[item.id] = (rgb[0], rgb[1], rgb[2], alpha)
    return out


FACTS_CHUNK = 4096
"""B-reps measured at a time (:func:`~._step_brep_facts.facts_of`, whose arrays are a few per edge of every B-rep
given).  All at once, glazing.step's 37,068 distinct B-reps at 88 × 60 faces added about 0.3 GB to its read's
peak (1,578 → 1,891 MB, the read taken step by step); in chunks of this size the time is the same."""


def read_text_solids(path: str | os.PathLike, data: bytes | None = None) -> list[TextSolid]:
    """Every solid of the STEP file ``path`` placed in its model space, depth first through the product tree
    (children in the order of their NEXT_ASSEMBLY_USAGE_OCCURRENCE), with names, assembly path and colour.
    A solid's name is that of the occurrence placing it (NEXT_ASSEMBLY_USAGE_OCCURRENCE's name), else its
    product's: a product of one shape placed many times (an instanced shape) is one solid per occurrence, each
    named by its occurrence.

    Raises :class:`StepTextError` on a file it cannot read, and the audit event ``fabrication.verify.read``."""
    sys.audit("fabrication.verify.read", os.fspath(path))
    if data is None:
        with open(path, "rb") as fh:
            data = fh.read()
    return solids_of(StepModel(read_entities(data)))


def solids_of(model: StepModel) -> list[TextSolid]:
    """The placed solids of a parsed file (:func:`read_text_solids`)."""
    rep_of: dict[int, list[int]] = {}                         # product definition → its shape representations
    for i in model.ids("SHAPE_DEFINITION_REPRESENTATION"):
        pds, rep = model.read(i)[:2]
        target = model.read(pds.id)[2]
        if isinstance(target, Ref) and model.kind(target.id) == "PRODUCT_DEFINITION":
            rep_of.setdefault(target.id, []).append(rep.id)
    linked: dict[int, list[int]] = {}                        # representation → representations tied to it
    for kind in ("SHAPE_REPRESENTATION_RELATIONSHIP",):
        for i in model.ids(kind):
            a = model.read(i)
            linked.setdefault(a[2].id, []).append(a[3].id)
            linked.setdefault(a[3].id, []).append(a[2].id)
    placement: dict[int, np.ndarray] = {}                    # NAUO → child coordinates → parent coordinates
    moves: list[tuple[int, int, int]] = []                   # NAUO, the placements it takes from and to
    for i in model.ids("CONTEXT_DEPENDENT_SHAPE_REPRESENTATION"):
        rr, pds = model.read(i)[:2]
        nauo = model.read(pds.id)[2]
        parts = {t.name: t.args for t in model.read(rr.id) if isinstance(t, Typed)}
        trans = parts.get("REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION")
        if trans is None or not isinstance(nauo, Ref):
            continue
        idt = trans[0].id
        if model.kind(idt) != "ITEM_DEFINED_TRANSFORMATION":
            raise StepTextError(f"#{idt} is a {model.kind(idt)}: placements by ITEM_DEFINED_TRANSFORMATION only")
        a1, a2 = model.read(idt)[2:4]
        moves.append((nauo.id, a1.id, a2.id))
    if moves:                                                # all placements' frames at once
        occurrences, from_, to = (np.array(c, dtype=np.int64) for c in zip(*moves))
        for nauo_id, m in zip(occurrences.tolist(), model.tables.matrices(to) @ np.linalg.inv(
                model.tables.matrices(from_))):
            placement[nauo_id] = m
    children: dict[int, list[tuple[int, int, str]]] = {}
    is_child: set[int] = set()
    for i in sorted(model.ids("NEXT_ASSEMBLY_USAGE_OCCURRENCE")):
        a = model.read(i)
        children.setdefault(a[3].id, []).append((i, a[4].id, str(a[1] or "")))
        is_child.add(a[4].id)
    colours = _colours(model)
    out: list[TextSolid] = []

    def name_of(pd: int) -> str:
        pdf = model.args(pd)[2].id
        return _name(model.args(model.args(pdf)[2].id))

    def breps(pd: int) -> list[int]:
        found: list[int] = []
        todo = list(rep_of.get(pd, []))
        seen: set[int] = set()
        while todo:
            r = todo.pop(0)
            if r in seen:
                continue
            seen.add(r)
            for item in model.args(r)[1]:
                if isinstance(item, Ref) and model.kind(item.id) == "MANIFOLD_SOLID_BREP":
                    found.append(item.id)
            todo.extend(linked.get(r, []))
        return found

    placed: list[tuple[int, np.ndarray, str, tuple[str, ...]]] = []
    # depth first, roots in id order, children in their occurrences' order, on a stack of its own: a recursive
    # closure is a reference cycle, which held the model, the file's text and its tables until the next
    # collection (at 88 × 60 faces through the kernel's read of glazing.step's sample)
    todo: list[tuple[int, np.ndarray, tuple[str, ...], str]] = [
        (pd, np.eye(4), (), "") for pd in sorted(model.ids("PRODUCT_DEFINITION"), reverse=True) if pd not in is_child]
    while todo:
        pd, transform, above, occurrence = todo.pop()
        name = name_of(pd)
        kids = children.get(pd, [])
        if kids:
            todo.extend((child, transform @ placement.get(nauo, np.eye(4)), above + (name,), called)
                        for nauo, child, called in reversed(kids))
            continue
        name = occurrence or name                      # a shape used by many occurrences: each one's name
        placed.extend((b, transform, name, above) for b in breps(pd))
    missing = sorted({b for b, *_ in placed} - model.breps.keys())
    if missing:
        model.breps.update(read_breps(model.tables, missing))
        for k in range(0, len(missing), FACTS_CHUNK):
            chunk = missing[k:k + FACTS_CHUNK]
            model.facts.update(zip(chunk, facts_of([model.breps[b] for b in chunk])))
    for b, transform, name, above in placed:
        local, code = model.breps[b]
        points = local @ transform[:3, :3].T + transform[:3, 3]
        out.append(TextSolid(name, above, colours.get(b), points, code, local, transform, b, shared=model.facts))
    return out
