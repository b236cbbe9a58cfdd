"""The glass support and the joints: ``glazing.step``, ``splices.step``, ``splices/<type>.dxf``,
``strip_cuts.csv``, ``welds.csv`` and ``bites.csv`` (see :mod:`fabrication.glazing`).

``glazing.step``: one solid per glazing strip (``GS-…``) and one per gasket (``GK-…``), each a rectangle
extruded once in the strip's frame (:class:`~fabrication.glazing.strips.Strip`), and the retention parts
(:mod:`fabrication.glazing.retention`: setting blocks ``SB-…``, stops ``ST-…``, pressure gaskets ``CG-…``,
pressure plates ``CP-…`` and cover caps ``CC-…``), listed in ``retention.csv`` with every pane's restraint check
in ``restraint.csv``; written from the template (:mod:`fabrication.writers.step_template`, solids of one shape
once, placed per part), not through the CAD kernel; ``splices.step``: the two
cover plates of every splice, each outline with its bolt holes extruded once from the beam plate's face, written
from the template too (cover plates of one type are one shape, placed per plate).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ppfab.frame import Frame

from ..contract import (BEVEL_COLUMNS, BEVELS_CSV, BITES_COLUMNS, BITES_CSV, GLAZING_STEP, RESTRAINT_COLUMNS,
                        RESTRAINT_CSV, RETENTION_COLUMNS, RETENTION_CSV, SPLICE_DIR, SPLICES_STEP, STRIP_CUTS_COLUMNS,
                        STRIP_CUTS_CSV, WELDS_COLUMNS, WELDS_CSV, gasket_id)
from ..parts import csv_text
from . import Files, writer

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord


def strip_solids(glazing) -> list:
    """The strip and gasket solids of every strip (strip ``GS-…``, gasket ``GK-…``)."""
    from .step import _colour, _placed_prism

    out = []
    g = glazing.params.gasket_thickness
    for s in glazing.strips:
        outline = s.outline()
        strip = _placed_prism(outline, s.frame, 0.0, s.thickness, s.part_id)
        strip.color = _colour("rows")
        gasket = _placed_prism(outline, s.frame, s.thickness, g, gasket_id(s.part_id))
        gasket.color = _colour("mesh")
        out += [strip, gasket]
    return out


def strip_prisms(glazing) -> list:
    """The solids of :func:`strip_solids` as :class:`~fabrication.writers.step_template.PlanarSolid` records (the
    same prisms and colours), for the template writer."""
    from ..contract import COLOURS
    from .step_template import PlanarSolid

    out = []
    g = glazing.params.gasket_thickness
    for s in glazing.strips:
        outline = s.outline()
        out.append(PlanarSolid.prism(s.part_id, COLOURS["rows"], outline, s.frame, 0.0, s.thickness))
        out.append(PlanarSolid.prism(gasket_id(s.part_id), COLOURS["mesh"], outline, s.frame, s.thickness, g))
    return out


def retention_prisms(retention) -> list:
    """The solids of :func:`retention_solids` as :class:`~fabrication.writers.step_template.PlanarSolid`
    records."""
    from ..contract import COLOURS
    from .step_template import PlanarSolid

    return [PlanarSolid.prism(part.part_id, COLOURS[RETENTION_COLOURS[part.kind]], part.outline, part.frame,
                              part.z0, part.height) for part in retention.parts]


RETENTION_COLOURS = {"setting_block": "mesh", "stop": "rows", "pressure_gasket": "mesh", "pressure_plate": "cols",
                     "cover_cap": "cols"}
"""The colour (a family name of :func:`.step._colour`) of each kind of retention solid."""


def retention_solids(retention) -> list:
    """One prism per retention part (:class:`~fabrication.glazing.retention.Prism`), labelled by its part id."""
    from .step import _colour, _placed_prism

    out = []
    for part in retention.parts:
        solid = _placed_prism(part.outline, part.frame, part.z0, part.height, part.part_id)
        solid.color = _colour(RETENTION_COLOURS[part.kind])
        out.append(solid)
    return out


def retention_material(part, params) -> str:
    """The material cell of a retention part."""
    from ..glazing.retention import material_of

    return material_of(part.kind, params)


def retention_rows(retention) -> list[dict[str, object]]:
    """The rows of ``retention.csv`` (columns :data:`~fabrication.contract.RETENTION_COLUMNS`)."""
    p = retention.params
    rows = []
    for part in retention.parts:
        xs = retention.stations.get(part.part_id)
        screw = ""
        if xs is not None and retention.bolt is not None:
            screw = f"{retention.bolt.size} {retention.bolt.grade} stud welded on {part.strip}"
        rows.append({"part_id": part.part_id, "kind": part.kind, "owner": part.owner, "strip": part.strip,
                     "beam": part.beam, "length_mm": _plain(part.length), "width_mm": _plain(part.width),
                     "height_mm": _plain(part.height), "material": retention_material(part, p), "screw": screw,
                     "screws": len(xs) if xs is not None else "",
                     "screw_stations_mm": ";".join(f"{_plain(x, 1):g}" for x in xs) if xs is not None else ""})
        bend = (retention.bending or {}).get(part.part_id)
        if bend is not None:
            rows[-1].update({"plate_load_N_mm": _plain(bend.load, 4), "plate_span_mm": _plain(bend.span, 1),
                             "plate_end_mm": _plain(bend.end, 1), "plate_stress_N_mm2": _plain(bend.stress, 2),
                             "plate_stress_limit_N_mm2": _plain(bend.stress_limit, 2),
                             "plate_deflection_mm": _plain(bend.deflection, 4),
                             "plate_deflection_limit_mm": _plain(bend.deflection_limit, 3)})
    return rows


def restraint_rows(retention) -> list[dict[str, object]]:
    """The rows of ``restraint.csv`` (columns :data:`~fabrication.contract.RESTRAINT_COLUMNS`)."""
    rows = []
    for r in retention.panes:
        rows.append({"panel": r.panel, "slope_deg": _plain(r.slope_deg, 3), "weight_kg": _plain(r.weight_kg),
                     "down_edge": r.down_edge, "strip": r.strip, "setting_blocks": 2,
                     "block_load_N": _plain(r.block_load_N, 1), "block_pressure_N_mm2": _plain(r.block_pressure, 4),
                     "block_contact_mm": _plain(r.block_contact_mm, 2),
                     "stops": "yes" if r.stops else "no", "uplift_kN": _plain(r.uplift_kN),
                     "screws": _plain(r.screws, 2), "resistance_kN": _plain(r.resistance_kN, 2),
                     "clamp_bite_mm": "" if r.clamp_bite_mm != r.clamp_bite_mm else _plain(r.clamp_bite_mm, 2),
                     "max_screw_spacing_mm": _plain(r.max_spacing_mm, 1) if retention.stations else "",
                     "plate_utilisation": "" if r.plate_utilisation != r.plate_utilisation
                     else _plain(r.plate_utilisation, 3),
                     "silicone_bite_mm": _plain(r.silicone_bite_mm, 1),
                     "ok": "yes" if not r.failures(retention.params) else "; ".join(r.failures(retention.params))})
    return rows


def splice_solids(glazing) -> list:
    """Two cover plates per splice, on both faces of the beam plate, with their bolt holes."""
    from build123d import Face, Location, Plane, Vector, Wire, Solid

    out = []
    for s in glazing.splices:
        for pid, sign in zip(s.part_ids, (1.0, -1.0)):
            z0 = 0.5 * s.beam_thickness if sign > 0 else -0.5 * s.beam_thickness - s.thickness
            outer = Wire.make_polygon([Vector(float(x), float(y), z0) for x, y in s.outline], close=True)
            holes = [Wire.make_circle(0.5 * s.hole, Plane(origin=(float(x), float(y), z0))) for x, y in s.holes]
            solid = Solid.extrude(Face(outer, holes), Vector(0.0, 0.0, s.thickness))
            f: Frame = s.frame
            plane = Plane(origin=tuple(map(float, f.origin)), x_dir=tuple(map(float, f.ex)),
                          z_dir=tuple(map(float, f.normal)))
            solid = solid.moved(Location(plane))
            solid.label = pid
            out.append(solid)
    return out


def splice_prisms(glazing) -> list:
    """The solids of :func:`splice_solids` as :class:`~fabrication.writers.step_template.PlanarSolid` records (the
    same outlines, bolt holes and places, no colour), for the template writer."""
    from .step_template import PlanarSolid

    out = []
    for s in glazing.splices:
        holes = np.c_[np.asarray(s.holes, dtype=float).reshape(-1, 2), np.full(len(s.holes), float(s.hole))]
        for pid, sign in zip(s.part_ids, (1.0, -1.0)):
            z0 = 0.5 * s.beam_thickness if sign > 0 else -0.5 * s.beam_thickness - s.thickness
            out.append(PlanarSolid.prism(pid, None, np.asarray(s.outline, dtype=float), s.frame, z0,
                                         float(s.thickness), holes))
    return out


def _splice_type_firsts(glazing) -> tuple[dict[str, object], dict[str, int]]:
    """Cover-plate type id → its first splice (in splice order) and → how many cover plates are of it."""
    from ..glazing.rows import splice_types

    types = splice_types(glazing.splices)
    first: dict[str, object] = {}
    count: dict[str, int] = {}
    for s in glazing.splices:
        t = types[s.part_ids[0]]
        first.setdefault(t, s)
        count[t] = count.get(t, 0) + 2
    return first, count


def splice_dxf_files(glazing) -> list[str]:
    """The flat DXFs of the cover-plate types (``splices/SP125x285-2.dxf`` …), in the order they are written."""
    return [f"{SPLICE_DIR}/{t}.dxf" for t in _splice_type_firsts(glazing)[0]]


def glazing_files(build: "BuildRecord") -> Files:
    """The files :func:`write_glazing` writes: glazing.step, the retention and restraint tables (with
    retention), bites, strip cuts and bevels (with strips); splices.step and the cover plates' DXFs (with
    splices); welds.csv (with welds)."""
    g = build.glazing
    if g is None:
        return {}
    files: Files = {}
    if g.strips:
        files["glazing_step"] = GLAZING_STEP
        if build.retention is not None:
            files["retention_csv"] = RETENTION_CSV
            files["restraint_csv"] = RESTRAINT_CSV
        files["bites_csv"] = BITES_CSV
        files["strip_cuts_csv"] = STRIP_CUTS_CSV
        files["bevels_csv"] = BEVELS_CSV
    if g.splices:
        files["splices_step"] = SPLICES_STEP
        files["splice_dxfs"] = splice_dxf_files(g)
    if g.welds:
        files["welds_csv"] = WELDS_CSV
    return files


def write_splice_dxfs(glazing, folder: Path) -> None:
    """One flat DXF per cover plate type: outline and bolt holes on ``CUT`` (XDATA ``part_id`` = type,
    ``quantity``, ``material``, ``thickness_mm``), the type id on ``LABEL`` and a title under the plate naming
    the material and thickness (also the header custom properties ``PPFAB_MATERIAL``, ``PPFAB_THICKNESS_MM``).

    The type label lies inside the plate, clear of its outline (the skewed ends included) and of every bolt hole
    by :data:`SPLICE_LABEL_MARGIN`, upright along the plate's long side (:func:`~fabrication.marking.place_label`,
    at most 20 mm high); on a plate with no room for it at :data:`SPLICE_LABEL_MIN` mm it goes above the plate."""
    from ..contract import XDATA_APPID, stock_xdata, thickness_text
    from .dxf import _fixed_metadata, _new_doc, add_stock, save_doc

    first, count = _splice_type_firsts(glazing)
    folder.mkdir(parents=True, exist_ok=True)
    for t, s in first.items():
        with _fixed_metadata():                 # ezdxf stamps the creation time into a new document
            doc = _new_doc()
        msp = doc.modelspace()
        outline = s.flat_outline                                   # type: ignore[attr-defined]
        pl = msp.add_lwpolyline([tuple(map(float, p)) for p in outline], close=True, dxfattribs={"layer": "CUT"})
        material = glazing.splice_params.material
        pl.set_xdata(XDATA_APPID, [(1000, f"part_id={t}"), (1000, f"quantity={count[t]}")]
                     + stock_xdata(material, s.thickness))                    # type: ignore[attr-defined]
        holes = [(float(x), float(y)) for x, y in s.flat_holes]   # type: ignore[attr-defined]
        for x, y in holes:
            msp.add_circle((x, y), 0.5 * s.hole, dxfattribs={"layer": "CUT"})  # type: ignore[attr-defined]
        label = f"{t} x{count[t]}"
        insert, height, angle = splice_label_place(np.asarray(outline, dtype=float), holes,
                                                   0.5 * float(s.hole), label)  # type: ignore[attr-defined]
        msp.add_text(label, height=height, rotation=angle, dxfattribs={"layer": "LABEL", "insert": insert})
        h = float(np.ptp(np.asarray(outline, dtype=float), axis=0)[1])
        add_stock(doc, msp, (material, thickness_text(s.thickness)), label,  # type: ignore[attr-defined]
                  height=min(10.0, 0.05 * h), insert=(0.0, -15.0))
        name = f"{SPLICE_DIR}/{t}.dxf"
        save_doc(doc, folder.parent / name)


SPLICE_LABEL_MARGIN, SPLICE_LABEL_MIN, SPLICE_LABEL_MAX = 3.0, 3.0, 20.0
"""Clearance of a cover plate's label from its outline and holes, and its smallest and largest height, mm."""


def splice_label_place(outline: np.ndarray, holes: list[tuple[float, float]], radius: float,
                       label: str) -> tuple[tuple[float, float], float, float]:
    """``(insert, height, rotation_deg)`` of a cover plate's label (left baseline insertion, as the DXF ``TEXT``
    is written): its box (:func:`~fabrication.marking.place_label`) inside ``outline (k, 2)`` and off the
    ``holes`` (circles of ``radius``); the text's baseline 0.45 heights under the box's middle, so cap height and
    descenders stay inside the box.  Without room, above the plate, horizontal."""
    from ..marking import LABEL_CHAR_WIDTH, TextLine, place_label

    ring = np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False)
    circles = tuple(np.c_[x + 1.02 * radius * np.cos(ring), y + 1.02 * radius * np.sin(ring)] for x, y in holes)
    where = place_label(outline, [TextLine(label, "LABEL")], margin=SPLICE_LABEL_MARGIN,
                        max_height=SPLICE_LABEL_MAX, min_height=SPLICE_LABEL_MIN, keep_out_areas=circles)
    line = where.lines[0]
    h, angle = float(line.height), float(line.rotation_deg)
    if not where.fits:
        h, angle = SPLICE_LABEL_MIN * 2, 0.0
        top = float(outline[:, 1].max())
        return (float(outline[:, 0].min()), top + SPLICE_LABEL_MARGIN + 0.3 * h), h, angle
    a = np.radians(angle)
    u, v = np.array([np.cos(a), np.sin(a)]), np.array([-np.sin(a), np.cos(a)])
    start = line.centre - 0.5 * LABEL_CHAR_WIDTH * len(label) * h * u - 0.45 * h * v
    return (float(start[0]), float(start[1])), h, angle


def _plain(value: float, digits: int = 3) -> float:
    v = round(float(value), digits)
    return 0.0 if v == 0 else v


@writer("glazing", order=25, declare=glazing_files)
def write_glazing(build: "BuildRecord", out: Path, files: Files) -> str:
    """The glazing and joint files of a build (nothing when the build has no glazing stage)."""
    from ._step_text import step_label
    from .step_template import Assembly, grouped, write_step

    g = build.glazing
    if g is None:
        return "no glazing"
    name = build.design.info.name
    notes = []
    if g.strips:
        retention = build.retention
        beams = [s.beam_id for s in g.strips for _ in range(2)]
        solids = strip_prisms(g)
        what = "glazing strips and gaskets"
        if retention is not None:
            solids += retention_prisms(retention)
            beams += [part.beam or "unsupported" for part in retention.parts]
            what += ", setting blocks, stops and pressure plates"
        write_step(Assembly(step_label(f"{name} glazing"), list(grouped(solids, beams))), out / GLAZING_STEP,
                   description=f"{what} of {name}")
        if retention is not None:
            (out / RETENTION_CSV).write_text(csv_text(retention_rows(retention), RETENTION_COLUMNS), encoding="utf-8")
            (out / RESTRAINT_CSV).write_text(csv_text(restraint_rows(retention), RESTRAINT_COLUMNS),
                                             encoding="utf-8")
            bad = [r for r in retention.panes if r.failures(g.params)]
            notes.append(f"{len(retention.parts)} retention parts"
                         + (f", {len(bad)} pane(s) not held (restraint.csv)" if bad else ""))
        rows = [{"panel": b.panel, "edge": b.edge, "mesh_edge": b.mesh_edge, "strip": b.strip,
                 "bite_mm": _plain(b.bite), "supported_mm": _plain(b.supported), "edge_mm": _plain(b.length),
                 "tilt_deg": _plain(b.tilt_deg, 4)} for b in g.bites]
        (out / BITES_CSV).write_text(csv_text(rows, BITES_COLUMNS), encoding="utf-8")
        from ..glazing.rows import strip_rows

        cuts = [{"bar": r["bar"], "start_mm": r["bar_start_mm"], "length_mm": r["length_mm"],
                 "part_id": r["part_id"], "nest_tag": r["nest_tag"], "beam": r["beam"]}
                for r in strip_rows(g, build.beams)]
        cuts.sort(key=lambda r: (r["bar"], r["start_mm"]))
        (out / STRIP_CUTS_CSV).write_text(csv_text(cuts, STRIP_CUTS_COLUMNS), encoding="utf-8")
        from ..glazing.bevel import strip_bevels

        bevels = strip_bevels(g.strips, build.beams.plates, g.params.bevel_min_deg, as_cut=True)
        rows = [{"strip": b.strip, "plate": b.plate, "lean_deg": _plain(b.lean_deg, 3), "overlap_mm": _plain(b.overlap_mm),
                 "delta_mm": _plain(b.delta_mm), "bevel": b.text()} for b in bevels]
        (out / BEVELS_CSV).write_text(csv_text(rows, BEVEL_COLUMNS), encoding="utf-8")
        notes.append(f"{len(g.strips)} strips, bite min {g.bite_min:.1f} mm")
        if any(b.bevelled for b in bevels):
            notes.append(f"{sum(b.bevelled for b in bevels)} plate top edges bevelled "
                         f"(lean up to {max(b.lean_deg for b in bevels):.1f}°)")
    if g.splices:
        beams = [s.beam_id for s in g.splices for _ in s.part_ids]
        write_step(Assembly(step_label(f"{name} splices"), list(grouped(splice_prisms(g), beams))),
                   out / SPLICES_STEP, description=f"splice cover plates of {name}")
        write_splice_dxfs(g, out / SPLICE_DIR)
        notes.append(f"{len(g.splices)} splices")
    if g.welds:
        rows = [{"node": w.vertex if w.vertex >= 0 else "", "part": w.part, "to": w.to,
                 "dihedral_deg": _plain(w.dihedral_deg, 4), "weld_length_mm": _plain(w.length_mm),
                 "preparation": w.preparation, "throat_mm": w.throat_mm, "joint": w.joint}
                for w in g.welds]
        (out / WELDS_CSV).write_text(csv_text(rows, WELDS_COLUMNS), encoding="utf-8")
        notes.append(f"{len(g.welds)} welds")
    return ", ".join(notes) or "nothing to write"
