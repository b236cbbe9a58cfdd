"""glass_order.csv against the parts list: one row per panel type, its quantity and parts those of parts.csv,
its file a per-type DXF of the build, its area and material those of the parts."""

from __future__ import annotations

from ..contract import ORDER_COLUMNS, csv_value
from . import Verification, check, read_csv
from ._shapes import number


@check("order", 35)
def check_order(v: Verification) -> None:
    files = v.data.get("manifest", {}).get("files", {})
    rel = files.get("glass_order_csv")
    parts = v.data.get("parts")
    if rel is None or parts is None:
        return
    rows = read_csv(v.folder / rel)
    if rows and list(rows[0]) != ORDER_COLUMNS:
        v.error(rel, "columns", f"{list(rows[0])} differ from the contract {ORDER_COLUMNS}")
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
