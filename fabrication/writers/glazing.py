"""The glass support and the joints: ``glazing.step``, ``splices.step``, ``splices/<type>.dxf``,
``strip_cuts.csv``, ``welds.csv`` and ``bites.csv`` (see :mod:`fabrication.glazing`).

``glazing.step``: one solid per glazing strip (``GS-…``) and one per gasket (``GK-…``), each a rectangle
extruded once in the strip's frame (:class:`~fabrication.glazing.strips.Strip`); ``splices.step``: the two
cover plates of every splice, each outline with its bolt holes extruded once from the beam plate's face.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ppfab.frame import Frame

from ..contract import BITES_CSV, GLAZING_STEP, SPLICE_DIR, SPLICES_STEP, STRIP_CUTS_CSV, WELDS_CSV, gasket_id
from ..parts import csv_text
from . import Files, writer

if TYPE_CHECKING:  # pragma: no cover
    from ..pipeline.records import Build


def by_beam(solids: list, beams: list[str], name: str):
    """The product tree ``name → beam id → solids`` (``beams[k]`` the beam of ``solids[k]``)."""
    from build123d import Compound

    from ._step_text import step_label
    from .step import grouped

    return Compound(children=grouped(solids, beams), label=step_label(name))


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


def write_splice_dxfs(glazing, folder: Path) -> list[str]:
    """One flat DXF per cover plate type: outline and bolt holes on ``CUT`` (XDATA ``part_id`` = type,
    ``quantity``, ``material``, ``thickness_mm``), the type id on ``LABEL`` and a title under the plate naming
    the material and thickness (also the header custom properties ``PPFAB_MATERIAL``, ``PPFAB_THICKNESS_MM``)."""
    from ..contract import XDATA_APPID, stock_xdata, thickness_text
    from ..glazing.rows import splice_types
    from .dxf import _fixed_metadata, _new_doc, add_stock, save_doc

    types = splice_types(glazing.splices)
    first: dict[str, object] = {}
    count: dict[str, int] = {}
    for s in glazing.splices:
        t = types[s.part_ids[0]]
        first.setdefault(t, s)
        count[t] = count.get(t, 0) + 2
    folder.mkdir(parents=True, exist_ok=True)
    names = []
    for t, s in first.items():
        with _fixed_metadata():                 # ezdxf stamps the creation time into a new document
            doc = _new_doc()
        msp = doc.modelspace()
        outline = s.flat_outline                                   # type: ignore[attr-defined]
        pl = msp.add_lwpolyline([tuple(map(float, p)) for p in outline], close=True, dxfattribs={"layer": "CUT"})
        material = glazing.splice_params.material
        pl.set_xdata(XDATA_APPID, [(1000, f"part_id={t}"), (1000, f"quantity={count[t]}")]
                     + stock_xdata(material, s.thickness))                    # type: ignore[attr-defined]
        for x, y in s.flat_holes:                                  # type: ignore[attr-defined]
            msp.add_circle((float(x), float(y)), 0.5 * s.hole, dxfattribs={"layer": "CUT"})  # type: ignore[attr-defined]
        w, h = np.ptp(outline, axis=0)
        msp.add_text(f"{t} x{count[t]}", height=min(20.0, 0.1 * float(h)),
                     dxfattribs={"layer": "LABEL", "insert": (0.5 * float(w) - 40.0, 0.5 * float(h))})
        add_stock(doc, msp, (material, thickness_text(s.thickness)), f"{t} x{count[t]}",  # type: ignore[attr-defined]
                  height=min(10.0, 0.05 * float(h)), insert=(0.0, -15.0))
        name = f"{SPLICE_DIR}/{t}.dxf"
        save_doc(doc, folder.parent / name)
        names.append(name)
    return names


def _plain(value: float, digits: int = 3) -> float:
    v = round(float(value), digits)
    return 0.0 if v == 0 else v


@writer("glazing", order=25, enabled=lambda design: True)
def write_glazing(build: "Build", out: Path, files: Files) -> str:
    """The glazing and joint files of a build (nothing when the build has no glazing stage)."""
    from .step import export_step

    g = build.glazing
    if g is None:
        return "no glazing"
    name = build.design.info.name
    notes = []
    if g.strips:
        beams = [s.beam_id for s in g.strips for _ in range(2)]
        export_step(by_beam(strip_solids(g), beams, f"{name} glazing"), out / GLAZING_STEP,
                    description=f"glazing strips and gaskets of {name}")
        files["glazing_step"] = GLAZING_STEP
        rows = [{"panel": b.panel, "edge": b.edge, "mesh_edge": b.mesh_edge, "strip": b.strip,
                 "bite_mm": _plain(b.bite), "supported_mm": _plain(b.supported), "edge_mm": _plain(b.length),
                 "tilt_deg": _plain(b.tilt_deg, 4)} for b in g.bites]
        (out / BITES_CSV).write_text(csv_text(rows, list(rows[0]) if rows else ["panel"]), encoding="utf-8")
        files["bites_csv"] = BITES_CSV
        from ..glazing.rows import strip_rows

        cuts = [{"bar": r["bar"], "start_mm": r["bar_start_mm"], "length_mm": r["length_mm"],
                 "part_id": r["part_id"], "nest_tag": r["nest_tag"], "beam": r["beam"]}
                for r in strip_rows(g, build.beams)]
        cuts.sort(key=lambda r: (r["bar"], r["start_mm"]))
        (out / STRIP_CUTS_CSV).write_text(csv_text(cuts, ["bar", "start_mm", "length_mm", "part_id", "nest_tag",
                                                             "beam"]), encoding="utf-8")
        files["strip_cuts_csv"] = STRIP_CUTS_CSV
        notes.append(f"{len(g.strips)} strips, bite min {g.bite_min:.1f} mm")
    if g.splices:
        beams = [s.beam_id for s in g.splices for _ in s.part_ids]
        export_step(by_beam(splice_solids(g), beams, f"{name} splices"), out / SPLICES_STEP,
                    description=f"splice cover plates of {name}")
        files["splices_step"] = SPLICES_STEP
        files["splice_dxfs"] = write_splice_dxfs(g, out / SPLICE_DIR)
        notes.append(f"{len(g.splices)} splices")
    if g.welds:
        rows = [{"node": w.vertex if w.vertex >= 0 else "", "part": w.part, "to": w.to,
                 "dihedral_deg": _plain(w.dihedral_deg, 4), "weld_length_mm": _plain(w.length_mm),
                 "preparation": w.preparation, "throat_mm": w.throat_mm, "joint": w.joint}
                for w in g.welds]
        (out / WELDS_CSV).write_text(csv_text(rows, list(rows[0])), encoding="utf-8")
        files["welds_csv"] = WELDS_CSV
        notes.append(f"{len(g.welds)} welds")
    return ", ".join(notes) or "nothing to write"
