"""``open_build(folder) -> Package``: every record of a finished build read back from its files.

The parts come from ``parts.json`` (``parts.csv`` when the JSON is absent); the flat outline and holes of a part
nested on a cutting sheet from its CUT outline on ``sheet_file`` mapped back through its placement, of a splice
cover plate from its type's DXF ``splices/<type_id>.dxf``, of a glazing strip or a retention box (setting block,
stop, pressure gasket, plate, cover cap: on its ``frame``) from its length and width; the
nodes from ``nodes.json``, the welds from ``welds.csv``, the sheets from the cutting DXFs the manifest lists and
the mesh from ``mesh.obj`` (``mesh.json`` for the grid).  A part of a kind added later keeps its columns and gets
an outline when it is on a cutting sheet.

Older builds (docs/migration.md, all written as ``ppfab 0.1.0``): ``flags`` read as ``panel_flags``, structured
``parts.csv`` cells written as Python literals, ``welds.csv`` without ``joint`` (``T``), folders without strips,
splices or welds.
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path
from typing import Any

from ..contract import SPLICE_DIR
from ..model import ColumnError, Package, Part, Sheet
from .dxf import DxfCuts, box, read_cuts
from .errors import BuildReadError, bad
from .geometry import BOX_KINDS, Points, strip_outline, unplace, unplace_outline
from .mesh import read_mesh
from .tables import read_manifest, read_nodes, read_parts, read_welds


def _sheet_files(manifest: dict[str, Any]) -> list[tuple[str, str]]:
    files = manifest.get("files") if isinstance(manifest.get("files"), dict) else {}
    assert isinstance(files, dict)
    out = []
    for key, kind in (("glass_sheets", "panel"), ("beam_sheets", "beam")):
        names = files.get(key) or []
        out += [(str(n), kind) for n in (names if isinstance(names, list) else [names])]
    return out


def open_build(folder: str | os.PathLike) -> Package:
    """The typed records of the ppfab output folder ``folder`` (see the module docstring); a missing or
    malformed file is a one-line :class:`~fabrication.readers.errors.BuildReadError`."""
    root = Path(folder)
    if not root.is_dir():
        raise BuildReadError(f"{root}: no such folder (give the output folder of ppfab build)")
    manifest = read_manifest(root)
    files = manifest.get("files") if isinstance(manifest.get("files"), dict) else {}
    parts_path, rows = read_parts(root)
    dxfs: dict[str, DxfCuts] = {}

    def cuts(rel: str, what: str) -> DxfCuts:
        if rel not in dxfs:
            dxfs[rel] = read_cuts(root / rel, what)
        return dxfs[rel]

    parts = []
    for n, cols in rows:
        try:
            plain = Part.from_columns(cols)
        except ColumnError as exc:
            raise bad(parts_path, exc.reason, row=n, column=exc.column) from None
        outline: Points | None = None
        holes: list[tuple[float, float, float]] = []
        pl = plain.placement
        if pl is not None and not pl.sheet_file:            # a table without sheet_file: the manifest's list
            listed = [rel for rel, kind in _sheet_files(manifest) if kind == plain.kind]
            if 1 <= pl.sheet <= len(listed):
                pl = replace(pl, sheet_file=listed[pl.sheet - 1])
        if pl is not None and pl.sheet_file:
            sheet = cuts(pl.sheet_file, f"the cutting sheet of {plain.part_id}, parts row {n}")
            if plain.part_id not in sheet.outlines:
                raise bad(sheet.path, f"no CUT outline of {plain.part_id} (parts row {n} places it here)")
            outline = unplace_outline(sheet.outlines[plain.part_id], pl)
            holes = [(*unplace([(x, y)], pl)[0], d) for x, y, d in sheet.holes.get(plain.part_id, [])]
        elif plain.kind == "splice" and plain.type_id:
            dxf = cuts(f"{SPLICE_DIR}/{plain.type_id}.dxf", f"the cover plate type of {plain.part_id}, row {n}")
            if plain.type_id not in dxf.outlines:
                raise bad(dxf.path, f"no CUT outline with part_id {plain.type_id}")
            outline = dxf.outlines[plain.type_id]
            holes = [h for key in ("", plain.type_id) for h in dxf.holes.get(key, [])]
        elif plain.kind == "strip" or (plain.kind in BOX_KINDS and plain.frame is not None):
            d = plain.details            # a strip, or a retention box on its frame: length × width from the origin
            outline = strip_outline(getattr(d, "length_mm", None), getattr(d, "width_mm", None))
        part = Part.from_columns(cols, outline, holes) if outline is not None else plain
        parts.append(part if pl is plain.placement else replace(part, placement=pl))
    sheets = []
    numbers: dict[str, int] = {}
    for rel, kind in _sheet_files(manifest):
        c = cuts(rel, "a cutting sheet the manifest lists")
        lo = box(c.sheet)
        numbers[kind] = numbers.get(kind, 0) + 1
        sheets.append(Sheet(rel, kind, numbers[kind], None if lo is None else (lo[2] - lo[0], lo[3] - lo[1]),
                            box(c.trim), c.material, c.thickness, tuple(c.outlines)))
    design = manifest.get("design") if isinstance(manifest.get("design"), dict) else {}
    assert isinstance(design, dict) and isinstance(files, dict)
    return Package(name=str(design.get("name", "")), generator=str(manifest.get("generator", "")),
                   parts=tuple(parts), nodes=read_nodes(root), welds=read_welds(root, "welds_csv" in files),
                   sheets=tuple(sheets), mesh=read_mesh(root))
