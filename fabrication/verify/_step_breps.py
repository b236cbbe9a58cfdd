"""Every B-rep of a STEP file read at once: the topology entities parsed into one table per type, the shells,
faces, loops and edges of all B-reps followed by array indexing, and each B-rep's faces packed
(:class:`~._step_shell.ShellCode`).

The B-rep entities of a file come in fixed layouts (``#7 = EDGE_CURVE('',#3,#4,#5,.T.);``), a million of
them in glazing.step at 44 × 30 faces.  Parsing them one by one (a Python call per entity, a few per reference
followed) took most of the text-level read.  Here each type's records are joined and matched by one regular
expression in C (:func:`parse_table`), the references become integer columns, and the B-reps are assembled over
all of them at once (:func:`read_breps`).  A record the expression does not match (another writer's spacing, a
2D point) is parsed by the general Part 21 parser (:func:`~._step_part21.parse_params`) and written back in the
layout, so the tables hold every record of the type either way.

What is read is exactly what :mod:`._step_text_read` documents: MANIFOLD_SOLID_BREP → CLOSED_SHELL →
ADVANCED_FACE (on PLANE or CYLINDRICAL_SURFACE) → FACE_BOUND / FACE_OUTER_BOUND → EDGE_LOOP → ORIENTED_EDGE →
EDGE_CURVE (on LINE or CIRCLE, through SURFACE_CURVE / SEAM_CURVE when written with p-curves) → VERTEX_POINT →
CARTESIAN_POINT.  A reference to an entity of another type, or to none, raises
:class:`~._step_part21.StepTextError` naming it.

Not a check (the leading underscore keeps it out of the registry).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ._step_part21 import Entities, Ref, StepTextError, narrow_ids, parse_params
from ._step_shell import ShellCode


_NAME = rb"\s*'(?:[^']|'')*'\s*"
_REAL = rb"\s*([-+0-9.][0-9.Ee+-]*)\s*"
_FIELDS: dict[str, tuple[bytes, int]] = {
    "ref": (rb"\s*#(\d+)\s*", 1),
    "ref?": (rb"\s*(?:#(\d+)|\$)\s*", 1),
    "real": (_REAL, 1),
    "bool": (rb"\s*\.([TF])\.\s*", 1),
    "*": (rb"\s*\*\s*", 0),
    "refs": (rb"\s*\(((?:\s*#\d+\s*,)*\s*#\d+\s*)\)\s*", 1),
    "xyz": (rb"\s*\(" + _REAL + b"," + _REAL + b"," + _REAL + rb"\)\s*", 3),
}
"""The parameter kinds of a layout: its pattern (on the record's bytes) and how many values it captures: a
reference, an optional reference (``$`` → -1), a real, a boolean, an omitted ``*``, a list of references, three
reals."""


@dataclass(frozen=True)
class Layout:
    """The types read into one table and the parameters after their name, in order (keys of :data:`_FIELDS`)."""

    types: tuple[str, ...]
    fields: tuple[str, ...]

    def pattern(self, anchored: bool) -> re.Pattern[bytes]:
        """The record's parameter text ``('', …)`` as a pattern; ``anchored`` between NUL separators (a joined
        chunk of records, each matched whole), else for one record alone."""
        body = rb"\(" + _NAME + b"".join(b"," + _FIELDS[f][0] for f in self.fields) + rb"\)"
        return re.compile(rb"\x00" + body + rb"(?=\x00)" if anchored else body)


LAYOUTS = {
    "point": Layout(("CARTESIAN_POINT", "DIRECTION"), ("xyz",)),
    "vertex": Layout(("VERTEX_POINT",), ("ref",)),
    "brep": Layout(("MANIFOLD_SOLID_BREP",), ("ref",)),
    "shell": Layout(("CLOSED_SHELL",), ("refs",)),
    "face": Layout(("ADVANCED_FACE",), ("refs", "ref", "bool")),
    "bound": Layout(("FACE_BOUND", "FACE_OUTER_BOUND"), ("ref", "bool")),
    "loop": Layout(("EDGE_LOOP",), ("refs",)),
    "oriented": Layout(("ORIENTED_EDGE",), ("*", "*", "ref", "bool")),
    "edge": Layout(("EDGE_CURVE",), ("ref", "ref", "ref", "bool")),
    "plane": Layout(("PLANE",), ("ref",)),
    "round": Layout(("CYLINDRICAL_SURFACE", "CIRCLE"), ("ref", "real")),
    "axis": Layout(("AXIS2_PLACEMENT_3D",), ("ref", "ref?", "ref?")),
}
"""The tables :func:`read_breps` reads, by name."""

CHUNK = 50_000
"""Records joined and matched at a time: the matches of one chunk are bytes objects until they become columns."""


@dataclass(frozen=True)
class Table:
    """The records of one :class:`Layout`, in file order: ``rows (m,)`` where each stands among the file's
    entities (:attr:`Entities.ids`), ``ints (m, i)`` its references (-1 for ``$``) and booleans (0/1) in the order
    of the layout's fields, ``reals (m, r)`` its reals (a 2D point's three are NaN), and its list of references,
    if the layout has one, as ``first (m + 1,)`` offsets into ``items``.  References are 32-bit where they fit
    (a file numbered from 1: a million entities is a large file)."""

    rows: np.ndarray
    ints: np.ndarray
    reals: np.ndarray
    first: np.ndarray
    items: np.ndarray


def _canonical(layout: Layout, i: int, kind: str, text: str) -> tuple[bytes, ...]:
    """The values of record ``#i`` read by the general parser, written as the layout's pattern captures them;
    :class:`StepTextError` when they do not fit the layout."""
    args = parse_params(text)
    out: list[bytes] = []
    values = args[1:] if args else []
    if len(values) != len(layout.fields):
        raise StepTextError(f"#{i} {kind} has {len(values)} parameters after its name, not {len(layout.fields)}")
    for field, x in zip(layout.fields, values):
        if field in ("ref", "ref?"):
            if isinstance(x, Ref):
                out.append(b"%d" % x.id)
            elif x is None and field == "ref?":
                out.append(b"")
            else:
                raise StepTextError(f"#{i} {kind}: {x!r} where a reference belongs")
        elif field == "real":
            if not isinstance(x, float):
                raise StepTextError(f"#{i} {kind}: {x!r} where a number belongs")
            out.append(repr(x).encode())
        elif field == "bool":
            if not isinstance(x, bool):
                raise StepTextError(f"#{i} {kind}: {x!r} where .T. or .F. belongs")
            out.append(b"T" if x else b"F")
        elif field == "*":
            continue
        elif field == "refs":
            if not isinstance(x, list) or not all(isinstance(r, Ref) for r in x):
                raise StepTextError(f"#{i} {kind}: {x!r} where a list of references belongs")
            out.append(b",".join(b"#%d" % r.id for r in x))
        else:                                                   # xyz: a 2D point reads as NaN
            if not isinstance(x, list) or not all(isinstance(c, float) for c in x) or len(x) not in (2, 3):
                raise StepTextError(f"#{i} {kind}: {x!r} where two or three coordinates belong")
            out.extend([repr(c).encode() for c in x] if len(x) == 3 else [b"nan"] * 3)
    return tuple(out)


def parse_table(ents: Entities, layout: Layout) -> Table:
    """Every record of the layout's types (:class:`Table`): chunks of records joined by NUL and matched whole by
    the layout's pattern; a chunk with a record that does not match is matched record by record, and those
    records parsed in full (:func:`_canonical`).  Each chunk's matches become numbers before the next is read."""
    codes = [ents.code(t) for t in layout.types]
    rows = np.flatnonzero(np.isin(ents.kinds, [c for c in codes if c >= 0]))
    anchored, alone = layout.pattern(True), layout.pattern(False)
    ints: list[np.ndarray] = []
    reals: list[np.ndarray] = []
    counts: list[np.ndarray] = []
    items: list[np.ndarray] = []
    for k in range(0, len(rows), CHUNK):
        chunk = rows[k:k + CHUNK]
        found: list = anchored.findall(b"\x00" + ents.joined(chunk, b"\x00") + b"\x00")
        if len(found) != len(chunk) or ents.has_nul:
            found = []
            for r, text in zip(chunk.tolist(), ents.texts(chunk)):
                m = alone.fullmatch(text)
                if m is not None:
                    found.append(m.groups(b""))        # a ``$`` reference: empty, as findall gives it
                else:
                    i = int(ents.ids[r])
                    found.append(_canonical(layout, i, ents.names[ents.kinds[r]], text.decode("latin-1")))
        columns = list(zip(*found)) if found and isinstance(found[0], tuple) else [found]
        chunk_ints, chunk_reals = _columns(layout, columns, counts, items)
        ints.append(chunk_ints.reshape(len(chunk), -1))
        reals.append(chunk_reals.reshape(len(chunk), -1))
    n_ints = sum(f in ("ref", "ref?", "bool") for f in layout.fields)
    n_reals = sum(1 if f == "real" else 3 if f == "xyz" else 0 for f in layout.fields)
    return Table(rows, np.concatenate(ints) if ints else np.zeros((0, n_ints), dtype=np.int32),
                 np.concatenate(reals) if reals else np.zeros((0, n_reals)),
                 np.concatenate([[0], np.cumsum(np.concatenate(counts))]).astype(np.int64) if counts
                 else np.zeros(1, dtype=np.int64),
                 np.concatenate(items) if items else np.zeros(0, dtype=np.int32))


def _columns(layout: Layout, columns: list, counts: list[np.ndarray], items: list[np.ndarray]
             ) -> tuple[np.ndarray, np.ndarray]:
    """One chunk's captures, a tuple of bytes per captured value, as ``(m, i)`` integers and ``(m, r)`` reals
    (:class:`Table`); a list of references appended to ``counts`` (per record) and ``items``."""
    ints: list[np.ndarray] = []
    reals: list[np.ndarray] = []
    j = 0
    for field in layout.fields:
        if field in ("ref", "ref?"):
            col = columns[j] if field == "ref" else [x or b"-1" for x in columns[j]]
            ints.append(narrow_ids(np.array(col, dtype=bytes).astype(np.int64)))
        elif field == "bool":
            ints.append(np.array([x == b"T" for x in columns[j]], dtype=np.int32))
        elif field == "real":
            reals.append(np.array(columns[j], dtype=bytes).astype(np.float64))
        elif field == "refs":
            counts.append(np.array([x.count(b"#") for x in columns[j]], dtype=np.int64))
            refs = re.findall(rb"#(\d+)", b",".join(columns[j]))
            items.append(narrow_ids(np.array(refs, dtype=bytes).astype(np.int64)) if refs
                         else np.zeros(0, dtype=np.int32))
        elif field == "xyz":
            reals.extend(np.array(columns[j + c], dtype=bytes).astype(np.float64) for c in range(3))
        j += _FIELDS[field][1]
    m = len(columns[0]) if columns else 0
    return (np.stack(ints, axis=1) if ints else np.zeros((m, 0), dtype=np.int32),
            np.stack(reals, axis=1) if reals else np.zeros((m, 0)))


def ranges(starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """``concatenate([arange(s, s + n) for s, n in zip(starts, counts)])`` without the loop."""
    counts = np.asarray(counts, dtype=np.int64)
    total = int(counts.sum())
    ends = np.cumsum(counts)
    return np.arange(total, dtype=np.int64) + np.repeat(np.asarray(starts, dtype=np.int64) - (ends - counts), counts)


class Tables:
    """The tables of one file, parsed when first asked for, and the references followed into them."""

    def __init__(self, ents: Entities):
        self.ents = ents
        self._tables: dict[str, Table] = {}
        self._place = np.full(len(ents), -1, dtype=np.int32)
        """Each entity's row in the table of its type (a type is in one layout only), -1 before it is read."""

    def table(self, name: str) -> Table:
        got = self._tables.get(name)
        if got is None:
            got = self._tables[name] = parse_table(self.ents, LAYOUTS[name])
            self._place[got.rows] = np.arange(len(got.rows), dtype=np.int32)
        return got

    def follow(self, refs: np.ndarray, name: str, types: Sequence[str] | None = None) -> np.ndarray:
        """The rows of table ``name`` the references ``refs`` point to; :class:`StepTextError` naming the first
        that is not defined or not of ``types`` (default: the table's)."""
        self.table(name)
        refs = np.asarray(refs, dtype=np.int64)
        rows = self.ents.rows(refs)
        missing = rows < 0
        if missing.any():
            raise StepTextError(f"#{int(refs[missing][0])} is referenced but not defined")
        wanted = types if types is not None else LAYOUTS[name].types
        ok = np.isin(self.ents.kinds[rows], [self.ents.code(t) for t in wanted])
        if not ok.all():
            bad = int(refs[~ok][0])
            article = "an" if wanted[0][0] in "AEIOU" else "a"
            raise StepTextError(f"#{bad} is a {self.ents.kind(bad)}, not {article} {' or '.join(wanted)}")
        return self._place[rows]

    def kinds_of(self, refs: np.ndarray) -> np.ndarray:
        """The type codes of the entities ``refs`` (:meth:`Entities.code`); :class:`StepTextError` for one not
        defined."""
        rows = self.ents.rows(np.asarray(refs, dtype=np.int64))
        if (rows < 0).any():
            raise StepTextError(f"#{int(np.asarray(refs)[rows < 0][0])} is referenced but not defined")
        return self.ents.kinds[rows]

    def points(self, refs: np.ndarray) -> np.ndarray:
        """``(k, 3)`` the coordinates of CARTESIAN_POINTs or DIRECTIONs ``refs``; a 2D one is refused."""
        xyz = self.table("point").reals[self.follow(refs, "point")]
        if np.isnan(xyz).any():
            bad = int(np.asarray(refs)[np.isnan(xyz).any(axis=1)][0])
            raise StepTextError(f"#{bad} is a {self.ents.kind(bad)}, not a 3D point or direction")
        return xyz

    def frames(self, refs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """AXIS2_PLACEMENT_3Ds ``refs`` → origins, unit z, unit x square to z, each ``(k, 3)``; defaults
        z = (0, 0, 1), x = (1, 0, 0) (or (0, 1, 0) when z is near x)."""
        axes = self.table("axis").ints[self.follow(refs, "axis")]
        k = len(axes)
        o = self.points(axes[:, 0])
        z = np.tile([0.0, 0.0, 1.0], (k, 1))
        given = axes[:, 1] >= 0
        z[given] = self.points(axes[given, 1])
        z /= np.linalg.norm(z, axis=1)[:, None]
        x = np.where((np.abs(z[:, 0]) < 0.9)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
        given = axes[:, 2] >= 0
        x[given] = self.points(axes[given, 2])
        x -= np.einsum("ij,ij->i", x, z)[:, None] * z
        x /= np.linalg.norm(x, axis=1)[:, None]
        return o, z, x


    def matrices(self, refs: np.ndarray) -> np.ndarray:
        """``(k, 4, 4)`` taking coordinates in each AXIS2_PLACEMENT_3D of ``refs`` into those it is given in:
        columns x, z × x, z and the origin (:meth:`frames`)."""
        o, z, x = self.frames(refs)
        m = np.zeros((len(o), 4, 4))
        m[:, :3, 0], m[:, :3, 1], m[:, :3, 2], m[:, :3, 3], m[:, 3, 3] = x, np.cross(z, x), z, o, 1.0
        return m


def _only(tables: Tables, refs: np.ndarray, kinds: np.ndarray, allowed: tuple[str, ...], what: str) -> None:
    """:class:`StepTextError` naming the first of ``refs`` (their type codes ``kinds``) of none of the types
    ``allowed`` — ``what`` the reader reads instead."""
    ok = np.isin(kinds, [tables.ents.code(t) for t in allowed])
    if not ok.all():
        bad = int(refs[~ok][0])
        raise StepTextError(f"#{bad} is a {tables.ents.kind(bad)}: {what} (ppfab verify --kernel reads any STEP "
                            "file)")


def _curves(tables: Tables, refs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The 3D curves of edges ``refs`` (a SURFACE_CURVE's or SEAM_CURVE's first curve, followed) and whether
    each is a CIRCLE (else a LINE); :class:`StepTextError` for any other curve."""
    ents = tables.ents
    wrapped = {ents.code(t) for t in ("SURFACE_CURVE", "SEAM_CURVE")} - {-1}
    curves = np.asarray(refs, dtype=np.int64).copy()
    kinds = tables.kinds_of(curves)
    while wrapped and np.isin(kinds, list(wrapped)).any():
        at = np.flatnonzero(np.isin(kinds, list(wrapped)))
        for k in at.tolist():
            first = parse_params(ents[int(curves[k])][1])[1]
            if not isinstance(first, Ref):
                raise StepTextError(f"#{int(curves[k])} {ents.kind(int(curves[k]))} has no 3D curve")
            curves[k] = first.id
        kinds = tables.kinds_of(curves)
    _only(tables, curves, kinds, ("LINE", "CIRCLE"), "edges on lines and circles only")
    return curves, kinds == ents.code("CIRCLE")


def read_breps(tables: Tables, breps: Sequence[int]) -> dict[int, tuple[np.ndarray, ShellCode]]:
    """Each MANIFOLD_SOLID_BREP ``breps`` → its vertices ``(n, 3)`` in its own coordinates (in the order its loops
    first reach them, each EDGE_CURVE's start before its end) and its faces packed (:class:`ShellCode`).

    Followed for all B-reps at once: the shells' faces, the faces' bounds, their loops' oriented edges, the edges'
    vertices and curves, as rows of :class:`Table` s.  A loop whose bound is ``.F.`` runs backwards: its edges
    are reversed and each one's sense with it.  An arc's axis is its circle's z, turned when the loop runs
    against the circle; its sweep runs from its start to its end vertex about that axis (2π for a closed
    circle)."""
    wanted = np.array(sorted(set(breps)), dtype=np.int64)
    nb = len(wanted)
    shells = tables.table("brep").ints[tables.follow(wanted, "brep"), 0]
    # shells → faces
    shell_t, s_rows = tables.table("shell"), tables.follow(shells, "shell")
    counts = shell_t.first[s_rows + 1] - shell_t.first[s_rows]
    face_refs = shell_t.items[ranges(shell_t.first[s_rows], counts)]
    face_brep = np.repeat(np.arange(nb), counts)
    face_t, f_rows = tables.table("face"), tables.follow(face_refs, "face")
    surfaces, same = face_t.ints[f_rows, 0], face_t.ints[f_rows, 1].astype(bool)
    # faces → bounds → loops
    counts = face_t.first[f_rows + 1] - face_t.first[f_rows]
    bound_refs = face_t.items[ranges(face_t.first[f_rows], counts)]
    loop_face = np.repeat(np.arange(len(face_refs)), counts)
    bound = tables.table("bound").ints[tables.follow(bound_refs, "bound")]
    loop_t, l_rows = tables.table("loop"), tables.follow(bound[:, 0], "loop")
    backwards = bound[:, 1] == 0
    # loops → oriented edges → edge curves
    per_loop = loop_t.first[l_rows + 1] - loop_t.first[l_rows]
    oriented = tables.table("oriented").ints[tables.follow(loop_t.items[ranges(loop_t.first[l_rows], per_loop)],
                                                           "oriented")]
    edge_ids = oriented[:, 0]
    edges = tables.table("edge").ints[tables.follow(edge_ids, "edge")]
    step_loop = np.repeat(np.arange(len(l_rows)), per_loop)
    step_brep = face_brep[loop_face[step_loop]]
    local, start, coords = _vertices(tables, edges[:, 0:2], step_brep, nb)
    # loops run backwards where their bound says so: edges reversed, each one's sense turned
    loop_first = np.concatenate([[0], np.cumsum(per_loop)])
    source = _reversed(loop_first, per_loop, step_loop, backwards)
    forward = (oriented[source, 1] == 1) ^ backwards[step_loop]
    del oriented
    local, edges, edge_ids = local[source], edges[source], edge_ids[source]
    del source
    begin = np.where(forward, local[:, 0], local[:, 1])
    end = np.where(forward, local[:, 1], local[:, 0])
    del local
    arcs, which, arc_first = _arcs(tables, edges, forward, begin, end, step_brep, coords, start, nb)
    del edges, end
    steps = np.stack([begin, edge_ids, forward.astype(np.int64), which], axis=1).reshape(-1, 4)
    del begin, edge_ids, forward, which
    planes, face_kinds = _surfaces(tables, surfaces, same)
    for array in (coords, planes, face_kinds, steps, arcs):
        array.flags.writeable = False                   # shared by every solid placing a B-rep
    # per B-rep: its slices
    face_first = np.concatenate([[0], np.cumsum(np.bincount(face_brep, minlength=nb))]).tolist()
    face_loop_first = np.concatenate([[0], np.cumsum(np.bincount(loop_face, minlength=len(face_refs)))])
    loop_first_l = loop_first.tolist()
    face_loop_l, start_l, arc_first_l = face_loop_first.tolist(), start.tolist(), arc_first.tolist()
    out: dict[int, tuple[np.ndarray, ShellCode]] = {}
    for b, brep in enumerate(wanted.tolist()):
        f0, f1 = face_first[b], face_first[b + 1]
        l0, l1 = face_loop_l[f0], face_loop_l[f1]
        s0, s1 = loop_first_l[l0], loop_first_l[l1]
        face_loops = face_loop_first[f0:f1 + 1] - l0
        loop_steps = loop_first[l0:l1 + 1] - s0
        face_loops.flags.writeable = loop_steps.flags.writeable = False
        code = ShellCode(planes[f0:f1], face_kinds[f0:f1], face_loops, loop_steps, steps[s0:s1],
                         arcs[arc_first_l[b]:arc_first_l[b + 1]])
        out[brep] = (coords[start_l[b]:start_l[b + 1]], code)
    return out


def _vertices(tables: Tables, visits: np.ndarray, step_brep: np.ndarray, nb: int
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The vertices of ``nb`` B-reps numbered per B-rep in the order the loops first reach them: ``visits
    (S, 2)`` each edge's start and end VERTEX_POINT in the loops' order, ``step_brep (S,)`` its B-rep.  Returns
    ``(S, 2)`` the two ends' numbers in their B-rep, ``(nb + 1,)`` where each B-rep's vertices start in
    ``(V, 3)`` their coordinates."""
    flat = visits.ravel()
    visit_brep = np.repeat(step_brep, 2)
    key = visit_brep * (int(flat.max(initial=0)) + 1) + flat
    _, first_at, inverse = np.unique(key, return_index=True, return_inverse=True)
    del key
    u_brep = visit_brep[first_at]
    order = np.lexsort((first_at, u_brep))
    start = np.concatenate([[0], np.cumsum(np.bincount(u_brep, minlength=nb))]).astype(np.int64)
    rank = np.empty(len(first_at), dtype=np.int64)
    rank[order] = np.arange(len(first_at)) - start[u_brep[order]]
    local = rank[inverse.ravel()].reshape(-1, 2)
    point_refs = tables.table("vertex").ints[tables.follow(flat[first_at[order]], "vertex"), 0]
    return local, start, tables.points(point_refs)


def _reversed(loop_first: np.ndarray, per_loop: np.ndarray, step_loop: np.ndarray, backwards: np.ndarray
              ) -> np.ndarray:
    """``(S,)`` where each step of the loops is taken from: its own place, or in a loop that runs backwards the
    mirror place in its loop."""
    offset = np.arange(len(step_loop)) - loop_first[step_loop]
    return np.where(backwards[step_loop], loop_first[step_loop] + per_loop[step_loop] - 1 - offset,
                    np.arange(len(step_loop)))


def _arcs(tables: Tables, edges: np.ndarray, forward: np.ndarray, begin: np.ndarray, end: np.ndarray,
          step_brep: np.ndarray, coords: np.ndarray, start: np.ndarray, nb: int
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The circular edges among the steps (``edges (S, 4)`` the EDGE_CURVEs' start, end, curve and sense; the
    steps' sense along them and their start and end vertices in their B-rep): ``(A, 8)`` their centres, axes,
    radii and sweeps (:class:`~._step_shell.Arc`), ``(S,)`` each step's arc in its B-rep's (-1 for a
    straight edge), and ``(nb + 1,)`` where each B-rep's arcs start."""
    curves, is_arc = _curves(tables, edges[:, 2])
    arc_steps = np.flatnonzero(is_arc)
    round_t = tables.table("round")
    circle_rows = tables.follow(curves[arc_steps], "round", ("CIRCLE",))
    circles, radius = round_t.ints[circle_rows, 0], round_t.reals[circle_rows, 0]
    c_origin, c_z, _ = tables.frames(circles)
    axis = np.where(((forward == (edges[:, 3] == 1))[arc_steps])[:, None], c_z, -c_z)
    arc_brep = step_brep[arc_steps]
    p_begin = coords[start[arc_brep] + begin[arc_steps]] - c_origin
    p_end = coords[start[arc_brep] + end[arc_steps]] - c_origin
    turn = np.einsum("ij,ij->i", np.cross(p_begin, p_end), axis)
    sweep = np.mod(np.arctan2(turn, np.einsum("ij,ij->i", p_begin, p_end)), 2.0 * math.pi)
    sweep = np.where(begin[arc_steps] == end[arc_steps], 2.0 * math.pi, sweep)
    arcs = np.concatenate([c_origin, axis, radius[:, None], sweep[:, None]], axis=1).reshape(-1, 8)
    arc_first = np.concatenate([[0], np.cumsum(np.bincount(arc_brep, minlength=nb))]).astype(np.int64)
    which = np.full(len(edges), -1, dtype=np.int64)
    which[arc_steps] = np.arange(len(arc_steps)) - arc_first[arc_brep]
    return arcs, which, arc_first


def _surfaces(tables: Tables, surfaces: np.ndarray, same: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The faces' surfaces ``surfaces`` (ids) with their ``same_sense`` flags: ``(F, 10)`` origin, outward normal
    (a cylinder's axis), reference direction and radius (0 for a plane), and ``(F, 2)`` whether each is a
    cylinder and whether its normal is the surface's (:class:`~._step_shell.ShellCode`); a surface other
    than a plane or a cylinder is refused by name."""
    ents = tables.ents
    kinds = tables.kinds_of(surfaces)
    _only(tables, surfaces, kinds, ("PLANE", "CYLINDRICAL_SURFACE"), "planes and cylinders only")
    is_cyl = kinds == ents.code("CYLINDRICAL_SURFACE")
    placement = np.zeros(len(surfaces), dtype=np.int64)
    radii = np.zeros(len(surfaces))
    at_plane, at_cyl = np.flatnonzero(~is_cyl), np.flatnonzero(is_cyl)
    placement[at_plane] = tables.table("plane").ints[tables.follow(surfaces[at_plane], "plane"), 0]
    round_t = tables.table("round")
    cyl_rows = tables.follow(surfaces[at_cyl], "round", ("CYLINDRICAL_SURFACE",))
    placement[at_cyl], radii[at_cyl] = round_t.ints[cyl_rows, 0], round_t.reals[cyl_rows, 0]
    s_origin, s_z, s_x = tables.frames(placement)
    normal = np.where((is_cyl | same)[:, None], s_z, -s_z)
    planes = np.concatenate([s_origin, normal, s_x, radii[:, None]], axis=1).reshape(-1, 10)
    return planes, np.stack([is_cyl, same], axis=1).reshape(-1, 2)
