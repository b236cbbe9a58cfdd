"""``model.3dm``: the structure for Rhino — layers per family, objects named by part id, user text, node axes, mesh.

Layers (:data:`fabrication.contract.RHINO_LAYERS`, colours :data:`~fabrication.contract.COLOURS`)::

    glass          one closed extrusion per pane (its inset outline parallel to the face, on its gaskets)
    beams::rows    one closed extrusion per beam plate of the row family (centred on its support plane); a plate
                   bevelled under its strips (two different faces) one closed mesh of its faces
    beams::cols    … of the column family
    retention::<kind>  one closed extrusion per setting block, stop, pressure gasket, pressure plate, cover cap;
                   one closed mesh per plate's screws (a prism per screw)
    nodes          one line per node: from the node along its unit axis by the beam depth
    mesh           the quad mesh

Repeated shapes are blocks: parts whose bodies are one shape moved (:func:`fabrication.writers._instances.plan_types`,
within 1e-5 mm: strips of one length, retention parts of one size, congruent panes and plates) are instances of
one block named by the type (``setting_block 100 x 12 x 6``, ``panel T001``), whose one member is the first such
part's body where that part is; each instance is placed by a rigid motion and carries the part's name, layer,
user text and material, so a part is still one selectable object.  The block members are instance-definition
objects on the part's layer.

Every object is named by its part id (node id for an axis, ``mesh`` for the mesh) and carries user text: the
``parts.csv`` values of :data:`~fabrication.contract.EXCHANGE_PROPERTIES` (nest tag, type, sheet, weight,
material, …) or, on an axis, the node's vertex, beams, joint and torsion.  Units are millimetres; the file is
written as Rhino 7 (read by Rhino 7 and later).

Reproducible: object, layer and block ids are name-based UUIDs of the design's name and the part id (or the
block's name; :meth:`RhinoModel.add_block`), the archive is
encoded in memory (no file path inside), and the two time stamps of the revision history, which openNURBS sets
to the wall clock on writing, are replaced by :data:`~fabrication.contract.FIXED_TIMESTAMP` with the chunk's
CRC recomputed (:func:`fix_revision_times`).  rhino3dm is imported inside the functions.
"""

from __future__ import annotations

import base64
import struct
import uuid
import zlib
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ppfab import __version__

from ..contract import COLOURS, RHINO_FILE, RHINO_LAYERS
from . import Files, writer
from ._elements import Element, elements, node_axes, object_uuid, part_material
from ._instances import plan_types

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord

RHINO_VERSION = 7
"""The 3dm archive version written."""

TCODE_REVISION_HISTORY = 0x20008021
"""openNURBS chunk of the revision history (created / last edited by, and when)."""

FIXED_TM = (0, 0, 0, 1, 0, 100, 6, 0)
"""``struct tm`` of 2000-01-01 00:00:00 (sec, min, hour, mday, mon, year − 1900, wday, yday)."""


def fix_revision_times(data: bytes) -> bytes:
    """The 3dm archive ``data`` with both revision-history times set to :data:`FIXED_TM` and the chunk's CRC-32
    recomputed (openNURBS: chunk = typecode (4) + length (8) + data, the last 4 bytes of data its CRC-32).

    Layout of the chunk data: a version byte, the "created by" string (uint32 count of UTF-16 units including
    the terminator, then the units), the creation time (8 int32), the "last edited by" string, the last-edit
    time (8 int32), the revision count (int32), the CRC.
    """
    code = struct.pack("<I", TCODE_REVISION_HISTORY)
    at = data.find(code)
    if at < 0:
        raise ValueError("no revision history chunk in the 3dm archive")
    (length,) = struct.unpack_from("<q", data, at + 4)
    start = at + 12
    chunk = bytearray(data[start:start + length])
    pos = 1
    tm = struct.pack("<8i", *FIXED_TM)
    for _ in range(2):
        (count,) = struct.unpack_from("<I", chunk, pos)
        pos += 4 + 2 * count
        chunk[pos:pos + 32] = tm
        pos += 32
    if pos + 8 != len(chunk):
        raise ValueError(f"unexpected revision history chunk ({len(chunk)} bytes)")
    chunk[-4:] = struct.pack("<I", zlib.crc32(bytes(chunk[:-4])))
    return data[:start] + bytes(chunk) + data[start + length:]


def _colour(layer: str) -> tuple[int, int, int, int]:
    r, g, b, a = COLOURS[layer]
    return (round(255 * r), round(255 * g), round(255 * b), 255)


class RhinoModel:
    """Builder of ``model.3dm``: layers first, then :meth:`add` parts, :meth:`add_axis`, :meth:`add_mesh`."""

    def __init__(self, name: str):
        import rhino3dm

        r: Any = rhino3dm                       # its stubs mark writable properties read-only
        self.r = r
        self.name = name
        f: Any = r.File3dm()
        self.f = f
        f.Settings.ModelUnitSystem = r.UnitSystem.Millimeters
        f.ApplicationName = "ppfab"
        f.ApplicationDetails = f"ppfab {__version__}: {name}"
        self.layers: dict[str, int] = {}
        self.materials: dict[str, int] = {}
        self._scratch: Any = None                # where block definitions are made (add_block)
        for path in RHINO_LAYERS:
            layer = r.Layer()
            parent, _, leaf = path.rpartition("::")
            layer.Name = leaf
            layer.Id = object_uuid(name, f"layer/{path}")
            if parent:
                layer.ParentLayerId = object_uuid(name, f"layer/{parent}")
            key = leaf if leaf in COLOURS else "mesh"
            layer.Color = _colour(key)
            self.layers[path] = f.Layers.Add(layer)

    def material(self, name: str, layer: str) -> int:
        """The index of the render material ``name`` in the colour of ``layer`` (glass transparent); a beam
        material gets one per family (``S355 steel plate (rows)``)."""
        label = name if layer == "glass" else f"{name} ({layer})"
        if label not in self.materials:
            m = self.r.Material()
            m.Id = object_uuid(self.name, f"material/{label}")
            m.Name = label
            m.DiffuseColor = _colour(layer)
            m.Transparency = 1.0 - COLOURS[layer][3]
            self.materials[label] = len(self.f.Materials)     # (Add returns no index in rhino3dm 8.0)
            self.f.Materials.Add(m)
        return self.materials[label]

    def _attributes(self, name: str, layer: str, props: dict[str, Any], key: str) -> Any:
        a = self.r.ObjectAttributes()
        a.Name = name
        a.LayerIndex = self.layers[layer]
        a.Id = object_uuid(self.name, key)
        for k, v in props.items():
            a.SetUserString(k, str(v))
        return a

    def add(self, el: Element, material: str) -> None:
        """One part as its own object: :meth:`solid`, named by its part id, on its layer, with its user text."""
        self.f.Objects.Add(self.solid(el), self._part_attributes(el, material))

    def solid(self, el: Element) -> Any:
        """A part's body: a closed extrusion of its outline along its frame normal from ``z0`` by its height
        (``Extrusion.Create`` of the counter-clockwise outline; the check of ``ppfab verify`` confirms the side),
        its bolt holes as inner profiles (circles, in the extrusion's profile plane) — or a closed mesh
        (:meth:`_mesh_solid`) for a part of many prisms or a plate bevelled under its strips."""
        r = self.r
        if el.copies is not None or el.two_faces:      # many prisms, or a plate bevelled under its strips
            return self._mesh_solid(el)
        base = el.base()
        ring = r.Point3dList()                   # (a list of Point3d is not accepted by rhino3dm 8.0)
        for p in list(base) + [base[0]]:
            ring.Add(*map(float, p))
        # the outline is counter-clockwise about the frame normal: Create extrudes it along that normal
        ext = r.Extrusion.Create(r.PolylineCurve(ring), float(el.height), True)
        if ext is None:
            from ppfab.errors import FabricationError

            from ._failures import outline_problem

            raise FabricationError(f"{el.part_id}: Rhino cannot make a solid of its outline "
                                   f"({outline_problem(el.outline, el.height)})")
        if len(el.holes):
            plane = ext.GetProfilePlane(0.0)
            origin = np.array([plane.Origin.X, plane.Origin.Y, plane.Origin.Z])
            axes = np.array([[plane.XAxis.X, plane.XAxis.Y, plane.XAxis.Z],
                             [plane.YAxis.X, plane.YAxis.Y, plane.YAxis.Z]])
            for x, y, d in np.asarray(el.holes, dtype=float).tolist():
                u, v = axes @ (el.frame.to3d(np.array([[x, y]]))[0] + el.z0 * el.frame.normal - origin)
                ext.AddInnerProfile(r.ArcCurve.CreateFromCircle(r.Circle(r.Point3d(float(u), float(v), 0.0), 0.5 * d)))
        return ext

    def _part_attributes(self, el: Element, material: str) -> Any:
        """Name, layer (``glass``, ``beams::<family>``, ``retention::<kind>``), user text and material of a part."""
        attrs = self._attributes(el.part_id, self._layer(el), el.props, el.part_id)
        self._set_material(attrs, el, material)
        return attrs

    @staticmethod
    def _layer(el: Element) -> str:
        if el.kind == "panel":
            return "glass"
        if el.layer == "retention":
            return f"retention::{el.kind}"
        return f"beams::{el.layer}"

    def _set_material(self, attrs: Any, el: Element, material: str) -> None:
        attrs.MaterialIndex = self.material(material, "glass" if el.kind == "panel" else el.layer)
        attrs.MaterialSource = self.r.ObjectMaterialSource.MaterialFromObject

    def _mesh_solid(self, el: Element) -> Any:
        """A part of many prisms (the screws of a plate) as one closed mesh of them all (light: an extrusion per
        screw would be an object per screw), or a plate whose two faces differ (bevelled under its strips: no
        extrusion) as the closed mesh of :meth:`Element.prism_mesh`, bolt holes as polygons of their area."""
        from ppfab.errors import FabricationError

        from ._failures import outline_problem

        try:
            v, faces = el.prism_mesh()
        except (FabricationError, ValueError) as exc:
            problem = outline_problem(el.outline, el.height)
            if problem.startswith("no defect"):
                problem = f"{exc}"
            raise FabricationError(f"{el.part_id}: Rhino cannot make a solid of its outline ({problem})") from None
        mesh = self.r.Mesh()
        mesh.Vertices.UseDoublePrecisionVertices = True
        for x, y, z in v.tolist():
            mesh.Vertices.Add(x, y, z)
        for a, b, c in faces.tolist():
            mesh.Faces.AddFace(int(a), int(b), int(c))
        mesh.Normals.ComputeNormals()
        return mesh

    def add_block(self, key: str, shape: Element, material: str) -> uuid.UUID:
        """The block (instance definition) named ``key`` whose one member is ``shape``'s body where ``shape`` is
        (base point the world origin, so the shape's own instance is the identity); its id.

        openNURBS gives a new definition and its member object random ids; they are made name-based like every
        other id of the file (:func:`object_uuid` of ``block/<key>`` and ``block/<key>/body``) by writing the
        definition into an archive of its own (``InstanceDefinition.Encode``), where each id occurs once as its
        16 bytes, replacing them there and reading it back (``Decode``).  The member is added to the object table
        under the new id as an instance-definition object on the part's layer."""
        r = self.r
        geometry = self.solid(shape)
        if self._scratch is None:              # one archive for every definition (a new one costs 0.4 ms)
            self._scratch = r.File3dm()
        index = self._scratch.InstanceDefinitions.Add(key, "", "", "", r.Point3d(0.0, 0.0, 0.0), (geometry,),
                                                      (r.ObjectAttributes(),))
        made = self._scratch.InstanceDefinitions[index]
        old_def, (old_body,) = made.Id, made.GetObjectIds()
        def_id = object_uuid(self.name, f"block/{key}")
        body_id = object_uuid(self.name, f"block/{key}/body")
        archive = made.Encode()
        data = base64.b64decode(archive["data"])
        if data.count(old_def.bytes_le) != 1 or data.count(old_body.bytes_le) != 1:
            raise RuntimeError(f"block {key!r}: its ids do not occur once each in the encoded definition")
        data = data.replace(old_def.bytes_le, def_id.bytes_le).replace(old_body.bytes_le, body_id.bytes_le)
        archive["data"] = base64.b64encode(data).decode("ascii")
        definition = r.InstanceDefinition.Decode(archive)
        attrs = r.ObjectAttributes()
        attrs.Id = body_id
        attrs.LayerIndex = self.layers[self._layer(shape)]
        attrs.Mode = r.ObjectMode.InstanceDefinitionObject
        self._set_material(attrs, shape, material)
        self.f.Objects.Add(geometry, attrs)
        self.f.InstanceDefinitions.AddInstanceDefinition(definition)
        return def_id

    def add_instance(self, el: Element, block: uuid.UUID, placement: np.ndarray, material: str) -> None:
        """Part ``el`` as an instance of ``block`` placed by ``placement (4, 4)`` (world mm → world mm), named by
        its part id, on its layer, with its user text and material."""
        xform = self.r.Transform(1.0)
        for i in range(4):
            for j in range(4):
                setattr(xform, f"M{i}{j}", float(placement[i, j]))
        self.f.Objects.AddInstanceObject(self.r.InstanceReference(block, xform), self._part_attributes(el, material))

    def add_axis(self, node_id: str, start, end, props: dict[str, Any]) -> None:
        r = self.r
        line = r.LineCurve(r.Point3d(*map(float, start)), r.Point3d(*map(float, end)))
        self.f.Objects.AddCurve(line, self._attributes(node_id, "nodes", props, f"node/{node_id}"))

    def add_mesh(self, vertices, faces) -> None:
        r = self.r
        mesh = r.Mesh()
        mesh.Vertices.UseDoublePrecisionVertices = True
        for p in vertices:
            mesh.Vertices.Add(*map(float, p))
        for face in faces:
            mesh.Faces.AddFace(*map(int, face))
        mesh.Normals.ComputeNormals()
        self.f.Objects.AddMesh(mesh, self._attributes("mesh", "mesh", {"design": self.name}, "mesh"))

    def to_bytes(self) -> bytes:
        """The archive (Rhino 7), with fixed revision times."""
        options = self.r.File3dmWriteOptions()
        options.Version = RHINO_VERSION
        return fix_revision_times(base64.b64decode(self.f.Encode(options)))


def block_name(kind: str, key: str) -> str:
    """The name of the block of a repeated shape of type ``key`` (:func:`~fabrication.writers._instances.type_key`)
    of parts of ``kind``: the key, led by the kind where the key does not name it (``panel P-0040``,
    ``strip 1234.5 x 60 x 8``)."""
    return key if key.startswith(kind) else f"{kind} {key}"


def rhino_model(build: "BuildRecord", files: Files) -> RhinoModel:
    """The Rhino model of a build: panels, beam plates, node axes, the mesh."""
    design = build.design
    model = RhinoModel(design.info.name)
    els = elements(build)
    plan = plan_types(els)
    shapes = {inst.shape.part_id for inst in plan.moved.values()}     # first parts of repeated shapes
    blocks: dict[str, uuid.UUID] = {}             # part id of such a shape → its block
    for el in els:
        material = design.panels.makeup if el.kind == "panel" else part_material(el, design.beams.material)
        moved = plan.moved.get(el.part_id)
        if el.part_id in shapes:                  # the block, and its first part placed as it is
            blocks[el.part_id] = model.add_block(block_name(*plan.keys[el.part_id]), el, material)
            model.add_instance(el, blocks[el.part_id], np.eye(4), material)
        elif moved is not None:
            model.add_instance(el, blocks[moved.shape.part_id], moved.placement(el), material)
        else:
            model.add(el, material)
    for axis in node_axes(build):
        model.add_axis(axis.node_id, axis.start, axis.end, axis.props)
    mesh = build.mesh
    qm = mesh.to_quadmesh() if hasattr(mesh, "to_quadmesh") else mesh
    model.add_mesh(qm.vertices, qm.faces)
    return model


@writer("rhino", order=65, declare=lambda build: {"rhino": RHINO_FILE}, enabled=lambda design: design.output.rhino)
def write_rhino(build: "BuildRecord", out: Path, files: Files) -> str:
    model = rhino_model(build, files)
    (out / RHINO_FILE).write_bytes(model.to_bytes())
    return f"{RHINO_FILE}: {len(model.f.Objects)} objects"

