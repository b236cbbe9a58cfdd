"""The per-type DXFs (the files the glass order sends the supplier): one flat outline each, congruent, within
the congruence tolerance, with the 3D face (inset by half the gap) of every panel of its type.

Each DIMENSION shows its measurement: its text override is empty or ``<>`` (the measured value), and the text
of its rendered block is that value to the one decimal the dimension style gives (a text that is no number is a
finding too).

The outlines are kept in :attr:`FolderData.type_outlines` (type id → outline) for the placement check, and each file as
read in :attr:`FolderData.dxf` (:func:`type_dxf`), so the glass order check reads none of them again.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..contract import csv_value
from .congruence import congruence_error, congruence_limits, inset_face_2d
from . import Verification, check
from ._tolerance import type_tolerance

if TYPE_CHECKING:  # pragma: no cover
    from ..writers.dxf import DXFContent


def type_dxf(v: Verification, rel: str) -> "DXFContent":
    """The per-type DXF ``rel`` read once per verification (:func:`._dxf_read.dxf_content`) and held to the contract
    of ``check_sheet_dxf`` without a sheet: its content, or the exception reading or the contract raised."""
    from ..writers.dxf import sheet_contract
    from ._dxf_read import dxf_content

    content = dxf_content(v, rel)
    sheet_contract(content, rel.rsplit("/", 1)[-1], require_sheet=False)
    return content


@check("types")
def check_types(v: Verification) -> None:
    m = v.manifest
    files = m.get("files", {})
    mesh = v.mesh
    parts = (v.parts or [])
    fab = m.get("fabrication", {})
    ctol = type_tolerance(fab)
    gap = float(fab.get("panel_gap", 0.0))
    by_type: dict[str, list[dict]] = {}
    for p in parts:
        if p["kind"] == "panel":
            by_type.setdefault(csv_value(p["type_id"]), []).append(p)
    outlines = v.read.type_outlines
    for rel in files.get("panel_type_dxfs", []):
        try:
            content = type_dxf(v, rel)
        except Exception as exc:  # noqa: BLE001 - reported as a finding
            v.error(rel, "", str(exc))
            continue
        if len(content.parts) != 1:
            v.error(rel, "", f"holds {len(content.parts)} CUT outlines, expected one")
            continue
        part = content.parts[0]
        tid = part.xdata.get("type_id", "")
        members = by_type.get(tid)
        if not members:
            v.error(rel, tid or part.part_id, "type is not a panel type of parts.csv")
            continue
        outlines[tid] = part.points
        _check_dimension_texts(v, rel, tid, content)
        if mesh is None:
            continue
        for row in members:
            if row.get("face", "") == "":
                continue
            face = int(row["face"])
            ref = inset_face_2d(mesh.vertices[mesh.faces[face]], 0.5 * gap)
            tl, ta = congruence_limits(ref, ctol)
            dl, da = congruence_error(ref, part.points, (tl, ta))
            if dl > tl or da > ta:
                v.error(rel, tid, f"outline is not congruent with face {face} ({row['part_id']}) inset by half the gap: "
                                  f"edge lengths differ by {dl:.3g} mm, angles by {da:.3g} rad (congruence "
                                  f"tolerance {ctol:g} mm)")
    for tid in sorted(set(by_type) - set(outlines)):
        if files.get("panel_type_dxfs"):
            v.error("glass/types", tid, "panel type has no per-type DXF")
    v.checked.append("types")


def _reads(text: str, value: float) -> bool:
    """Whether a dimension text (``"1826"``, ``"1765.1"``) is ``value`` to the style's one decimal."""
    try:
        return abs(float(text.strip()) - value) <= 0.05 + 1e-9
    except ValueError:
        return False


def _check_dimension_texts(v: Verification, rel: str, tid: str, content: "DXFContent") -> None:
    """Every DIMENSION of a per-type DXF reads its measurement (override ``""``/``"<>"``, block text to 0.1 mm)."""
    for d in content.dimension_texts:
        what = f"{tid} DIMENSION #{d.handle}"
        if d.override not in ("", "<>") and not _reads(d.override, d.measurement):
            v.error(rel, what, f"text is overridden to {d.override!r}; the dimension measures {d.measurement:.1f} mm")
        if d.shown is not None and not _reads(d.shown, d.measurement):
            v.error(rel, what, f"shows {d.shown!r}; the dimension measures {d.measurement:.1f} mm")
