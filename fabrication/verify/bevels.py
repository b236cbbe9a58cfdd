"""bevels.csv against the files: every strip's lean on its beam plate, re-measured, and the bevel it calls for.

For each glazing strip of ``parts.csv``: its normal ``u`` is the thin direction of its solid in glazing.step (the
least-variance direction of its vertices), the plate under it is a beam row of ``parts.csv`` of the strip's
``beam`` holding both its ``edge_nodes`` (else one of them), with unit plane normal ``n_p`` and thickness ``t``.
The lean is ``λ = arcsin |u·n_p|``; bevels.csv must state it within :data:`LEAN_TOL`, the overlap
``(t/2)·sin λ`` and ``Δ = (t/2)·tan λ`` within 0.01 mm, and a bevel exactly where ``λ`` exceeds
``glazing.bevel_min_deg`` (:mod:`fabrication.glazing.bevel`).  Where a row states a bevel, the plate's solid in
beams.step must have it (:mod:`fabrication.beams.bevel_cut`): corners on both its faces in the strip's underside
plane (within :data:`FACE_TOL`), their plane within :data:`ANGLE_TOL` of it, ``Δ`` above the mid-plane edge on one
face and below it on the other.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..contract import BEVEL_COLUMNS
from . import Verification, check
from ._shapes import faces_union, frame_of, literal, number, solid_points, to_frame

FACE_TOL = 0.05
"""mm: how far a corner of a bevelled plate may lie from its strip's underside plane (the STEP file's decimals;
a square top edge under a strip leaning 2° stands (t/2)·sin 2° = 0.21 mm off it on a 12 mm plate)."""

ANGLE_TOL = 0.05
"""Degrees: how far the bevelled face may turn off the strip's underside."""

LEAN_TOL = 0.05
"""Degrees: how far the stated lean may be from the one re-measured (the STEP file's decimals on an 8 mm thick
strip's vertices)."""


def face_rings(solid, normal: np.ndarray) -> list[np.ndarray]:
    """The outer boundaries ``(k, 3)`` of the planar faces of ``solid`` square to ``normal`` (either sense): a
    beam plate's two faces, kernel solid or text-level record alike."""
    n = np.asarray(normal, dtype=float)
    out = []
    if hasattr(solid, "face_area"):                          # a record of the text-level reader
        for f in solid.faces():
            if f.surface == "plane" and abs(float(f.normal @ n)) >= 1.0 - 1e-9:
                out.append(solid.ring(solid.outer_loop(f)))
        return out
    from ._shapes import _chain

    for face in solid.faces():
        try:
            fn = np.array(tuple(face.normal_at()), dtype=float)
        except Exception:  # noqa: BLE001 - a non-planar face
            continue
        if abs(float(fn @ n)) < 1.0 - 1e-9:
            continue
        ring = _chain([(np.array(tuple(e.start_point())), np.array(tuple(e.end_point())))
                       for e in face.outer_wire().edges()])
        if ring is not None:
            out.append(ring)
    return out


def largest_face_normal(solid) -> np.ndarray | None:
    """The unit normal of the solid's largest planar face (a plate's face: square to its thickness, whether or
    not its top edge is bevelled), ``None`` without a planar face."""
    best: tuple[float, np.ndarray] | None = None
    if hasattr(solid, "face_area"):                          # a record of the text-level reader
        for f in solid.faces():
            if f.surface == "plane":
                a = float(solid.face_area(f))
                if best is None or a > best[0]:
                    best = (a, np.asarray(f.normal, dtype=float))
    else:
        for face in solid.faces():
            try:
                n = np.array(tuple(face.normal_at()), dtype=float)
            except Exception:  # noqa: BLE001 - a non-planar face
                continue
            if "PLANE" in str(face.geom_type).upper() and (best is None or face.area > best[0]):
                best = (float(face.area), n)
    return None if best is None else best[1] / np.linalg.norm(best[1])


@dataclass(frozen=True)
class PlateFaces:
    """A plate solid's two faces in its frame (2D, counter-clockwise): ``front`` at ``z = +t/2``, ``back`` at
    ``z = −t/2``; ``mid`` its section in the mid-plane (vertex by vertex the mean of the two: a bevelled plate's
    faces have the same vertices in the same order, :mod:`fabrication.beams.bevel_cut`), ``None`` when they do
    not correspond; ``cut`` their union, the outline cut from the sheet."""

    front: np.ndarray
    back: np.ndarray
    mid: np.ndarray | None
    cut: np.ndarray


def _ccw(q: np.ndarray) -> np.ndarray:
    from ppfab.metrics import polygon_area

    return q if polygon_area(q) > 0 else q[::-1]


def plate_faces(solid, frame: dict[str, np.ndarray]) -> PlateFaces | None:
    """The :class:`PlateFaces` of a beam plate solid in its ``parts.csv`` frame, ``None`` without two faces."""

    from ._shapes import to_frame

    rings = [to_frame(r, frame) for r in face_rings(solid, frame["normal"])]
    if len(rings) < 2:
        return None
    rings.sort(key=lambda r: -float(r[:, 2].mean()))
    front, back = _ccw(rings[0][:, :2]), _ccw(rings[-1][:, :2])
    mid = None
    if len(front) == len(back):
        # the turn of the back ring that lies closest to the front one corner by corner (not the corner nearest
        # front[0]: a notch's wall can be shorter than the bevel moves a corner along it)
        n = len(front)
        turns = np.stack([np.roll(back, -k, axis=0) for k in range(n)])
        k = int(np.argmin(np.linalg.norm(turns - front[None], axis=2).max(axis=1)))
        aligned = turns[k]
        if float(np.linalg.norm(aligned - front, axis=1).max()) < 0.5 * float(np.ptp(front, axis=0).min()):
            mid = 0.5 * (front + aligned)
    cut = faces_union(front, back)
    if cut is None:
        return None
    return PlateFaces(front, back, mid, _ccw(cut))


def _check_bevel_face(v: Verification, pid: str, row: dict, strip_pts: np.ndarray, solid,
                      frame: dict | None, ends: np.ndarray | None = None, thickness: float = 0.0) -> None:
    """A bevelled row of bevels.csv against beams.step: the plate has a face in the strip's underside plane —
    corners on both of its faces within :data:`FACE_TOL` of that plane, their plane within :data:`ANGLE_TOL` of
    it — standing ``Δ`` (``delta_mm``, within 0.01 mm) above the mid-plane edge on one face and below it on the
    other.  The corners looked at are those along the strip's mesh edge (``ends``: its two vertices of mesh.obj,
    ``(2, 3)``; a plate thickness beyond them, where a bevel's corners meet the next span's); without them,
    along the strip's own length and as much again on either side."""
    if frame is None:
        return
    plate = row.get("plate", "")
    c = strip_pts.mean(axis=0)
    axes = np.linalg.svd(strip_pts - c)[2]
    u, along = axes[2], axes[0]
    pts = solid_points(solid)
    s = (strip_pts - c) @ along
    a = (pts - c) @ along
    if ends is not None:
        e = (np.asarray(ends, dtype=float) - c) @ along
        lo, hi = float(e.min()) - thickness, float(e.max()) + thickness
    else:
        reach = float(np.ptp(s))
        lo, hi = float(s.min()) - reach, float(s.max()) + reach
    # the plate's corners along the strip's span (a strip stopping short of a node, as at a corner where the other
    # polyline meets it at a few degrees, can be a quarter of its span); the strip's face the bevel bears on: of
    # its two faces the one the plate's corners lie on (the strip's underside, on the plate's top edge)
    span = (a >= lo) & (a <= hi)
    faces = []
    for under in ((strip_pts @ u).min(), (strip_pts @ u).max()):
        d = pts @ u - float(under)
        faces.append((d, (np.abs(d) <= FACE_TOL) & span))
    d, near = max(faces, key=lambda f: int(f[1].sum()))
    z = to_frame(pts[near], frame)[:, 2]
    front, back = pts[near][z > 0], pts[near][z < 0]
    if len(front) < 2 or len(back) < 2:
        lowest = float(np.abs(d[span]).min()) if np.any(span) else float("nan")
        v.error("beams.step", plate, f"has no bevelled face in the underside plane of {pid} (bevels.csv: "
                                     f"{row.get('bevel', '')}); its nearest corner along the strip is {lowest:.3f} mm "
                                     "off that plane")
        return
    face = pts[near]

    def turn(q: np.ndarray) -> float:
        n = np.linalg.svd(q - q.mean(axis=0))[2][2]
        return math.degrees(math.acos(min(1.0, abs(float(n @ u)))))

    # a corner of a notch wall or end cut can lie within FACE_TOL of the plane without being on the bevel (Fig. 16:
    # one 0.05 mm below it tilted the fit 0.054°): the face is the fit that leaves out at most one corner
    angle = min([turn(face)] + ([turn(np.delete(face, k, axis=0)) for k in range(len(face))] if len(face) > 3
                                else []))
    if angle > ANGLE_TOL:
        v.error("beams.step", plate, f"its bevel under {pid} turns {angle:.3f}° off the strip's underside (at most "
                                     f"{ANGLE_TOL:g}°)")
    m = np.cross(frame["normal"], along - (along @ frame["normal"]) * frame["normal"])
    m = m / np.linalg.norm(m)
    rise = 0.5 * abs(float((front @ m).mean() - (back @ m).mean()))
    want = number(row.get("delta_mm"))
    if not abs(rise - want) <= 0.01:
        v.error("beams.step", plate, f"its bevel under {pid} stands {rise:.3f} mm above the mid-plane edge, "
                                     f"bevels.csv's delta_mm is {row.get('delta_mm')!r}")


@check("bevels")
def check_bevels(v: Verification) -> None:
    from ._step_read import read_or_report

    m = v.manifest
    files = m.get("files", {})
    rel, rel_g = files.get("bevels_csv"), files.get("glazing_step")
    if rel is None or rel_g is None:
        return
    rows = v.read_table(rel, BEVEL_COLUMNS)
    read = read_or_report(v, rel_g)
    if rows is None or read is None:
        return
    threshold = float(m.get("fabrication", {}).get("glazing", {}).get("bevel_min_deg", 0.0))
    solids = {s.name: s.solid for s in read if s.name.startswith("GS-")}
    parts = (v.parts or [])
    strips = {r["part_id"]: r for r in parts if r.get("kind") == "strip"}
    plates: dict[str, list[tuple[set[int], np.ndarray, float]]] = {}
    for r in parts:
        pl, nodes = literal(r.get("plane", "")), literal(r.get("nodes", ""))
        if r.get("kind") == "beam" and isinstance(pl, list) and len(pl) == 4 and isinstance(nodes, list):
            n = np.asarray(pl[:3], dtype=float)
            plates.setdefault(r.get("beam_id", ""), []).append(({int(k) for k in nodes}, n / np.linalg.norm(n),
                                                                number(r.get("thickness_mm"))))
    stated = {r.get("strip", ""): r for r in rows}
    beam_solids = (v.beam_solids or {})
    frames = {r["part_id"]: frame_of(r) for r in parts if r.get("kind") == "beam"}
    plate_rows = {r["part_id"]: r for r in parts if r.get("kind") == "beam"}
    kept_square: list[str] = []
    for pid in sorted(set(strips) - set(stated)):
        v.error(rel, pid, "strip has no row")
    for pid, r in sorted(stated.items()):
        s, solid = strips.get(pid), solids.get(pid)
        if s is None or solid is None:
            v.error(rel, pid, f"is not a strip of parts.csv with a solid in {rel_g}")
            continue
        try:
            i, j = (int(x) for x in s.get("edge_nodes", "").split(";"))
        except ValueError:
            continue                                 # the glazing_step check names a bad edge_nodes
        mine = plates.get(s.get("beam", ""), [])
        plate = next((p for p in mine if i in p[0] and j in p[0]), next((p for p in mine if i in p[0] or j in p[0]),
                                                                      None))
        if plate is None:
            continue                                 # the glazing_step check names a strip without a plate
        pts = solid_points(solid)
        u = np.linalg.svd(pts - pts.mean(axis=0))[2][2]
        sin = min(1.0, abs(float(u @ plate[1])))
        lean = math.degrees(math.asin(sin))
        half = 0.5 * plate[2]
        want = {"lean_deg": (lean, LEAN_TOL), "overlap_mm": (half * sin, 0.01),
                "delta_mm": (half * math.tan(math.radians(lean)), 0.01)}
        for key, (value, tol) in want.items():
            got = number(r.get(key))
            if not abs(got - value) <= tol:
                v.error(rel, pid, f"{key} {r.get(key)!r} is not the {value:.3f} re-measured from {rel_g} and the "
                                  "plate's plane in parts.csv")
        bevelled = r.get("bevel", "") != "square"
        if bevelled and r.get("plate", "") in beam_solids:
            mesh = v.mesh
            ends = mesh.vertices[[i, j]] if mesh is not None and max(i, j) < len(mesh.vertices) else None
            _check_bevel_face(v, pid, r, pts, beam_solids[r["plate"]], frames.get(r["plate"]), ends, plate[2])
        if lean > threshold + LEAN_TOL and not bevelled:
            if not number(plate_rows.get(r.get("plate", ""), {}).get("bevels"), 0.0) and r.get("plate") in plate_rows:
                kept_square.append(pid)      # the plate kept its square top edge (its bevel could not be drawn)
                continue
            v.error(rel, pid, f"leans {lean:.2f}° on its plate, more than glazing.bevel_min_deg = {threshold:g}°, "
                              "but has no bevel")
        elif lean < threshold - LEAN_TOL and bevelled:
            v.error(rel, pid, f"is bevelled but leans only {lean:.2f}° (glazing.bevel_min_deg = {threshold:g}°)")
    if kept_square:
        import logging

        logging.getLogger("ppfab").warning(
            "bevels: %d strip(s) lean past glazing.bevel_min_deg = %g° on plates that keep a square top edge (their "
            "bevel could not be drawn; the fillet weld's fit-up takes the overlap): %s", len(kept_square), threshold,
            ", ".join(kept_square[:6]))
    v.checked.append("bevels")
