"""beams.step: one valid solid per beam part, named by its part id, a plate of the beam thickness, under its beam
and family in the product tree, in its family's colour; panels.step: one solid per panel; both headers name ppfab."""

from __future__ import annotations

import numpy as np

from . import Verification, check
from ._shapes import frame_of, solid_points
from ._step_read import StepSolid
from .bevels import largest_face_normal


@check("step")
def check_step(v: Verification) -> None:
    """beams.step: one valid solid per beam part, named by its part id, a plate of the beam thickness."""
    files = v.manifest.get("files", {})
    rel = files.get("beams_step")
    if rel is None:
        return
    from ._step_read import read_or_report

    read = read_or_report(v, rel, colours=True)
    if read is None:
        return
    pairs = [(s.name, s.solid) for s in read]
    v.read.beam_solids = {name: solid for name, solid in reversed(pairs)}
    beams = {r["part_id"]: r for r in (v.parts or []) if r["kind"] == "beam"}
    t = float(v.manifest.get("fabrication", {}).get("beam_thickness", 0.0))
    names = [n for n, _ in pairs]
    for name in sorted(set(beams) - set(names)):
        v.error(rel, name, "beam part has no solid")
    for name in sorted({n for n in names if names.count(n) > 1}):
        v.error(rel, name, "more than one solid carries this name")
    for name, solid in pairs:
        if name not in beams:
            v.error(rel, name or "(unnamed)", "solid is not a beam part in parts.csv")
            continue
        if not hasattr(solid, "problems") and not solid.is_valid:   # a text-level record's: findings of the reader
            v.error(rel, name, "solid is not valid (BRepCheck)")
        pts = solid_points(solid)
        c = pts - pts.mean(axis=0)
        frame = frame_of(beams[name])
        # across its largest face (a bevelled plate's corners would tilt a fitted plane); where the plate lies is
        # the step_geometry check's
        normal = largest_face_normal(solid)
        spread = float(np.ptp(c @ (normal if normal is not None else np.linalg.svd(c)[2][2])))
        if t and abs(spread - t) > 1e-6 * max(1.0, t):
            v.error(rel, name, f"solid is {spread:.6g} mm thick, expected {t:g} mm")
        _check_volume(v, rel, name, beams[name], solid, frame, t)
    _check_tree(v, rel, beams, read)
    v.checked.append("step")


def _check_volume(v: Verification, rel: str, name: str, row: dict, solid, frame: dict | None, t: float) -> None:
    """A plate's volume is ``t`` times the mean area of its two faces less its bolt holes (a bevelled top edge
    moves the faces' outlines apart, :mod:`fabrication.beams.bevel_cut`; a square plate's faces are one outline),
    and its ``area_mm2`` the area of the two faces' union, the outline cut from the sheet."""
    from ppfab.metrics import polygon_area

    from .bevels import plate_faces

    holes = np.pi / 4.0 * float(row.get("holes") or 0) * float(row.get("hole_mm") or 0.0) ** 2
    area = float(row.get("area_mm2") or 0.0)
    faces = plate_faces(solid, frame) if frame is not None else None
    if faces is None:
        mean = cut = area
    else:
        mean = 0.5 * (float(polygon_area(faces.front)) + float(polygon_area(faces.back)))
        cut = float(polygon_area(faces.cut))
        if area and abs(cut - area) > 1e-6 * area + 1e-3:
            v.error(rel, name, f"its faces' outline encloses {cut:.6g} mm², parts.csv's area_mm2 is {area:.6g} mm²")
    want = (mean - holes) * t
    if t and area and abs(solid.volume - want) > 1e-4 * want:
        v.error(rel, name, f"volume {solid.volume:.6g} mm³ ≠ face area × thickness {want:.6g} mm³")


def check_header(v: Verification, rel: str) -> None:
    from ppfab import __version__

    from ..contract import FIXED_TIMESTAMP

    head = (v.folder / rel).read_bytes().partition(b"ENDSEC;")[0].decode("ascii", "replace")
    for needed in (f"'ppfab {__version__}'", f"'{FIXED_TIMESTAMP}'", "FILE_DESCRIPTION(('ppfab"):
        if needed not in head:
            v.error(rel, "header", f"does not name {needed} (ppfab, its version, the fixed time stamp)")


def _check_tree(v: Verification, rel: str, beams: dict, read: list[StepSolid]) -> None:
    """The product tree of beams.step: design → family → beam id → plate, each solid in its family's colour."""
    from ..contract import COLOURS

    check_header(v, rel)
    for s in read:
        row = beams.get(s.name)
        if row is None:
            continue
        want = (row.get("family", ""), row.get("beam_id", ""))
        if tuple(s.path[-2:]) != want:
            v.error(rel, s.name, f"sits under {'/'.join(s.path[1:]) or 'the root'}, expected {'/'.join(want)}")
        rgb = COLOURS.get(want[0])
        if rgb is not None and (s.colour is None or max(abs(a - b) for a, b in zip(s.colour, rgb)) > 1e-3):
            colour = "none" if s.colour is None else "(" + ", ".join(f"{c:.3g}" for c in s.colour[:3]) + ")"
            v.error(rel, s.name, f"colour {colour} is not the colour of family {want[0]}")
