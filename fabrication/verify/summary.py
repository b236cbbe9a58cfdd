"""manifest.json ``summary``, ``glazing`` and ``fabrication``: every figure recomputed from the files and compared.

The totals come from the rows the build wrote and the other checks hold to the geometry: counts, areas,
weights and lengths of the ``panel`` and ``beam`` rows of ``parts.csv`` (each written rounded, so a sum may be
off by half a unit of its last digit per row), the extent of ``mesh.obj``, the sheets listed in ``files``, the
utilisation as part area over the sheets' area (``fabrication.nesting.sheet``, ``beam_nesting.sheet``), the
largest ``torsion_deg`` of ``nodes.csv``; the glazing figures from ``parts.csv`` (strips, cover plates),
``bites.csv`` and ``welds.csv``; the ``fabrication`` values the rows of ``parts.csv`` repeat (beam depth and
thickness, glass thickness, strip section, materials) and the densities their masses give.  The
sheet sizes and spacing are the DXF check's, the panel gap its congruence check's.  A nesting's lower bound is not recomputed (that is the nesting's own search);
it must be a whole number between the sheets' area bound and the sheets used.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..contract import RETENTION_KINDS, csv_value
from . import Verification, check, read_csv
from ._cells import file_list, is_number


@dataclass(frozen=True)
class Figure:
    """One recomputed figure: its value and how far the manifest's may be from it (rounding of the rows)."""

    value: Any
    tolerance: float = 0.0


def _count(x: int) -> Figure:
    return Figure(x)


def recompute_summary(v: Verification) -> dict[str, Figure]:
    """The manifest's ``summary`` as the files give it (figures whose sources are missing are left out)."""
    m = v.manifest
    files = m.get("files", {})
    fab = m.get("fabrication", {})
    parts = (v.parts or [])
    mesh = v.mesh
    out: dict[str, Figure] = {}
    if mesh is not None:
        out["extent_mm"] = Figure([float(x) for x in np.ptp(mesh.vertices, axis=0)], 1e-6)
        out["nodes"] = _count(len(mesh.vertices))
    panels = [r for r in parts if r["kind"] == "panel"]
    plates = [r for r in parts if r["kind"] == "beam"]
    if parts:
        n, k = len(panels), len(plates)
        glass = sum(_num(r["area_mm2"]) for r in panels)
        steel = sum(_num(r["area_mm2"]) for r in plates)
        out.update(panels=_count(n), panel_types=_count(len({r["type_id"] for r in panels if r["type_id"]})),
                   glass_area_m2=Figure(glass / 1e6, 5e-8 * n + 1e-9),     # area_mm2 to 0.1 mm²
                   glass_weight_kg=Figure(sum(_num(r["weight_kg"]) for r in panels), 5e-4 * n + 1e-9),
                   beams=_count(len({r.get("beam_id", "") for r in plates})), beam_plates=_count(k),
                   beam_types=_count(len({r["type_id"] for r in plates if r["type_id"]})),
                   beam_length_m=Figure(sum(_num(r["length_mm"]) for r in plates) / 1e3, 5e-7 * k + 1e-9),
                   beam_mass_kg=Figure(sum(_num(r["mass_kg"]) for r in plates), 5e-5 * k + 1e-9),
                   plate_area_m2=Figure(steel / 1e6, 5e-8 * k + 1e-9))
        metal = [r for r in parts if r["kind"] in ("beam", "strip", "splice")]
        out["steel_mass_kg"] = Figure(sum(_num(r["mass_kg"]) for r in metal), 5e-4 * len(metal) + 1e-9)
        held = [r for r in parts if r["kind"] in RETENTION_KINDS]
        out["retention_mass_kg"] = Figure(sum(_num(r["mass_kg"]) for r in held), 5e-5 * len(held) + 1e-9)
    if files.get("welds_csv") or parts:
        welds = _rows(v, files["welds_csv"]) if files.get("welds_csv") else []
        out["weld_length_m"] = Figure(sum(_num(r.get("weld_length_mm", "")) for r in welds) / 1e3,
                                      5e-7 * len(welds) + 1e-9)
        for prefix, key, section, area, rows in (("glass", "glass_sheets", "nesting", glass, n),
                                                 ("plate", "beam_sheets", "beam_nesting", steel, k)):
            sheets = len(file_list(files, key))
            out[f"{prefix}_sheets"] = _count(sheets)
            size = fab.get(section, {}).get("sheet", fab.get("sheet"))
            if sheets and isinstance(size, list) and len(size) == 2 and all(is_number(x) for x in size):
                whole = sheets * float(size[0]) * float(size[1])
                out[f"{prefix}_utilisation"] = Figure(area / whole, (5e-4 * rows + 1e-6) / whole + 1e-12)
    nodes = v.nodes
    if nodes and mesh is not None and len(nodes) == len(mesh.vertices):
        tors = [_num(r.get("torsion_deg", "")) for r in nodes]
        if all(math.isfinite(t) for t in tors):
            out["torsion_max_deg"] = Figure(max(tors, default=0.0), 1e-8)
    return out


def recompute_glazing(v: Verification) -> dict[str, Figure]:
    """The manifest's ``glazing`` figures as parts.csv, bites.csv and welds.csv give them."""
    m = v.manifest
    files = m.get("files", {})
    fab = m.get("fabrication", {})
    parts = (v.parts or [])
    gl, panels = fab.get("glazing", {}), fab.get("panels", {})
    covers = sum(r["kind"] == "splice" for r in parts)
    out: dict[str, Figure] = {"strips": _count(sum(r["kind"] == "strip" for r in parts)),
                              "splices": _count(covers // 2), "cover_plates": _count(covers)}
    if is_number(gl.get("thickness")) and is_number(gl.get("gasket_thickness")):
        strips = out["strips"].value > 0
        out["offset_mm"] = Figure(float(gl["thickness"]) + float(gl["gasket_thickness"]) if strips else 0.0, 1e-9)
    if is_number(panels.get("min_bite")):
        out["min_bite_mm"] = Figure(float(panels["min_bite"]), 1e-9)
    if files.get("bites_csv"):
        bites = [_num(r.get("bite_mm", "")) for r in _rows(v, files["bites_csv"])]
        if bites and all(math.isfinite(b) for b in bites):
            out["bite_min_mm"] = Figure(min(bites), 5e-4 + 1e-9)
    welds = _rows(v, files["welds_csv"]) if files.get("welds_csv") else []
    out["welds"] = _count(len(welds))
    out["welded_splices"] = _count(sum(r.get("joint") == "splice" for r in welds))
    return out


FROM_ROWS = (("beams.depth", "beam", "depth_mm"), ("beams.thickness", "beam", "thickness_mm"),
             ("beams.material", "beam", "material"), ("panels.thickness", "panel", "thickness_mm"),
             ("glazing.thickness", "strip", "thickness_mm"),
             ("glazing.width", "strip", "width_mm"), ("glazing.material", "strip", "material"))
"""``fabrication`` keys that every ``parts.csv`` row of a kind repeats: key, kind, column."""
DENSITY = (("beams.density", "beam", "mass_kg"), ("glazing.density", "strip", "mass_kg"))
"""Densities (kg/m³) that every row of a kind gives as its mass over area × thickness (``area_mm2``,
``thickness_mm``; not the glass, whose weight follows its make-up's plies)."""


def recompute_fabrication(v: Verification) -> dict[str, Figure]:
    """The ``fabrication`` values the rows of ``parts.csv`` repeat (the value most rows of the kind hold) and
    the densities their masses give (the median over the rows, to 0.1 %: masses are written rounded)."""
    parts = (v.parts or [])
    out: dict[str, Figure] = {}
    for key, kind, column in FROM_ROWS:
        values = [csv_value(r.get(column, "")) for r in parts if r["kind"] == kind and r.get(column, "") != ""]
        if not values:
            continue
        common = max(sorted(set(values)), key=values.count)
        number = _num(common)
        out[key] = Figure(common) if key.endswith("material") or math.isnan(number) \
            else Figure(number, 1e-6 * max(1.0, abs(number)))
    for key, kind, column in DENSITY:
        rho = [_num(r.get(column)) / (_num(r.get("area_mm2")) * _num(r.get("thickness_mm")) * 1e-9)
               for r in parts if r["kind"] == kind and _num(r.get("area_mm2")) > 1e3 and _num(r.get("thickness_mm")) > 0]
        rho = [x for x in rho if math.isfinite(x)]
        if rho:
            mid = float(np.median(rho))
            out[key] = Figure(mid, 1e-3 * mid)
    return out


def _rows(v: Verification, rel: str) -> list[dict[str, str]]:
    try:
        return read_csv(v.folder / rel)
    except (OSError, UnicodeDecodeError, ValueError):
        return []                                    # named by the check that reads the table


def _num(text: Any) -> float:
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def _differs(got: Any, want: Figure) -> bool:
    if isinstance(want.value, list):
        return not (isinstance(got, list) and len(got) == len(want.value)
                    and not any(_differs(g, Figure(w, want.tolerance * max(1.0, abs(w))))
                                for g, w in zip(got, want.value)))
    if isinstance(want.value, int) and not isinstance(want.value, bool):
        return not (is_number(got) and float(got) == want.value)
    if not is_number(got):
        return True
    return not abs(float(got) - float(want.value)) <= want.tolerance


def _show(value: Any) -> str:
    if isinstance(value, list):
        return "[" + ", ".join(_show(x) for x in value) + "]"
    return f"{value:.6g}" if isinstance(value, float) else repr(value)


@check("summary")
def check_summary(v: Verification) -> None:
    m = v.manifest
    summary = m.get("summary")
    if isinstance(summary, dict):
        want = recompute_summary(v)
        for key, fig in want.items():
            if key in summary and _differs(summary[key], fig):
                v.error("manifest.json", f"summary.{key}", f"{_show(summary[key])} written, {_show(fig.value)} "
                                                           "from the files")
        for prefix in ("glass", "plate"):
            bound, sheets = summary.get(f"{prefix}_lower_bound"), summary.get(f"{prefix}_sheets")
            if bound is None or not is_number(sheets):
                continue
            util, used = summary.get(f"{prefix}_utilisation"), float(sheets or 0)
            floor = math.ceil(float(util or 0) * used - 1e-9) if is_number(util) else 0
            if not (isinstance(bound, int) and floor <= bound <= used):
                v.error("manifest.json", f"summary.{prefix}_lower_bound",
                        f"{bound!r} is not a whole number from {floor} (the sheets' area) to {sheets} (the sheets used)")
    fab = m.get("fabrication", {})
    for path, fig in recompute_fabrication(v).items():
        section, key = path.split(".")
        got = fab.get(section, {}).get(key)
        if got is not None and (got != fig.value if isinstance(fig.value, str) else _differs(got, fig)):
            v.error("manifest.json", f"fabrication.{path}", f"{_show(got)} written, {_show(fig.value)} from the "
                                                            "rows of parts.csv")
    glazing = m.get("glazing")
    if isinstance(glazing, dict):
        for key, fig in recompute_glazing(v).items():
            if key in glazing and glazing[key] is not None and _differs(glazing[key], fig):
                v.error("manifest.json", f"glazing.{key}", f"{_show(glazing[key])} written, {_show(fig.value)} "
                                                           "from the files")
    v.checked.append("summary")
