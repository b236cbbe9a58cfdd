"""The output contract in one place: columns, layers, DXF version, XDATA layout, part ids and file names.

Other programs read ppfab's files; the writers (:mod:`fabrication.writers`) and ``ppfab verify``
(:mod:`fabrication.verify`) both take every name and format from here, so the two cannot drift apart.
The README's "Contract" section documents the same.
"""

from __future__ import annotations

import math
import re
from typing import TYPE_CHECKING, Any

from .model.part import NOT_ON_A_SHEET as NOT_ON_A_SHEET  # ``sheet`` of a part on no cutting sheet (0)

if TYPE_CHECKING:  # pragma: no cover
    from ppfab.support.structure import SupportStructure

# -- parts.csv / parts.json -----------------------------------------------------------------------------

PARTS_CONTRACT_COLUMNS = ["part_id", "kind", "sheet", "x", "y", "rotation_deg", "nest_tag", "area_mm2"]
"""The first columns of ``parts.csv``, in this order (DESIGN.md)."""

PARTS_KNOWN_COLUMNS = ["mirrored", "sheet_file", "face", "face_i", "face_j", "type_id", "material", "thickness_mm",
                       "width_mm", "height_mm", "perimeter_mm", "weight_kg", "planarity_dev_mm", "min_angle_deg",
                       "panel_flags", "outside"]
"""Further columns of ``parts.csv`` in this order when present; any others follow sorted by name.  A structured
value (a list or a table: a beam plate's ``nodes``, ``frame``, ``plane``) is one JSON cell (:func:`csv_cell`).
``panel_flags`` was ``flags`` before 0.2 (it shadowed ``pandas.DataFrame.flags``; docs/migration.md)."""

PARTS_MORE_COLUMNS: dict[str, str] = {
    "bar": "strip: the 1-based stock bar it is cut from (strip_cuts.csv)",
    "bar_start_mm": "strip: where it starts along its bar",
    "beam": "strip, splice cover plate, retention part, screw: the beam plate (part id) it sits on",
    "beam_id": "beam plate: the beam (one planar mesh polyline, split into pieces) it belongs to",
    "bevels": "beam plate: the spans of its top edge bevelled under leaning strips (bevels.csv)",
    "bite_min_mm": "panel: its smallest bite on a glazing strip",
    "bolts": "splice cover plate (side A): the bolt set through both plates, '<n> x <bolt>'",
    "depth_mm": "beam plate: its depth across the support plane",
    "diameter_mm": "screw: its shank diameter",
    "edge_nodes": "strip: the two nodes of its mesh edge, 'a;b'",
    "family": "beam plate, strip, splice cover plate: the mesh polyline family, rows or cols",
    "frame": "beam plate, retention part, screw: JSON {origin, x, y, normal} placing the flat outline (or the "
             "part's box from a corner of its underside) in the building, mm",
    "gasket": "strip: the gasket laid on it (material, width x thickness, length)",
    "hole_mm": "beam plate, splice cover plate: the bolt hole diameter",
    "holes": "beam plate, splice cover plate: how many bolt holes",
    "joins": "beam plate, splice cover plate: the pieces of the beam joined at its cuts, ';'-separated",
    "length_mm": "beam plate, strip, retention part, screw: its length",
    "mass_kg": "beam plate, strip, splice cover plate, retention part, screw: its mass (steel as cut, before "
               "planing a bevel; screws: all of the row's quantity)",
    "nodes": "beam plate: JSON list of the mesh vertices it runs through, in order",
    "notches": "beam plate: JSON list of the notches of its top edge under strips of other beams that run over "
               "it, each {strip, node, depth_mm, length_mm} (fabrication.beams.notch)",
    "owner": "retention part: the pane it holds (a screw: the pressure plate it clamps)",
    "piece": "beam plate: 0-based piece of its beam",
    "pieces": "beam plate: how many pieces its beam is cut into",
    "plane": "beam plate: JSON [a, b, c, d] of its support plane a x + b y + c z = d (mm)",
    "quantity": "retention part, screw: how many (a screw row: the screws of one plate)",
    "rotation": "panel: how the pane may turn on the stock sheet ([panels] rotation)",
    "screw_stations_mm": "screw: the stations of the screws along the strip, ';'-separated",
    "setting_blocks": "panel: the setting blocks under its lower edge, '2 x <length> mm'",
    "slots": "beam plate: how many half-lap slots are cut into it",
    "splices": "beam plate: the splice cover plates on its cuts, ';'-separated",
    "strip": "retention part, screw: the glazing strip it sits over",
    "weld": "strip: its weld to the beam plate",
}
"""Every further column of ``parts.csv`` with what it holds (units mm and kg unless said); in the file they
follow :data:`PARTS_KNOWN_COLUMNS`, sorted by name.  A cell that does not apply to a part's kind is blank."""

ORDER_COLUMNS = ["type_id", "quantity", "parts", "width_mm", "height_mm", "area_mm2", "material", "thickness_mm",
                 "rotations", "mirror_allowed", "file"]
"""The first columns of ``glass_order.csv`` (one row per panel type); :data:`ORDER_SHAPE_COLUMNS` follow."""

ORDER_CORNERS = 4
"""Corners per pane in ``glass_order.csv`` (the panels of a quad mesh are quadrilaterals)."""

ORDER_SHAPE_COLUMNS = (["weight_kg", "perimeter_mm", "edge_finish", "coated_side"]
                       + [f"c{k}_{xy}_mm" for k in range(1, ORDER_CORNERS + 1) for xy in "xy"]
                       + [f"edge_{k}{k % ORDER_CORNERS + 1}_mm" for k in range(1, ORDER_CORNERS + 1)]
                       + ["diag_13_mm", "diag_24_mm"]
                       + [f"angle_{k}_deg" for k in range(1, ORDER_CORNERS + 1)])
"""The shape of a pane type as a processor checks it, after :data:`ORDER_COLUMNS`: weight of one pane, perimeter,
edge work and coated side (``[panels]``), the corners 1–4 in the panel's own frame (the per-type DXF: corner 1 at
the origin, edge 12 along +x, seen from outside, counter-clockwise), the edge lengths 12, 23, 34, 41, both
diagonals and the interior corner angles."""

ORDER_MAKEUP_COLUMNS = ["makeup", "glass", "laminated", "heat_soak", "thickness_tolerance_mm", "size_tolerance_mm",
                        "stamp_corner", "stamp_face", "coated_face"]
"""The make-up of a pane type as the processor orders it, after :data:`ORDER_SHAPE_COLUMNS`
(:mod:`fabrication.panels.makeup`): the build-up outside ply first, the glass in words, laminated (``yes``/``no``),
the heat-soak standard of toughened plies or ``no``, the ± tolerances of thickness and of the cut size (mm), the
corner (1 = the reference corner) and face (``inside``) of the safety-glass stamp, and the face number of a coating
(1 = outside face, counting every glass surface from outside; ``none``)."""

ORDER_ALL_COLUMNS = ORDER_COLUMNS + ORDER_SHAPE_COLUMNS + ORDER_MAKEUP_COLUMNS
"""Every column of ``glass_order.csv``, in order."""

RETENTION_KINDS = ("setting_block", "stop", "pressure_gasket", "pressure_plate", "cover_cap", "screw")
"""The ``kind`` of a retention row of ``parts.csv`` (:mod:`fabrication.glazing.retention`): the prisms of
``glazing.step`` (setting blocks, stops, pressure gaskets, pressure plates, cover caps), one row each, and the
clamping screws of a pressure plate, one row per plate with their ``quantity`` (:func:`screw_set_id`)."""

PART_KINDS = ("panel", "beam", "strip", "splice") + RETENTION_KINDS
"""The ``kind`` of a ``parts.csv`` row: a glass ``panel``, a ``beam`` plate (or a piece or segment of one), a
glazing ``strip`` (flat bar on a beam's top edge, cut from stock bars: no ``sheet``, ``bar``/``bar_start_mm``
and ``strip_cuts.csv`` say where), a ``splice`` cover plate (cut to its type's DXF in ``splices/``: no
``sheet``; ``joins`` names the two beam pieces it joins) and the retention parts (:data:`RETENTION_KINDS`)."""

RETENTION_PART_COLUMNS = ["owner", "strip", "beam", "length_mm", "width_mm", "height_mm", "quantity", "mass_kg",
                          "frame", "screw_stations_mm", "diameter_mm"]
"""The columns of a retention row of ``parts.csv`` beyond the common ones (``material``, ``thickness_mm`` = the
height): the pane (blocks, stops) or strip (plates, their gaskets and caps) it belongs to and the strip and beam
under it, its size (length along ``frame``'s ``x_dir``, width along ``y_dir``, height along ``normal``, from the
frame's ``origin`` at the part's underside corner), ``quantity`` (1; a screw row: the screws of its plate) and
``mass_kg`` of the row (all its pieces); a screw row's ``frame`` is the strip's at the plate's start on the strip's
top face, its screws at ``x`` = each of ``screw_stations_mm`` on the centre line ``y = 0``, each a cylinder of
``diameter_mm`` and ``length_mm`` along ``normal``."""

SHEET_KINDS = ("panel", "beam")
"""The kinds nested on the cutting sheets (``sheet``, ``x``, ``y``, ``rotation_deg`` set, one CUT outline on
``sheet_file``); rows of the other kinds have ``sheet`` = :data:`NOT_ON_A_SHEET` and leave the placement cells
empty."""


# -- nodes.csv / nodes.json ------------------------------------------------------------------------------

NODES_CONTRACT_COLUMNS = ["node_id", "vertex", "x", "y", "z", "axis_x", "axis_y", "axis_z", "beams"]
"""Columns ``nodes.csv`` must have (DESIGN.md)."""

NODES_COLUMNS = ["node_id", "vertex", "i", "j", "x", "y", "z", "axis_x", "axis_y", "axis_z", "beams", "roles",
                 "joint", "valence", "boundary", "dihedral_deg", "beam_panel_deg", "torsion_deg", "torsion_mm",
                 "slot_width_mm", "trims_mm"]
"""All columns of ``nodes.csv`` as written."""

# -- DXF -------------------------------------------------------------------------------------------------

DXF_VERSION = "R2010"
"""The DXF version written (AC1024); the contract promises R2000 (AC1015) or newer."""

DXF_OLDEST = "AC1015"
"""The oldest DXF version ``ppfab verify`` accepts (R2000)."""

DXF_INSUNITS_MM = 4

LAYERS = {"SHEET": 8, "TRIM": 3, "CUT": 1, "LABEL": 5, "MARK": 6, "MARK_BACK": 4, "BEVEL": 2}
"""Layer name → ACI colour.  SHEET stock outline, TRIM usable area, CUT part outlines (one closed LWPOLYLINE
per part), LABEL part id text (never machined), MARK scribe/marking lines and engraved text on the face that
looks up from the sheet (node axes, the part id and, on a beam plate, its face mark), MARK_BACK the marks of
the face underneath (node axes at the same sheet coordinates, the underside's face mark as backward text, read
when the plate is turned over)."""

REQUIRED_LAYERS = ("SHEET", "TRIM", "CUT", "LABEL", "MARK")
"""The layers every cutting file must have (DESIGN.md); ``MARK_BACK`` is written as well but not required."""

BEVEL_LAYER = "BEVEL"
"""The layer of a beam plate's bevelled top-edge spans: the raised edge as cut (an open polyline, XDATA
``part_id=…``, ``bevel=…``) and the instruction as TEXT (``BEVEL 13.6° U+ +1.45``: plane at 13.6° to the strip,
the face marked ``U+`` keeps the edge, ``Δ`` mm; :mod:`fabrication.beams.bevel_cut`); never cut, read by the shop
that planes the bevel."""

MARK_LAYERS = ("MARK", "MARK_BACK")
"""The layers a CAM engraves or inks; TEXT on them carries XDATA ``part_id=…`` and ``mark=id|face``."""

FACE_MARK_PATTERN = r"^[UWR][+-]$"
"""A face mark: the plate family's letter and the side of its plane ``n·x + d = 0`` (``parts.csv`` ``plane``)
the marked face looks to (see :mod:`fabrication.marking`)."""

KERF_NOTES = {
    "laser": "kerf 0.2-0.4 mm; sharp inner corners (tool_radius 0)",
    "plasma": "kerf 1.5-3 mm; inner corners need a relief radius of about the kerf",
    "waterjet": "kerf 0.8-1.2 mm; inner corners radius about half the kerf",
    "router": "kerf = cutter diameter; dog-bone corners with tool_radius = cutter radius",
}
"""Notes per cutting process written into each cutting sheet's header (``$CUSTOMPROPERTY``) and the report:
outlines are nominal (no kerf offset); the CAM applies its kerf compensation."""

XDATA_APPID = "PPFAB"
"""The application id of the XDATA on every CUT outline: group-1000 strings ``key=value``."""

XDATA_KEYS = ("part_id", "nest_tag", "kind", "type_id")
"""The ``key=value`` strings on a CUT outline, in this order (``part_id`` and ``nest_tag`` are the contract)."""


STOCK_XDATA_KEYS = ("material", "thickness_mm")
"""The ``key=value`` strings after :data:`XDATA_KEYS` on every CUT outline: the part's material and thickness as
``parts.csv`` gives them (a splice DXF's outline carries them after ``part_id`` and ``quantity``)."""

STOCK_HEADER_VARS = ("PPFAB_MATERIAL", "PPFAB_THICKNESS_MM")
"""The ``$CUSTOMPROPERTY`` header entries (R2004 and later) of every DXF ppfab writes: the material and thickness
of the parts on it (distinct values joined by ``"; "``); the title text on ``LABEL`` ends with
``material <material>, thickness <t> mm``."""


def stock_xdata(material: str, thickness_mm: float | str) -> list[tuple[int, str]]:
    """``[(1000, "material=…"), (1000, "thickness_mm=…")]`` (thickness as ``%g``).

    >>> stock_xdata("S355 plate", 10.0)
    [(1000, 'material=S355 plate'), (1000, 'thickness_mm=10')]
    """
    return [(1000, f"material={material}"), (1000, f"thickness_mm={thickness_text(thickness_mm)}")]


def thickness_text(value: float | str) -> str:
    """A thickness as written to DXF XDATA, headers and titles: ``%g`` of the number (``"12"``, ``"10.76"``)."""
    try:
        return f"{float(value):g}"
    except (TypeError, ValueError):
        return str(value)


def stock_title(material: str, thickness: str) -> str:
    """The end of a DXF title: ``material S355 plate, thickness 10 mm``."""
    return f"material {material}, thickness {thickness} mm"


DIM_LAYER, DIM_COLOUR = "DIM", 2
"""The layer of the dimensions (edges and diagonals) in the per-type DXFs: annotation, never machined."""

LEGACY_DXF = {"R12": "dxf_r12", "R2000": "dxf_r2000"}
"""``[output] dxf_r12`` / ``dxf_r2000``: the DXF version → the folder holding a copy of every cutting sheet and
per-type DXF in that version (same relative paths; R12 draws CUT outlines as closed POLYLINEs and has no
``$INSUNITS``)."""

R12_OLDEST = "AC1009"


def xdata_strings(part_id: str, nest_tag: str, kind: str, type_id: str) -> list[tuple[int, str]]:
    """The XDATA tags of a CUT outline: ``[(1000, "part_id=…"), (1000, "nest_tag=…"), …]``.

    >>> xdata_strings("P-0001", "G01-001", "panel", "T001")[:2]
    [(1000, 'part_id=P-0001'), (1000, 'nest_tag=G01-001')]
    """
    values = (part_id, nest_tag, kind, type_id)
    return [(1000, f"{k}={v}") for k, v in zip(XDATA_KEYS, values)]


def xdata_fields(entity: Any) -> dict[str, str]:
    """The ``key=value`` strings of an ezdxf entity's :data:`XDATA_APPID` XDATA as a dict (empty without any):
    the reading of :func:`xdata_strings` and the other tags ppfab writes."""
    out: dict[str, str] = {}
    if entity.has_xdata(XDATA_APPID):
        for code, value in entity.get_xdata(XDATA_APPID):
            if code == 1000 and "=" in str(value):
                k, val = str(value).split("=", 1)
                out[k] = val
    return out


# -- identifiers -----------------------------------------------------------------------------------------

def digits(count: int, minimum: int = 2) -> int:
    """Width of zero-padded numbers ``0 … count − 1`` (at least ``minimum``)."""
    return max(minimum, len(str(max(count - 1, 0))))


def panel_id_grid(i: int, j: int, wi: int, wj: int) -> str:
    """``P-U07-V12``: the panel of face ``f[i, j]`` of a regular patch."""
    return f"P-U{i:0{wi}d}-V{j:0{wj}d}"


def panel_id(face: int, width: int) -> str:
    """``P-0042``: the panel of face 42 of a general quad mesh."""
    return f"P-{face:0{width}d}"


def beam_id_grid(family: int, index: int, width: int) -> str:
    """``B-U03`` (row polyline 3, plane ``U_3``) or ``B-W07`` (column 7)."""
    return f"B-{'UW'[family]}{index:0{width}d}"


def beam_id(polyline: int, width: int) -> str:
    """``B-R0012``: polyline 12 of a general mesh."""
    return f"B-R{polyline:0{width}d}"


def beam_ids(support: "SupportStructure") -> list[str]:
    """Part id stem of every polyline: ``B-U03``/``B-W07`` on a regular patch, ``B-R0012`` otherwise."""
    lines = support.polylines
    if support.mesh.grid is not None:
        m1, n1 = support.mesh.grid.shape
        w = digits(max(m1, n1))
        out = []
        for k in range(len(lines)):
            found = support.polyline_grid_index(k)
            assert found is not None
            fam, idx = found
            out.append(beam_id_grid(fam, idx, w))
        return out
    w = digits(len(lines), 4)
    return [beam_id(k, w) for k in range(len(lines))]


def piece_id(beam: str, piece: int, width: int) -> str:
    """``B-U03-S02``: piece 2 of a long beam, or segment 2 of a segmented joint."""
    return f"{beam}-S{piece:0{width}d}"


def strip_id(beam: str, k: int) -> str:
    """``GS-U03-07``: glazing strip 7 (0-based, along the beam) on beam ``B-U03``."""
    return f"GS{beam[1:]}-{k:02d}"


def gasket_id(strip: str) -> str:
    """``GK-U03-07``: the gasket on strip ``GS-U03-07`` (a solid of ``glazing.step``, no row of its own: the
    strip's ``gasket`` cell describes it)."""
    return "GK" + strip[2:]


def pressure_plate_id(strip: str) -> str:
    """``CP-U03-07``: the pressure (clamping) plate over strip ``GS-U03-07`` (a solid of ``glazing.step``, a row
    of ``retention.csv``)."""
    return "CP" + strip[2:]


def pressure_gasket_id(strip: str) -> str:
    """``CG-U03-07``: the EPDM gasket between the pressure plate over strip ``GS-U03-07`` and the glass."""
    return "CG" + strip[2:]


def cover_cap_id(strip: str) -> str:
    """``CC-U03-07``: the cover cap clipped over the pressure plate over strip ``GS-U03-07``."""
    return "CC" + strip[2:]


def setting_block_id(panel: str, k: int) -> str:
    """``SB-U07-V12-1``: setting block ``k`` (1 or 2) under the down-slope edge of pane ``P-U07-V12``."""
    return f"SB{panel[1:]}-{k}"


def screw_set_id(strip: str) -> str:
    """``SC-U03-07``: the clamping screws of the pressure plate over strip ``GS-U03-07`` (one ``parts.csv`` row
    with their quantity, a bill of materials' line)."""
    return "SC" + strip[2:]


def stop_id(panel: str, k: int) -> str:
    """``ST-U07-V12-1``: the steel stop behind setting block ``k`` of pane ``P-U07-V12``."""
    return f"ST{panel[1:]}-{k}"


RETENTION_PREFIXES = ("CP-", "CG-", "CC-", "SB-", "ST-")
"""The part id prefixes of the retention solids of ``glazing.step`` (pressure plates, their gaskets and caps,
setting blocks, stops): rows of ``retention.csv`` and of ``parts.csv`` (:data:`RETENTION_KINDS`)."""


def splice_plate_ids(beam: str, piece: int) -> tuple[str, str]:
    """``(SP-U03-02A, SP-U03-02B)``: the two cover plates (both faces of the plate) of the cut after piece 2
    of beam ``B-U03``."""
    return f"SP{beam[1:]}-{piece:02d}A", f"SP{beam[1:]}-{piece:02d}B"


def node_id(vertex: int) -> str:
    """``N0042``: the node at OBJ vertex 42."""
    return f"N{vertex:04d}"


def nest_tag(prefix: str, sheet: int, part: int, sheet_width: int, part_width: int) -> str:
    """``G03-017``: 1-based ``sheet`` 3, 1-based ``part`` 17 on it, with the glass or plate prefix."""
    return f"{prefix}{sheet:0{sheet_width}d}-{part:0{part_width}d}"


# -- file names ------------------------------------------------------------------------------------------

GLASS_SHEET_DIR, GLASS_SHEET_PREFIX = "glass", "glass"
GLAZING_STEP, SPLICES_STEP, SPLICE_DIR = "glazing.step", "splices.step", "splices"
"""The strips (``GS-…``) and gaskets (``GK-…``); the splice cover plates with their bolt holes; the folder of
one flat DXF per cover-plate type (``splices/SP125x285-2.dxf``: CUT outline and holes, XDATA ``part_id`` = the
type id and ``quantity``)."""
BITES_CSV, STRIP_CUTS_CSV, WELDS_CSV = "bites.csv", "strip_cuts.csv", "welds.csv"
BITES_COLUMNS = ["panel", "edge", "mesh_edge", "strip", "bite_mm", "supported_mm", "edge_mm", "tilt_deg"]
STRIP_CUTS_COLUMNS = ["bar", "start_mm", "length_mm", "part_id", "nest_tag", "beam"]
WELDS_COLUMNS = ["node", "part", "to", "dihedral_deg", "weld_length_mm", "preparation", "throat_mm", "joint"]
BEVELS_CSV = "bevels.csv"
"""The fit of every glazing strip on its beam plate: :data:`BEVEL_COLUMNS` (:mod:`fabrication.glazing.bevel`)."""
BEVEL_COLUMNS = ["strip", "plate", "lean_deg", "overlap_mm", "delta_mm", "bevel"]
RETENTION_CSV, RESTRAINT_CSV = "retention.csv", "restraint.csv"
"""The retention parts of ``glazing.step`` (one row each: :data:`RETENTION_COLUMNS`) and the restraint check of
every pane (:data:`RESTRAINT_COLUMNS`), see ``docs/glazing.md``.  A pressure plate's row carries its bending
between the screws (:class:`fabrication.glazing.retention_strength.PlateBending`: design line load, largest span and end
overhang, stress and its limit ``f/γ``, deflection under the characteristic load and its limit); a pane's
``plate_utilisation`` is the largest of the plates over it."""
RETENTION_COLUMNS = ["part_id", "kind", "owner", "strip", "beam", "length_mm", "width_mm", "height_mm", "material",
                     "screw", "screws", "screw_stations_mm", "plate_load_N_mm", "plate_span_mm", "plate_end_mm",
                     "plate_stress_N_mm2", "plate_stress_limit_N_mm2", "plate_deflection_mm",
                     "plate_deflection_limit_mm"]
RESTRAINT_COLUMNS = ["panel", "slope_deg", "weight_kg", "down_edge", "strip", "setting_blocks", "block_load_N",
                     "block_pressure_N_mm2", "block_contact_mm", "stops", "uplift_kN", "screws", "resistance_kN", "clamp_bite_mm",
                     "max_screw_spacing_mm", "plate_utilisation", "silicone_bite_mm", "ok"]
"""The bite of every pane edge (:data:`BITES_COLUMNS`); the strips cut from bars (:data:`STRIP_CUTS_COLUMNS`);
the welds (:data:`WELDS_COLUMNS`): ``joint = "T"`` a plate
ending against one running through ``node``, ``joint = "halflap"`` the two plates crossing at a half-lap
``node`` welded in its four corners, ``joint = "corner"`` two plates ending at a ``node`` where none runs
through, ``joint = "splice"`` a welded splice across the cut between two pieces of a beam (no node)."""
BOLTS_CSV = "bolts.csv"
"""The bolt sets of the bolted splices, one row per splice: :data:`BOLTS_COLUMNS` (:mod:`fabrication.glazing.bolts`)."""
BOLTS_COLUMNS = ["splice", "beam", "pieces", "bolt", "size", "grade", "length_mm", "grip_mm", "washers", "nut",
                 "projection_mm", "category", "preload", "quantity"]
ERECTION_CSV = "erection.csv"
"""The erection sequence, one row per part (and per weld): :data:`ERECTION_COLUMNS`
(:mod:`fabrication.erection`)."""
ERECTION_COLUMNS = ["step", "part_id", "kind", "direction_x", "direction_y", "direction_z", "after",
                    "blocked_spread_deg"]
"""``blocked_spread_deg``: for a plate that no single direction puts through its slots, the angle spread of its
slot directions; empty otherwise."""
PLATE_SHEET_DIR, PLATE_SHEET_PREFIX = "beams", "plates"
TYPE_DIR, TYPE_PREFIX = "glass/types", "type"


DRAWINGS_DIR, NODE_SHEET_DIR = "drawings", "nodes"
"""The installers' drawings: ``drawings/<view>.svg`` and ``drawings/nodes/node_type_<id>.svg``."""


def view_file(view: str) -> str:
    """``key_plan.svg`` for the plan, ``elevation_front.svg`` for an elevation."""
    return "key_plan.svg" if view == "plan" else f"elevation_{view}.svg"


def node_sheet_file(type_id: str) -> str:
    """``node_type_NT03.svg``: the sheet of a node type."""
    return f"node_type_{type_id}.svg"


def sheet_file(prefix: str, sheet: int, sheets: int) -> str:
    """``glass_03.dxf``: the file of 1-based ``sheet`` out of ``sheets``."""
    return f"{prefix}_{sheet:0{max(2, len(str(sheets)))}d}.dxf"


def sheet_files(directory: str, prefix: str, sheets: int) -> list[str]:
    """The cutting-sheet files of one kind, relative to the build folder, in sheet order:
    ``["glass/glass_01.dxf", …]`` for ``(GLASS_SHEET_DIR, GLASS_SHEET_PREFIX, sheets)``.  The DXF writer writes
    these files; the parts list names them in its ``sheet_file`` column without waiting for it."""
    return [f"{directory}/{sheet_file(prefix, k + 1, sheets)}" for k in range(sheets)]


def type_file(type_id: str, prefix: str = TYPE_PREFIX) -> str:
    """``type_T017.dxf``: the flat DXF of a panel type."""
    return f"{prefix}_{type_id}.dxf"


# -- exchange models: IFC, Rhino, glTF; structure and colours of the STEP files ------------------------

IFC_FILE, RHINO_FILE, GLB_FILE = "model.ifc", "model.3dm", "model.glb"

GLB_HOLE_SEGMENTS = 24
"""Corners of a bolt hole in ``model.glb``: a regular polygon of the hole's area (its circumradius
``r √(π / (m/2 · sin(2π/m)))``), so the mesh's volume is exact; each ring follows the outline's in the vertex
order (:meth:`fabrication.writers._elements.Element.prism_mesh`)."""

FIXED_TIMESTAMP = "2000-01-01T00:00:00"
"""The time stamp written into every file header that has one (STEP, IFC, Rhino): builds stay byte-identical."""

IFC_SCHEMA = "IFC4"
IFC_PSET = "PPFAB_Part"
"""The property set on every IFC element; its properties are :data:`EXCHANGE_PROPERTIES` (the ``parts.csv``
columns of the same name; ``weight_kg`` is ``mass_kg`` for beam plates)."""

IFC_CLASSES = {"panel": ("IfcPlate", "CURTAIN_PANEL"), "beam": ("IfcMember", "MEMBER"),
               "setting_block": ("IfcDiscreteAccessory", "USERDEFINED"),
               "stop": ("IfcDiscreteAccessory", "BRACKET"),
               "pressure_gasket": ("IfcDiscreteAccessory", "USERDEFINED"),
               "pressure_plate": ("IfcPlate", "SHEET"), "cover_cap": ("IfcCovering", "CLADDING"),
               "screw": ("IfcMechanicalFastener", "BOLT")}
"""Part kind → IFC class and predefined type; a part of any other kind becomes an ``IfcMember``.  Setting blocks,
stops and pressure gaskets are discrete accessories of the glazing (``USERDEFINED``: ``ObjectType`` the kind), a
pressure plate a sheet plate, a cover cap cladding, and the screws of a plate one mechanical fastener holding
one extruded circle per screw."""

EXCHANGE_PROPERTIES = ("part_id", "kind", "nest_tag", "type_id", "sheet", "sheet_file", "material", "thickness_mm",
                       "area_mm2", "weight_kg", "planarity_dev_mm", "beam_id", "family", "piece", "length_mm",
                       "owner", "quantity")
"""Keys of the IFC property set and the Rhino user text of a part (those that apply to it)."""

RHINO_LAYERS = ("glass", "beams", "beams::rows", "beams::cols", "nodes", "mesh", "retention",
                "retention::setting_block", "retention::stop", "retention::pressure_gasket",
                "retention::pressure_plate", "retention::screw", "retention::cover_cap")
"""Layers of ``model.3dm`` (full paths): panels on ``glass``, beam plates on ``beams::<family>``, node axes on
``nodes``, the quad mesh on ``mesh``, the retention parts on ``retention::<kind>``."""

COLOURS = {"glass": (0.55, 0.75, 0.90, 0.35), "rows": (0.80, 0.36, 0.12, 1.0), "cols": (0.16, 0.42, 0.68, 1.0),
           "nodes": (0.15, 0.15, 0.15, 1.0), "mesh": (0.45, 0.45, 0.45, 1.0),
           "retention": (0.62, 0.64, 0.66, 1.0)}
"""RGBA (0–1) of the glass, each beam family, the node axes and the mesh in STEP, IFC, Rhino and glTF."""

STEP_GLASS_GROUP = "glass"
"""The assembly of the panels in ``panels.step`` (below the design's assembly; the panels sit in one assembly
per row below it); in ``beams.step`` the design's
assembly holds one assembly per family (``rows``, ``cols``), each one per beam (``B-U03``) holding its plates."""


# -- text in files ----------------------------------------------------------------------------------------
# Text a designer typed (the design name, materials) reaches OBJ comments, DXF TEXT, CSV cells and JSON;
# each format gets it in a form that cannot break the file or be executed by the program that opens it.

_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029]")

CSV_FORMULA_PREFIXES = ("=", "+", "-", "@", "\t", "\r")
"""A text cell starting with one of these is read as a formula by spreadsheet programs (OWASP, "CSV
injection"): such cells are written with a leading ``'``, which :func:`csv_value` removes again."""


def one_line(text: str) -> str:
    """``text`` with every control character and line separator replaced by a space."""
    return _CONTROL.sub(" ", text)


def dxf_text(text: str, limit: int = 250) -> str:
    """The value of a DXF TEXT entity: one line without control characters (a NUL or a newline would end
    the group value), at most ``limit`` characters.

    >>> dxf_text("roof\\x00 A\\nB")
    'roof  A B'
    """
    return one_line(text)[:limit]


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def csv_cell(value: object) -> object:
    """A CSV cell value: text on one line, and text that a spreadsheet would run as a formula (starting with
    ``= + - @``, tab or CR) prefixed with ``'`` — numbers, and text that is a plain number, stay as they are;
    a list, tuple or dict becomes one JSON cell (double quotes, keys sorted, no NaN).

    >>> csv_cell("=HYPERLINK(1)"), csv_cell("-12.5"), csv_cell(-3), csv_cell("a\\nb")
    ("'=HYPERLINK(1)", '-12.5', -3, 'a b')
    >>> csv_cell({"o": [0, 1.5]}), csv_cell((1, 2))
    ('{"o": [0, 1.5]}', '[1, 2]')
    """
    if isinstance(value, (list, tuple, dict)):
        import json
        return json.dumps(json_safe(value), sort_keys=True, ensure_ascii=False, allow_nan=False)
    if not isinstance(value, str):
        return value
    if value.startswith(CSV_FORMULA_PREFIXES) and not _is_number(value):
        value = "'" + value
    return one_line(value)


def csv_value(cell: str) -> str:
    """The text a :func:`csv_cell` stands for (the ``'`` before a formula character removed)."""
    if len(cell) > 1 and cell[0] == "'" and cell[1:].startswith(CSV_FORMULA_PREFIXES):
        return cell[1:]
    return cell


def json_safe(obj: object) -> object:
    """``obj`` with every non-finite float (NaN, ±inf, which JSON cannot hold) replaced by ``None``; dicts,
    lists, tuples and numpy arrays become plain copies.

    >>> json_safe({"a": [1.0, float("nan")], "b": float("inf")})
    {'a': [1.0, None], 'b': None}
    """
    if hasattr(obj, "tolist") and not isinstance(obj, (str, bytes)):      # numpy arrays and scalars
        obj = obj.tolist()
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    return obj


PARTIAL_MARKER = ".ppfab-partial"
"""The file a build keeps in its temporary folder while it writes (removed before the folder is committed);
:mod:`fabrication.pipeline.lock` writes it, ``ppfab verify`` does not count it as a stray file."""


TABLE_COLUMNS: dict[str, list[str]] = {
    "nodes.csv": NODES_COLUMNS, "glass_order.csv": ORDER_ALL_COLUMNS, BEVELS_CSV: BEVEL_COLUMNS,
    RETENTION_CSV: RETENTION_COLUMNS, RESTRAINT_CSV: RESTRAINT_COLUMNS, BITES_CSV: BITES_COLUMNS,
    STRIP_CUTS_CSV: STRIP_CUTS_COLUMNS, WELDS_CSV: WELDS_COLUMNS, BOLTS_CSV: BOLTS_COLUMNS,
    ERECTION_CSV: ERECTION_COLUMNS}
"""Every CSV table a build writes with a fixed header → its columns in order; ``parts.csv`` is the one whose
columns depend on the parts it lists: :data:`PARTS_CONTRACT_COLUMNS`, then those of
:data:`PARTS_KNOWN_COLUMNS` present, then those of :data:`PARTS_MORE_COLUMNS` present, sorted by name."""
