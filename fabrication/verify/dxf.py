"""The DXF cutting sheets: audit, layers, parts once, inside TRIM, spacing, parts.csv, panel congruence, labels
and marks.  The outlines found are kept in :attr:`FolderData.cut` (part id → sheet file, outline) for other checks."""

from __future__ import annotations

from .. import contract
from ..contract import SHEET_KINDS
from .congruence import congruence_error, congruence_limits, inset_face_2d
from . import Verification, check
from ._cells import file_list
from ._tolerance import type_tolerance


@check("dxf")
def check_dxf(v: Verification) -> None:
    """Every cutting sheet: ezdxf audit, contract layers/entities, parts once, inside TRIM, spacing,
    agreement with parts.csv, and (glass) congruence with the 3D face inset by half the gap."""
    from shapely import Polygon, STRtree

    from ..writers.dxf import sheet_contract
    from ._dxf_read import dxf_content

    m = v.manifest
    files = m.get("files", {})
    fab = m.get("fabrication", {})
    parts = {r["part_id"]: r for r in (v.parts or [])}
    mesh = v.mesh
    panels_fab = fab.get("panels", {})
    ctol = type_tolerance(fab)
    marks_wanted = float(panels_fab.get("mark_size", 0.0)) > 0
    seen: dict[str, str] = {}
    cut = v.read.cut
    for key, spacing_key in (("glass_sheets", "nesting"), ("beam_sheets", "beam_nesting")):
        spacing = float(fab.get(spacing_key, {}).get("spacing", fab.get("part_spacing", 0.0)))
        for sheet_no, rel in enumerate(file_list(files, key), start=1):
            try:
                content = dxf_content(v, rel)
                sheet_contract(content, rel.rsplit("/", 1)[-1])
            except Exception as exc:  # noqa: BLE001 - reported as a finding
                v.error(rel, "", str(exc))
                continue
            polys = []
            v.read.dxf_texts[rel] = content.texts          # for the marking check
            v.read.dxf_marks[rel] = content.mark_lines
            v.read.dxf_trim[rel] = content.trim_outline
            trim = Polygon(content.trim_outline).buffer(1e-6)
            for label in content.labels:
                if contract.one_line(label) != label:
                    v.error(rel, "LABEL", f"text {label!r} holds control characters")
            if key == "glass_sheets" and marks_wanted and content.marks < len(content.parts):
                v.error(rel, "MARK", f"{content.marks} reference marks for {len(content.parts)} panels "
                                     f"(panels.mark_size {panels_fab.get('mark_size')} mm)")
            for part in content.parts:
                pid = part.part_id
                if pid in seen:
                    v.error(rel, pid, f"part is also cut on {seen[pid]}")
                seen[pid] = rel
                cut[pid] = (rel, part.points)
                row = parts.get(pid)
                if row is None:
                    v.error(rel, pid, "part is not in parts.csv")
                elif str(row.get("sheet")) != str(sheet_no) or row.get("nest_tag") != part.nest_tag:
                    v.error(rel, pid, f"sheet/nest tag ({sheet_no}, {part.nest_tag}) differ from parts.csv "
                                      f"({row.get('sheet')}, {row.get('nest_tag')})")
                poly = Polygon(part.points)
                if not poly.is_valid:
                    v.error(rel, pid, "outline intersects itself")
                if not trim.contains(poly):
                    v.error(rel, pid, "outline leaves the usable (TRIM) area")
                polys.append((pid, poly))
                v.read.dxf_outlines[pid] = part.points      # sheet coordinates
                if key == "glass_sheets" and mesh is not None and row is not None and row.get("face", "") != "":
                    face = int(row["face"])
                    ref = inset_face_2d(mesh.vertices[mesh.faces[face]], 0.5 * float(fab.get("panel_gap", 0.0)))
                    tl, ta = congruence_limits(ref, ctol)
                    dl, da = congruence_error(ref, part.points, (tl, ta))
                    if dl > tl or da > ta:
                        v.error(rel, pid, f"outline is not the face {face} inset by half the gap within the "
                                          f"congruence tolerance {ctol:g} mm (edge lengths differ by {dl:.3g} mm, "
                                          f"angles by {da:.3g} rad)")
            tree = STRtree([p for _, p in polys])
            for i, (pid, poly) in enumerate(polys):
                for j in tree.query(poly, predicate="dwithin", distance=max(spacing - 1e-6, 0.0)):
                    if j > i:
                        d = poly.distance(polys[j][1])
                        what = "overlaps" if d == 0 else f"is {d:.3g} mm from"
                        v.error(rel, pid, f"{what} {polys[j][0]} (spacing {spacing:g} mm)")
    for rel in file_list(files, "splice_dxfs"):
        check_splice_label(v, rel)
    for pid, row in parts.items():
        if pid not in seen and row["kind"] in SHEET_KINDS and (files.get("glass_sheets") or files.get("beam_sheets")):
            v.error("parts.csv", pid, "part is on no cutting sheet")
    v.checked.append("dxf")


def check_splice_label(v: Verification, rel: str) -> None:
    """A cover plate DXF's type label (the ``LABEL`` text ``<type> x<count>``) lies inside its ``CUT`` outline and
    off its bolt holes: its box (:data:`fabrication.marking.LABEL_CHAR_WIDTH` per character, from the cap height
    down to the descenders, about its insertion point and rotation) within the outline, crossing no hole."""
    import re

    import numpy as np
    from shapely.geometry import Point, Polygon

    from ..marking import LABEL_CHAR_WIDTH
    from ._dxf_read import dxf_content

    try:
        content = dxf_content(v, rel)
    except Exception as exc:  # noqa: BLE001 - reported as a finding
        v.error(rel, "", f"cannot be read as DXF: {exc}")
        return
    outlines = [Polygon(p.points) for p in content.parts]
    if len(outlines) != 1 or not outlines[0].is_valid:
        return                                  # the splice check reports the outline itself
    plate = outlines[0]
    holes = [Point(tuple(c.centre)).buffer(0.5 * c.diameter, 24) for c in content.circles]
    stem = rel.rsplit("/", 1)[-1].removesuffix(".dxf")
    for t in content.texts:
        if t.layer != "LABEL" or not re.fullmatch(rf"{re.escape(stem)} x\d+", t.text):
            continue
        h, a = t.height, np.radians(t.rotation_deg)
        w = LABEL_CHAR_WIDTH * len(t.text) * h
        u, n = np.array([np.cos(a), np.sin(a)]), np.array([-np.sin(a), np.cos(a)])
        p = np.asarray(t.insert if t.insert is not None else t.centre, dtype=float)
        box = Polygon([p - 0.3 * h * n, p + w * u - 0.3 * h * n, p + w * u + h * n, p + h * n])
        if not plate.contains(box):
            v.error(rel, t.text, "type label runs over the plate's outline")
        elif any(box.intersects(c) for c in holes):
            v.error(rel, t.text, "type label runs over a bolt hole")
