"""STEP files of planar-faced solids written as text, without the CAD kernel: ``glazing.step`` and ``panels.step``.

Every solid of these files is a prism of a planar polygon (strips, gaskets, setting blocks, stops, pressure
plates, caps, panes), so its boundary representation can be written from a template: a
``MANIFOLD_SOLID_BREP`` of a ``CLOSED_SHELL`` of ``ADVANCED_FACE``\\ s on ``PLANE``\\ s, bounded by
``EDGE_LOOP``\\ s of ``EDGE_CURVE``\\ s on ``LINE``\\ s, each vertex and each edge written once and shared by the
faces that meet there.  The schema, the product tree, the names and the colours are those the kernel writes
(AP214, ``AUTOMOTIVE_DESIGN``; a ``PRODUCT`` per assembly and per solid, placed in its parent by a
``NEXT_ASSEMBLY_USAGE_OCCURRENCE`` with a ``CONTEXT_DEPENDENT_SHAPE_REPRESENTATION``; a ``STYLED_ITEM`` per
B-rep), the header ppfab's (:func:`~fabrication.writers._step_text.step_header`); the text is a function of
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
from typing import Sequence, Union

import numpy as np

from ppfab.errors import FabricationError
from ppfab.frame import Frame

from ._step_text import step_header, step_label, step_string

SCHEMA = "AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }"
"""The schema the kernel writes (AP214 automotive design), kept so that downstream tools see the same files."""

PREPROCESSOR = "ppfab STEP template writer"
"""The preprocessor named in ``FILE_NAME`` (the kernel's files name its STEP processor there)."""

INSTANCE_GRID = 1e-6
"""Solids whose vertices (in their own coordinates, relative to the first vertex) agree within this many mm are
one shape, written once and placed per solid."""


@dataclass(frozen=True)
class PlanarSolid:
    """A closed solid bounded by planar faces, in its own coordinates, and its placement in model space.

    Attributes
    ----------
    label : the product name (a part id)
    colour : ``(r, g, b, a)`` in 0 … 1; ``a < 1`` is written as a transparency
    vertices : (n, 3) float, mm, in the solid's own coordinates
    faces : per face its loops of vertex indices, the outer loop first, each running counter-clockwise seen from
        outside the solid (holes clockwise)
    placement : (4, 4) float, a rigid motion taking the solid's coordinates into model space
    """

    label: str
    colour: tuple[float, float, float, float]
    vertices: np.ndarray
    faces: tuple[tuple[tuple[int, ...], ...], ...]
    placement: np.ndarray

    @classmethod
    def prism(cls, label: str, colour: Sequence[float], outline: np.ndarray, frame: Frame, z0: float,
              height: float) -> "PlanarSolid":
        """The prism over ``outline (n, 2)`` (frame coordinates, either turning sense) from ``z = z0`` to
        ``z0 + height`` along the frame's normal, placed by ``frame`` (the solid the kernel's
        ``_placed_prism`` makes)."""
        q = np.asarray(outline, dtype=float).reshape(-1, 2)
        if len(q) < 3:
            raise FabricationError(f"{label}: a prism needs an outline of at least 3 points, got {len(q)}")
        if not height > 0:
            raise FabricationError(f"{label}: a prism needs a positive height, got {height}")
        area = 0.5 * float(np.sum(q[:, 0] * np.roll(q[:, 1], -1) - np.roll(q[:, 0], -1) * q[:, 1]))
        if area == 0.0:
            raise FabricationError(f"{label}: the prism's outline has no area")
        if area < 0:
            q = q[::-1]
        n = len(q)
        lo = np.column_stack([q, np.full(n, float(z0))])
        hi = np.column_stack([q, np.full(n, float(z0) + float(height))])
        faces: list[tuple[tuple[int, ...], ...]] = [(tuple(range(n - 1, -1, -1)),), (tuple(range(n, 2 * n)),)]
        faces += [((k, (k + 1) % n, n + (k + 1) % n, n + k),) for k in range(n)]
        c4 = tuple(float(c) for c in colour) + (1.0,) * (4 - len(colour))
        return cls(label, (c4[0], c4[1], c4[2], c4[3]), np.vstack([lo, hi]), tuple(faces), frame_matrix(frame))

    def placed(self) -> np.ndarray:
        """``(n, 3)`` the vertices in model space."""
        return self.vertices @ self.placement[:3, :3].T + self.placement[:3, 3]


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

    def text(self) -> str:
        return "".join(f"#{k} = {line};\n" for k, line in enumerate(self.lines, 1))


def _placement_axis(data: _Data, m: np.ndarray) -> int:
    """An AXIS2_PLACEMENT_3D of the rigid motion ``m`` (its z and x columns at its origin)."""
    return data.axis(m[:3, 3], m[:3, 2], m[:3, 0])


def _brep(data: _Data, solid: PlanarSolid, vertices: np.ndarray) -> int:
    """The MANIFOLD_SOLID_BREP of ``solid``'s faces over ``vertices (n, 3)``: each vertex and each edge once."""
    pts = [data.point(p) for p in vertices]
    vps = [data.add(f"VERTEX_POINT('',#{p})") for p in pts]
    edges: dict[tuple[int, int], int] = {}
    faces = []
    for loops in solid.faces:
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
        ref = _unit(outer[1] - outer[0])
        plane = data.add(f"PLANE('',#{data.axis(pts[loops[0][0]], normal, ref)})")
        faces.append(data.add("ADVANCED_FACE('',(" + ",".join(f"#{b}" for b in bounds) + f"),#{plane},.T.)"))
    shell = data.add("CLOSED_SHELL('',(" + ",".join(f"#{f}" for f in faces) + "))")
    return data.add(f"MANIFOLD_SOLID_BREP('',#{shell})")


def _shape_key(solid: PlanarSolid) -> tuple:
    """What makes two solids one shape: faces, colour and vertices relative to the first on
    :data:`INSTANCE_GRID`."""
    rel = np.round((solid.vertices - solid.vertices[0]) / INSTANCE_GRID).astype(np.int64)
    return (solid.faces, solid.colour, rel.tobytes(), rel.shape)


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
            brep = _brep(data, s, s.vertices - s.vertices[0])
            styled.append((brep, s.colour))
            rep = data.add(f"ADVANCED_BREP_SHAPE_REPRESENTATION('',(#{origin},#{brep}),#{ctx})")
            data.add(f"SHAPE_DEFINITION_REPRESENTATION(#{pds},#{rep})")
            got = shapes[key] = (pd, rep)
        return got

    def assembly(node: Assembly) -> tuple[int, int]:
        pd, pds = product(node.name)
        rep = data.add("")                                 # the items are known once the children are placed
        data.add(f"SHAPE_DEFINITION_REPRESENTATION(#{pds},#{rep})")
        items = [origin]
        for kid in node.children:
            if isinstance(kid, Assembly):
                kpd, krep = assembly(kid)
                items.append(place(pd, rep, kpd, krep, kid.name, None))
            else:
                spd, srep = shape_of(kid)                 # its B-rep starts at the shape's first vertex
                items.append(place(pd, rep, spd, srep, kid.label, _shift(kid.placement, kid.vertices[0])))
        data.lines[rep - 1] = "SHAPE_REPRESENTATION('',(" + ",".join(f"#{i}" for i in dict.fromkeys(items)) \
            + f"),#{ctx})"
        return pd, rep

    assembly(root)
    _styles(data, styled, ctx)
    head = ("ISO-10303-21;\nHEADER;\n" + step_header(file_name, description, PREPROCESSOR).decode("ascii")
            + f"FILE_SCHEMA(('{SCHEMA}'));\nENDSEC;\nDATA;\n")
    return (head + data.text() + "ENDSEC;\nEND-ISO-10303-21;\n").encode("ascii")


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
    """Write the product tree ``root`` to the STEP file ``path`` (:func:`step_text`)."""
    path = Path(path)
    path.write_bytes(step_text(root, path.name, description, instance))
    return path
