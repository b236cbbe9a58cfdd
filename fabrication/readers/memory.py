"""``package_of(build) -> Package``: the records of a build in memory, made as :func:`open_build` makes them
from its folder, so that ``differences(open_build(build.write(out)), package_of(build)) == []``.

The parts' columns are the rows the parts table is written from (the build's :class:`~fabrication.model.PartsTable`);
the outlines the flat parts', the splice types' and the strips' own, unrounded; nodes, welds, sheets and mesh
from the build's stage records.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..contract import GLASS_SHEET_DIR, GLASS_SHEET_PREFIX, PLATE_SHEET_DIR, PLATE_SHEET_PREFIX, json_safe, sheet_files
from ..model import MeshData, Node, Package, Part, Sheet, Weld
from .geometry import strip_outline

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord


def _geometry(build: "BuildRecord") -> dict[str, tuple[Any, Any]]:
    """Part id → (flat outline, holes ``(h, 3)``) of every part whose outline a file of the build draws."""
    out: dict[str, tuple[Any, Any]] = {}
    for p in list(build.nesting.glass_parts) + list(build.nesting.beam_parts):
        out[p.part_id] = (p.outline, np.asarray(getattr(p, "holes", np.zeros((0, 3))), dtype=float).reshape(-1, 3))
    g = build.glazing
    if g is not None:
        from ..glazing.rows import splice_types

        types = splice_types(g.splices)
        first: dict[str, Any] = {}
        for s in g.splices:
            first.setdefault(types[s.part_ids[0]], s)
        for s in g.splices:
            rep = first[types[s.part_ids[0]]]                  # the type's DXF draws its first plate
            holes = [(x, y, rep.hole) for x, y in rep.flat_holes]
            for pid in s.part_ids:
                out[pid] = (rep.flat_outline, holes)
        for st in g.strips:
            out[st.part_id] = (strip_outline(st.length, st.width), ())

        retention = build.retention
        for prism in retention.parts if retention is not None else ():
            out[prism.part_id] = (strip_outline(round(prism.length, 6), round(prism.width, 6)), ())
    return out


def _sheets(build: "BuildRecord") -> tuple[Sheet, ...]:
    from ..writers.dxf import stock_of

    nest = build.nesting
    sheets = []
    for nesting, parts, kind, directory, prefix in (
            (nest.glass, nest.glass_parts, "panel", GLASS_SHEET_DIR, GLASS_SHEET_PREFIX),
            (nest.plates, nest.beam_parts, "beam", PLATE_SHEET_DIR, PLATE_SHEET_PREFIX)):
        by_id = {p.part_id: p for p in parts}
        names = sheet_files(directory, prefix, nesting.sheets)
        for k, group in enumerate(nesting.by_sheet()):
            material, thickness = stock_of([by_id[pl.part_id] for pl in group])
            sheets.append(Sheet(names[k], kind, k + 1, (float(nesting.sheet_size[0]), float(nesting.sheet_size[1])),
                                tuple(float(x) for x in nesting.usable), material, thickness,  # type: ignore[arg-type]
                                tuple(pl.part_id for pl in group)))
    return tuple(sheets)


def _mesh(build: "BuildRecord") -> MeshData:
    from ppfab.mesh import QuadGrid
    from ppfab.topology import grid_face_indices

    mesh = build.mesh
    if isinstance(mesh, QuadGrid):
        m1, n1 = mesh.shape
        vertices = mesh.vertices.reshape(-1, 3)
        faces = grid_face_indices(np.arange(m1 * n1).reshape(m1, n1), mesh.closed).reshape(-1, 4)
        grid = mesh
    else:
        vertices, faces, grid = mesh.vertices, mesh.faces, mesh.grid
    return MeshData(tuple(tuple(float(c) for c in p) for p in vertices),              # type: ignore[misc]
                    tuple(tuple(int(k) for k in f if k >= 0) for f in faces),
                    None if grid is None else (int(grid.shape[0]), int(grid.shape[1])),
                    bool(grid.closed) if grid is not None else False)


def package_of(build: "BuildRecord") -> Package:
    """The :class:`~fabrication.model.Package` of ``build`` without writing a file."""
    geometry = _geometry(build)
    parts = []
    for row in build.parts:
        cols = json_safe(row)
        assert isinstance(cols, dict)
        outline, holes = geometry.get(row["part_id"], (None, ()))
        parts.append(Part.from_columns(cols, outline, holes))
    g = build.glazing
    welds = tuple(Weld(node=w.vertex if w.vertex >= 0 else None, part=w.part, to=w.to,
                       dihedral_deg=float(w.dihedral_deg), weld_length_mm=float(w.length_mm),
                       preparation=w.preparation, throat_mm=float(w.throat_mm), joint=w.joint)
                  for w in (g.welds if g is not None else ()))
    nodes = []
    for rec in build.nodes.records:
        plain = json_safe(rec)
        assert isinstance(plain, dict)
        nodes.append(Node.from_record(plain))
    return Package(name=build.design.info.name, generator=_generator(), parts=tuple(parts), nodes=tuple(nodes),
                   welds=welds, sheets=_sheets(build), mesh=_mesh(build))


def _generator() -> str:
    from ppfab import __version__

    return f"ppfab {__version__}"
