"""``dxf_r12/`` and ``dxf_r2000/``: every cutting sheet and per-type DXF again in an older DXF version.

With ``[output] dxf_r12`` / ``dxf_r2000`` the glass and plate cutting sheets and the per-type DXFs are written a
second time into the folder of :data:`fabrication.contract.LEGACY_DXF`, under the same relative paths
(``dxf_r12/glass/glass_03.dxf`` …), with the same layers, XDATA, labels and dimensions — for cutting tables that
read nothing newer.  R2000 files are built as R2000 documents; R12 files by ezdxf's R12 exporter
(:mod:`fabrication.writers._dxf_r12`).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ..contract import (GLASS_SHEET_DIR, GLASS_SHEET_PREFIX, LEGACY_DXF, PLATE_SHEET_DIR, PLATE_SHEET_PREFIX, TYPE_DIR,
                        sheet_files)
from . import Files, writer
from .dxf import type_dxf_files, write_sheet_dxfs, write_type_dxfs

if TYPE_CHECKING:  # pragma: no cover
    from ..design import Design
    from ..records import BuildRecord


def legacy_versions(design: "Design") -> list[str]:
    """The older DXF versions a design asks for, in :data:`LEGACY_DXF` order."""
    wanted = {"R12": design.output.dxf_r12, "R2000": design.output.dxf_r2000}
    return [v for v in LEGACY_DXF if wanted[v]]


def legacy_files(build: "BuildRecord") -> Files:
    """Per version asked for, under its folder: the cutting sheets, and with ``per_type_dxf`` the per-type DXFs."""
    nest = build.nesting
    files: Files = {}
    for version in legacy_versions(build.design):
        root = LEGACY_DXF[version]
        rel = [f"{root}/{f}" for f in sheet_files(GLASS_SHEET_DIR, GLASS_SHEET_PREFIX, nest.glass.sheets)
               + sheet_files(PLATE_SHEET_DIR, PLATE_SHEET_PREFIX, nest.plates.sheets)]
        if build.design.output.per_type_dxf:
            rel += type_dxf_files(list(nest.glass_parts), f"{root}/{TYPE_DIR}")
        files[root] = rel
    return files


@writer("dxf_legacy", order=40, declare=legacy_files, enabled=lambda design: bool(legacy_versions(design)))
def write_legacy_dxfs(build: "BuildRecord", out: Path, files: Files) -> str:
    """The cutting sheets (and, with ``per_type_dxf``, the per-type DXFs) in each version asked for."""
    name = build.design.info.name
    nest = build.nesting
    output = build.design.output
    notes = []
    for version in legacy_versions(build.design):
        root = out / LEGACY_DXF[version]
        paths = write_sheet_dxfs(list(nest.glass_parts), nest.glass, root / GLASS_SHEET_DIR, GLASS_SHEET_PREFIX,
                                 f"{name} glass", version)
        paths += write_sheet_dxfs(list(nest.beam_parts), nest.plates, root / PLATE_SHEET_DIR, PLATE_SHEET_PREFIX,
                                  f"{name} beam plates", version)
        count = len(paths)
        if output.per_type_dxf:
            count += len(write_type_dxfs(list(nest.glass_parts), root / TYPE_DIR, version=version,
                                         dimensions=output.type_dimensions))
        notes.append(f"{count} {version}")
    return ", ".join(notes) + " files"
