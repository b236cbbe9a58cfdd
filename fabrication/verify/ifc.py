"""model.ifc: schema-valid IFC4, one IfcPlate per panel and one IfcMember per beam part, named by part id, with
the property set of parts.csv, in millimetres, each solid on its mesh face or support plane."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ppfab.metrics import polygon_area

from ..contract import EXCHANGE_PROPERTIES, IFC_CLASSES, IFC_PSET, IFC_SCHEMA, csv_value
from . import Verification, check
from ._shapes import cross3, cross_rows, open_ring
from ._solids import check_screw_points, check_names, check_part_solid, same_value
from ._tolerance import type_tolerance


def _unit(v: tuple[float, ...] | None, default: tuple[float, float, float]) -> tuple[float, float, float]:
    """The unit vector along the direction ratios ``v`` (``default`` when absent or of length 0)."""
    if v is None:
        return default
    x, y, z = (float(c) for c in (tuple(v) + (0.0, 0.0))[:3])
    n = math.sqrt(x * x + y * y + z * z)
    return (x / n, y / n, z / n) if n > 0.0 else default


def _frame(origin, z: tuple[float, float, float], ref: tuple[float, float, float]) -> np.ndarray:
    """``(4, 4)`` the placement with origin ``origin``, z axis ``z`` (unit) and x axis ``ref`` made orthogonal to
    it (IFC4's ``IfcBuildAxes``: the reference direction projected onto the plane normal to z)."""
    d = ref[0] * z[0] + ref[1] * z[1] + ref[2] * z[2]
    x = _unit((ref[0] - d * z[0], ref[1] - d * z[1], ref[2] - d * z[2]), (1.0, 0.0, 0.0))
    y = cross3(z, x)
    o = (tuple(float(c) for c in origin) + (0.0, 0.0))[:3]
    return np.array([[x[0], y[0], z[0], o[0]], [x[1], y[1], z[1], o[1]], [x[2], y[2], z[2], o[2]],
                     [0.0, 0.0, 0.0, 1.0]])


# Attribute positions of the entities read here most often (IFC4): the readers below take ``entity[i]``, a
# third of the time of ``entity.Name`` in IfcOpenShell's Python binding.
_LOCATION, _AXIS, _REF_DIRECTION = 0, 1, 2                  # IfcAxis2Placement3D
_PLACEMENT_REL_TO, _RELATIVE_PLACEMENT = 0, 1               # IfcLocalPlacement (IfcObjectPlacement's 0 is
                                                            # PlacementRelTo in IFC4)
_AXIS1, _AXIS2, _LOCAL_ORIGIN, _SCALE, _AXIS3 = 0, 1, 2, 3, 4   # IfcCartesianTransformationOperator3D


def axis2placement(p) -> np.ndarray:
    """``(4, 4)`` an ``IfcAxis2Placement3D`` (or 2D: in its plane) from its coordinates to its parent's: origin
    at its ``Location``, z along ``Axis`` (default +z), x along ``RefDirection`` projected normal to z (default
    +x), y = z × x — IFC4's definition, written here rather than taken from ``ifcopenshell.util.placement``
    (which does not project the reference direction, and costs ten times as much per placement)."""
    if p.is_a("IfcAxis2Placement2D"):
        ref = p[1]
        return _frame(p[0][0], (0.0, 0.0, 1.0), _unit(None if ref is None else ref[0], (1.0, 0.0, 0.0)))
    axis, ref = p[_AXIS], p[_REF_DIRECTION]
    return _frame(p[_LOCATION][0], _unit(None if axis is None else axis[0], (0.0, 0.0, 1.0)),
                  _unit(None if ref is None else ref[0], (1.0, 0.0, 0.0)))


def transformation_operator(op) -> np.ndarray:
    """``(4, 4)`` an ``IfcCartesianTransformationOperator3D``: IFC4's ``IfcBaseAxis`` (z along ``Axis3``, x along
    ``Axis1`` projected normal to it, y = z × x, reversed when ``Axis2`` points against it) scaled by ``Scale``
    (and ``Scale2``, ``Scale3`` of a non-uniform one), at ``LocalOrigin``."""
    a1, a2, a3 = op[_AXIS1], op[_AXIS2], op[_AXIS3]
    m = _frame(op[_LOCAL_ORIGIN][0], _unit(None if a3 is None else a3[0], (0.0, 0.0, 1.0)),
               _unit(None if a1 is None else a1[0], (1.0, 0.0, 0.0)))
    if a2 is not None and float(np.dot(m[:3, 1], _unit(a2[0], (0.0, 1.0, 0.0)))) < 0.0:
        m[:3, 1] *= -1.0
    scale = op[_SCALE]
    s1 = 1.0 if scale is None else float(scale)
    scales = [s1, s1, s1]
    if op.is_a("IfcCartesianTransformationOperator3DnonUniform"):
        scales[1] = s1 if op.Scale2 is None else float(op.Scale2)
        scales[2] = s1 if op.Scale3 is None else float(op.Scale3)
    m[:3, :3] *= scales
    return m


@dataclass
class IfcReading:
    """What the geometry readers below keep while one file is checked: each ``IfcLocalPlacement`` 's matrix to the
    world (a placement's parents are shared by every product under them: each is worked out once), each
    ``IfcAxis2Placement3D`` 's (the writer shares some) and each extruded solid's profile, by entity id (an
    instanced type's solid is read once for all its products)."""

    placements: dict[int, np.ndarray] = field(default_factory=dict)
    axes: dict[int, np.ndarray] = field(default_factory=dict)
    prisms: dict[int, "_Prism | None"] = field(default_factory=dict)

    def placement(self, placement) -> np.ndarray:
        """``(4, 4)`` the ``IfcLocalPlacement`` to the world (its ``RelativePlacement`` after its parent's,
        :func:`axis2placement`; its parents kept)."""
        if placement is None:
            return np.eye(4)
        got = self.placements.get(placement.id())
        if got is None:
            parent = self.placement(placement[_PLACEMENT_REL_TO])
            got = parent @ self.axis2placement(placement[_RELATIVE_PLACEMENT])
            self.placements[placement.id()] = got
        return got

    def axis2placement(self, p) -> np.ndarray:
        """:func:`axis2placement` of ``p``, kept by id."""
        got = self.axes.get(p.id())
        if got is None:
            got = self.axes[p.id()] = axis2placement(p)
        return got

    def mapped(self, item) -> np.ndarray:
        """``(4, 4)`` an ``IfcMappedItem`` 's motion: its target operator after its source's origin."""
        source = item.MappingSource
        return transformation_operator(item.MappingTarget) @ self.axis2placement(source.MappingOrigin)


def body_items(product, reading: IfcReading | None = None) -> list[tuple[Any, np.ndarray]]:
    """The solids of a product's body, each with the ``(4, 4)`` matrix from its coordinates to the world (mm):
    its own items under its placement, or the items of the type's shape an ``IfcMappedItem`` places (the
    placement times the mapping's operator and origin, :meth:`IfcReading.mapped`)."""
    rep = product.Representation
    if rep is None:
        return []
    reading = reading or IfcReading()
    m = reading.placement(product.ObjectPlacement)
    out = []
    for r in rep.Representations:
        for it in r.Items:
            if it.is_a("IfcMappedItem"):
                t = m @ reading.mapped(it)
                out += [(sub, t) for sub in it.MappingSource.MappedRepresentation.Items]
            else:
                out.append((it, m))
    return out


def mapped_items(product) -> list[Any]:
    """The ``IfcMappedItem`` s of a product's body (none when it has its own)."""
    rep = product.Representation
    return [it for r in (rep.Representations if rep else ()) for it in r.Items if it.is_a("IfcMappedItem")]


def type_of(product) -> Any | None:
    """The type object a product is an occurrence of (``IsTypedBy``, IFC4), ``None`` when it has none:
    ``ifcopenshell.util.element.get_type`` for an occurrence, without its look-up of the file's schema (a third
    of its time)."""
    rels = product.IsTypedBy
    return rels[0].RelatingType if rels else None


def mapping_problem(product) -> str | None:
    """What is wrong with how a product maps its type's shape, ``None`` when nothing is (or it has its own body):
    the shape must be one of its type's ``RepresentationMaps`` and the operator a rigid motion (orthonormal
    axes, right-handed, scale 1).  Where the moved shape lies is judged like any body (a pane's outline to its
    type tolerance: the glass is cut to its type's outline)."""
    items = mapped_items(product)
    if not items:
        return None
    t = type_of(product)
    maps = list(t.RepresentationMaps or ()) if t is not None else []
    for it in items:
        if it.MappingSource not in maps:
            return "maps a shape that is not its type's"
        op = it.MappingTarget
        if op.Scale not in (None, 1.0) or op.is_a("IfcCartesianTransformationOperator3DnonUniform"):
            return f"maps its type's shape at scale {op.Scale}"
        axes = np.array([np.asarray(a.DirectionRatios, dtype=float) if a is not None else e
                         for a, e in zip((op.Axis1, op.Axis2, op.Axis3), np.eye(3))])
        if np.abs(axes @ axes.T - np.eye(3)).max() > 1e-9 or np.linalg.det(axes) < 0:
            return "maps its type's shape by an operator that is not a rotation (mirrored, skewed or scaled)"
    return None


def named_pset(product, name: str) -> dict[str, Any] | None:
    """``ifcopenshell.util.element.get_psets(product).get(name)``, reading that one set only: the properties of
    every definition named ``name`` of the product's type, then of the product itself (later ones updating
    earlier ones, as ``get_psets`` merges them); ``None`` when neither has one.  ``get_psets`` reads every set
    and quantity set of the product and its type: a fifth of the ifc check's time on the bundled default."""
    import ifcopenshell.util.element as ue

    out: dict[str, Any] | None = None
    t = type_of(product)
    definitions = list(t.HasPropertySets or ()) if t is not None and t.is_a("IfcTypeObject") else []
    for rel in product.IsDefinedBy or ():
        if rel.is_a("IfcRelDefinesByProperties"):
            d = rel.RelatingPropertyDefinition
            definitions += list(d.wrappedValue) if d.is_a("IfcPropertySetDefinitionSet") else [d]
    for d in definitions:
        if d.Name == name:
            out = out if out is not None else {}
            out.update(ue.get_property_definition(d))
    return out


def is_mapped(product) -> bool:
    """Whether the product's body is its type's shape placed by an ``IfcMappedItem``."""
    return bool(mapped_items(product))


@dataclass(frozen=True)
class _Prism:
    """An ``IfcExtrudedAreaSolid`` of a polyline profile in its own coordinates: its base ring ``(k, 4)``
    (homogeneous, after its ``Position``), the extrusion vector ``(3,)`` and its volume (mm³)."""

    base: np.ndarray
    extrusion: np.ndarray
    volume: float


def _prism_of(s, reading: IfcReading) -> _Prism | None:
    curve = s.SweptArea.OuterCurve if s.SweptArea.is_a("IfcArbitraryClosedProfileDef") else None
    if curve is None or not curve.is_a("IfcPolyline"):
        return None
    q = open_ring(np.array([p.Coordinates for p in curve.Points], dtype=float))
    pos = reading.axis2placement(s.Position)
    direction = np.asarray(s.ExtrudedDirection.DirectionRatios, dtype=float)
    direction = direction / np.linalg.norm(direction)
    area = abs(float(polygon_area(q)))
    for inner in getattr(s.SweptArea, "InnerCurves", None) or ():      # voids: circles (bolt holes), polylines
        if inner.is_a("IfcCircle"):
            area -= np.pi * float(inner.Radius) ** 2
        elif inner.is_a("IfcPolyline"):
            area -= abs(float(polygon_area(np.array([p.Coordinates for p in inner.Points], dtype=float))))
    height = s.Depth * abs(float(direction[2]))
    return _Prism(np.c_[q, np.zeros(len(q)), np.ones(len(q))] @ pos.T, s.Depth * (pos[:3, :3] @ direction),
                  area * height)


def extruded_prism(product, reading: IfcReading | None = None) -> tuple[np.ndarray, float] | None:
    """The vertices ``(2k, 3)`` (mm, world) and volume (mm³) of a product's single ``IfcExtrudedAreaSolid`` with an
    ``IfcArbitraryClosedProfileDef`` of an ``IfcPolyline``, from its placement — exact, no tessellation.
    ``reading`` keeps placements and profiles read before (one file's)."""
    reading = reading or IfcReading()
    solids = [(it, m) for it, m in body_items(product, reading) if it.is_a("IfcExtrudedAreaSolid")]
    if len(solids) != 1:
        return None
    s, m = solids[0]
    key = s.id()
    if key not in reading.prisms:
        reading.prisms[key] = _prism_of(s, reading)
    prism = reading.prisms[key]
    if prism is None:
        return None
    top = prism.base.copy()
    top[:, :3] += prism.extrusion
    world = np.concatenate([prism.base, top]) @ m.T
    return world[:, :3], prism.volume


def faceted_plate(product, reading: IfcReading | None = None) -> tuple[np.ndarray, float, np.ndarray, np.ndarray] | None:
    """A product's single ``IfcFacetedBrep`` (a plate bevelled under its strips): its vertices ``(n, 3)`` (mm,
    world), its volume (mm³, the divergence theorem over its faces: each face's vector area from its loops, the
    inner bounds running against the outer), and the outer rings of its two largest faces (the plate's faces,
    world); ``None`` for any other body."""
    breps = [(it, m) for it, m in body_items(product, reading) if it.is_a("IfcFacetedBrep")]
    if len(breps) != 1:
        return None
    brep, m = breps[0]
    loops: list[tuple[int, bool, list]] = []           # (face, outer bound, points in the brep's coordinates)
    for k, face in enumerate(brep.Outer.CfsFaces):
        for bound in face.Bounds:
            loop = bound.Bound
            if not loop.is_a("IfcPolyLoop"):
                return None
            q = [pt.Coordinates for pt in loop.Polygon]
            loops.append((k, bound.is_a("IfcFaceOuterBound"), q if bound.Orientation else q[::-1]))
    if not loops or any(len(q) < 3 for _, _, q in loops):     # an IfcPolyLoop has three points or more
        return None
    loops.sort(key=lambda x: (x[0], not x[1]))          # face by face, the outer bound first
    sizes = np.array([len(q) for _, _, q in loops])
    local = np.array([p for _, _, q in loops for p in q], dtype=float).reshape(-1, 3)
    pts = local @ m[:3, :3].T + m[:3, 3]                                                     # (N, 3) world
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    nxt = np.arange(len(pts)) + 1                                        # each point's successor in its loop
    nxt[starts + sizes - 1] = starts
    face_of = np.repeat([k for k, _, _ in loops], sizes)
    c0 = pts.mean(axis=0)
    # each face's vector area: half the sum of (p − c0) × (p_next − c0) over its loops (inner bounds reversed)
    twice = cross_rows(pts - c0, pts[nxt] - c0)
    n_faces = int(face_of.max()) + 1
    vec = 0.5 * np.stack([np.bincount(face_of, weights=twice[:, j], minlength=n_faces) for j in range(3)], axis=1)
    outer: dict[int, tuple[int, int]] = {}              # face → where its outer ring starts among pts, its size
    for (k, _, _), st, n in zip(loops, starts.tolist(), sizes.tolist()):
        outer.setdefault(k, (st, n))
    if len(outer) < 2:
        return None
    present = np.array(sorted(outer))
    volume = float(np.einsum("ij,ij->", pts[[outer[k][0] for k in present.tolist()]] - c0, vec[present])) / 3.0
    areas = np.linalg.norm(vec[present], axis=1)
    (s0, n0), (s1, n1) = (outer[int(k)] for k in present[np.argsort(areas)[::-1][:2]])
    return pts, abs(volume), pts[s0:s0 + n0], pts[s1:s1 + n1]


def circle_items(product, sides: int = 16, reading: IfcReading | None = None) -> np.ndarray:
    """``(m·2·sides, 3)`` mm, world: points on the bottom and top circles of every ``IfcExtrudedAreaSolid`` of an
    ``IfcCircleProfileDef`` in the product's body (the screws of a plate), from its placement."""
    reading = reading or IfcReading()
    t = 2.0 * np.pi * np.arange(sides) / sides
    out = []
    for s, m in ((it, m) for it, m in body_items(product, reading) if it.is_a("IfcExtrudedAreaSolid")):
        if not s.SweptArea.is_a("IfcCircleProfileDef"):
            continue
        r = float(s.SweptArea.Radius)
        pos = reading.axis2placement(s.Position)
        direction = np.asarray(s.ExtrudedDirection.DirectionRatios, dtype=float)
        direction = direction / np.linalg.norm(direction)
        ring = np.c_[r * np.cos(t), r * np.sin(t), np.zeros(sides), np.ones(sides)] @ pos.T
        top = ring.copy()
        top[:, :3] += s.Depth * (pos[:3, :3] @ direction)
        out.append((np.concatenate([ring, top]) @ m.T)[:, :3])
    return np.concatenate(out) if out else np.zeros((0, 3))


SAMPLED_CLASSES = ("IfcRepresentationItem", "IfcRepresentation", "IfcRepresentationMap", "IfcProductRepresentation",
                   "IfcProfileDef", "IfcProperty", "IfcPhysicalQuantity", "IfcObjectPlacement",
                   "IfcRelDefinesByProperties", "IfcPropertySetDefinition")
"""The IFC classes whose instances the schema validation samples by kind (:func:`schema_sample`): shapes and their
items, property and quantity values, the parts' placements, property sets and quantity sets and the relations
giving them to the parts — what ppfab writes once per part, about 96 % of its instances."""


def _kind_of(cls: str, supers: set[str]):
    """The kind (:func:`_kind`) of an instance of the IFC class ``cls`` (an exact class; ``supers`` its
    :func:`_ancestry`), as a function of the instance: what makes two instances alike for the schema — their
    class, and for a representation its identifier, type and item classes, for a product shape its
    representations' identifiers, for a property or quantity, a property or quantity set its name (and a single
    value's value class), for a placement whether it is relative to another, for a property relation the class
    and name of the set it gives."""
    def sub(name: str) -> bool:
        return name in supers

    if sub("IfcRepresentation"):
        return lambda i: (cls, i.RepresentationIdentifier, i.RepresentationType,
                          tuple(sorted({it.is_a() for it in i.Items})))
    if sub("IfcProductRepresentation"):
        return lambda i: (cls, tuple(sorted({r.RepresentationIdentifier or "" for r in i.Representations})))
    if cls == "IfcPropertySingleValue":
        def single(i) -> tuple:
            value = i[2]
            return (cls, i[0], value.is_a() if value is not None else None)
        return single
    if sub("IfcProperty") or sub("IfcPhysicalQuantity") or sub("IfcPropertySetDefinition"):
        return lambda i: (cls, i.Name)
    if sub("IfcObjectPlacement"):
        return lambda i: (cls, i.PlacementRelTo is None)
    if cls == "IfcRelDefinesByProperties":
        def relation(i) -> tuple:
            d = i.RelatingPropertyDefinition
            return (cls, d.is_a(), d.Name)
        return relation
    return lambda i: (cls,)


def _ancestry(schema_name: str, cls: str) -> set[str]:
    """The entity ``cls`` of the IFC schema ``schema_name`` and all its supertypes, by name."""
    import ifcopenshell.ifcopenshell_wrapper as w

    decl: Any = w.schema_by_name(schema_name).declaration_by_name(cls)
    out: set[str] = set()
    while decl is not None:
        out.add(decl.name())
        decl = decl.supertype()
    return out


def _kind(inst) -> tuple:
    """What makes two sampled instances alike for the schema (:func:`_kind_of` of its class)."""
    cls = inst.is_a()
    return _kind_of(cls, _ancestry(inst.file.schema, cls))(inst)


_ROOT_CLASSES = ("IfcObjectPlacement", "IfcRelDefinesByProperties", "IfcPropertySetDefinition",
                 "IfcRepresentationMap", "IfcProductRepresentation", "IfcRepresentation", "IfcProperty",
                 "IfcPhysicalQuantity")
"""The sampled classes whose first instance of each kind is validated with everything it references (the other
sampled classes — representation items, profiles — are reached from these)."""


def schema_sample(f) -> list:
    """The instances of IFC file ``f`` that the schema validation reads, in file order: every instance not of
    :data:`SAMPLED_CLASSES` (the product tree: project, site, building, roof, every element, type, structural
    member and connection, the relations of types, materials, containment and structure, materials and units),
    and of the sampled classes the first instance of each kind (:func:`_kind_of`) with everything it references.
    The checks below read every element's solid, placement, properties and quantities themselves, and
    :func:`global_id_problems` holds every GlobalId (of sampled instances too) to the schema's rules;
    ``ppfab verify --kernel`` validates every instance.

    Picked class by class (each instance's class is its file's, no per-instance test of the class tree), the
    kinds over the roots' classes only."""
    keep: set[int] = set()
    roots: list[Any] = []
    sampled, rooted = set(SAMPLED_CLASSES), set(_ROOT_CLASSES)
    for cls in sorted(f.types()):
        supers = _ancestry(f.schema, cls)
        instances = f.by_type(cls, include_subtypes=False)
        if not supers & sampled:
            keep.update(i.id() for i in instances)
        elif supers & rooted:
            kind = _kind_of(cls, supers)
            seen: set[tuple] = set()
            for inst in instances:
                k = kind(inst)
                if k not in seen:
                    seen.add(k)
                    roots.append(inst)
    for root in roots:
        keep.update(x.id() for x in f.traverse(root))
    keep.discard(0)                       # values of defined types (IfcLabel, …) are instances without an id
    return [f.by_id(i) for i in sorted(keep)]


def global_id_problems(f, validated: set[int] | None = None) -> list[tuple[Any, str]]:
    """``(instance, message)`` for every ``IfcRoot`` of ``f`` (in file order) whose GlobalId breaks the
    validator's GlobalId rules: not a compressed GUID, or used by an earlier instance (rule IfcRoot.UR1).  With
    ``validated`` (the ids the validator has seen), what it reports itself is left out: a bad GlobalId of an
    instance it saw, a duplicate of two instances it saw."""
    import ifcopenshell.validate

    seen = validated or set()
    used: dict[str, Any] = {}
    out = []
    for inst in sorted(f.by_type("IfcRoot"), key=lambda i: i.id()):
        guid = inst.GlobalId
        mine = inst.id() not in seen
        if guid is None:                                    # a missing GlobalId: the validator's finding
            if mine:
                out.append((inst, "has no GlobalId (IfcRoot.GlobalId is not optional)"))
            continue
        earlier = used.get(guid)
        if earlier is not None:
            if mine or earlier.id() not in seen:
                out.append((inst, f"GlobalId {guid} is used by #{earlier.id()} too (IfcRoot.UR1: GlobalIds are "
                                  "unique)"))
            continue
        bad = ifcopenshell.validate.validate_guid(guid) if isinstance(guid, str) else "not a string"
        if bad is not None:
            if mine:
                out.append((inst, f"GlobalId {guid!r} is not a compressed GUID ({bad})"))
            continue
        used[guid] = inst
    return out


def validate_schema(f, logger, every: bool = False) -> None:
    """ifcopenshell's schema validation (attribute types, aggregates, inverse cardinalities, GlobalIds) of the
    instances :func:`schema_sample` picks and the GlobalIds of every instance (:func:`global_id_problems`), or of
    every instance with ``every``; findings go to ``logger``."""
    import ifcopenshell.validate

    if every:
        ifcopenshell.validate.validate(f, logger)
        return
    sample = schema_sample(f)
    cls = type(f)

    class _Sampled(cls):                # type: ignore[misc, valid-type]
        """The same file, iterated over the sample: the validator walks ``for inst in f``."""

        def __iter__(self):
            return iter(sample)

    f.__class__ = _Sampled
    try:
        ifcopenshell.validate.validate(f, logger)
    finally:
        f.__class__ = cls
    for inst, message in global_id_problems(f, {i.id() for i in sample}):
        if isinstance(logger, ifcopenshell.validate.json_logger):
            logger.set_state("instance", inst)
        logger.error("%s", message)


@check("ifc")
def check_ifc(v: Verification) -> None:
    files = v.manifest.get("files", {})
    rel = files.get("ifc")
    if rel is None:
        return
    import ifcopenshell
    import ifcopenshell.util.element as ue
    import ifcopenshell.util.unit as uu
    import ifcopenshell.validate

    try:
        f = ifcopenshell.open(str(v.folder / rel))
    except Exception as exc:  # noqa: BLE001 - reported as a finding
        v.error(rel, "", f"cannot be read by ifcopenshell ({exc})")
        return
    if f.schema != IFC_SCHEMA:
        v.error(rel, "", f"schema {f.schema}, expected {IFC_SCHEMA}")
    log = ifcopenshell.validate.json_logger()
    validate_schema(f, log, every=v.kernel)
    for s in log.statements[:10]:
        text = " ".join(str(s.get("message", s)).split())
        inst: Any = s.get("instance")
        v.error(rel, f"#{inst.id()}" if inst is not None and hasattr(inst, "id") else "",
                f"schema validation: {text[:240]}")
    scale = uu.calculate_unit_scale(f)
    if abs(scale - 1e-3) > 1e-12:
        v.error(rel, "units", f"length unit is {scale:g} m, expected millimetres")
    rows = {r["part_id"]: r for r in (v.parts or [])}
    products: list[Any] = [p for p in f.by_type("IfcElement") if not p.is_a("IfcElementAssembly") and not p.is_a("IfcRoof")]
    check_names(v, rel, [p.Name for p in products], {k: r["kind"] for k, r in rows.items()}, "IFC element")
    reading = IfcReading()
    for p in products:
        row = rows.get(p.Name)
        if row is None:
            continue
        cls, predefined = IFC_CLASSES.get(row["kind"], ("IfcMember", "USERDEFINED"))
        if not p.is_a(cls) or p.PredefinedType != predefined:
            v.error(rel, p.Name, f"is {p.is_a()} {p.PredefinedType}, expected {cls} {predefined}")
        pset = named_pset(p, IFC_PSET)
        if pset is None:
            v.error(rel, p.Name, f"has no property set {IFC_PSET}")
        else:
            for key in EXCHANGE_PROPERTIES:
                cell = csv_value(row.get(key, ""))
                if key == "weight_kg" and not cell:
                    cell = row.get("mass_kg", "")
                if cell == "":
                    continue
                if key not in pset or not same_value(cell, pset[key]):
                    v.error(rel, p.Name, f"{IFC_PSET}.{key} is {pset.get(key)!r}, parts.csv has {cell!r}")
        if ue.get_container(p) is None:
            v.error(rel, p.Name, "is not in the spatial structure (site, building, storey)")
        _check_material_and_type(v, rel, p, row)
        problem = mapping_problem(p)
        if problem is not None:
            v.error(rel, p.Name, problem)
            continue
        if row["kind"] == "screw":
            check_screw_points(v, rel, row, circle_items(p, reading=reading))
            continue
        prism = extruded_prism(p, reading)
        brep = faceted_plate(p, reading) if prism is None and row["kind"] == "beam" else None
        if brep is not None:                     # a plate bevelled under its strips: the solid between its faces
            check_part_solid(v, rel, row, brep[0], brep[1], volume_tol=1e-4, ring=brep[2], holes=True,
                             top_ring=brep[3])
            continue
        if prism is None:
            v.error(rel, p.Name, "has no single extruded solid of a polyline profile")
            continue
        # a pane drawn as its type's shape is that outline as cut: within the type tolerance of its own face
        outline_eps = type_tolerance(v.manifest.get("fabrication", {})) + 1e-4 \
            if row["kind"] == "panel" and is_mapped(p) else None
        check_part_solid(v, rel, row, prism[0], prism[1], ring=prism[0][:len(prism[0]) // 2], holes=True,
                         outline_eps=outline_eps)
    names = [m.Name for m in f.by_type("IfcMaterial")]
    for name in sorted({n for n in names if names.count(n) > 1}):
        v.error(rel, f"IfcMaterial {name}", f"defined {names.count(name)} times (one shared material per name)")
    materials: list[Any] = list(f.by_type("IfcMaterial"))
    for m in materials:
        if not f.get_inverse(m):
            v.error(rel, f"IfcMaterial {m.Name}", "is associated with no element and no layer (orphaned)")
    v.checked.append("ifc")


def _check_material_and_type(v: Verification, rel: str, product: Any, row: dict[str, str]) -> None:
    """A pane's material is the layer set of its make-up (named as parts.csv's material, its layers as thick as
    the pane) and its type the ``IfcPlateType`` of its type id; any other part's material is its ``IfcMaterial``."""
    import ifcopenshell.util.element as ue

    material = csv_value(row.get("material", ""))
    if row["kind"] == "panel":
        layers = ue.get_material(product, should_skip_usage=True)
        if layers is None or not layers.is_a("IfcMaterialLayerSet") or layers.LayerSetName != material:
            v.error(rel, product.Name, f"material is not the layer set {material!r} of parts.csv")
        else:
            total = sum(float(x.LayerThickness) for x in layers.MaterialLayers)
            if abs(total - float(row.get("thickness_mm") or "nan")) > 1e-6:
                v.error(rel, product.Name, f"layers add up to {total:g} mm, parts.csv thickness_mm is "
                                           f"{row.get('thickness_mm')}")
        t = type_of(product)
        if t is None or not t.is_a("IfcPlateType") or t.Name != csv_value(row.get("type_id", "")):
            v.error(rel, product.Name, f"is not an occurrence of the IfcPlateType {row.get('type_id')}")
        return
    m = ue.get_material(product)
    if m is None or not m.is_a("IfcMaterial") or m.Name != material:
        v.error(rel, product.Name, f"material {getattr(m, 'Name', None)!r}, parts.csv has {material!r}")
