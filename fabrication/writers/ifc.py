"""``model.ifc``: the structure as IFC4 for BIM tools — an ``IfcPlate`` per pane, an ``IfcMember`` per beam plate,
and the glass retention (:data:`~fabrication.contract.IFC_CLASSES`): setting blocks, stops and pressure gaskets as
``IfcDiscreteAccessory``, pressure plates as ``IfcPlate`` SHEET, cover caps as ``IfcCovering`` CLADDING, the screws
of each plate as one ``IfcMechanicalFastener`` BOLT (one shared ``IfcCircleProfileDef``, an extruded solid per
screw: the plate's row of parts.csv with its quantity).

Spatial structure and decomposition (``IfcRelAggregates`` unless noted)::

    IfcProject (the design's name; units mm, m², m³, kg, rad)
      IfcSite → IfcBuilding → IfcBuildingStorey "Roof"
        IfcRoof FREEFORM (the design's name)         (IfcRelContainedInSpatialStructure)
          IfcPlate CURTAIN_PANEL  P-U07-V12 …        one per glass panel
          IfcElementAssembly GIRDER  B-U03 …         one per beam
            IfcMember MEMBER  B-U03-S00 …            one per plate of the beam

Each element (:mod:`fabrication.writers._elements`) is one ``IfcExtrudedAreaSolid``: its flat outline as an
``IfcArbitraryClosedProfileDef`` in its own placement (origin, normal, x direction of the part's frame), extruded
along the local z from ``z0`` by its height, in millimetres — the same prism as ``beams.step`` and the DXF outline;
a plate bevelled under its strips, whose two faces differ, is an ``IfcFacetedBrep`` of its faces in the same
placement (the solid of ``beams.step``, holes as polygons of their area).
It carries the property set :data:`~fabrication.contract.IFC_PSET` (the ``parts.csv`` values of
:data:`~fabrication.contract.EXCHANGE_PROPERTIES`; ``area_mm2`` with an explicit mm² unit), the base quantities
``Qto_PlateBaseQuantities`` / ``Qto_MemberBaseQuantities`` (width or length, net area, net volume, net weight in
the project units), the standard property set ``Pset_PlateCommon`` / ``Pset_MemberCommon`` (Reference = the type's
name, IsExternal, LoadBearing; written once on the type, which its occurrences inherit, or on an untyped part with
Reference = its part id), its type (:mod:`fabrication.writers._instances`: an ``IfcPlateType`` per panel type, an
``IfcMemberType`` per repeated beam-plate, cover-plate or strip size, the retention types by size;
``IfcRelDefinesByType``) whose shape, an ``IfcRepresentationMap``, the occurrence places by an ``IfcMappedItem``
(a pane always — the glass is cut to its type's outline —, another part where that shape is its own), the
classification reference of its kind when the design names one (``[output.classification]``), its material —
one ``IfcMaterial`` per material name, shared; a pane's make-up as an ``IfcMaterialLayerSet`` of its plies and interlayers (``IfcMaterialLayerSetUsage`` along the pane's local z from
its underside) — and a surface style of its family's colour (:data:`~fabrication.contract.COLOURS`).

Reproducible: every ``GlobalId`` is derived from the design's name and the element's key (its part id;
``beam/B-U03`` for a beam's assembly, which may share its id with its only plate) by a name-based UUID
(RFC 4122 version 5), there is no owner history, and the header time stamp is fixed.

The file is written as text as its entities are made (:class:`~fabrication.writers._ifc_text.IfcText`, with
IfcOpenShell's schema): the same bytes IfcOpenShell's own file writes from the same calls, at a fraction of its
cost and memory; ``ppfab verify`` reads it back with IfcOpenShell.  ifcopenshell is imported inside the
functions.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from ppfab import __version__

from ..contract import COLOURS, FIXED_TIMESTAMP, IFC_CLASSES, IFC_FILE, IFC_PSET, IFC_SCHEMA
from . import Files, writer
from ._elements import Element, elements, object_uuid, part_material
from ._ifc_text import IfcText
from ._instances import TypePlan, mappable, plan_types

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord

LENGTH_KEYS = {"thickness_mm", "planarity_dev_mm"}


@dataclass
class _Type:
    """One IFC element type being filled: its class and predefined type, the part kind, its occurrences, its
    shape's ``IfcRepresentationMap`` (the body of its first part), how many occurrences keep their own body,
    and the largest distance of a mapped shape from an occurrence's own outline (mm, reported for the panes by
    the writer's line)."""

    cls: str
    predefined: str
    kind: str
    members: list[Any] = field(default_factory=list)
    map: Any = None
    own: int = 0
    largest_error: float = 0.0


def _clean(v: np.ndarray) -> tuple[float, ...]:
    """A direction or point with its round-off zeros made exact zeros (``-0.0`` and 1e-17 are not written)."""
    return tuple(0.0 if abs(float(x)) < 1e-12 else float(x) for x in v)


def ifc_guid(design: str, key: str) -> str:
    """The 22-character IFC GlobalId of ``key`` (a part id, ``project``, …) in the design named ``design``.

    >>> ifc_guid("roof", "P-U00-V00") == ifc_guid("roof", "P-U00-V00") != ifc_guid("roof", "P-U00-V01")
    True
    """
    import ifcopenshell.guid

    return str(ifcopenshell.guid.compress(object_uuid(design, key).hex))


class IfcModel:
    """Builder of ``model.ifc``: :meth:`add` elements into the roof, then :meth:`write`.

    The file is an :class:`~fabrication.writers._ifc_text.IfcText` (text made as the entities are); ``file``
    may give another maker of the same calls — ``ifcopenshell.file``, which writes the same bytes
    (``tests/test_ifc_text.py``)."""

    def __init__(self, name: str, description: str = "", file: Callable[..., Any] = IfcText):
        self.name = name
        f = self.f = file(schema=IFC_SCHEMA)
        h = f.header
        h.file_description.description = ("ViewDefinition [DesignTransferView]",)
        h.file_name.name = IFC_FILE
        h.file_name.time_stamp = FIXED_TIMESTAMP
        h.file_name.author = ("ppfab",)
        h.file_name.organization = ("",)
        h.file_name.preprocessor_version = f"ppfab {__version__}"
        h.file_name.originating_system = f"ppfab {__version__}"
        h.file_name.authorization = ""
        self._dirs: dict[tuple[float, ...], Any] = {}
        self.origin = self._placement3d((0.0, 0.0, 0.0))
        self.mm2 = f.create_entity("IfcSIUnit", UnitType="AREAUNIT", Prefix="MILLI", Name="SQUARE_METRE")
        units = f.create_entity("IfcUnitAssignment", Units=[
            f.create_entity("IfcSIUnit", UnitType="LENGTHUNIT", Prefix="MILLI", Name="METRE"),
            f.create_entity("IfcSIUnit", UnitType="AREAUNIT", Name="SQUARE_METRE"),
            f.create_entity("IfcSIUnit", UnitType="VOLUMEUNIT", Name="CUBIC_METRE"),
            f.create_entity("IfcSIUnit", UnitType="MASSUNIT", Prefix="KILO", Name="GRAM"),
            f.create_entity("IfcSIUnit", UnitType="PLANEANGLEUNIT", Name="RADIAN")])
        ctx = self.context = f.create_entity("IfcGeometricRepresentationContext", ContextType="Model",
                                             CoordinateSpaceDimension=3, Precision=1e-5,
                                             WorldCoordinateSystem=self.origin)
        self.body = f.create_entity("IfcGeometricRepresentationSubContext", ContextIdentifier="Body",
                                    ContextType="Model", ParentContext=ctx, TargetView="MODEL_VIEW")
        project = self.project = f.create_entity("IfcProject", GlobalId=self.guid("project"), Name=name,
                                                 Description=description or None, RepresentationContexts=[ctx],
                                                 UnitsInContext=units)
        world = f.create_entity("IfcLocalPlacement", RelativePlacement=self.origin)
        site = f.create_entity("IfcSite", GlobalId=self.guid("site"), Name="Site", ObjectPlacement=world,
                               CompositionType="ELEMENT")
        self.site_placement = world
        building_placement = self._local(world)
        building = self.building = f.create_entity("IfcBuilding", GlobalId=self.guid("building"), Name=name,
                                                   ObjectPlacement=building_placement, CompositionType="ELEMENT")
        storey_placement = self._local(building_placement)
        storey = f.create_entity("IfcBuildingStorey", GlobalId=self.guid("storey"), Name="Roof",
                                 ObjectPlacement=storey_placement, CompositionType="ELEMENT", Elevation=0.0)
        self.roof_placement = self._local(storey_placement)
        self.roof = f.create_entity("IfcRoof", GlobalId=self.guid("roof"), Name=name,
                                    ObjectPlacement=self.roof_placement, PredefinedType="FREEFORM")
        self._aggregate("project", project, [site])
        self._aggregate("site", site, [building])
        self._aggregate("building", building, [storey])
        f.create_entity("IfcRelContainedInSpatialStructure", GlobalId=self.guid("storey/contains"),
                        RelatedElements=[self.roof], RelatingStructure=storey)
        self._roof_parts: list[Any] = []
        self._assemblies: dict[str, tuple[Any, list[Any]]] = {}
        self._assembly_placements: dict[str, Any] = {}
        self._materials: dict[str, Any] = {}
        self._associations: dict[str, tuple[Any, list[Any]]] = {}
        self._types: dict[tuple[str, str], _Type] = {}
        self._plan = TypePlan({}, {}, {}, {})
        self.pane_tolerance = 0.0
        self.classification: dict[str, str] = {}
        self._references: dict[str, tuple[Any, list[Any]]] = {}
        self._styles: dict[str, Any] = {}
        self._profiles: dict[str, Any] = {}
        self._properties: dict[tuple[str, str, str, Any], Any] = {}

    # -- small entities ------------------------------------------------------------------------------
    def guid(self, key: str) -> str:
        return ifc_guid(self.name, key)

    def _dir(self, v) -> Any:
        key = tuple(float(x) for x in v)
        if key not in self._dirs:
            self._dirs[key] = self.f.create_entity("IfcDirection", DirectionRatios=key)
        return self._dirs[key]

    def _point(self, p) -> Any:
        return self.f.create_entity("IfcCartesianPoint", Coordinates=tuple(float(x) for x in p))

    def _placement3d(self, origin, axis=None, ref=None) -> Any:
        return self.f.create_entity("IfcAxis2Placement3D", Location=self._point(origin),
                                    Axis=None if axis is None else self._dir(axis),
                                    RefDirection=None if ref is None else self._dir(ref))

    def _local(self, parent, relative=None) -> Any:
        return self.f.create_entity("IfcLocalPlacement", PlacementRelTo=parent,
                                    RelativePlacement=relative or self.origin)

    def _aggregate(self, key: str, whole, parts: list) -> None:
        self.f.create_entity("IfcRelAggregates", GlobalId=self.guid(f"{key}/aggregates"), RelatingObject=whole,
                             RelatedObjects=parts)

    def _style(self, layer: str) -> Any:
        if layer not in self._styles:
            r, g, b, a = COLOURS.get(layer, COLOURS["rows"])
            colour = self.f.create_entity("IfcColourRgb", Name=layer, Red=r, Green=g, Blue=b)
            shading = self.f.create_entity("IfcSurfaceStyleShading", SurfaceColour=colour, Transparency=1.0 - a)
            self._styles[layer] = self.f.create_entity("IfcSurfaceStyle", Name=layer, Side="BOTH", Styles=[shading])
        return self._styles[layer]

    @staticmethod
    def _value_type(key: str, value: Any) -> str:
        """The IFC type of the property ``key``'s value ``value``: a measure by the column, else by Python type."""
        if isinstance(value, int):
            return "IfcInteger"
        if isinstance(value, float):
            if key == "weight_kg":
                return "IfcMassMeasure"
            if key == "area_mm2":
                return "IfcAreaMeasure"
            return "IfcLengthMeasure" if key in LENGTH_KEYS else "IfcReal"
        return "IfcIdentifier" if key in ("part_id", "nest_tag", "type_id", "beam_id") else "IfcLabel"

    def _property(self, key: str, value: Any, value_type: str | None = None) -> Any:
        """The ``IfcPropertySingleValue`` ``key`` = ``value`` (of ``value_type``, by default :meth:`_value_type`;
        area in mm²), one per distinct name, type and value, shared by every property set that holds it: IFC4 lets
        a property belong to any number of sets (``IfcProperty.PartOfPset`` is a set).  Most of the parts'
        properties repeat (kind, material, sheet, quantity, thickness): on the bundled default at 44 × 30 faces
        243,533 properties were 70,400 values."""
        value_type = value_type or self._value_type(key, value)
        k = (key, value_type, type(value).__name__, value)
        got = self._properties.get(k)
        if got is None:
            got = self._properties[k] = self.f.create_entity(
                "IfcPropertySingleValue", Name=key, NominalValue=self.f.create_entity(value_type, value),
                Unit=self.mm2 if key == "area_mm2" else None)
        return got

    # -- elements ------------------------------------------------------------------------------------
    def plan_types(self, els: list[Element]) -> None:
        """Decide which parts share a type and which are drawn as their type's shape
        (:func:`~fabrication.writers._instances.plan_types`: a pane within the panel type tolerance, any other part
        within 1e-5 mm) before the first :meth:`add`."""
        self._plan = plan_types(els, pane_tolerance=self.pane_tolerance)

    def add(self, el: Element, material: str, category: str | None) -> Any:
        """One element: placement, body (its own solid, or its type's shape moved onto it), style, property
        sets, quantities, material, type and decomposition."""
        fr = el.frame
        parent = self.roof_placement
        if el.kind == "beam" and el.group:
            parent = self._assembly_placement(el)
        placement = self._local(parent, self._placement3d(fr.origin, fr.normal, fr.ex))
        kind_key = self._plan.keys.get(el.part_id)
        group = self._type_of(el, kind_key[1]) if kind_key is not None and self._plan.shared(kind_key) else None
        mapped = self._mapped_body(el, group) if group is not None and mappable(el) else None
        if mapped is not None:
            items, representation, extra = [mapped], "MappedRepresentation", self._fastener_size(el)
        else:
            items, representation, extra = self._own_body(el)
        product = self._product(el, material, category, placement, items, representation, extra,
                                typed=group is not None)
        if group is not None:
            group.members.append(product)
        return product

    def _own_body(self, el: Element) -> tuple[list[Any], str, dict[str, Any]]:
        """The solids of ``el`` in its frame, their IFC representation type and extra product attributes."""
        if el.copies is not None:
            return self._copy_items(el), "SweptSolid", self._fastener_size(el)
        if el.two_faces:
            return [self._brep_item(el)], "Brep", {}
        return [self._prism_item(el)], "SweptSolid", {}

    def _mapped_body(self, el: Element, group: "_Type") -> Any | None:
        """An ``IfcMappedItem`` of the type's shape placed on ``el`` (the type's first part gives the shape, its
        ``IfcRepresentationMap``); ``None`` when the shape does not fit ``el`` (the plan's motions) — then ``el``
        keeps its own body."""
        f = self.f
        if self._plan.first.get(self._plan.keys[el.part_id]) == el.part_id:
            items, representation, _ = self._own_body(el)
            rep = f.create_entity("IfcShapeRepresentation", ContextOfItems=self.body, RepresentationIdentifier="Body",
                                  RepresentationType=representation, Items=items)
            group.map = f.create_entity("IfcRepresentationMap", MappingOrigin=self.origin, MappedRepresentation=rep)
            rotation, shift = np.eye(3), np.zeros(3)
        elif (moved := self._plan.moved.get(el.part_id)) is not None and group.map is not None:
            group.largest_error = max(group.largest_error, moved.motion.error)
            rotation, shift = moved.motion.rotation, moved.motion.shift
        else:
            group.own += 1
            return None
        target = f.create_entity("IfcCartesianTransformationOperator3D", Axis1=self._dir(_clean(rotation[:, 0])),
                                 Axis2=self._dir(_clean(rotation[:, 1])), LocalOrigin=self._point(_clean(shift)),
                                 Scale=1.0, Axis3=self._dir(_clean(rotation[:, 2])))
        return f.create_entity("IfcMappedItem", MappingSource=group.map, MappingTarget=target)

    def _prism_item(self, el: Element) -> Any:
        """The extruded solid of a flat outline with its bolt holes as circular voids."""
        f = self.f
        pts = [f.create_entity("IfcCartesianPoint", Coordinates=(float(x), float(y))) for x, y in el.outline]
        outer = f.create_entity("IfcPolyline", Points=pts + pts[:1])
        if len(el.holes):                        # bolt holes: circular voids of the profile
            inner = [f.create_entity("IfcCircle", Radius=0.5 * float(d), Position=f.create_entity(
                "IfcAxis2Placement2D", Location=f.create_entity("IfcCartesianPoint", Coordinates=(float(x), float(y)))))
                for x, y, d in np.asarray(el.holes, dtype=float).tolist()]
            profile = f.create_entity("IfcArbitraryProfileDefWithVoids", ProfileType="AREA", OuterCurve=outer,
                                      InnerCurves=inner)
        else:
            profile = f.create_entity("IfcArbitraryClosedProfileDef", ProfileType="AREA", OuterCurve=outer)
        solid = f.create_entity("IfcExtrudedAreaSolid", SweptArea=profile,
                                Position=self._placement3d((0.0, 0.0, el.z0)),
                                ExtrudedDirection=self._dir((0.0, 0.0, 1.0)), Depth=el.height)
        f.create_entity("IfcStyledItem", Item=solid, Styles=[self._style(el.layer)])
        return solid

    def _brep_item(self, el: Element) -> Any:
        """A part whose two faces differ (a plate bevelled under its strips) as an ``IfcFacetedBrep`` in its frame:
        the bottom and top faces with the bolt holes as inner bounds (polygons of the hole's area,
        :meth:`Element.hole_rings`), a planar side face per outline edge and per hole edge — the faces of
        :meth:`Element.prism_mesh` before triangulation."""
        f = self.f
        bottom = [np.asarray(el.outline, dtype=float)] + el.hole_rings()
        top = [el.top_outline()] + bottom[1:]
        z0, z1 = float(el.z0), float(el.z0 + el.height)

        def points(ring: np.ndarray, z: float) -> list:
            return [f.create_entity("IfcCartesianPoint", Coordinates=(float(x), float(y), z)) for x, y in ring]

        lo = [points(r, z0) for r in bottom]
        hi = [points(r, z1) for r in top]

        def face(outer: list, inner: list[list] = ()) -> Any:      # type: ignore[assignment]
            bounds = [f.create_entity("IfcFaceOuterBound", Bound=f.create_entity("IfcPolyLoop", Polygon=outer),
                                      Orientation=True)]
            bounds += [f.create_entity("IfcFaceBound", Bound=f.create_entity("IfcPolyLoop", Polygon=ring),
                                       Orientation=True) for ring in inner]
            return f.create_entity("IfcFace", Bounds=bounds)

        # the outline is counter-clockwise about +z, the hole rings clockwise: the bottom face (normal −z) runs
        # every ring backwards, the top face forwards; a side face runs p_k, p_k+1 on top back to the bottom
        faces = [face(lo[0][::-1], [r[::-1] for r in lo[1:]]), face(hi[0], hi[1:])]
        for a, b in zip(lo, hi):
            m = len(a)
            faces += [face([a[k], a[(k + 1) % m], b[(k + 1) % m], b[k]]) for k in range(m)]
        brep = f.create_entity("IfcFacetedBrep", Outer=f.create_entity("IfcClosedShell", CfsFaces=faces))
        f.create_entity("IfcStyledItem", Item=brep, Styles=[self._style(el.layer)])
        return brep

    def _copy_items(self, el: Element) -> list[Any]:
        """An element of many equal round prisms (the screws of a plate): one shared ``IfcCircleProfileDef``
        and an ``IfcExtrudedAreaSolid`` per copy at its offset, all in the one product's representation."""
        f = self.f
        radius = round(float(np.linalg.norm(np.asarray(el.outline, dtype=float), axis=1).max()), 6)
        key = f"circle/{radius!r}"
        if key not in self._profiles:
            self._profiles[key] = f.create_entity("IfcCircleProfileDef", ProfileType="AREA", Radius=radius)
        solids = []
        for x, y in np.asarray(el.copies, dtype=float).tolist():
            solid = f.create_entity("IfcExtrudedAreaSolid", SweptArea=self._profiles[key],
                                    Position=self._placement3d((float(x), float(y), el.z0)),
                                    ExtrudedDirection=self._dir((0.0, 0.0, 1.0)), Depth=el.height)
            f.create_entity("IfcStyledItem", Item=solid, Styles=[self._style(el.layer)])
            solids.append(solid)
        return solids

    @staticmethod
    def _fastener_size(el: Element) -> dict[str, Any]:
        """``NominalDiameter`` and ``NominalLength`` of a mechanical fastener (the screws of a plate)."""
        if el.copies is None or IFC_CLASSES.get(el.kind, ("",))[0] != "IfcMechanicalFastener":
            return {}
        radius = round(float(np.linalg.norm(np.asarray(el.outline, dtype=float), axis=1).max()), 6)
        return {"NominalDiameter": 2.0 * radius, "NominalLength": float(el.height)}

    def _product(self, el: Element, material: str, category: str | None, placement, solids: list,
                 representation: str = "SweptSolid", attributes: dict[str, Any] | None = None,
                 typed: bool = False) -> Any:
        """The product of ``el`` with its body ``solids`` (of the IFC representation type ``representation``),
        extra product ``attributes``, property sets, quantities, material and place; a ``typed`` part's common
        property set is its type's (written once on the type, :meth:`write`), others carry their own."""
        f = self.f
        extra = dict(attributes or {})
        shape = f.create_entity("IfcShapeRepresentation", ContextOfItems=self.body, RepresentationIdentifier="Body",
                                RepresentationType=representation, Items=solids)
        cls, predefined = IFC_CLASSES.get(el.kind, ("IfcMember", "USERDEFINED"))
        if predefined == "USERDEFINED":
            extra["ObjectType"] = el.kind
        product = f.create_entity(cls, GlobalId=self.guid(el.part_id), Name=el.part_id,
                                  Description=str(el.props.get("type_id", "")) or None, ObjectPlacement=placement,
                                  Representation=f.create_entity("IfcProductDefinitionShape", Representations=[shape]),
                                  Tag=el.part_id, PredefinedType=predefined, **extra)
        props = [self._property(key, value) for key, value in el.props.items()]
        pset = f.create_entity("IfcPropertySet", GlobalId=self.guid(f"{el.part_id}/pset"), Name=IFC_PSET,
                               HasProperties=props)
        f.create_entity("IfcRelDefinesByProperties", GlobalId=self.guid(f"{el.part_id}/pset/rel"),
                        RelatedObjects=[product], RelatingPropertyDefinition=pset)
        self._quantities(el, product)
        self._associate(material, category, el, product)
        if not typed:
            common = self._common_pset(el.kind, str(el.props.get("type_id", "") or el.part_id), f"{el.part_id}/common")
            f.create_entity("IfcRelDefinesByProperties", GlobalId=self.guid(f"{el.part_id}/common/rel"),
                            RelatedObjects=[product], RelatingPropertyDefinition=common)
        self._classify(el.kind, product)
        if el.kind == "beam" and el.group:
            self._assemblies[el.group][1].append(product)
        else:
            self._roof_parts.append(product)
        return product

    def material(self, name: str, category: str | None) -> Any:
        """The one ``IfcMaterial`` of this name (shared by every element made of it)."""
        if name not in self._materials:
            self._materials[name] = self.f.create_entity("IfcMaterial", Name=name, Category=category)
        return self._materials[name]

    def _associate(self, material: str, category: str | None, el: Element, product) -> None:
        """Associate ``product`` with its material: a pane with the layer set of its make-up (one layer per ply,
        outside first, along the pane's local z from its underside), every other part with its ``IfcMaterial``."""
        f = self.f
        key = material if el.kind != "panel" else f"{material}@{el.z0!r}"
        if key not in self._associations:
            if el.kind == "panel":
                relating: Any = f.create_entity("IfcMaterialLayerSetUsage", ForLayerSet=self._layer_set(material),
                                                LayerSetDirection="AXIS3", DirectionSense="POSITIVE",
                                                OffsetFromReferenceLine=float(el.z0))
            else:
                relating = self.material(material, category)
            self._associations[key] = (relating, [])
        self._associations[key][1].append(product)

    def _layer_set(self, makeup: str) -> Any:
        """The ``IfcMaterialLayerSet`` of a glass make-up (:mod:`fabrication.panels.makeup`); a make-up ppfab
        cannot parse (an old build's words) is one layer of the pane's material."""
        from ppfab.errors import DesignError

        from ..panels.makeup import GLASS_KINDS, parse_makeup

        if f"layers/{makeup}" in self._materials:
            return self._materials[f"layers/{makeup}"]
        try:
            plies = [(p.text(), GLASS_KINDS.get(p.kind, f"{p.kind} interlayer"), p.thickness_mm,
                      "glass" if p.is_glass else "interlayer") for p in parse_makeup(makeup).plies]
        except DesignError:
            plies = [(makeup, makeup, 0.0, "glass")]
        layers = [self.f.create_entity("IfcMaterialLayer", Material=self.material(name, category),
                                       LayerThickness=float(t), Name=text, Category=category)
                  for text, name, t, category in plies]
        out = self._materials[f"layers/{makeup}"] = self.f.create_entity(
            "IfcMaterialLayerSet", MaterialLayers=layers, LayerSetName=makeup)
        return out

    def _common_pset(self, kind: str, reference: str, key: str) -> Any:
        """``Pset_PlateCommon`` (panes) or the common set of the kind's class (``Pset_MemberCommon`` of plates,
        strips, cover plates; ``Pset_DiscreteAccessoryCommon``, ``Pset_MechanicalFastenerCommon``, … of the
        retention parts) with the standard properties BIM tools read: Reference (the type's name, else the part
        id), IsExternal, LoadBearing.  ``key`` names its GlobalId."""
        f = self.f
        cls = IFC_CLASSES.get(kind, ("IfcMember", ""))[0]
        name = "Pset_PlateCommon" if kind == "panel" else f"Pset_{cls[3:]}Common"
        props = [self._property("Reference", reference, "IfcIdentifier"),
                 self._property("IsExternal", True, "IfcBoolean"),
                 self._property("LoadBearing", kind != "panel", "IfcBoolean")]
        return f.create_entity("IfcPropertySet", GlobalId=self.guid(key), Name=name, HasProperties=props)

    def _classify(self, kind: str, obj: Any) -> None:
        """Note ``obj`` (a part or a type) for the classification reference of its kind, if the design gives one
        (``[output.classification]``)."""
        code = self.classification.get(kind)
        if not code:
            return
        if kind not in self._references:
            system = self._classification_system()
            ident, _, title = code.partition(" ")
            ref = self.f.create_entity("IfcClassificationReference", Identification=ident, Name=title or None,
                                       ReferencedSource=system)
            self._references[kind] = (ref, [])
        self._references[kind][1].append(obj)

    def _classification_system(self) -> Any:
        if "system" not in self._references:
            c = self.classification
            system = self.f.create_entity("IfcClassification", Name=c["system"], Edition=c.get("edition") or None,
                                          Source=c.get("source") or None)
            self._references["system"] = (system, [])
        return self._references["system"][0]

    def type_summary(self) -> tuple[int, float]:
        """How many typed parts keep a body of their own, and the largest distance (mm) of a mapped pane's shape
        from its own outline — for the writer's line."""
        own = sum(t.own for t in self._types.values())
        panes = max((t.largest_error for (kind, _), t in self._types.items() if kind == "panel"), default=0.0)
        return own, panes

    def _close_classification(self) -> None:
        """The project declares the classification system; each kind's reference classifies its parts and types."""
        if "system" not in self._references:
            return
        f = self.f
        system = self._references["system"][0]
        f.create_entity("IfcRelAssociatesClassification", GlobalId=self.guid("classification"),
                        RelatedObjects=[self.project], RelatingClassification=system)
        for kind, (ref, objects) in self._references.items():
            if kind != "system":
                f.create_entity("IfcRelAssociatesClassification", GlobalId=self.guid(f"classification/{kind}"),
                                RelatedObjects=objects, RelatingClassification=ref)

    def _type_of(self, el: Element, key: str) -> "_Type":
        """The type ``key`` of ``el``'s kind (one ``IfcPlateType``, ``IfcMemberType``, … made by :meth:`write`)."""
        cls, predefined = IFC_CLASSES.get(el.kind, ("IfcMember", "USERDEFINED"))
        return self._types.setdefault((el.kind, key), _Type(f"{cls}Type", predefined, el.kind))

    def _quantities(self, el: Element, product) -> None:
        f = self.f
        area = float(el.props.get("area_mm2", 0.0))
        if len(el.holes):                        # the net area: less the bolt holes
            d = np.asarray(el.holes, dtype=float)[:, 2]
            area -= float(np.pi / 4.0 * (d * d).sum())
        weight = el.props.get("weight_kg")
        if el.copies is not None:                # the screws of a plate: their circles' area, every copy
            r = float(np.linalg.norm(np.asarray(el.outline, dtype=float), axis=1).max())
            area = len(el.copies) * np.pi * r * r
        q = [f.create_entity("IfcQuantityArea", Name="NetArea", AreaValue=area * 1e-6),
             f.create_entity("IfcQuantityVolume", Name="NetVolume",      # two faces: their mean area (net)
                             VolumeValue=(el.net_area if el.two_faces else area) * el.height * 1e-9)]
        if isinstance(weight, float):
            q.append(f.create_entity("IfcQuantityWeight", Name="NetWeight", WeightValue=weight))
        if el.kind == "panel":
            name = "Qto_PlateBaseQuantities"
            q.insert(0, f.create_entity("IfcQuantityLength", Name="Width", LengthValue=el.height))
        else:
            name = "Qto_MemberBaseQuantities"
            length = el.props.get("length_mm")
            if isinstance(length, float):
                q.insert(0, f.create_entity("IfcQuantityLength", Name="Length", LengthValue=length))
        qto = f.create_entity("IfcElementQuantity", GlobalId=self.guid(f"{el.part_id}/qto"), Name=name, Quantities=q)
        f.create_entity("IfcRelDefinesByProperties", GlobalId=self.guid(f"{el.part_id}/qto/rel"),
                        RelatedObjects=[product], RelatingPropertyDefinition=qto)

    def _assembly_placement(self, el: Element) -> Any:
        """The placement of the beam assembly ``el`` belongs to (made with the assembly on its first plate)."""
        if el.group not in self._assemblies:
            placement = self._assembly_placements[el.group] = self._local(self.roof_placement)
            a = self.f.create_entity("IfcElementAssembly", GlobalId=self.guid(f"beam/{el.group}"), Name=el.group,
                                     Description=el.layer, ObjectPlacement=placement,
                                     Tag=el.group, AssemblyPlace="FACTORY", PredefinedType="GIRDER")
            self._assemblies[el.group] = (a, [])
            self._roof_parts.append(a)
        return self._assembly_placements[el.group]

    def count(self, cls: str) -> int:
        """How many entities of ``cls`` or a subclass of it the file has."""
        f = self.f
        return f.count(cls) if isinstance(f, IfcText) else len(f.by_type(cls))

    def write(self, path: Path) -> Path:
        """Close the decompositions and material associations, then write the file."""
        f = self.f
        self._aggregate("roof", self.roof, self._roof_parts)
        for beam, (assembly, members) in self._assemblies.items():
            self._aggregate(f"beam/{beam}", assembly, members)
        for name, (material, products) in self._associations.items():
            f.create_entity("IfcRelAssociatesMaterial", GlobalId=self.guid(f"material/{name}"),
                            RelatedObjects=products, RelatingMaterial=material)
        for (kind, name), group in self._types.items():
            extra = {"ElementType": kind} if group.predefined == "USERDEFINED" else {}
            t = f.create_entity(group.cls, GlobalId=self.guid(f"type/{kind}/{name}"), Name=name,
                                PredefinedType=group.predefined,
                                RepresentationMaps=[group.map] if group.map is not None else None,
                                HasPropertySets=[self._common_pset(kind, name, f"type/{kind}/{name}/common")], **extra)
            f.create_entity("IfcRelDefinesByType", GlobalId=self.guid(f"type/{kind}/{name}/rel"),
                            RelatedObjects=group.members, RelatingType=t)
            self._classify(kind, t)
        self._close_classification()
        f.write(str(path))
        return path


def material_category(name: str) -> str | None:
    """The IFC material category a material name suggests (``steel``, ``aluminium``, ``wood``), else ``None``.

    >>> material_category("S355 steel plate"), material_category("glulam GL24h")
    ('steel', 'wood')
    """
    low = name.lower()
    for category, words in (("steel", ("steel", "s235", "s275", "s355", "s460")), ("aluminium", ("alumin",)),
                            ("wood", ("timber", "wood", "glulam", "lvl", "clt"))):
        if any(w in low for w in words):
            return category
    return None


def ifc_model(build: "BuildRecord", files: Files, file: Callable[..., Any] = IfcText) -> IfcModel:
    """The IFC model of a build (panels, then beams grouped by beam id, then glazing strips and splice cover
    plates with the materials of their ``parts.csv`` rows), in a ``file`` of :class:`IfcModel`'s kind."""
    design = build.design
    model = IfcModel(design.info.name, design.info.description, file)
    model.pane_tolerance = float(design.panels.type_tol)
    model.classification = dict(design.output.classification)
    els = elements(build)
    model.plan_types(els)
    for el in els:
        try:
            if el.kind == "panel":
                model.add(el, design.panels.makeup, "glass")
            else:
                material = part_material(el, design.beams.material)
                model.add(el, material, material_category(material))
        except Exception as exc:            # a degenerate outline: name the part and what is wrong with it
            from ._failures import part_failure

            raise part_failure(el.part_id, el.outline, el.height, "its IFC solid", exc) from None
    return model


@writer("ifc", order=60, declare=lambda build: {"ifc": IFC_FILE}, enabled=lambda design: design.output.ifc)
def write_ifc(build: "BuildRecord", out: Path, files: Files) -> str:
    from .ifc_analysis import add_analysis_model

    model = ifc_model(build, files)
    add_analysis_model(model, build)
    model.write(out / IFC_FILE)
    plates = model.count("IfcPlate")
    members = model.count("IfcMember")
    analysis = model.count("IfcStructuralCurveMember")
    types = model.count("IfcElementType")
    mapped = model.count("IfcMappedItem")
    own, panes = model.type_summary()
    return (f"{IFC_FILE}: {plates} IfcPlate, {members} IfcMember, {types} types ({mapped} parts drawn as their "
            f"type's shape, {own} typed parts with a body of their own, a pane within {panes:.2g} mm of its face), "
            f"analysis model of {analysis} members")
