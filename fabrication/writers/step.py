"""``beams.step`` and ``panels.step``; the beam plates as build123d solids for tests and the re-import check.

Each plate is its 2D outline (slots and end cuts already drawn in, see :mod:`fabrication.beams.joints`) at
``z = −t/2`` in the plate's own frame, extruded once by ``t`` and placed by the frame — no boolean cuts, and the
polygon is exactly planar; a plate whose top edge is bevelled under its strips is the solid between its two face
outlines (:mod:`fabrication.beams.bevel_cut`); the bolt holes of its splices are round through holes.  The files
are assemblies; a reader sees the product tree (names survive every level)

    beams.step                                panels.step
    <design name>                             <design name>
      rows | cols          one per family       glass
        B-U03              one per beam           P-U07 …       one per row of faces
          B-U03-S00 …      one solid per plate      P-U07-V12 … one solid per pane, on its gaskets

with every solid coloured by its family (:data:`fabrication.contract.COLOURS`) and a header naming ppfab, its
version and the design (:mod:`fabrication.writers._step_text`).  Both are written as text from
:mod:`fabrication.writers.step_template` (:func:`plate_prism`, :func:`beam_tree`), not through the kernel: solids
of one shape are one product placed once per solid, each occurrence named by its part id.  The kernel-built
solids (:func:`plate_solid`: the polygon faces sewn, the holes cut by boolean subtraction of cylinders) are what
the tests hold the template's to.

build123d is imported inside the functions (≈3.5 s).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Iterable, Sequence

import numpy as np

from ppfab import planes as pl
from ppfab.errors import FabricationError

from ppfab.frame import Frame

from ppfab.topology import FAMILY_NAMES

from ..beams.plates import BeamPlate
from ppfab.metrics import polygon_area
from ..contract import COLOURS, FIXED_TIMESTAMP, STEP_GLASS_GROUP
from ._step_text import canonical_styles, replace_header, step_label
from .step_template import Assembly, PlanarSolid, write_step
from .step_template import grouped as template_grouped

from . import Files, writer

if TYPE_CHECKING:  # pragma: no cover
    from build123d import Shape, Solid

    from ..panels import Panel
    from ..records import BuildRecord


def _is_valid(shape) -> bool:
    v = shape.is_valid
    return bool(v() if callable(v) else v)


def _placed_prism(outline: np.ndarray, frame: Frame, z0: float, height: float, label: str):
    """The prism over ``outline (n, 2)`` (frame coordinates, either turning sense) from ``z = z0`` to
    ``z0 + height`` along the frame's normal, placed by ``frame``: a build123d ``Solid`` labelled ``label``.

    Made with the kernel directly (polygon → planar face → one prism → a location), which gives the same
    vertices and volume as build123d's ``Solid.extrude(Face(wire))`` followed by ``moved`` (checked in
    tests/test_beams_step.py) at a quarter of the cost: build123d's face runs shape healing and ``moved``
    copies the solid, and a glazing.step of an 88 × 60 roof holds 21,416 of these.  The outline is made
    counter-clockwise first, so the face's normal is the extrusion direction (the healing did that before)."""
    from build123d import Solid
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakePolygon
    from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism
    from OCP.gp import gp_Ax3, gp_Dir, gp_Pnt, gp_Trsf, gp_Vec
    from OCP.TopLoc import TopLoc_Location

    q = np.asarray(outline, dtype=float)
    if polygon_area(q) < 0:
        q = q[::-1]
    polygon = BRepBuilderAPI_MakePolygon()
    for px, py in q.tolist():
        polygon.Add(gp_Pnt(px, py, float(z0)))
    polygon.Close()
    face = BRepBuilderAPI_MakeFace(polygon.Wire(), True).Face()          # True: a plane only
    prism = BRepPrimAPI_MakePrism(face, gp_Vec(0.0, 0.0, float(height))).Shape()
    to_frame = gp_Trsf()                                                  # frame coordinates → model space
    to_frame.SetTransformation(gp_Ax3(gp_Pnt(*map(float, frame.origin)), gp_Dir(*map(float, frame.normal)),
                                      gp_Dir(*map(float, frame.ex))), gp_Ax3())
    solid = Solid(prism.Moved(TopLoc_Location(to_frame)))
    solid.label = label
    return solid


def _placed_loft(front: np.ndarray, back: np.ndarray, frame: Frame, t: float, label: str):
    """The solid between ``front`` at ``z = +t/2`` and ``back`` at ``z = −t/2`` (frame coordinates, CCW, vertex
    ``k`` of one joined to vertex ``k`` of the other; :func:`fabrication.beams.bevel_cut.face_outlines`), placed by
    ``frame``: a build123d ``Solid`` labelled ``label``, every face planar — the two faces and one side face per
    edge, which joins two parallel segments — sewn into a closed shell (no boolean)."""
    from build123d import Solid
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakePolygon, BRepBuilderAPI_Sewing
    from OCP.BRepLib import BRepLib
    from OCP.gp import gp_Ax3, gp_Dir, gp_Pnt, gp_Trsf
    from OCP.TopAbs import TopAbs_SHELL
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS, TopoDS_Solid

    h = 0.5 * float(t)
    top = [gp_Pnt(float(x), float(y), h) for x, y in np.asarray(front, dtype=float).tolist()]
    bot = [gp_Pnt(float(x), float(y), -h) for x, y in np.asarray(back, dtype=float).tolist()]

    def face(points: list) -> object:
        poly = BRepBuilderAPI_MakePolygon()
        for p in points:
            poly.Add(p)
        poly.Close()
        return BRepBuilderAPI_MakeFace(poly.Wire(), True).Face()       # True: a plane only

    sew = BRepBuilderAPI_Sewing(1e-6)
    sew.Add(face(top))
    sew.Add(face(bot[::-1]))
    m = len(top)
    for k in range(m):
        j = (k + 1) % m
        quad = [top[k], bot[k], bot[j], top[j]]
        if top[k].Distance(bot[k]) < 1e-9 or top[j].Distance(bot[j]) < 1e-9:  # pragma: no cover - t > 0
            continue
        sew.Add(face(quad))
    sew.Perform()
    explorer = TopExp_Explorer(sew.SewedShape(), TopAbs_SHELL)
    if not explorer.More():
        raise FabricationError(f"{label}: the faces of the bevelled plate do not close into a shell")
    solid = TopoDS_Solid()
    builder = BRep_Builder()
    builder.MakeSolid(solid)
    builder.Add(solid, TopoDS.Shell(explorer.Current()))
    BRepLib.OrientClosedSolid_s(solid)
    to_frame = gp_Trsf()
    to_frame.SetTransformation(gp_Ax3(gp_Pnt(*map(float, frame.origin)), gp_Dir(*map(float, frame.normal)),
                                      gp_Dir(*map(float, frame.ex))), gp_Ax3())
    out = Solid(solid.Moved(TopLoc_Location(to_frame)))
    out.label = label
    return out


def _colour(layer: str):
    from build123d import Color

    return Color(*COLOURS[layer])


def plate_solid(plate: BeamPlate):
    """The solid of one plate: its outline extruded once, thickness centred on the support plane (a plate with
    bevelled top-edge spans: the solid between its two face outlines, :func:`_placed_loft`), less its bolt
    holes (:attr:`~fabrication.beams.plates.BeamPlate.holes`, cylinders cut through it), in the colour of its
    family."""
    t = plate.thickness
    if plate.bevels:
        from ..beams.bevel_cut import face_outlines

        solid = _placed_loft(*face_outlines(plate), plate.frame, t, plate.part_id)
    else:
        solid = _placed_prism(plate.outline, plate.frame, -0.5 * t, t, plate.part_id)
    if len(plate.holes):
        solid = _drilled(solid, plate, t)
    solid.color = _colour(FAMILY_NAMES[plate.family])
    return solid


def _drilled(solid, plate: BeamPlate, t: float):
    """``solid`` with a cylinder of each hole's diameter cut through its thickness (true circles)."""
    from build123d import Solid
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
    from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt

    shape = solid.wrapped
    f = plate.frame
    n = gp_Dir(*map(float, f.normal))
    for x, y, d in plate.holes.tolist():
        p = f.origin + x * f.ex + y * f.ey - (0.5 * t + 1.0) * f.normal
        tool = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(*map(float, p)), n), 0.5 * d, t + 2.0).Shape()
        shape = BRepAlgoAPI_Cut(shape, tool).Shape()
    out = Solid(shape)
    out.label = plate.part_id
    return out


def build_solids(plates: Sequence[BeamPlate], check: bool = True) -> list:
    """One solid per plate, labelled by part id; with ``check`` each must pass the kernel's validity check
    (BRepCheck) and invalid ones raise, all named.

    The build's writer passes ``check=False``: BRepCheck is most of the cost of a plate (about 30 ms for a
    slotted outline of 20 vertices), and the self-check of every build (:mod:`fabrication.verify.step`) runs
    it on every solid re-read from ``beams.step`` before the folder is renamed into place, naming the part.
    """
    solids = [plate_solid(p) for p in plates]
    if not check:
        return solids
    bad = [p.part_id for p, s in zip(plates, solids) if not _is_valid(s)]
    if bad:
        raise FabricationError(f"{len(bad)} beam solid(s) fail the kernel's validity check: {', '.join(bad[:10])}")
    return solids


def plate_prism(plate: BeamPlate) -> PlanarSolid:
    """The solid of :func:`plate_solid` as a :class:`~fabrication.writers.step_template.PlanarSolid` (the same
    faces, holes and colour), for the template writer: the outline extruded through the plate's thickness,
    centred on its support plane, or the solid between its two face outlines where it is bevelled under its
    strips; the bolt holes as round bores."""
    t = plate.thickness
    colour = COLOURS[FAMILY_NAMES[plate.family]]
    holes = np.asarray(plate.holes, dtype=float).reshape(-1, 3)
    if plate.bevels:
        from ..beams.bevel_cut import face_outlines

        front, back = face_outlines(plate)
        return PlanarSolid.loft(plate.part_id, colour, front, back, plate.frame, t, holes)
    return PlanarSolid.prism(plate.part_id, colour, plate.outline, plate.frame, -0.5 * t, t, holes)


def beam_tree(plates: Sequence[BeamPlate], name: str) -> Assembly:
    """The product tree of ``beams.step`` for the template writer: ``name`` → family → beam id → the plate
    solids (:func:`plate_prism`), in plate order (the tree :func:`beam_assembly` builds for the kernel)."""
    families: dict[str, dict[str, list]] = {}
    for plate in plates:
        families.setdefault(FAMILY_NAMES[plate.family], {}).setdefault(plate.beam_id, []).append(plate_prism(plate))
    kids: list = [Assembly(family, [Assembly(step_label(beam), members) for beam, members in beams.items()])
                  for family, beams in families.items()]
    return Assembly(step_label(name), kids)


def grouped(solids: Sequence, keys: Sequence[str]) -> list:
    """One assembly per key, labelled by it (folded to ASCII), holding the solids of that key (``keys[k]`` that
    of ``solids[k]``); keys in first-seen order, solids in their given order.  ppfab's STEP trees are built
    from these so no assembly holds thousands of components: the kernel's STEP reader compares every
    component with its siblings (docs/performance.md)."""
    from build123d import Compound

    groups: dict[str, list] = {}
    for solid, key in zip(solids, keys):
        groups.setdefault(key, []).append(solid)
    return [Compound(children=kids, label=step_label(key)) for key, kids in groups.items()]


def beam_assembly(plates: Sequence[BeamPlate], solids: Sequence, name: str):
    """The product tree of ``beams.step`` as the kernel writes it (the benchmarks' baseline; the build writes
    :func:`beam_tree` from the template): ``name`` → family → beam id → the plate solids, in plate order."""
    from build123d import Compound

    families: dict[str, dict[str, list]] = {}
    for plate, solid in zip(plates, solids):
        families.setdefault(FAMILY_NAMES[plate.family], {}).setdefault(plate.beam_id, []).append(solid)
    kids = []
    for family, beams in families.items():
        group = [Compound(children=members, label=beam) for beam, members in beams.items()]
        for g in group:
            g.color = _colour(family)
        kids.append(Compound(children=group, label=family))
    return Compound(children=kids, label=step_label(name))


def export_step(shapes, path: str | os.PathLike, name: str = "", description: str = "") -> Path:
    """Write an assembly, or a list of solids as one flat assembly named ``name``, to STEP (mm, no p-curves)
    with a reproducible header naming ppfab and ``description``."""
    from build123d import Compound, Unit
    from build123d import export_step as _export

    path = Path(path)
    if isinstance(shapes, (list, tuple)):
        shapes = Compound(children=list(shapes), label=step_label(name) if name else "")
    if not _export(shapes, str(path), unit=Unit.MM, write_pcurves=False):
        raise FabricationError(f"{path}: writing the STEP file failed")
    _make_reproducible(path, description or name)
    return path


STEP_TIMESTAMP = FIXED_TIMESTAMP
"""The time stamp written into the STEP header (FILE_NAME)."""


def _make_reproducible(path: Path, description: str = "") -> None:
    """Make two exports of the same solids byte-identical, with ppfab's header.

    The kernel writes the wall-clock time into the header and numbers assembly occurrences
    (``NEXT_ASSEMBLY_USAGE_OCCURRENCE('43', …)``) with a counter that runs on across exports in one
    process; a fixed time stamp (as ``SOURCE_DATE_EPOCH`` does for other build tools) and occurrence
    ids renumbered 1, 2, … in file order change nothing else.  The colours, which the kernel writes in an
    order that follows memory addresses, are put in a canonical order
    (:func:`~fabrication.writers._step_text.canonical_styles`).  The header's ``FILE_DESCRIPTION`` and
    ``FILE_NAME`` are ppfab's (:func:`~fabrication.writers._step_text.replace_header`).
    """
    import itertools
    import re

    data = path.read_bytes()
    head, sep, rest = data.partition(b"ENDSEC;")
    try:
        head = replace_header(head, path.name, description)
    except ValueError as exc:
        raise FabricationError(f"{path}: {exc}") from None
    counter = itertools.count(1)
    rest = re.sub(rb"(NEXT_ASSEMBLY_USAGE_OCCURRENCE\(')[0-9]+(')",
                  lambda m: m.group(1) + str(next(counter)).encode() + m.group(2), rest)
    # the kernel wraps an entity's line by the width of its own (process-wide) id: unwrap these entities
    rest = re.sub(rb"NEXT_ASSEMBLY_USAGE_OCCURRENCE\([^;]*;", lambda m: re.sub(rb"\r?\n[ ]*", b"", m.group(0)), rest)
    before, data_sep, data = rest.partition(b"DATA;")
    body, end_sep, after = data.partition(b"ENDSEC;")
    try:
        rest = before + data_sep + canonical_styles(body) + end_sep + after
    except ValueError as exc:
        raise FabricationError(f"{path}: {exc}") from None
    path.write_bytes(head + sep + rest)


@dataclass
class StepCheck:
    """What re-importing a STEP file showed (see :func:`check_step`)."""

    path: str
    solids: int
    expected: int
    missing: list[str] = field(default_factory=list)
    unexpected: list[str] = field(default_factory=list)
    invalid: list[str] = field(default_factory=list)
    thickness_error: dict[str, float] = field(default_factory=dict)
    volume_error: dict[str, float] = field(default_factory=dict)
    max_thickness_error: float = 0.0

    @property
    def problems(self) -> list[str]:
        out = []
        if self.solids != self.expected:
            out.append(f"{self.solids} solids, expected {self.expected}")
        if self.missing:
            out.append(f"missing {', '.join(self.missing[:5])}")
        if self.unexpected:
            out.append(f"unexpected names {', '.join(self.unexpected[:5])}")
        if self.invalid:
            out.append(f"invalid solids {', '.join(self.invalid[:5])}")
        for name, err in list(self.thickness_error.items())[:5]:
            out.append(f"{name} leaves its plate by {err:.2e} mm")
        for name, err in list(self.volume_error.items())[:5]:
            out.append(f"{name} volume off by {err:.2e} (relative)")
        return out

    @property
    def ok(self) -> bool:
        return not self.problems


def check_step(path: str | os.PathLike, plates: Sequence[BeamPlate], tol: float = 1e-6,
               planes: dict[str, np.ndarray] | None = None) -> StepCheck:
    """Re-import a beams STEP file and compare it with the plates.

    Checks: one solid per plate, names equal to the part ids, every solid valid,
    every vertex of a solid at distance ``t/2 ± tol`` from its support plane on
    both sides (a plate of the given thickness centred on the plane), and volume
    ``= (outline area − bolt holes) × t`` (relative 1e-6).

    Parameters
    ----------
    planes : part id → (4,) plane to check against (default: each plate's own support plane)
    """
    from build123d import import_step

    pairs = named_solids(import_step(str(path)))
    names = [n for n, _ in pairs]
    solids = [s for _, s in pairs]
    by_name = {p.part_id: p for p in plates}
    res = StepCheck(str(path), len(solids), len(plates))
    res.missing = sorted(set(by_name) - set(names))
    res.unexpected = sorted(set(names) - set(by_name))
    for s, name in zip(solids, names):
        p = by_name.get(name)
        if p is None:
            continue
        if not _is_valid(s):
            res.invalid.append(name)
        plane = pl.normalize(planes[name] if planes is not None else p.plane)
        x = np.array([[v.X, v.Y, v.Z] for v in s.vertices()])
        dist = x @ plane[:3] + plane[3]
        t = p.thickness
        err = float(np.abs(np.abs(dist) - 0.5 * t).max())
        if err > tol or not (np.any(dist > 0) and np.any(dist < 0)):
            res.thickness_error[name] = err
        res.max_thickness_error = max(res.max_thickness_error, err)
        vol_err = abs(s.volume - p.net_area * t) / max(p.net_area * t, 1e-300)
        if vol_err > 1e-6:
            res.volume_error[name] = vol_err
    return res


def named_solids(shape: Shape) -> list[tuple[str, Solid]]:
    """``(label, solid)`` of every solid in an imported shape, walking the assembly children
    (``shape.solids()`` would drop the labels)."""
    from build123d import Solid

    out: list[tuple[str, Solid]] = []
    stack: list[Shape] = [shape]
    while stack:
        node = stack.pop(0)
        if isinstance(node, Solid):
            out.append((node.label, node))
            continue
        kids = list(getattr(node, "children", ()) or ())
        if kids:
            stack[0:0] = kids
        else:
            out.extend((node.label, s) for s in node.solids())
    return out


def solid_vertices(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """Name → ``(k, 3)`` vertices of every solid in a STEP file."""
    from build123d import import_step

    return {name: np.array([[v.X, v.Y, v.Z] for v in s.vertices()])
            for name, s in named_solids(import_step(str(path)))}


# -- glass panels for clash checks ------------------------------------------------------------------------

def panel_solids(corners: np.ndarray, thickness: float, ids: Iterable[str]) -> list:
    """Thin solids of quad panels ``(F, 4, 3)``: each quad projected into its least-squares plane,
    extruded by ``thickness`` to the outside (along the oriented face normal)."""
    c = np.asarray(corners, dtype=float)
    planes, _ = pl.fit_plane(c)
    n = np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1])
    flip = np.einsum("ij,ij->i", planes[:, :3], n) < 0
    planes[flip] *= -1.0
    out = []
    for k, name in enumerate(ids):
        nrm = planes[k, :3]
        proj = c[k] - np.outer(c[k] @ nrm + planes[k, 3], nrm)
        ex = proj[1] - proj[0]
        ex /= np.linalg.norm(ex)
        frame = Frame(proj.mean(axis=0), ex, np.cross(nrm, ex))
        out.append(_placed_prism(frame.to2d(proj), frame, 0.0, thickness, name))
    return out


PANEL_BLOCK = 100
"""Panels per assembly below ``glass`` in ``panels.step`` when the panels carry no row (see :func:`panel_groups`)."""


def panel_groups(ids: Sequence[str]) -> list[str]:
    """The assembly of each panel below ``glass``: its row of a regular patch (``P-U07`` for ``P-U07-V12``), else
    a block of :data:`PANEL_BLOCK` consecutive panels (``P-0100-0199``).  One flat assembly of thousands of
    panels is slow to read back: the kernel's STEP reader compares every component with its siblings."""
    if all(pid.count("-") == 2 for pid in ids):
        return [pid.rsplit("-", 1)[0] for pid in ids]
    out = []
    for k, pid in enumerate(ids):
        lo = k - k % PANEL_BLOCK
        hi = min(lo + PANEL_BLOCK, len(ids)) - 1
        out.append(f"{ids[lo]}-{ids[hi].split('-')[-1]}")
    return out


def placed_pane_solids(panels: Sequence["Panel"], offsets: dict[str, float]) -> list:
    """The panes as placed: each inset outline in its panel frame, from ``z = offsets[part id]`` (its seat on the
    gaskets, :meth:`fabrication.records.BuildRecord.pane_offsets`) to that plus the glass thickness along the outside
    normal; the same prism as the pane of model.ifc, model.3dm and model.glb."""
    return [_placed_prism(p.outline, p.frame, offsets[p.part_id], float(p.thickness_mm), p.part_id) for p in panels]


def _export_glass(solids: list, ids: list[str], path: str | os.PathLike, name: str) -> Path:
    """The assembly ``name`` → ``glass`` → row (:func:`panel_groups`) → one solid per pane, in the glass colour,
    written by the CAD kernel from build123d solids (a tampered copy in the tests; a build writes
    :func:`_write_glass`)."""
    from build123d import Compound

    for s in solids:
        s.color = _colour("glass")
    glass = Compound(children=grouped(solids, panel_groups(ids)), label=STEP_GLASS_GROUP)
    root = Compound(children=[glass], label=step_label(name or "panels"))
    return export_step(root, path, description=f"glass panels of {name}" if name else "glass panels")


def glass_tree(solids: Sequence[PlanarSolid], name: str) -> Assembly:
    """The product tree of ``panels.step``: ``name`` → ``glass`` → row (:func:`panel_groups`) → one solid per
    pane."""
    ids = [s.label for s in solids]
    glass = Assembly(STEP_GLASS_GROUP, list(template_grouped(solids, panel_groups(ids))))
    return Assembly(step_label(name or "panels"), [glass])


def _write_glass(solids: list[PlanarSolid], path: str | os.PathLike, name: str) -> Path:
    """``panels.step`` written from the template (:mod:`fabrication.writers.step_template`): panes of one shape
    are written once and placed per pane."""
    return write_step(glass_tree(solids, name), path,
                      description=f"glass panels of {name}" if name else "glass panels")


def panel_prisms(corners: np.ndarray, thickness: float, ids: Iterable[str]) -> list[PlanarSolid]:
    """The solids of :func:`panel_solids` as :class:`~fabrication.writers.step_template.PlanarSolid` records
    (the same frames, outlines and heights), in the glass colour."""
    c = np.asarray(corners, dtype=float)
    planes, _ = pl.fit_plane(c)
    n = np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1])
    flip = np.einsum("ij,ij->i", planes[:, :3], n) < 0
    planes[flip] *= -1.0
    out = []
    for k, pid in enumerate(ids):
        nrm = planes[k, :3]
        proj = c[k] - np.outer(c[k] @ nrm + planes[k, 3], nrm)
        ex = proj[1] - proj[0]
        ex /= np.linalg.norm(ex)
        frame = Frame(proj.mean(axis=0), ex, np.cross(nrm, ex))
        out.append(PlanarSolid.prism(pid, COLOURS["glass"], frame.to2d(proj), frame, 0.0, thickness))
    return out


def export_panels_step(corners: np.ndarray, path: str | os.PathLike, thickness: float = 10.0,
                       ids: Sequence[str] | None = None, name: str = "") -> Path:
    """A STEP file of whole mesh faces as thin solids on the outside of the mesh (:func:`panel_prisms`), for a
    quick look at a mesh; a build's ``panels.step`` holds the placed panes instead (:func:`export_placed_panes`)."""
    ids = list(ids) if ids is not None else [f"P{k:04d}" for k in range(len(corners))]
    if len(ids) != len(corners):
        raise FabricationError(f"{len(ids)} panel ids for {len(corners)} panels")
    return _write_glass(panel_prisms(corners, thickness, ids), path, name)


def placed_panes(panels: Sequence["Panel"], offsets: dict[str, float]) -> list[PlanarSolid]:
    """The panes of :func:`placed_pane_solids` as :class:`~fabrication.writers.step_template.PlanarSolid`
    records, in the glass colour."""
    return [PlanarSolid.prism(p.part_id, COLOURS["glass"], p.outline, p.frame, offsets[p.part_id],
                              float(p.thickness_mm)) for p in panels]


def export_placed_panes(panels: Sequence["Panel"], offsets: dict[str, float], path: str | os.PathLike,
                        name: str = "") -> Path:
    """``panels.step``: the panes as cut (inset outlines) where they sit on the gaskets (:func:`placed_panes`),
    for clash checks, written from the template."""
    return _write_glass(placed_panes(panels, offsets), path, name)


def step_files(build: "BuildRecord") -> Files:
    """beams.step, and panels.step with ``[output] panels_step``."""
    return {"beams_step": "beams.step", **({"panels_step": "panels.step"} if build.design.output.panels_step else {})}


@writer("step", order=20, declare=step_files)
def write_step_files(build: "BuildRecord", out: Path, files: Files) -> str:
    """``beams.step`` (one solid per beam plate, grouped by family and beam) and, with ``[output] panels_step``,
    ``panels.step``."""
    name = build.design.info.name
    write_step(beam_tree(list(build.beams.plates), name), out / "beams.step", description=f"beam plates of {name}")
    if build.design.output.panels_step:

        export_placed_panes(build.panels.panels, build.pane_offsets(), out / "panels.step", name)
        return "beams.step, panels.step"
    return "beams.step"
