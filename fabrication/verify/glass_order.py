"""glass_order.csv and the per-type DXFs: the order list against the parts list (one row per panel type, its
quantity, parts, area, material and file); every panel ordered once under its type; each type's corners, edges,
diagonals, angles and area consistent with each other and with its mesh face inset by half the gap; its DXF
outline at those corners, dimensioned with those edges and diagonals."""

from __future__ import annotations

import numpy as np

from ppfab.metrics import polygon_area

from ..contract import ORDER_ALL_COLUMNS, ORDER_CORNERS, ORDER_MAKEUP_COLUMNS, csv_value
from ..glassorder import makeup_columns, reference_frame
from . import Verification, check, read_csv
from ._cells import CellReader
from ._shapes import number
from .congruence import congruence_error, inset_face_2d
from .types import type_dxf


@check("order")
def check_order(v: Verification) -> None:
    """The order list against parts.csv: one row per panel type, its quantity, parts, area and material."""
    files = v.manifest.get("files", {})
    rel = files.get("glass_order_csv")
    parts = v.parts
    if rel is None or parts is None:
        return
    rows = read_csv(v.folder / rel)
    if rows and list(rows[0]) != ORDER_ALL_COLUMNS:
        v.error(rel, "columns", f"{list(rows[0])} differ from the contract {ORDER_ALL_COLUMNS}")
        return
    panels: dict[str, list[dict]] = {}
    for p in parts:
        if p["kind"] == "panel":
            panels.setdefault(csv_value(p["type_id"]), []).append(p)
    type_files = set(files.get("panel_type_dxfs", []))
    seen = set()
    for r in rows:
        tid = csv_value(r["type_id"])
        if tid in seen:
            v.error(rel, tid, "type is ordered twice")
        seen.add(tid)
        members = panels.get(tid, [])
        ids = [csv_value(x) for x in r["parts"].split(";") if x]
        if number(r["quantity"], -1) != len(members):
            v.error(rel, tid, f"quantity {r['quantity']} but parts.csv has {len(members)} panel(s) of this type")
        if len(ids) != number(r["quantity"], -1) or sorted(ids) != sorted(p["part_id"] for p in members):
            v.error(rel, tid, f"parts {r['parts']!r} are not the {len(members)} panel(s) of this type in parts.csv")
        if members:
            area = number(members[0]["area_mm2"])
            if abs(number(r["area_mm2"]) - area) > 0.05 + 1e-9 * area:
                v.error(rel, tid, f"area {r['area_mm2']} mm² differs from the parts' {area:g} mm²")
            if csv_value(r["material"]) != csv_value(members[0]["material"]):
                v.error(rel, tid, f"material {r['material']!r} differs from parts.csv {members[0]['material']!r}")
        if type_files and r["file"] not in type_files:
            v.error(rel, tid, f"file {r['file']!r} is not a per-type DXF of this build")
    for tid in sorted(set(panels) - seen):
        v.error(rel, tid, f"panel type of {len(panels[tid])} panel(s) in parts.csv is not on the order list")
    v.checked.append("order")


@check("glass_order")
def check_glass_order(v: Verification) -> None:
    m = v.manifest
    files = m.get("files", {})
    rel = files.get("glass_order_csv")
    if rel is None:
        return
    rows = read_csv(v.folder / rel)
    missing = [c for c in ORDER_ALL_COLUMNS if rows and c not in rows[0]]
    if missing:
        v.error(rel, "columns", f"missing columns {missing}")
        return
    parts = {r["part_id"]: r for r in (v.parts or []) if r["kind"] == "panel"}
    ordered: dict[str, str] = {}
    mesh = v.mesh
    gap = float(m.get("fabrication", {}).get("panel_gap", 0.0))
    dimensioned = bool(m.get("fabrication", {}).get("output", {}).get("type_dimensions", False))
    n = ORDER_CORNERS
    cells = CellReader(v, rel)
    numeric = ([f"c{k}_{xy}_mm" for k in range(1, n + 1) for xy in "xy"] +
               [f"edge_{k}{k % n + 1}_mm" for k in range(1, n + 1)] + ["diag_13_mm", "diag_24_mm"] +
               [f"angle_{k}_deg" for k in range(1, n + 1)] + ["area_mm2"])
    for row_no, row in enumerate(rows, 1):
        tid = row["type_id"]
        members = [p for p in row["parts"].split(";") if p]
        quantity = cells.integer(row_no, row, "quantity", low=0)
        if quantity is not None and len(members) != quantity:
            v.error(rel, tid, f"quantity {row['quantity']} but {len(members)} position ids")
        for pid in members:
            if pid in ordered:
                v.error(rel, pid, f"is ordered under {ordered[pid]} and {tid}")
            ordered[pid] = tid
            if pid in parts and parts[pid].get("type_id") != tid:
                v.error(rel, pid, f"is type {parts[pid].get('type_id')} in parts.csv, ordered as {tid}")
        read = {col: cells.number(row_no, row, col) for col in numeric}     # a bad cell is a finding
        if any(x is None for x in read.values()):
            continue
        c = np.array([[read[f"c{k}_{xy}_mm"] for xy in "xy"] for k in range(1, n + 1)], dtype=float)
        edges = np.array([read[f"edge_{k}{k % n + 1}_mm"] for k in range(1, n + 1)], dtype=float)
        diags = np.array([read["diag_13_mm"], read["diag_24_mm"]], dtype=float)
        angles = np.array([read[f"angle_{k}_deg"] for k in range(1, n + 1)], dtype=float)
        if np.abs(np.hypot(*(np.roll(c, -1, axis=0) - c).T) - edges).max() > 0.02 or np.abs(
                np.hypot(*(c[[2, 3]] - c[[0, 1]]).T) - diags).max() > 0.02:
            v.error(rel, tid, "edge lengths or diagonals do not match the corners")
        if abs(angles.sum() - 180.0 * (n - 2)) > 0.01:
            v.error(rel, tid, f"corner angles sum to {angles.sum():.4f}°, not {180 * (n - 2)}°")
        area = float(polygon_area(c))
        if abs(area - float(read["area_mm2"] or 0.0)) > 1e-4 * abs(area) + 1.0:
            v.error(rel, tid, f"corners enclose {area:.1f} mm², area_mm2 is {row['area_mm2']}")
        first = parts.get(members[0]) if members else None
        if mesh is not None and first is not None and first.get("face", "") != "":
            ref = inset_face_2d(mesh.vertices[mesh.faces[int(first["face"])]], 0.5 * gap)
            dl, da = congruence_error(ref, c, (0.02, 1e-4))
            if dl > 0.02 or da > 1e-4:
                v.error(rel, tid, f"shape is not face {first['face']} inset by half the gap "
                                  f"(edges differ by {dl:.3g} mm, angles by {da:.3g} rad)")
        if row["file"]:
            try:
                dxf = type_dxf(v, row["file"])
            except Exception as exc:  # noqa: BLE001 - reported as a finding
                v.error(row["file"], "", str(exc))
                continue
            if len(dxf.parts) != 1 or dxf.parts[0].points.shape != c.shape or \
                    np.abs(reference_frame(dxf.parts[0].points) - c).max() > 0.006:
                v.error(row["file"], tid, "CUT outline, moved to corner 1 at the origin and edge 12 along +x, "
                                          "is not at the corners of the glass order")
            want = sorted(np.r_[edges, diags]) if dimensioned else []
            got = sorted(dxf.dimensions)
            if len(got) != len(want) or (want and np.abs(np.array(got) - want).max() > 0.006):
                v.error(row["file"], tid, f"dimensions {[round(d, 2) for d in got]} are not the edges and "
                                          f"diagonals {[round(d, 2) for d in want]}")
    for pid in sorted(set(parts) - set(ordered)):
        v.error(rel, pid, "panel is in no row of the glass order")
    _check_makeup(v, rel, rows, m.get("fabrication", {}).get("panels", {}))
    v.checked.append("glass_order")


def _check_makeup(v: Verification, rel: str, rows: list[dict[str, str]], panels: dict) -> None:
    """Every type's make-up columns and weight recomputed from the manifest's ``[panels]`` make-up, density and
    coated side (:mod:`fabrication.panels.makeup`)."""
    from ppfab.errors import DesignError

    from ..panels.makeup import parse_makeup

    try:
        makeup = parse_makeup(str(panels.get("makeup", "")))
        mass = makeup.mass_per_m2(float(panels.get("density", 2500.0)))
        coated = str(panels.get("coated_side", "none"))
    except (DesignError, TypeError, ValueError) as exc:
        v.error("manifest.json", "fabrication.panels.makeup", f"cannot be read ({exc})")
        return
    for row in rows:
        tid = row["type_id"]
        try:
            longest = max(float(row["width_mm"]), float(row["height_mm"]))
            want = makeup_columns(makeup, coated, longest)
            weight = number(row["area_mm2"]) * 1e-6 * mass
        except (KeyError, ValueError) as exc:
            v.error(rel, tid, f"width, height or area cannot be read ({exc})")
            continue
        for col in ORDER_MAKEUP_COLUMNS:
            if csv_value(row.get(col, "")) != csv_value(str(want[col])):
                v.error(rel, tid, f"{col} {row.get(col)!r}, but the make-up {makeup.text()!r} gives {want[col]!r}")
        if abs(number(row["weight_kg"], -1.0) - weight) > 0.01 + 1e-4 * weight:
            v.error(rel, tid, f"weight {row['weight_kg']} kg, but {row['area_mm2']} mm² of {makeup.text()} "
                              f"({mass:.3f} kg/m²) weigh {weight:.3f} kg")
