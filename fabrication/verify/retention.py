"""What holds the panes, re-measured from the files: setting blocks, stops and pressure plates of glazing.step
against the panes of panels.step, with the loads of restraint.csv recomputed.

For every pane ``P-…`` of panels.step, from its solid alone: its normal ``n`` (least variance of its vertices,
turned up), its slope ``α = arccos |n_z|``, its thickness ``t`` (extent along ``n``), its underside polygon, and
its *down-slope edge*, the polygon edge whose outward normal in the pane's plane points most along ``−z`` made
parallel to the pane.  Then:

* **setting blocks**: the two ``SB-…-1``/``-2`` solids of ``retention.csv`` for the pane exist in glazing.step;
  each lies against that edge — its nearest vertices within :data:`TOUCH` of the edge's face (neither entering
  the glass nor standing off it), its centre beyond the edge within the edge's length — and bears on at least
  :data:`MIN_CONTACT` of the glass thickness along ``n`` (less than half of it is a warning);
* **stops**: where ``restraint.csv`` says ``stops = yes``, the two ``ST-…`` solids exist, beyond their blocks and
  touching them (within :data:`TOUCH`);
* **pressure plates** (``glazing.retention = "pressure_plate"``): at a quarter, half and three quarters of every
  edge of the pane, the point ``glazing.min_clamp_bite`` inside the edge on the glass top lies, seen along ``n``,
  under a pressure gasket ``CG-…`` (the convex hull of its vertices projected into the pane's plane);
* **loads**: the bearing pressure of a block ``m·g·sin α / (2·ℓ·h)`` (``m`` the pane's ``weight_kg`` of
  parts.csv, ``ℓ`` the block's extent along the edge, ``h`` the height over which it bears on the glass) at most ``glazing.setting_block_pressure``; the wind
  uplift ``γ_Q·q·A`` (``A`` the pane's ``area_mm2``) at most the tension resistance of its share of the screws of
  the plates over its edges (``screws`` of ``retention.csv`` over the number of panes a plate covers), and no two
  screws of a plate farther apart than ``glazing.bolt_pitch`` (an end counting at twice its distance).

* **parts.csv**: every retention part has its row, the box the row's frame and size give on its solid's vertices
  (1e-3 mm), and every pressure plate the row of its screws (``SC-…``: quantity and stations as retention.csv);
* **plate bending**: each pressure plate between its screws under the suction of the panes its gasket covers
  (area over perimeter of each, parts.csv), stress against ``f/γ`` and deflection against span/200 recomputed
  (:class:`fabrication.glazing.retention_strength.PlateBending`), a finding where either is exceeded.

That no retention solid enters the glass is the clash check's (it measures every solid of glazing.step).
"""

from __future__ import annotations

import logging
import math

import numpy as np

from ..contract import RESTRAINT_COLUMNS, RETENTION_COLUMNS
from . import Verification, check
from ._shapes import face_outline, number, solid_points

MIN_CONTACT = 3.0
"""mm: the least height over which a setting block must bear on the glass edge (less than half the glass is a
warning: a kink closing the joint over the block)."""
TOUCH = 0.1
"""mm: how far a setting block may stand off, or reach into, the glass edge face it bears on (the STEP file's
decimals), and a stop off its block."""
G = 9.81


def _pane_geometry(solid) -> tuple[np.ndarray, np.ndarray, float, np.ndarray] | None:
    """``(n, underside polygon (k, 3), thickness, centre)`` of a pane solid; ``n`` points up (``n_z ≥ 0``)."""
    pts = solid_points(solid)
    c = pts.mean(axis=0)
    n = np.linalg.svd(pts - c)[2][2]
    if n[2] < 0:
        n = -n
    z = pts @ n
    ring = face_outline(solid, n)
    if ring is None or len(ring) < 3:
        return None
    ring = ring - np.outer(ring @ n - z.min(), n)
    return n, ring, float(z.max() - z.min()), c


LEVEL_DEG = 0.5
"""A pane sloping less than this (degrees) has no down-slope edge to speak of: its blocks may sit under any edge,
and the check takes the edge they are against."""


def _down_edge(n: np.ndarray, ring: np.ndarray, near: np.ndarray | None = None) -> tuple[int, np.ndarray]:
    """The edge ``k`` of ``ring`` whose outward in-plane normal points most down the slope, and the outward
    normals ``(k, 3)`` of all edges; on a pane sloping less than :data:`LEVEL_DEG`, the edge nearest the point
    ``near`` (the setting blocks' centre) when given."""
    d = np.roll(ring, -1, axis=0) - ring
    o = np.cross(d, n)
    o /= np.linalg.norm(o, axis=1, keepdims=True)
    centre = ring.mean(axis=0)
    mid = 0.5 * (ring + np.roll(ring, -1, axis=0))
    o *= np.sign(np.einsum("ij,ij->i", mid - centre, o))[:, None]          # outward whatever the turning sense
    down = np.array([0.0, 0.0, -1.0])
    down = down - (down @ n) * n
    if near is not None and float(np.linalg.norm(down)) < np.sin(np.radians(LEVEL_DEG)):
        return int(np.argmin(np.linalg.norm(mid - near, axis=1))), o
    if float(np.linalg.norm(down)) < 1e-9:
        return int(np.argmin(mid[:, 2])), o
    return int(np.argmax(o @ down)), o


def _projected_hull(points: np.ndarray, origin: np.ndarray, ex: np.ndarray, ey: np.ndarray):
    from shapely.geometry import MultiPoint

    d = points - origin
    return MultiPoint(np.stack([d @ ex, d @ ey], axis=1)).convex_hull


@check("retention")
def check_retention(v: Verification) -> None:
    from shapely.geometry import Point

    from ..glazing.retention_strength import RetentionBolt
    from ._step_read import read_or_report

    m = v.manifest
    files = m.get("files", {})
    rel_r, rel_x = files.get("retention_csv"), files.get("restraint_csv")
    rel_g, rel_p = files.get("glazing_step"), files.get("panels_step")
    if rel_r is None or rel_x is None or rel_g is None or rel_p is None:
        return
    gl = m.get("fabrication", {}).get("glazing", {})
    rows = v.read_table(rel_r, RETENTION_COLUMNS)
    checks = v.read_table(rel_x, RESTRAINT_COLUMNS)
    glass = read_or_report(v, rel_p)
    support = read_or_report(v, rel_g)
    if rows is None or checks is None or glass is None or support is None:
        return
    solids = {s.name: solid_points(s.solid) for s in support}
    _check_parts_rows(v, files.get("parts_csv", "parts.csv"), rel_r, rel_g, rows, solids)
    panes = {s.name: s.solid for s in glass if s.name.startswith("P-")}
    parts = {r["part_id"]: r for r in (v.parts or []) if r.get("kind") == "panel"}
    by_owner: dict[str, dict[str, list[dict[str, str]]]] = {}
    for r in rows:
        by_owner.setdefault(r.get("owner", ""), {}).setdefault(r.get("kind", ""), []).append(r)
        if r["part_id"] not in solids:
            v.error(rel_g, r["part_id"], f"retention part of {rel_r} has no solid")
    restraint = {r.get("panel", ""): r for r in checks}
    plates = m.get("fabrication", {}).get("glazing", {}).get("retention") == "pressure_plate"
    gaskets = [(name, pts) for name, pts in solids.items() if name.startswith("CG-")]
    tree, reach = None, 0.0
    if gaskets:
        from scipy.spatial import cKDTree

        tree = cKDTree(np.array([pts.mean(axis=0) for _, pts in gaskets]))
        reach = max(0.5 * float(np.linalg.norm(np.ptp(pts, axis=0))) for _, pts in gaskets)
    limit = float(gl.get("setting_block_pressure", math.inf))
    bite = float(gl.get("min_clamp_bite", 0.0))
    low: list[str] = []
    covers: dict[str, set[str]] = {}
    plate_of: dict[str, set[str]] = {}
    for pane_id, solid in sorted(panes.items()):
        geo = _pane_geometry(solid)
        if geo is None:
            v.error(rel_p, pane_id, "pane has no planar face to measure its restraint on")
            continue
        n, ring, t, centre = geo
        mine = by_owner.get(pane_id, {})
        blocks = sorted(mine.get("setting_block", []), key=lambda r: r["part_id"])
        placed = [solids[r["part_id"]] for r in blocks if r["part_id"] in solids]
        k, outward = _down_edge(n, ring, np.concatenate(placed).mean(axis=0) if placed else None)
        a, b = ring[k], ring[(k + 1) % len(ring)]
        L = float(np.linalg.norm(b - a))
        d = (b - a) / L
        o = outward[k]
        if len(blocks) != 2:
            v.error(rel_r, pane_id, f"has {len(blocks)} setting blocks, expected 2 under its down-slope edge")
        lengths: list[float] = []
        contacts: list[float] = []
        for r in blocks:
            pts = solids.get(r["part_id"])
            if pts is None:
                continue
            out = (pts - a) @ o
            along = (pts - a) @ d
            up = (pts - ring[0]) @ n
            span = min(float(up.max()), t) - max(float(up.min()), 0.0)
            c = float(along.mean())
            if span < 0.5 * t:
                low.append(f"{r['part_id']} ({span:.1f} of {t:.1f} mm)")
            if abs(float(out.min())) > TOUCH or not 0.0 < c < L or span < MIN_CONTACT:
                v.error(rel_g, r["part_id"], f"setting block of {pane_id} is not against its down-slope edge: "
                                             f"{float(out.min()):.2f} mm off the edge face, centre {c:.0f} mm along "
                                             f"its {L:.0f} mm, {span:.1f} mm of the {t:.1f} mm glass")
            lengths.append(float(np.ptp(along)))
            contacts.append(max(span, MIN_CONTACT))
            for s in mine.get("stop", []):
                if s["part_id"][-2:] == r["part_id"][-2:] and s["part_id"] in solids:
                    gap = float(((solids[s["part_id"]] - a) @ o).min()) - float(out.max())
                    if abs(gap) > TOUCH:
                        how = f"{gap:.2f} mm off" if gap > 0 else f"{-gap:.2f} mm into"
                        v.error(rel_g, s["part_id"], f"stop is {how} its setting block {r['part_id']}")
        x = restraint.get(pane_id)
        if x is None:
            v.error(rel_x, pane_id, "pane has no restraint row")
        elif x.get("stops") == "yes" and len(mine.get("stop", [])) != 2:
            v.error(rel_r, pane_id, f"has {len(mine.get('stop', []))} stops, restraint.csv says it has stops")
        weight = number(parts.get(pane_id, {}).get("weight_kg"))
        slope = math.acos(min(1.0, abs(float(n[2]))))
        if lengths and math.isfinite(weight) and t > 0:
            p = weight * G * math.sin(slope) / (2.0 * min(lengths) * min(contacts))
            if p > limit + 1e-6:
                v.error(rel_x, pane_id, f"setting block pressure {p:.3f} N/mm² is above glazing.setting_block_pressure"
                                        f" = {limit:g} N/mm²")
        if not plates:
            continue
        ex = d - (d @ n) * n
        ex /= np.linalg.norm(ex)
        ey = np.cross(n, ex)
        top = ring + t * n
        for q in range(len(ring)):
            qa, qb = top[q], top[(q + 1) % len(top)]
            qd = qb - qa
            for f in (0.25, 0.5, 0.75):
                probe = qa + f * qd - bite * outward[q]
                hit = None
                near = sorted(tree.query_ball_point(probe, reach + t + 1.0)) if tree is not None else []
                for name, pts in (gaskets[j] for j in near):
                    hull = _projected_hull(pts, qa, ex, ey)
                    w = probe - qa
                    if hull.buffer(1e-6).contains(Point(float(w @ ex), float(w @ ey))):
                        hit = name
                        break
                if hit is None:
                    v.error(rel_g, pane_id, f"edge {q} has no pressure plate over it {bite:g} mm inside its edge at "
                                            f"{f:.0%} of its length")
                    break
                covers.setdefault(hit, set()).add(pane_id)
                plate_of.setdefault(pane_id, set()).add("CP" + hit[2:])
    if low:
        logging.getLogger("ppfab").warning(
            "retention: %d setting block(s) bear on less than half the glass edge (a kink closes the joint over them): "
            "%s; the block carries the pane on its edge's arris: widen [panels] gap or give these panes a bracket "
            "under the edge", len(low), ", ".join(low[:6]))
    if not plates:
        v.checked.append("retention")
        return
    try:
        bolt = RetentionBolt.parse(str(gl.get("retention_bolt", "")))
    except Exception as exc:  # noqa: BLE001 - the manifest's value, named in the finding
        v.error("manifest.json", "glazing.retention_bolt", str(exc))
        return
    screws = {r["part_id"]: r for r in rows if r.get("kind") == "pressure_plate"}
    pitch = float(gl.get("bolt_pitch", math.inf))
    for pid, r in sorted(screws.items()):
        try:
            xs = [float(x) for x in r.get("screw_stations_mm", "").split(";") if x]
        except ValueError:
            v.error(rel_r, pid, "screw_stations_mm is not numbers separated by ';'")
            continue
        length = number(r.get("length_mm"))
        if len(xs) != int(number(r.get("screws"), -1)):
            v.error(rel_r, pid, f"lists {len(xs)} screw stations for {r.get('screws')} screws")
        gaps = [y - x for x, y in zip(xs, xs[1:])] + ([2.0 * xs[0], 2.0 * (length - xs[-1])] if xs else [math.inf])
        if max(gaps) > pitch + 0.5:
            v.error(rel_r, pid, f"screws are {max(gaps):.0f} mm apart, more than glazing.bolt_pitch = {pitch:g} mm")
    suction = float(gl.get("wind_suction", 0.0)) * float(gl.get("load_factor", 1.0))
    _check_plate_bending(v, rel_r, screws, covers, parts, suction, float(gl.get("load_factor", 1.0)),
                         str(gl.get("pressure_plate_material", "")))
    for pane_id in sorted(panes):
        area = number(parts.get(pane_id, {}).get("area_mm2"))
        n_screws = 0.0
        for plate in plate_of.get(pane_id, set()):
            row = screws.get(plate)
            if row is not None:
                n_screws += number(row.get("screws"), 0.0) / max(len(covers.get("CG" + plate[2:], {pane_id})), 1)
        uplift = suction * area * 1e-6
        if math.isfinite(uplift) and uplift > n_screws * bolt.tension_resistance_kN + 1e-6:
            v.error(rel_x, pane_id, f"wind uplift {uplift:.2f} kN is above the {n_screws:.1f} screws' "
                                    f"{n_screws * bolt.tension_resistance_kN:.2f} kN holding it")
    v.checked.append("retention")


def _check_parts_rows(v: Verification, rel_parts: str, rel_r: str, rel_g: str, rows: list[dict[str, str]],
                      solids: dict[str, np.ndarray]) -> None:
    """Every retention part of retention.csv has its row in parts.csv, placed where glazing.step has its solid
    (the eight corners of the row's box, :func:`~._solids.box_corners`, on the solid's vertices within 1e-3 mm),
    and every pressure plate the row of its screws with their number; no retention row of parts.csv without
    its part."""
    from ..contract import RETENTION_KINDS, screw_set_id
    from ._solids import box_corners

    parts = {r["part_id"]: r for r in (v.parts or []) if r.get("kind") in RETENTION_KINDS}
    if not v.parts:
        return
    wanted = {r["part_id"] for r in rows}
    for r in rows:
        row = parts.get(r["part_id"])
        if row is None or row.get("kind") != r.get("kind"):
            v.error(rel_parts, r["part_id"], f"{r.get('kind')} of {rel_r} has no row of its kind in parts.csv")
            continue
        pts, box = solids.get(r["part_id"]), box_corners(row)
        if pts is None or box is None:
            continue
        gap = float(np.linalg.norm(box[:, None, :] - pts[None, :, :], axis=2).min(axis=1).max())
        if gap > 1e-3:
            v.error(rel_parts, r["part_id"], f"its row places it {gap:.3g} mm from its solid in {rel_g}")
        if r.get("kind") == "pressure_plate":
            sid = screw_set_id("GS" + r["part_id"][2:])
            wanted.add(sid)
            sc = parts.get(sid)
            if sc is None:
                v.error(rel_parts, sid, f"the screws of {r['part_id']} have no row")
            elif sc.get("quantity") != r.get("screws") or not _same_stations(sc.get("screw_stations_mm", ""),
                                                                               r.get("screw_stations_mm", "")):
                v.error(rel_parts, sid, f"{sc.get('quantity')} screws at {sc.get('screw_stations_mm')} mm, "
                                        f"{rel_r} has {r.get('screws')} at {r.get('screw_stations_mm')} mm")
    for pid in sorted(set(parts) - wanted):
        v.error(rel_parts, pid, f"retention part is not in {rel_r}")


def _same_stations(a: str, b: str) -> bool:
    """Two ``;``-separated station lists agree to retention.csv's 0.1 mm."""
    try:
        xa, xb = ([float(x) for x in t.split(";") if x] for t in (a, b))
    except ValueError:
        return False
    return len(xa) == len(xb) and all(abs(p - q) <= 0.051 for p, q in zip(xa, xb))


def _check_plate_bending(v: Verification, rel_r: str, plates: dict[str, dict[str, str]],
                         covers: dict[str, set[str]], panels: dict[str, dict[str, str]], suction: float,
                         load_factor: float, material: str) -> None:
    """Each pressure plate bent between its screws (:class:`~fabrication.glazing.retention_strength.PlateBending`)
    recomputed: its line load from the panes its gasket covers (measured on the STEP files above), each pane's
    design suction times its ``area_mm2`` over its ``perimeter_mm`` (parts.csv); the span and end overhang from
    its stations; stress ``M/(b·t²/6)`` against ``f/γ`` of its material and the deflection against span/200.
    A finding where either is exceeded, or where retention.csv states other figures (beyond 1 %)."""
    from ppfab.errors import DesignError

    from ..glazing.retention_strength import plate_bending, plate_material

    if not plates:
        return
    try:
        strength = plate_material(material)
    except DesignError as exc:
        v.error("manifest.json", "glazing.pressure_plate_material", str(exc))
        return
    for pid, r in sorted(plates.items()):
        xs = [float(x) for x in r.get("screw_stations_mm", "").split(";") if x]
        try:
            length, width, thick = (float(r[k]) for k in ("length_mm", "width_mm", "height_mm"))
        except (KeyError, ValueError):
            continue
        over = covers.get("CG" + pid[2:], set())
        line = sum(suction * 1e-3 * number(panels.get(p, {}).get("area_mm2"))
                   / number(panels.get(p, {}).get("perimeter_mm")) for p in over)
        if not math.isfinite(line):
            continue
        b = plate_bending(pid, line, xs, length, width, thick, strength, load_factor)
        for text in b.failures():
            v.error(rel_r, pid, text)
        stated = number(r.get("plate_stress_N_mm2"))
        if math.isfinite(stated) and abs(stated - b.stress) > 0.01 * max(b.stress, 1.0):
            v.error(rel_r, pid, f"plate_stress_N_mm2 {stated:g} but its screws and the panes it clamps give "
                                f"{b.stress:.2f} N/mm²")
