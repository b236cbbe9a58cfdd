"""The parts as 3D elements for the exchange models (IFC, Rhino, glTF): one prism per part, with its data.

Every part is a flat outline extruded once, so one record describes it for every format: the outline ``(k, 2)``
(counter-clockwise, the flat outline of ``parts.csv`` and the DXF files) in a plane frame
(:class:`ppfab.frame.Frame`: ``X = origin + x·ex + y·ey``, normal ``ex × ey``), extruded from ``z0`` to
``z0 + height`` along the normal:

* a glass panel: the inset outline in the panel frame (the face's least-squares plane, normal to the outside),
  from its seat ``z0`` (:meth:`fabrication.records.BuildRecord.pane_offsets`: the underside on the gaskets, about
  strip + gasket above the mesh face) to ``z0`` + the glass thickness;
* a beam plate: its outline (slots and end cuts drawn in) in the plate frame (its support plane), from
  ``z0 = −t/2`` to ``t/2`` — the plate is centred on its support plane; a plate bevelled under its glazing strips
  is the solid between its two faces (``outline`` on ``z = −t/2``, ``outline_top`` on ``z = +t/2``, the same
  corners in the same order, :func:`fabrication.beams.bevel_cut.face_outlines`), as in ``beams.step`` — with the
  bolt holes of its splices
  (``holes``: centre and diameter in the frame; IFC and Rhino cut them as circles, the glTF mesh as polygons of
  the same area, :data:`fabrication.contract.GLB_HOLE_SEGMENTS`);
* a splice cover plate: its outline and bolt holes in the splice frame, on either face of the beam plate;
* a retention part (:func:`retention_elements`): the box of its ``parts.csv`` row; the screws of a pressure plate
  one element with a prism per screw (:attr:`Element.copies`).

The data of an element (:data:`fabrication.contract.EXCHANGE_PROPERTIES`) are the values of its ``parts.csv``
row, so the IFC property sets and the Rhino user text agree with the parts list by construction; for a beam plate
``weight_kg`` is the row's ``mass_kg`` and ``planarity_dev_mm`` the largest distance of its mesh vertices from
the support plane.
"""

from __future__ import annotations

import uuid
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ppfab.errors import FabricationError
from ppfab.frame import Frame
from ppfab.topology import FAMILY_NAMES

from ..contract import EXCHANGE_PROPERTIES

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord


Value = str | int | float

GUID_NAMESPACE = uuid.UUID("ace20579-3526-4925-9189-9184988e2125")
"""The namespace of ppfab's name-based object ids (IFC GlobalIds, Rhino object and layer ids)."""


def object_uuid(design: str, key: str) -> uuid.UUID:
    """The id of ``key`` (a part id, ``layer/glass``, ``project`` …) in the design named ``design``: a name-based
    UUID (RFC 4122 version 5), the same in every build of that design and different between designs.

    >>> str(object_uuid("roof", "P-U00-V00")) == str(object_uuid("roof", "P-U00-V00"))
    True
    """
    return uuid.uuid5(GUID_NAMESPACE, f"{design}\n{key}")


@dataclass(frozen=True, eq=False)
class Element:
    """One part as a prism: ``outline (k, 2)`` in ``frame``, extruded from ``z0`` by ``height`` (mm).

    ``layer`` is ``"glass"`` or the beam family (``"rows"``, ``"cols"``), ``group`` the beam id of a plate
    (``""`` for a panel), ``props`` the part's data (the keys of ``EXCHANGE_PROPERTIES`` that apply), ``holes``
    ``(h, 3)`` the through holes: centre ``x, y`` in the frame and diameter, mm.  ``outline_top (k, 2)``, when
    given, is the outline on the top face ``z0 + height`` (a bevelled plate: its corners correspond to
    ``outline``'s, each side face joins two parallel edges and is planar); otherwise the top is ``outline``.
    """

    part_id: str
    kind: str
    layer: str
    group: str
    outline: np.ndarray
    frame: Frame
    z0: float
    height: float
    props: dict[str, Value] = field(default_factory=dict)
    holes: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    copies: np.ndarray | None = None
    outline_top: np.ndarray | None = None

    @property
    def two_faces(self) -> bool:
        """Whether the top face differs from the bottom one (a bevelled plate: not a prism)."""
        return self.outline_top is not None

    def top_outline(self) -> np.ndarray:
        """``(k, 2)`` the outline on the top face."""
        return np.asarray(self.outline if self.outline_top is None else self.outline_top, dtype=float)

    def copy_frames(self) -> list[Frame]:
        """The frame of each copy of the prism: ``[frame]``, or one per ``copies (m, 2)`` offset in the frame (the
        clamping screws of a plate: one element, a prism per screw)."""
        if self.copies is None:
            return [self.frame]
        f = self.frame
        return [Frame(f.origin + f.vec3d(np.asarray(c, dtype=float)), f.ex, f.ey) for c in self.copies]

    @property
    def net_area(self) -> float:
        """The outline's area less its holes, mm² (of two faces, their mean: the volume is ``net_area × height``
        to the bevel's second order, as :mod:`fabrication.verify.step` takes it)."""
        from ppfab.metrics import polygon_area

        d = np.asarray(self.holes, dtype=float).reshape(-1, 3)[:, 2]
        area = 0.5 * (abs(float(polygon_area(np.asarray(self.outline, dtype=float))))
                      + abs(float(polygon_area(self.top_outline()))))
        return area - float(np.pi / 4.0 * (d * d).sum())

    def base(self, z: float | None = None) -> np.ndarray:
        """``(k, 3)`` the outline in 3D at height ``z`` above the frame (default ``z0``), mm."""
        h = self.z0 if z is None else z
        return self.frame.to3d(np.asarray(self.outline, dtype=float)) + h * self.frame.normal

    def hole_rings(self) -> list[np.ndarray]:
        """Each bolt hole as a clockwise regular polygon ``(m, 2)`` in the frame with the hole's area
        (:data:`~fabrication.contract.GLB_HOLE_SEGMENTS` corners)."""
        from ..contract import GLB_HOLE_SEGMENTS as m

        grow = np.sqrt(np.pi / (0.5 * m * np.sin(2.0 * np.pi / m)))
        t = -2.0 * np.pi * np.arange(m) / m                   # clockwise: the material lies outside
        unit = np.c_[np.cos(t), np.sin(t)]
        return [np.array([x, y]) + 0.5 * d * grow * unit for x, y, d in np.asarray(self.holes, float).reshape(-1, 3)]

    def prism_mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """The closed triangle mesh of the prism: vertices ``(2n, 3)`` (the bottom rings — the outline's ``k``
        corners, then each hole's — then the top rings in the same order) and faces oriented outwards (caps by a
        constrained Delaunay triangulation, a side quad per ring edge); with ``copies``, the meshes of every copy
        one after the other."""
        rings = [np.asarray(self.outline, dtype=float)] + self.hole_rings()
        tri = cap_triangles(self.outline, rings[1:])
        top_tri = tri if self.outline_top is None else cap_triangles(self.top_outline(), rings[1:])
        if self.copies is not None:              # every copy has the same caps: triangulated once
            meshes = [replace(self, frame=f, copies=None)._mesh(rings, tri, top_tri) for f in self.copy_frames()]
            offsets = np.cumsum([0] + [len(v) for v, _ in meshes[:-1]])
            return (np.concatenate([v for v, _ in meshes]),
                    np.concatenate([f + o for (_, f), o in zip(meshes, offsets)]))
        return self._mesh(rings, tri, top_tri)

    def _mesh(self, rings: list[np.ndarray], tri: np.ndarray, top_tri: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The mesh of one prism in this element's frame, of its ``rings`` and its caps' triangles."""
        flat = np.concatenate(rings)
        n = len(flat)
        bottom = self.frame.to3d(flat) + self.z0 * self.frame.normal
        if self.outline_top is None:
            top = bottom + self.height * self.frame.normal
        else:                                   # two faces: each cap triangulated on its own corners
            top_flat = np.concatenate([self.top_outline()] + rings[1:])
            top = self.frame.to3d(top_flat) + (self.z0 + self.height) * self.frame.normal
        sides = []
        start = 0
        for r in rings:
            ring = start + np.arange(len(r))
            nxt = start + np.roll(np.arange(len(r)), -1)
            sides += [np.stack([ring, nxt, nxt + n], axis=1), np.stack([ring, nxt + n, ring + n], axis=1)]
            start += len(r)
        faces = np.concatenate([tri[:, ::-1], top_tri + n] + sides)
        return np.concatenate([bottom, top]), faces


def cap_triangles(outline: np.ndarray, holes: list[np.ndarray] | tuple = ()) -> np.ndarray:
    """``(k + Σ m_i + 2h − 2, 3)`` counter-clockwise triangles of a simple polygon ``(k, 2)`` with ``h`` holes
    ``(m_i, 2)`` on their own vertices, numbered outline first, then each hole (shapely's constrained Delaunay
    triangulation, its corners read at once and mapped back to vertex indices)."""
    import shapely

    rings = [np.asarray(outline, dtype=float)] + [np.asarray(h, dtype=float) for h in holes]
    pts = np.concatenate(rings)
    index = {(x, y): i for i, (x, y) in enumerate(pts.tolist())}
    triangles = shapely.constrained_delaunay_triangles(shapely.Polygon(rings[0], rings[1:]))
    corners = shapely.get_coordinates(triangles).reshape(-1, 4, 2)[:, :3]      # each triangle's closed ring
    try:
        out = np.array([index[(x, y)] for x, y in corners.reshape(-1, 2).tolist()], dtype=np.int64).reshape(-1, 3)
    except KeyError:
        raise FabricationError("a cap triangulation added a point to a part outline") from None
    a, b, c = pts[out[:, 0]], pts[out[:, 1]], pts[out[:, 2]]
    clockwise = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) < 0
    out[clockwise] = out[clockwise, ::-1]
    if len(out) != len(pts) + 2 * len(holes) - 2:
        raise FabricationError(f"triangulating a part outline of {len(pts)} corners gave {len(out)} triangles")
    return out


def _value(v: Any) -> Value | None:
    if v is None or v == "":
        return None
    if isinstance(v, (bool, np.bool_)):
        return int(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return float(v)
    return str(v)


def elements(build: "BuildRecord") -> list[Element]:
    """The panels (in face order), then the beam plates (in plate order), as :class:`Element` records."""

    rows = build.parts.by_id()
    seat = build.pane_offsets()
    out = []
    for p in build.panels.panels:
        props = _props(rows[p.part_id])
        out.append(Element(p.part_id, "panel", "glass", "", p.outline, p.frame, seat[p.part_id],
                           float(p.thickness_mm), props))
    for b in build.beams.plates:
        row = dict(rows[b.part_id])
        row["weight_kg"] = row.get("mass_kg", "")
        row["planarity_dev_mm"] = round(float(b.plane_deviation), 4)
        row.setdefault("family", FAMILY_NAMES[b.family])
        t = float(b.thickness)
        holes = np.asarray(b.holes, dtype=float).reshape(-1, 3)
        if b.bevels and b.cut_outline is not None:          # the solid between its two faces, as in beams.step
            from ..beams.bevel_cut import face_outlines

            front, back = face_outlines(b)
            out.append(Element(b.part_id, "beam", FAMILY_NAMES[b.family], b.beam_id, back, b.frame, -0.5 * t, t,
                               _props(row), holes, outline_top=front))
            continue
        out.append(Element(b.part_id, "beam", FAMILY_NAMES[b.family], b.beam_id, b.flat_outline, b.frame, -0.5 * t, t,
                           _props(row), holes))
    return out + _glazing_elements(build, rows)


def _glazing_elements(build: "BuildRecord", rows: dict[str, dict]) -> list[Element]:
    """The glazing strips (on their beams' top edges) and the splice cover plates with their bolt holes."""
    g = build.glazing
    if g is None:
        return []
    out = []
    for s in g.strips:
        row = dict(rows[s.part_id])
        row["weight_kg"] = row.get("mass_kg", "")
        out.append(Element(s.part_id, "strip", str(row.get("family") or "rows"), "", s.outline(), s.frame, 0.0,
                           float(s.thickness), _props(row)))
    for sp in g.splices:
        for pid, sign in zip(sp.part_ids, (1.0, -1.0)):
            row = dict(rows[pid])
            row["weight_kg"] = row.get("mass_kg", "")
            z0 = 0.5 * sp.beam_thickness if sign > 0 else -0.5 * sp.beam_thickness - sp.thickness
            holes = np.c_[np.asarray(sp.holes, dtype=float).reshape(-1, 2), np.full(len(sp.holes), float(sp.hole))]
            out.append(Element(pid, "splice", str(row.get("family") or "rows"), "", sp.outline, sp.frame, z0,
                               float(sp.thickness), _props(row), holes))
    return out + retention_elements(build, rows)


SCREW_SIDES = 12
"""Corners of the polygon a clamping screw is drawn as in the exchange models (its circle's inscribed 12-gon;
IFC draws the circle itself)."""


def retention_elements(build: "BuildRecord", rows: dict[str, dict]) -> list[Element]:
    """The retention parts (:mod:`fabrication.glazing.retention`) on layer ``retention``: each setting block, stop,
    pressure gasket, pressure plate and cover cap the box of its ``parts.csv`` row (the prism of glazing.step,
    from a corner of its underside along the row's ``frame``), and the screws of a plate one element with a
    prism per screw (``copies`` at its stations along the strip)."""

    retention = build.retention
    if retention is None:
        return []
    out = []
    for part in retention.parts:
        origin, x, y, _ = part.box_frame()
        row = dict(rows[part.part_id])
        row["weight_kg"] = row.get("mass_kg", "")
        box = np.array([[0.0, 0.0], [part.length, 0.0], [part.length, part.width], [0.0, part.width]])
        out.append(Element(part.part_id, part.kind, "retention", "", box, Frame(origin, x, y), 0.0,
                           float(part.height), _props(row)))
    t = 2.0 * np.pi * np.arange(SCREW_SIDES) / SCREW_SIDES
    for sc in retention.screws:
        row = dict(rows[sc.part_id])
        row["weight_kg"] = row.get("mass_kg", "")
        f = sc.frame
        origin = f.to3d(np.array([sc.x0, 0.0])) + sc.z0 * f.normal
        circle = 0.5 * sc.diameter * np.c_[np.cos(t), np.sin(t)]
        out.append(Element(sc.part_id, "screw", "retention", "", circle, Frame(origin, f.ex, f.ey), 0.0,
                           float(sc.length), _props(row), copies=np.array([[x, 0.0] for x in sc.stations])))
    return out


def part_material(el: Element, beams: str) -> str:
    """The material of a steel element: ``beams`` (``[beams] material``) for a beam plate, the ``material`` of
    its ``parts.csv`` row for a glazing strip or splice cover plate (``[glazing]`` / ``[splices] material``)."""
    if el.kind == "beam":
        return beams
    return str(el.props.get("material") or beams)


def _props(row: dict) -> dict[str, Value]:
    out: dict[str, Value] = {}
    for k in EXCHANGE_PROPERTIES:
        v = _value(row.get(k))
        if v is not None:
            out[k] = v
    return out


@dataclass(frozen=True)
class NodeAxis:
    """A node axis as a line from the node (on the mesh) ``length`` mm along the unit axis, with its data."""

    node_id: str
    start: np.ndarray
    end: np.ndarray
    props: dict[str, Value]


def node_axes(build: "BuildRecord") -> list[NodeAxis]:
    """One line per node: from its position along its unit axis (into the structure) by the beam depth."""
    depth = float(build.beams.params.depth)
    out = []
    for r in build.nodes.records:
        start = np.asarray(r["position"], dtype=float)
        axis = np.asarray(r["axis"], dtype=float)
        props: dict[str, Value] = {"node_id": r["node_id"], "vertex": int(r["vertex"]),
                                   "beams": ";".join(b["part_id"] for b in r["beams"]), "joint": str(r["joint"])}
        if r.get("torsion_deg") is not None:
            props["torsion_deg"] = round(float(r["torsion_deg"]), 6)
        out.append(NodeAxis(r["node_id"], start, start + depth * axis, props))
    return out
