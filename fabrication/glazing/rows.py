"""The parts-list rows of the glazing strips, the splice cover plates and the retention parts, and what each beam
piece joins.

Strips (``kind = "strip"``) are cut from flat bar (:mod:`.cutlist`): no sheet, their nest tag names the bar and
the cut (``F03-07``).  Cover plates (``kind = "splice"``) are cut from plate to the per-type DXF
``splices/<type>.dxf`` (outline and bolt holes): nest tag ``J<splice>-A|B``.  ``area_mm2`` of a cover plate
is its outline's (before holes); ``mass_kg`` is net of the holes.

Retention parts (:func:`retention_part_rows`, kinds :data:`~fabrication.contract.RETENTION_KINDS`): one row per
setting block, stop, pressure gasket, pressure plate and cover cap, placed as a box by its ``frame`` (columns
:data:`~fabrication.contract.RETENTION_PART_COLUMNS`), and one row per pressure plate for its clamping screws with
their ``quantity`` — a bill of materials lists fasteners as one line per assembly and size, and the screws of a
plate go in together; where each one stands is ``screw_stations_mm``.  No sheet; the nest tag is the part id (the
label on the bag or the part).
"""

from __future__ import annotations

import math

import numpy as np

from ppfab.metrics import polygon_area
from ppfab.topology import FAMILY_NAMES

from ..contract import NOT_ON_A_SHEET
from .cutlist import cut_bars


def _r(x: float, digits: int = 3) -> float:
    v = round(float(x), digits)
    return 0.0 if v == 0 else v


def splice_types(splices) -> dict[str, str]:
    """Cover plate part id → type id ``SP<height>x<length>[-<skew>]``: plates of one size, skew (the angle of the
    ends off square, whole degrees) and hole pattern."""
    out = {}
    for s in splices:
        w, h = np.ptp(s.flat_outline, axis=0)
        o = s.flat_outline
        e0, e1 = o[1] - o[0], o[3] - o[0]
        skew = int(round(abs(90.0 - np.degrees(np.arccos(abs(e0 @ e1) / np.linalg.norm(e0) / np.linalg.norm(e1))))))
        key = f"SP{int(round(h))}x{int(round(w))}" + (f"-{skew}" if skew else "")
        for pid in s.part_ids:
            out[pid] = key
    return out


def strip_rows(glazing, beams) -> list[dict]:
    """One row per glazing strip (with its bar, gasket and weld)."""
    p = glazing.params
    lengths = {s.part_id: s.length for s in glazing.strips}
    cuts, _ = cut_bars(lengths, p.bar_length, p.saw_kerf, p.bar_end_allowance) if lengths else ([], 0)
    family = {pl.beam_id: FAMILY_NAMES[pl.family] for pl in beams.plates}
    rows = []
    for s, c in zip(glazing.strips, cuts):
        rows.append({
            "part_id": s.part_id, "kind": "strip", "sheet": NOT_ON_A_SHEET, "x": "", "y": "", "rotation_deg": "",
            "nest_tag": c.nest_tag, "area_mm2": _r(s.length * s.width), "mirrored": "", "sheet_file": "",
            "type_id": "", "material": p.material, "thickness_mm": p.thickness, "width_mm": _r(s.width),
            "height_mm": _r(s.length), "length_mm": _r(s.length), "family": family.get(s.beam_id, ""),
            "beam": s.beam_id, "edge_nodes": f"{s.vertices[0]};{s.vertices[1]}",
            "bar": c.bar + 1, "bar_start_mm": _r(c.start),
            "mass_kg": _r(s.length * s.width * p.thickness * p.density * 1e-9),
            "gasket": f"{p.gasket_material} {s.width:g} x {p.gasket_thickness:g} mm, {s.length:.0f} mm",
            "weld": f"double fillet a=4 to {s.beam_id}, 2 x {s.length:.0f} mm",
        })
    return rows


def splice_rows(glazing, beams) -> list[dict]:
    """Two rows per splice (the cover plates on both faces of the beam), with the pieces they join."""
    sp = glazing.splice_params
    types = splice_types(glazing.splices)
    family = {pl.beam_id: FAMILY_NAMES[pl.family] for pl in beams.plates}
    rows = []
    width = max(4, len(str(len(glazing.splices))))
    for k, s in enumerate(glazing.splices):
        w, h = np.ptp(s.flat_outline, axis=0)
        gross = abs(float(polygon_area(s.flat_outline)))                   # the parallelogram
        net = gross - len(s.holes) * math.pi * 0.25 * s.hole ** 2
        for side, pid in zip("AB", s.part_ids):
            rows.append({
                "part_id": pid, "kind": "splice", "sheet": NOT_ON_A_SHEET, "x": "", "y": "", "rotation_deg": "",
                "nest_tag": f"J{k + 1:0{width}d}-{side}", "area_mm2": _r(gross), "mirrored": "", "sheet_file": "",
                "type_id": types[pid], "material": sp.material, "thickness_mm": s.thickness, "width_mm": _r(w),
                "height_mm": _r(h), "family": family.get(s.beam_id, ""), "beam": s.beam_id,
                "joins": f"{s.pieces[0]};{s.pieces[1]}", "holes": len(s.holes), "hole_mm": s.hole,
                "bolts": f"{len(s.holes)} x {sp.bolt}" if side == "A" else "",
                "mass_kg": _r(net * s.thickness * 7850.0 * 1e-9),
            })
    return rows


def beam_joins(glazing) -> dict[str, dict[str, str]]:
    """Beam piece part id → ``{"joins": neighbouring pieces, "splices": cover plates}`` (``;``-separated); a
    welded splice joins its pieces without cover plates (its weld is a ``joint = "splice"`` row of welds.csv)."""
    out: dict[str, dict[str, list[str]]] = {}
    pairs = [(s.pieces, list(s.part_ids)) for s in glazing.splices]
    pairs += [((w.part, w.to), []) for w in glazing.welds if w.joint == "splice"]
    for (a, b), plates in pairs:
        for me, other in ((a, b), (b, a)):
            rec = out.setdefault(me, {"joins": [], "splices": []})
            rec["joins"].append(other)
            rec["splices"].extend(plates)
    return {k: {"joins": ";".join(v["joins"]), "splices": ";".join(v["splices"])} for k, v in out.items()}


def _frame_cell(origin, x_dir, y_dir, normal) -> dict[str, list[float]]:
    return {k: [float(c) + 0.0 for c in vec] for k, vec in (("origin", origin), ("x_dir", x_dir), ("y_dir", y_dir),
                                                       ("normal", normal))}


def retention_part_rows(retention) -> list[dict]:
    """The parts-list rows of a :class:`~fabrication.glazing.retention.Retention`: its prisms in their order, then
    one screw row per pressure plate (module docstring)."""
    from .retention import material_of

    p = retention.params
    rows = []
    for part in retention.parts:
        origin, x, y, n = part.box_frame()
        rows.append({
            "part_id": part.part_id, "kind": part.kind, "sheet": NOT_ON_A_SHEET, "x": "", "y": "", "rotation_deg": "",
            "nest_tag": part.part_id, "area_mm2": _r(part.length * part.width, 6), "mirrored": "",
            "sheet_file": "", "type_id": "", "material": material_of(part.kind, p), "thickness_mm": _r(part.height, 6),
            "owner": part.owner, "strip": part.strip, "beam": part.beam, "length_mm": _r(part.length, 6),
            "width_mm": _r(part.width, 6), "height_mm": _r(part.height, 6), "quantity": 1,
            "mass_kg": _r(part.mass_kg, 4),
            "frame": _frame_cell(origin, x, y, n),
        })
    for sc in retention.screws:
        f = sc.frame
        origin = f.to3d(np.array([[sc.x0, 0.0]]))[0] + sc.z0 * f.normal
        rows.append({
            "part_id": sc.part_id, "kind": "screw", "sheet": NOT_ON_A_SHEET, "x": "", "y": "", "rotation_deg": "",
            "nest_tag": sc.part_id, "area_mm2": "", "mirrored": "", "sheet_file": "", "type_id": "",
            "material": material_of("screw", p), "thickness_mm": "", "owner": sc.plate, "strip": sc.strip,
            "beam": sc.beam, "length_mm": _r(sc.length, 6), "diameter_mm": _r(sc.diameter, 6),
            "quantity": len(sc.stations),
            "mass_kg": _r(sc.mass_kg, 4), "frame": _frame_cell(origin, f.ex, f.ey, f.normal),
            "screw_stations_mm": ";".join(str(_r(x, 3)) for x in sc.stations),
        })
    return rows
