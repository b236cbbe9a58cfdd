"""STEP files of planar-faced solids written as text, without the CAD kernel: ``glazing.step``, ``panels.step``,
``beams.step`` and ``splices.step``.

Every solid of these files is a prism of a planar polygon (strips, gaskets, setting blocks, stops, pressure
plates, caps, panes, beam plates, splice cover plates) or, for a beam plate bevelled under its glazing strips, the
solid between two face outlines whose side faces are planar, some with round through holes (bolt holes), so its
boundary representation can be written from a template: a ``MANIFOLD_SOLID_BREP`` of a ``CLOSED_SHELL`` of
``ADVANCED_FACE``\\ s on ``PLANE``\\ s, bounded by ``EDGE_LOOP``\\ s of ``EDGE_CURVE``\\ s on ``LINE``\\ s, each
vertex and each edge written once and shared by the faces that meet there; a hole (:class:`Bore`) is a
``CIRCLE`` on each face it passes through (an inner bound of one edge and one vertex) and a face on a
``CYLINDRICAL_SURFACE`` bounded by the two circles and a straight seam, as the kernel writes a drilled hole.

The schema, the product tree, the names and the colours are those the kernel writes (AP214, ``AUTOMOTIVE_DESIGN``; a ``PRODUCT`` per assembly and per solid, placed in its parent by a
``NEXT_ASSEMBLY_USAGE_OCCURRENCE`` with a ``CONTEXT_DEPENDENT_SHAPE_REPRESENTATION``; a ``STYLED_ITEM`` per
coloured B-rep), the header ppfab's (:func:`~fabrication.writers._step_text.step_header`); the text is a function of
the input alone (byte-identical on every write).

**Instancing.**  Solids of one shape — the same vertices in their own coordinates, up to a shift, within
:data:`INSTANCE_GRID` mm, the same faces and colour — are written once: the first solid's B-rep in an
``ADVANCED_BREP_SHAPE_REPRESENTATION`` of its own, and every solid of that shape as a product (its part id)
whose ``SHAPE_REPRESENTATION`` holds a ``MAPPED_ITEM`` of that representation with the solid's placement as the
mapping target.  The product tree and the names are unchanged; a reader places the shared B-rep once per
product.

Coordinates are written with Python's shortest round-trip ``repr`` of each float, so a reader gets the very
numbers given.

Input: a :class:`PlanarSolid` per solid (:meth:`PlanarSolid.prism` for a prism of an outline in a frame) and
:class:`Assembly` nodes for the tree; :func:`write_step` writes the file.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterator, Sequence, Union

import numpy as np

from ppfab.errors import FabricationError
from ppfab.frame import Frame
from ppfab.metrics import polygon_area

from ._step_text import step_header, step_label, step_string

SCHEMA = "AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }"
"""The schema the kernel writes (AP214 automotive design), kept so that downstream tools see the same files."""

PREPROCESSOR = "ppfab STEP template writer"
"""The preprocessor named in ``FILE_NAME`` (the kernel's files name its STEP processor there)."""

INSTANCE_GRID = 1e-6
"""Solids whose vertices (in their own coordinates, relative to the first vertex) agree within this many mm are
one shape, written once and placed per solid."""


@dataclass(frozen=True)
class Bore:
    """A round through hole of a solid: the cylinder of ``radius`` (mm) about the line through ``(x, y)`` along the
    solid's own z axis, from its planar face ``faces[low]`` at ``z = z_low`` to its face ``faces[high]`` at
    ``z = z_high`` (both normal to z, the solid between them; ``z_low < z_high``)."""

    x: float
    y: float
    radius: float
    z_low: float
    z_high: float
    low: int
    high: int


@dataclass(frozen=True)
class PlanarSolid:
    """A closed solid bounded by planar faces, with round through holes, in its own coordinates, and its placement
    in model space.

    Attributes
    ----------
    label : the product name (a part id)
    colour : ``(r, g, b, a)`` in 0 … 1 (``a < 1`` is written as a transparency), or ``None``: no style
    vertices : (n, 3) float, mm, in the solid's own coordinates
    faces : per face its loops of vertex indices, the outer loop first, each running counter-clockwise seen from
        outside the solid (holes clockwise)
    placement : (4, 4) float, a rigid motion taking the solid's coordinates into model space
    bores : the round holes through it (:class:`Bore`), each an inner bound of the two faces it joins
    """

    label: str
    colour: tuple[float, float, float, float] | None
    vertices: np.ndarray
    faces: tuple[tuple[tuple[int, ...], ...], ...]
    placement: np.ndarray
    bores: tuple[Bore, ...] = ()

    @classmethod
    def prism(cls, label: str, colour: Sequence[float] | None, outline: np.ndarray, frame: Frame, z0: float,
              height: float, holes: np.ndarray | None = None) -> "PlanarSolid":
        """The prism over ``outline (n, 2)`` (frame coordinates, either turning sense) from ``z = z0`` to
        ``z0 + height`` along the frame's normal, placed by ``frame`` (the solid the kernel's
        ``_placed_prism`` makes), less the through holes ``holes (h, 3)`` (centre ``x, y`` in the frame and
        diameter, mm)."""
        q = np.asarray(outline, dtype=float).reshape(-1, 2)
        if len(q) < 3:
            raise FabricationError(f"{label}: a prism needs an outline of at least 3 points, got {len(q)}")
        if not height > 0:
            raise FabricationError(f"{label}: a prism needs a positive height, got {height}")
        return cls._between(label, colour, q, q, float(z0), float(z0) + float(height), frame, holes)

    @classmethod
    def loft(cls, label: str, colour: Sequence[float] | None, top: np.ndarray, bottom: np.ndarray, frame: Frame,
             thickness: float, holes: np.ndarray | None = None) -> "PlanarSolid":
        """The solid between ``top (n, 2)`` on ``z = +thickness/2`` and ``bottom (n, 2)`` on ``z = −thickness/2``
        (frame coordinates, one turning sense, corner ``k`` of one joined to corner ``k`` of the other by a planar
        side face: :func:`fabrication.beams.bevel_cut.face_outlines`), placed by ``frame``, less ``holes (h, 3)``
        (centre ``x, y`` and diameter): a beam plate bevelled under its strips (the kernel's ``_placed_loft``)."""
        a, b = (np.asarray(o, dtype=float).reshape(-1, 2) for o in (top, bottom))
        if len(a) < 3 or a.shape != b.shape:
            raise FabricationError(f"{label}: a plate's two faces need outlines of the same 3 or more corners, got "
                                   f"{len(a)} and {len(b)}")
        if not thickness > 0:
            raise FabricationError(f"{label}: a plate needs a positive thickness, got {thickness}")
        h = 0.5 * float(thickness)
        return cls._between(label, colour, b, a, -h, h, frame, holes)

    @classmethod
    def _between(cls, label: str, colour: Sequence[float] | None, lo_q: np.ndarray, hi_q: np.ndarray, z_lo: float,
                 z_hi: float, frame: Frame, holes: np.ndarray | None) -> "PlanarSolid":
        """The solid between ``lo_q`` on ``z = z_lo`` and ``hi_q`` on ``z = z_hi`` (corners joined in order),
        counter-clockwise first; corners that coincide on one face merged (a side face turns into a triangle)."""
        areas = [float(polygon_area(q)) for q in (lo_q, hi_q)]
        if areas[0] == 0.0 or areas[1] == 0.0:
            raise FabricationError(f"{label}: the solid's outline has no area")
        if (areas[0] > 0) != (areas[1] > 0):
            raise FabricationError(f"{label}: its two face outlines turn opposite ways")
        if areas[0] < 0:
            lo_q, hi_q = lo_q[::-1], hi_q[::-1]
        n = len(lo_q)
        lo, hi = _merged(lo_q), _merged(hi_q)                  # corner k → the first of its equal neighbours
        keep_lo = sorted(set(lo))
        keep_hi = sorted(set(hi))
        index_lo = {k: i for i, k in enumerate(keep_lo)}
        index_hi = {k: len(keep_lo) + i for i, k in enumerate(keep_hi)}
        L = [index_lo[k] for k in lo]
        H = [index_hi[k] for k in hi]
        vertices = np.vstack([np.column_stack([lo_q[keep_lo], np.full(len(keep_lo), z_lo)]),
                              np.column_stack([hi_q[keep_hi], np.full(len(keep_hi), z_hi)])])
        faces: list[tuple[tuple[int, ...], ...]] = [(_ring(L[::-1]),), (_ring(H),)]
        for k in range(n):
            j = (k + 1) % n
            side = _ring([L[k], L[j], H[j], H[k]])
            if len(side) >= 3:
                faces.append((side,))
        if len(faces[0][0]) < 3 or len(faces[1][0]) < 3:
            raise FabricationError(f"{label}: a face of the solid has fewer than 3 distinct corners")
        bores = tuple(Bore(float(x), float(y), 0.5 * float(d), z_lo, z_hi, 0, 1)
                      for x, y, d in np.asarray(holes if holes is not None else np.zeros((0, 3)),
                                                dtype=float).reshape(-1, 3).tolist())
        _holes_inside(label, bores, (lo_q, hi_q))
        return cls(label, _rgba(colour), vertices, tuple(faces), frame_matrix(frame), bores)

    def placed(self) -> np.ndarray:
        """``(n, 3)`` the vertices in model space."""
        return self.vertices @ self.placement[:3, :3].T + self.placement[:3, 3]


def _holes_inside(label: str, bores: tuple[Bore, ...], outlines: tuple[np.ndarray, ...]) -> None:
    """Refuse a hole that is not a positive circle strictly inside every outline and apart from the other holes: a
    hole through an edge or into another is a notch, which a template B-rep cannot hold."""
    from shapely.geometry import Point, Polygon

    polygons = [Polygon(q) for q in outlines]
    for k, b in enumerate(bores):
        if not (b.radius > 0 and math.isfinite(b.radius) and math.isfinite(b.x) and math.isfinite(b.y)):
            raise FabricationError(f"{label}: hole {k + 1} needs a finite centre and a positive diameter, got "
                                   f"({b.x}, {b.y}), {2.0 * b.radius}")
        centre = Point(b.x, b.y)
        for poly in polygons:
            gap = float(poly.exterior.distance(centre))
            if not poly.contains(centre) or gap <= b.radius:
                raise FabricationError(f"{label}: hole {k + 1} at ({b.x:.1f}, {b.y:.1f}), Ø {2.0 * b.radius:g} mm, is "
                                       f"not inside the outline with material around it ({gap:.2f} mm from its edge)")
        for j in range(k):
            o = bores[j]
            if math.hypot(b.x - o.x, b.y - o.y) <= b.radius + o.radius:
                raise FabricationError(f"{label}: holes {j + 1} and {k + 1} at ({o.x:.1f}, {o.y:.1f}) and "
                                       f"({b.x:.1f}, {b.y:.1f}) overlap")


def _merged(q: np.ndarray) -> list[int]:
    """Per corner of the closed polygon ``q (n, 2)`` the first of its run of equal consecutive corners (cyclic:
    a run through the last corner and the first maps to corner 0's)."""
    n = len(q)
    rep = list(range(n))
    for k in range(1, n):
        if q[k, 0] == q[k - 1, 0] and q[k, 1] == q[k - 1, 1]:
            rep[k] = rep[k - 1]
    k = n - 1
    while k > 0 and rep[k] != 0 and q[k, 0] == q[0, 0] and q[k, 1] == q[0, 1]:
        rep[k] = 0
        k -= 1
    return rep


def _ring(idx: list[int]) -> tuple[int, ...]:
    """``idx`` with consecutive repeats dropped (cyclically)."""
    out: list[int] = []
    for i in idx:
        if not out or out[-1] != i:
            out.append(i)
    while len(out) > 1 and out[-1] == out[0]:
        out.pop()
    return tuple(out)


def _rgba(colour: Sequence[float] | None) -> tuple[float, float, float, float] | None:
    if colour is None:
        return None
    c4 = tuple(float(c) for c in colour) + (1.0,) * (4 - len(colour))
    return (c4[0], c4[1], c4[2], c4[3])


@dataclass
class Assembly:
    """A product holding other products: ``name`` and its children (assemblies or solids) in order."""

    name: str
    children: list[Union["Assembly", PlanarSolid]] = field(default_factory=list)


def frame_matrix(frame: Frame) -> np.ndarray:
    """``(4, 4)`` taking frame coordinates ``(x, y, z)`` to ``origin + x ex + y ey + z normal``."""
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = frame.ex, frame.ey, frame.normal, frame.origin
    return m


def grouped(solids: Sequence[PlanarSolid], keys: Sequence[str]) -> list[Assembly]:
    """One assembly per key (folded to ASCII), holding the solids of that key in their given order, keys in
    first-seen order (the tree :func:`fabrication.writers.step.grouped` builds for the kernel)."""
    groups: dict[str, list[Union[Assembly, PlanarSolid]]] = {}
    for solid, key in zip(solids, keys):
        groups.setdefault(key, []).append(solid)
    return [Assembly(step_label(key), kids) for key, kids in groups.items()]


def real(x: float) -> str:
    """A float as an ISO 10303-21 real, exactly (shortest round-trip digits).

    >>> real(1.0), real(-0.0), real(1e-07), real(1234.5678)
    ('1.', '0.', '1.E-07', '1234.5678')
    """
    v = float(x)
    if not math.isfinite(v):
        raise FabricationError(f"a STEP coordinate is {v}: the geometry is broken (not a finite number)")
    if v == 0.0:
        return "0."
    r = repr(v)
    mant, _, exp = r.partition("e")
    if "." not in mant:
        mant += "."
    elif mant.endswith(".0"):
        mant = mant[:-1]
    return mant + ("E" + exp if exp else "")


def _unit(v: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(v))
    if not n > 0:
        raise FabricationError("a STEP face or edge has no extent (two vertices coincide)")
    return v / n


def _newell(points: np.ndarray) -> np.ndarray:
    """The (unnormalised) normal of a polygon, counter-clockwise seen from its tip."""
    nxt = np.roll(points, -1, axis=0)
    return np.cross(points, nxt).sum(axis=0)


PIECE_RECORDS = 20_000
"""Records of the DATA section written at a time by :func:`write_step` (a piece of about 2 MB)."""


class _Data:
    """The DATA section being written: entities numbered in order."""

    def __init__(self) -> None:
        self.lines: list[str] = []

    def add(self, text: str) -> int:
        self.lines.append(text)
        return len(self.lines)

    def point(self, p: np.ndarray) -> int:
        return self.add(f"CARTESIAN_POINT('',({real(p[0])},{real(p[1])},{real(p[2])}))")

    def direction(self, d: np.ndarray) -> int:
        return self.add(f"DIRECTION('',({real(d[0])},{real(d[1])},{real(d[2])}))")

    def axis(self, origin: int | np.ndarray, z: np.ndarray, x: np.ndarray) -> int:
        o = origin if isinstance(origin, int) else self.point(origin)
        return self.add(f"AXIS2_PLACEMENT_3D('',#{o},#{self.direction(z)},#{self.direction(x)})")

    def chunks(self) -> Iterator[str]:
        """The records ``#k = …;`` one per line, :data:`PIECE_RECORDS` records a piece (a large file need not be
        one string)."""
        size = PIECE_RECORDS
        for start in range(0, len(self.lines), size):
            yield "".join(f"#{k} = {line};\n" for k, line in enumerate(self.lines[start:start + size], start + 1))


def _placement_axis(data: _Data, m: np.ndarray) -> int:
    """An AXIS2_PLACEMENT_3D of the rigid motion ``m`` (its z and x columns at its origin)."""
    return data.axis(m[:3, 3], m[:3, 2], m[:3, 0])


def _brep(data: _Data, solid: PlanarSolid, origin: np.ndarray) -> int:
    """The MANIFOLD_SOLID_BREP of ``solid``'s faces and bores in its own coordinates less ``origin (3,)``: each
    vertex and each edge once."""
    vertices = solid.vertices - origin
    pts = [data.point(p) for p in vertices]
    vps = [data.add(f"VERTEX_POINT('',#{p})") for p in pts]
    edges: dict[tuple[int, int], int] = {}
    holes: dict[int, list[int]] = {}                         # face index → its FACE_BOUNDs of bores
    cylinders = [_bore(data, solid, bore, origin, holes) for bore in solid.bores]
    faces = []
    for f, loops in enumerate(solid.faces):
        outer = vertices[list(loops[0])]
        normal = _unit(_newell(outer - outer.mean(axis=0)))
        bounds = []
        for k, loop in enumerate(loops):
            oriented = []
            for a, b in zip(loop, loop[1:] + loop[:1]):
                key = (min(a, b), max(a, b))
                e = edges.get(key)
                if e is None:
                    i, j = key
                    d = vertices[j] - vertices[i]
                    length = float(np.linalg.norm(d))
                    if not length > 0:
                        raise FabricationError(f"{solid.label}: two of its vertices coincide (an edge of no length)")
                    vector = data.add("VECTOR('',#%d,1.)" % data.direction(d / length))
                    line = data.add(f"LINE('',#{pts[i]},#{vector})")
                    e = edges[key] = data.add(f"EDGE_CURVE('',#{vps[i]},#{vps[j]},#{line},.T.)")
                sense = ".T." if a < b else ".F."
                oriented.append(data.add(f"ORIENTED_EDGE('',*,*,#{e},{sense})"))
            loop_id = data.add("EDGE_LOOP('',(" + ",".join(f"#{o}" for o in oriented) + "))")
            kind = "FACE_OUTER_BOUND" if k == 0 else "FACE_BOUND"
            bounds.append(data.add(f"{kind}('',#{loop_id},.T.)"))
        bounds += holes.pop(f, [])
        ref = _unit(outer[1] - outer[0])
        plane = data.add(f"PLANE('',#{data.axis(pts[loops[0][0]], normal, ref)})")
        faces.append(data.add("ADVANCED_FACE('',(" + ",".join(f"#{b}" for b in bounds) + f"),#{plane},.T.)"))
    if holes:
        raise FabricationError(f"{solid.label}: a hole ends on face {min(holes)}, which the solid does not have")
    shell = data.add("CLOSED_SHELL('',(" + ",".join(f"#{f}" for f in faces + cylinders) + "))")
    return data.add(f"MANIFOLD_SOLID_BREP('',#{shell})")


_Z = np.array([0.0, 0.0, 1.0])
_X = np.array([1.0, 0.0, 0.0])


def _bore(data: _Data, solid: PlanarSolid, bore: Bore, origin: np.ndarray, holes: dict[int, list[int]]) -> int:
    """The cylindrical face of ``bore`` (its ADVANCED_FACE), its two circles put in ``holes`` as inner bounds of the
    faces it joins.

    Each circle is one closed edge from one vertex (on the circle's x axis), running counter-clockwise about +z:
    the lower face (outward normal −z) takes it forward, the upper face (+z) backwards — a hole runs clockwise
    seen from outside.  The cylinder's face points to the axis (``same_sense`` false: into the hole), its loop
    the lower circle backwards, the seam up, the upper circle forwards and the seam down (each edge used twice,
    in opposite senses)."""
    if not bore.z_low < bore.z_high or not bore.radius > 0:
        raise FabricationError(f"{solid.label}: a hole needs a positive radius and length, got r = {bore.radius}, "
                               f"z {bore.z_low} … {bore.z_high}")
    circles = []
    for z in (bore.z_low, bore.z_high):
        centre = np.array([bore.x, bore.y, z]) - origin
        start = data.point(centre + bore.radius * _X)
        v = data.add(f"VERTEX_POINT('',#{start})")
        circle = data.add(f"CIRCLE('',#{data.axis(centre, _Z, _X)},{real(bore.radius)})")
        circles.append((v, data.add(f"EDGE_CURVE('',#{v},#{v},#{circle},.T.)"), centre, start))
    (v_low, c_low, centre_low, start_low), (v_high, c_high, _, _) = circles
    vector = data.add("VECTOR('',#%d,1.)" % data.direction(_Z))
    seam_line = data.add(f"LINE('',#{start_low},#{vector})")
    seam = data.add(f"EDGE_CURVE('',#{v_low},#{v_high},#{seam_line},.T.)")
    for face, circle, sense in ((bore.low, c_low, ".T."), (bore.high, c_high, ".F.")):
        oriented = data.add(f"ORIENTED_EDGE('',*,*,#{circle},{sense})")
        loop = data.add(f"EDGE_LOOP('',(#{oriented}))")
        holes.setdefault(face, []).append(data.add(f"FACE_BOUND('',#{loop},.T.)"))
    steps = [(c_low, ".F."), (seam, ".T."), (c_high, ".T."), (seam, ".F.")]
    oriented_ids = [data.add(f"ORIENTED_EDGE('',*,*,#{e},{sense})") for e, sense in steps]
    loop = data.add("EDGE_LOOP('',(" + ",".join(f"#{o}" for o in oriented_ids) + "))")
    bound = data.add(f"FACE_BOUND('',#{loop},.T.)")
    surface = data.add(f"CYLINDRICAL_SURFACE('',#{data.axis(centre_low, _Z, _X)},{real(bore.radius)})")
    return data.add(f"ADVANCED_FACE('',(#{bound}),#{surface},.F.)")


def _shape_key(solid: PlanarSolid) -> tuple:
    """What makes two solids one shape: faces, colour, and vertices and bores relative to the first vertex on
    :data:`INSTANCE_GRID`."""
    rel = np.round((solid.vertices - solid.vertices[0]) / INSTANCE_GRID).astype(np.int64)
    v0 = solid.vertices[0]
    bores = np.round(np.array([(b.x - v0[0], b.y - v0[1], b.z_low - v0[2], b.z_high - v0[2], b.radius)
                               for b in solid.bores]).reshape(-1, 5) / INSTANCE_GRID).astype(np.int64)
    return (solid.faces, solid.colour, rel.tobytes(), rel.shape, bores.tobytes(),
            tuple((b.low, b.high) for b in solid.bores))


def _shift(m: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``m`` followed after a shift by ``t`` in its own coordinates (``m · translate(t)``)."""
    s = np.eye(4)
    s[:3, 3] = t
    return m @ s


def _check(solid: PlanarSolid) -> None:
    """Refuse a solid with a coordinate that is not a finite number or a placement that is not a rigid motion."""
    if not np.all(np.isfinite(solid.vertices)):
        raise FabricationError(f"{solid.label}: a vertex is not a finite number: the geometry is broken")
    m = np.asarray(solid.placement, dtype=float)
    r = m[:3, :3]
    if m.shape != (4, 4) or not np.all(np.isfinite(m)) or float(np.abs(r.T @ r - np.eye(3)).max()) > 1e-9 \
            or np.linalg.det(r) < 0:
        raise FabricationError(f"{solid.label}: its placement is not a rigid motion (orthonormal, right-handed)")


def step_text(root: Assembly, file_name: str, description: str = "", instance: bool = True) -> bytes:
    """The whole STEP file of the product tree ``root`` (see the module docstring); ``instance``: solids of
    one shape share one product and B-rep, else every solid is a product of its own."""
    return "".join(_step_pieces(root, file_name, description, instance)).encode("ascii")


def _step_pieces(root: Assembly, file_name: str, description: str, instance: bool) -> Iterator[str]:
    """:func:`step_text` as pieces of text: the header, the DATA section in pieces, the end."""
    data = _Data()
    app = data.add("APPLICATION_CONTEXT('core data for automotive mechanical design processes')")
    data.add(f"APPLICATION_PROTOCOL_DEFINITION('international standard','automotive_design',2000,#{app})")
    mm = data.add("( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) )")
    rad = data.add("( NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.) )")
    sr = data.add("( NAMED_UNIT(*) SI_UNIT($,.STERADIAN.) SOLID_ANGLE_UNIT() )")
    unc = data.add(f"UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(1.E-07),#{mm},'distance_accuracy_value',"
                   "'confusion accuracy')")
    ctx = data.add(f"( GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#{unc})) "
                   f"GLOBAL_UNIT_ASSIGNED_CONTEXT((#{mm},#{rad},#{sr})) REPRESENTATION_CONTEXT('Context #1',"
                   "'3D Context with UNIT and UNCERTAINTY') )")
    pctx = data.add(f"PRODUCT_CONTEXT('',#{app},'mechanical')")
    pdctx = data.add(f"PRODUCT_DEFINITION_CONTEXT('part definition',#{app},'design')")
    origin = data.axis(np.zeros(3), np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]))
    solids = list(_leaves(root))
    for s in solids:
        _check(s)
    keys = [_shape_key(s) if instance else k for k, s in enumerate(solids)]
    count: dict[object, int] = {}
    for key in keys:
        count[key] = count.get(key, 0) + 1
    key_of = {id(s): key for s, key in zip(solids, keys)}
    styled: list[tuple[int, tuple[float, float, float, float]]] = []
    shapes: dict[object, tuple[int, int]] = {}               # shape key → (product definition, B-rep representation)
    nauo = [0]

    def product(name: str) -> tuple[int, int]:
        label = step_string(step_label(name))
        p = data.add(f"PRODUCT({label},{label},'',(#{pctx}))")
        data.add(f"PRODUCT_RELATED_PRODUCT_CATEGORY('part',$,(#{p}))")
        pdf = data.add(f"PRODUCT_DEFINITION_FORMATION('','',#{p})")
        pd = data.add(f"PRODUCT_DEFINITION('design','',#{pdf},#{pdctx})")
        pds = data.add(f"PRODUCT_DEFINITION_SHAPE('','',#{pd})")
        return pd, pds

    def place(ppd: int, prep: int, child_pd: int, child_rep: int, name: str, m: np.ndarray | None) -> int:
        """The occurrence ``name`` of a child in its parent, placed by the rigid motion ``m``; the parent's item
        the placement is (its id)."""
        nauo[0] += 1
        occ = data.add(f"NEXT_ASSEMBLY_USAGE_OCCURRENCE('{nauo[0]}',{step_string(step_label(name))},'',#{ppd},"
                       f"#{child_pd},$)")
        pds = data.add(f"PRODUCT_DEFINITION_SHAPE('Placement','Placement of an item',#{occ})")
        target = origin if m is None else _placement_axis(data, m)
        idt = data.add(f"ITEM_DEFINED_TRANSFORMATION('','',#{origin},#{target})")
        rel = data.add(f"( REPRESENTATION_RELATIONSHIP('','',#{child_rep},#{prep}) "
                       f"REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION(#{idt}) "
                       "SHAPE_REPRESENTATION_RELATIONSHIP() )")
        data.add(f"CONTEXT_DEPENDENT_SHAPE_REPRESENTATION(#{rel},#{pds})")
        return target

    def shape_of(s: PlanarSolid) -> tuple[int, int]:
        """The product of ``s``'s shape (written at its first solid): named by the solid when the shape is used
        once, else ``<prefix> shape <k>``; its B-rep in the first solid's coordinates shifted to its first
        vertex."""
        key = key_of[id(s)]
        got = shapes.get(key)
        if got is None:
            name = s.label if count[key] == 1 else f"{s.label.split('-')[0]} shape {len(shapes) + 1}"
            pd, pds = product(name)
            brep = _brep(data, s, s.vertices[0])
            if s.colour is not None:
                styled.append((brep, s.colour))
            rep = data.add(f"ADVANCED_BREP_SHAPE_REPRESENTATION('',(#{origin},#{brep}),#{ctx})")
            data.add(f"SHAPE_DEFINITION_REPRESENTATION(#{pds},#{rep})")
            got = shapes[key] = (pd, rep)
        return got

    def assembly(node: Assembly, again: Callable[..., tuple[int, int]]) -> tuple[int, int]:
        """``node``'s product and representation, its children's first; ``again`` is ``assembly`` itself,
        passed in: a closure calling itself by name is a reference cycle, which held the file's lines
        (``data``) after the last piece until the next collection."""
        pd, pds = product(node.name)
        rep = data.add("")                                 # the items are known once the children are placed
        data.add(f"SHAPE_DEFINITION_REPRESENTATION(#{pds},#{rep})")
        items = [origin]
        for kid in node.children:
            if isinstance(kid, Assembly):
                kpd, krep = again(kid, again)
                items.append(place(pd, rep, kpd, krep, kid.name, None))
            else:
                spd, srep = shape_of(kid)                 # its B-rep starts at the shape's first vertex
                items.append(place(pd, rep, spd, srep, kid.label, _shift(kid.placement, kid.vertices[0])))
        data.lines[rep - 1] = "SHAPE_REPRESENTATION('',(" + ",".join(f"#{i}" for i in dict.fromkeys(items)) \
            + f"),#{ctx})"
        return pd, rep

    assembly(root, assembly)
    _styles(data, styled, ctx)
    head = ("ISO-10303-21;\nHEADER;\n" + step_header(file_name, description, PREPROCESSOR).decode("ascii")
            + f"FILE_SCHEMA(('{SCHEMA}'));\nENDSEC;\nDATA;\n")
    yield head
    yield from data.chunks()
    yield "ENDSEC;\nEND-ISO-10303-21;\n"


def _leaves(node: Assembly):
    """The solids below ``node``, depth first."""
    for kid in node.children:
        if isinstance(kid, Assembly):
            yield from _leaves(kid)
        else:
            yield kid


def _styles(data: _Data, styled: list[tuple[int, tuple[float, float, float, float]]], ctx: int) -> None:
    """One STYLED_ITEM per B-rep with its colour (surface fill and curve style, a transparency when alpha < 1),
    the style entities of one colour written once, all in one presentation representation."""
    if not styled:
        return
    font = data.add("DRAUGHTING_PRE_DEFINED_CURVE_FONT('continuous')")
    psa: dict[tuple[float, float, float, float], int] = {}
    items = []
    for brep, colour in styled:
        p = psa.get(colour)
        if p is None:
            r, g, b, a = colour
            rgb = data.add(f"COLOUR_RGB('',{real(r)},{real(g)},{real(b)})")
            fill_colour = data.add(f"FILL_AREA_STYLE_COLOUR('',#{rgb})")
            fill = data.add(f"FILL_AREA_STYLE('',(#{fill_colour}))")
            sides = [data.add(f"SURFACE_STYLE_FILL_AREA(#{fill})")]
            if a < 1.0:
                tr = data.add(f"SURFACE_STYLE_TRANSPARENT({real(1.0 - a)})")
                sides.append(data.add(f"SURFACE_STYLE_RENDERING_WITH_PROPERTIES(.NORMAL_SHADING.,#{rgb},(#{tr}))"))
            side = data.add("SURFACE_SIDE_STYLE('',(" + ",".join(f"#{s}" for s in sides) + "))")
            usage = data.add(f"SURFACE_STYLE_USAGE(.BOTH.,#{side})")
            curve = data.add(f"CURVE_STYLE('',#{font},POSITIVE_LENGTH_MEASURE(0.1),#{rgb})")
            p = psa[colour] = data.add(f"PRESENTATION_STYLE_ASSIGNMENT((#{usage},#{curve}))")
        items.append(data.add(f"STYLED_ITEM('color',(#{p}),#{brep})"))
    data.add("MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION(''," + "(" + ",".join(f"#{i}" for i in items)
             + f"),#{ctx})")


def write_step(root: Assembly, path: str | os.PathLike, description: str = "", instance: bool = True) -> Path:
    """Write the product tree ``root`` to the STEP file ``path``: the bytes of :func:`step_text`, written piece by
    piece (at 88 × 60 faces glazing.step is some 300 MB: its text and its bytes need not be held at once)."""
    path = Path(path)
    pieces = _step_pieces(root, path.name, description, instance)
    first = next(pieces)                            # the checks of every solid run before the file is opened
    with open(path, "w", encoding="ascii", newline="\n") as fh:
        fh.write(first)
        for piece in pieces:
            fh.write(piece)
    return path
