"""erection.csv: every part once, in an order in which each goes into its place along its direction from far away
without passing through a part of an earlier step, measured on the written solids with manifold3d (the clamping
screws, which no STEP file draws, rebuilt from their parts.csv row: :func:`screw_bodies`).

The rows are read as written: a step (1, 2, …), a kind, a unit insertion direction (none for a weld) and
``after`` below the step.  Every part of ``parts.csv`` and every gasket of a strip appears exactly once.

The solids come from the STEP files (``beams.step`` as the step check read it, ``glazing.step``,
``splices.step``, ``panels.step``) and are rebuilt in manifold3d from the boundary of their largest face, so
nothing is shared with the code that made the order: a convex solid is the hull of its vertices, any other (a
slotted plate, a cover plate with holes, a non-convex pane) that face's polygon extruded by the solid's
thickness.  A part moving along ``d`` sweeps the Minkowski sum of itself and the segment ``[−L·d, 0]``, with
``L`` far enough that it starts beyond every part of the earlier steps (a retention part, fitted by hand, from
:data:`HAND_APPROACH_MM` beyond its place): for a convex solid the hull of the solid and the solid moved back
by ``L``; for a plate moving in its own plane the extrusion of its polygon's 2D Minkowski sum with the segment;
otherwise the union of the hulls of the prisms over the polygon's triangles and their moved copies.  The sweep is
intersected with every part of an
earlier step whose box, and whose box seen along ``d``, overlaps its own (the neighbours); the *depth* of an
intersection is the thinnest extent of its thickest connected piece (the smallest width over the piece's face
normals), how far the two would have to move apart.  Deeper than :data:`TOLERANCE` is a finding naming the part,
the part it passes through and the depth.

Two parts that overlap where they stand (a pass's ``static`` depth: the common of the part in its place and
the earlier one) by more than :data:`TOLERANCE` are a finding of the finished model, whatever the order: a part
of a plate's own polyline deeper in it than half its thickness is *inside the steel*, a part in a pane is *in
the glass*, any other pair *overlaps in its final place*.

A plate whose slot directions spread too far for one direction (``blocked_spread_deg`` set by the build) is
expected to pass through the plates it is slotted with: its passes through beam plates are not findings, but a
plate so marked that slides in cleanly is (the mark is wrong).
"""

from __future__ import annotations

import logging
import re

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from . import Verification, check, read_csv

HAND_APPROACH_MM = 300.0
"""How far (mm) a part fitted by hand (:data:`BY_HAND`) is brought along its direction before it reaches its place:
it comes from the installer's reach, not from beyond the whole roof (on a surface that folds over itself, a
cover cap swept from beyond every part went through the panes of the fold above it: Enneper, 17.5 mm)."""

BY_HAND = ("setting_block", "stop", "pressure_gasket", "pressure_plate", "screw", "cover_cap")
"""The kinds of ``erection.csv`` fitted by hand: the retention parts."""

TOLERANCE = 0.25
"""mm: the depth up to which a sweep may overlap an earlier part: a pane may sit 0.1 mm into its gasket
(:data:`fabrication.glazing.seat.SEAT_TOLERANCE`), parts touch along faces, and the STEP decimals and the
sampled arcs add their numerics."""

KINDS = {"row", "column", "weld", "splice", "strip", "gasket", "panel", "setting_block", "stop", "pressure_gasket",
         "pressure_plate", "screw", "cover_cap"}
RETENTION = ("setting_block", "stop", "pressure_gasket", "pressure_plate", "screw", "cover_cap")
"""The retention kinds: lowered like the panes, past leaning steel as they are (a warning, not a finding)."""
SCREW_SIDES = 16
"""A clamping screw is rebuilt as the hull of two 16-gons of its diameter (its foot and its top)."""


@dataclass(frozen=True)
class Pass:
    """A part whose sweep passes through a part of an earlier step: the two ids, the depth (mm) and volume (mm³)
    of their intersection, and the depth (mm) by which the two overlap where they stand (``static``, 0 when
    they do not: a clash of the finished assembly, not of the order)."""

    part: str
    through: str
    depth: float
    volume: float
    static: float

    @property
    def excess(self) -> float:
        """How much deeper (mm) the way in passes than the two overlap in place; 0 for a pair that already
        overlaps in place (a clash of the finished model, not of the order: the clash check's and the glazing's)
        or whose common part has no volume (a touch)."""
        if self.static > TOLERANCE or self.volume < MIN_VOLUME_MM3:
            return 0.0
        return self.depth - self.static


MIN_VOLUME_MM3 = 1.0
"""A common part of a swept part and a placed one smaller than this (mm³) is a touch, not a pass."""


@dataclass
class Body:
    """A solid rebuilt for the sweep, with its box: either ``convex`` (the hull of ``points``) or a flat prism,
    the polygon ``flat`` (shapely, holes included) in the plane ``origin + x·ex + y·ey`` extruded by ``thick``
    along ``n``."""

    points: np.ndarray
    convex: bool
    origin: np.ndarray
    ex: np.ndarray
    ey: np.ndarray
    n: np.ndarray
    thick: float
    flat: Any
    _shape: Any = None

    @property
    def lo(self) -> np.ndarray:
        return self.points.min(axis=0)

    @property
    def hi(self) -> np.ndarray:
        return self.points.max(axis=0)

    def prism(self, polygon: Any) -> Any:
        """A shapely polygon of this body's plane extruded like the body (a manifold3d ``Manifold``)."""
        import manifold3d as m3  # type: ignore[import-not-found]
        from shapely.geometry import MultiPolygon

        polys = polygon.geoms if isinstance(polygon, MultiPolygon) else [polygon]
        rings = []
        for poly in polys:
            rings.append(np.asarray(poly.exterior.coords)[:-1])
            rings += [np.asarray(r.coords)[:-1] for r in poly.interiors]
        m = m3.Manifold.extrude(m3.CrossSection(rings, m3.FillRule.EvenOdd), self.thick)
        return m.transform(np.column_stack([self.ex, self.ey, self.n, self.origin]))

    def shape(self) -> Any:
        """The solid itself."""
        if self._shape is None:
            self._shape = hull(self.points) if self.convex else self.prism(self.flat)
        return self._shape

    def swept(self, d: np.ndarray, far: float) -> Any:
        """The Minkowski sum of the solid and the segment ``[−far·d, 0]``: the hull of the solid and its copy moved
        back when convex; a prism moving in its own plane sweeps its polygon's 2D Minkowski sum with the segment
        (the polygon, its copy and a parallelogram over every edge); moving out of its plane, the union of the
        swept prisms over the triangles of its polygon."""
        import shapely
        from shapely.geometry import Polygon
        from shapely.ops import unary_union

        if self.convex:
            return hull(np.vstack([self.points, self.points - far * d]))
        s2 = -far * np.array([d @ self.ex, d @ self.ey])
        if abs(float(d @ self.n)) < 1e-6:
            pieces = [self.flat, shapely.affinity.translate(self.flat, float(s2[0]), float(s2[1]))]
            polys = [self.flat] if not hasattr(self.flat, "geoms") else list(self.flat.geoms)
            for poly in polys:
                for ring in [poly.exterior, *poly.interiors]:
                    c = np.asarray(ring.coords)
                    for a, b in zip(c[:-1], c[1:]):
                        quad = Polygon([a, b, b + s2, a + s2])
                        if quad.area > 1e-9:
                            pieces.append(quad)
            return self.prism(unary_union(pieces).buffer(0))
        out = []
        for tri in shapely.constrained_delaunay_triangles(self.flat).geoms:
            q = np.asarray(tri.exterior.coords)[:3]
            p3 = self.origin + np.outer(q[:, 0], self.ex) + np.outer(q[:, 1], self.ey)
            p3 = np.vstack([p3, p3 + self.thick * self.n])
            out.append(hull(np.vstack([p3, p3 - far * d])))
        return union(out)


def hull(points: np.ndarray) -> Any:
    import manifold3d as m3

    return m3.Manifold.hull_points(np.ascontiguousarray(points, dtype=float))


def union(shapes: list[Any]) -> Any:
    import manifold3d as m3

    return shapes[0] if len(shapes) == 1 else m3.Manifold.batch_boolean(shapes, m3.OpType.Add)


def _ring(wire: Any, arc_points: int = 16) -> np.ndarray:
    """``(k, 3)`` the closed boundary ``wire`` of a face as a ring of points: each straight edge by its ends, a
    curved one (a bolt hole, a slot's relief) by ``arc_points`` points along it, the edges chained end to start."""
    runs = []
    for e in wire.edges():
        if e.geom_type.name == "LINE":
            runs.append(np.array([tuple(e.start_point()), tuple(e.end_point())], dtype=float))
        else:
            runs.append(np.array([tuple(e.position_at(t)) for t in np.linspace(0.0, 1.0, arc_points + 1)],
                                 dtype=float))
    ring = [runs.pop(0)]
    while runs:
        end = ring[-1][-1]
        k = min(range(len(runs)), key=lambda i: min(float(np.linalg.norm(runs[i][0] - end)),
                                                   float(np.linalg.norm(runs[i][-1] - end))))
        r = runs.pop(k)
        ring.append(r if np.linalg.norm(r[0] - end) <= np.linalg.norm(r[-1] - end) else r[::-1])
    return np.vstack([r[:-1] for r in ring])


CONVEX_MM2 = 0.5
"""How much area (mm²) a prism's face may miss of the hull of its vertices and still be taken as convex (its hull
is then its body): a notch or slot is larger, rounding far smaller."""


def body_of(solid: Any) -> Body:
    """A thin prism read from STEP as a :class:`Body`: its largest face gives the plane and the polygon (its outer
    and inner boundaries, :func:`_ring`), convex when the polygon fills its hull."""
    from shapely.geometry import MultiPoint, Polygon

    text = hasattr(solid, "face_area")                  # a record of the text-level reader
    if text:
        pts = solid.points
        planes = [f for f in solid.faces() if f.surface == "plane"]
        face = max(planes, key=solid.face_area)
        outer = solid.outer_loop(face)
        outer_ring = solid.ring(outer, 16)
        inner_rings = [solid.ring(lp, 16) for lp in face.loops if lp is not outer]
    else:
        pts = np.array([tuple(p) for p in solid.vertices()], dtype=float).reshape(-1, 3)
        face = max(solid.faces(), key=lambda f: f.area)
        outer_ring = _ring(face.outer_wire())
        inner_rings = [_ring(w) for w in face.inner_wires()]
    c = pts.mean(axis=0)
    axes = np.linalg.svd(pts - c)[2]
    n = axes[2]
    own = np.asarray(face.normal if text else tuple(face.normal_at()), dtype=float)
    if abs(float(own @ n)) < 1.0 - 1e-12:               # a bevelled plate's corners tilt the fitted plane
        n = own / np.linalg.norm(own)
    fo = outer_ring[0]
    off = (pts - fo) @ n
    if abs(off.min()) > abs(off.max()):                 # n from the face into the solid
        n, off = -n, -off
    ex = axes[0] - (axes[0] @ n) * n
    ex /= np.linalg.norm(ex)
    ey = np.cross(n, ex)
    thick = float(off.max())

    def to2(q: np.ndarray) -> np.ndarray:
        return np.stack([(q - fo) @ ex, (q - fo) @ ey], axis=1)

    flat = Polygon(to2(outer_ring), [to2(r) for r in inner_rings]).buffer(0)
    other = _opposite_ring(solid, face, n, text)
    if other is not None:                               # a bevelled plate's faces differ: the part both hold
        flat = flat.intersection(Polygon(to2(other)).buffer(0))
        if flat.geom_type == "GeometryCollection":      # the faces meet along a notch's wall: a line beside it
            import shapely
            from shapely.ops import unary_union

            flat = unary_union([g for g in shapely.get_parts(flat) if g.geom_type == "Polygon"])
    # convex: the polygon fills the hull of the solid's vertices up to rounding.  An absolute bound: 1e-4 of the
    # area (28 mm² on a 1.6 m plate) took a notch of 24 mm² under a crossing strip for convex, and the hull that
    # filled it stood 0.55 mm into the strip (p_optimised_conical1's corner plates)
    convex = abs(flat.area - MultiPoint(to2(pts)).convex_hull.area) <= max(CONVEX_MM2, 1e-9 * flat.area)
    return Body(pts, convex, fo, ex, ey, n, thick, flat)


def _opposite_ring(solid: Any, face: Any, n: np.ndarray, text: bool) -> np.ndarray | None:
    """The outer boundary of the solid's other large face parallel to ``face`` (a plate's other side), ``None``
    when there is none.  A plate whose top edge is bevelled under its strip has two faces of different outline
    (:mod:`fabrication.beams.bevel_cut`); its body is the prism over what both hold, inside the solid by at most
    the bevel's wedge, so that a square plate's overlap with its strip is still measured in full."""
    if text:
        area = solid.face_area(face)
        for f in solid.faces():
            if f is not face and f.surface == "plane" and abs(float(f.normal @ n)) >= 1.0 - 1e-9 \
                    and solid.face_area(f) > 0.5 * area:
                return solid.ring(solid.outer_loop(f), 16)
        return None
    for f in solid.faces():
        if f.is_same(face) or f.area <= 0.5 * face.area:
            continue
        try:
            fn = np.array(tuple(f.normal_at()), dtype=float)
        except Exception:  # noqa: BLE001 - a non-planar face
            continue
        if abs(float(fn @ n)) >= 1.0 - 1e-9:
            return _ring(f.outer_wire())
    return None


def depth_of(shape: Any) -> tuple[float, float]:
    """``(depth, volume)`` of an intersection: the depth of its thickest connected piece — the smallest width over
    its face normals; a sliver left where two solids only touch (no face with an area, or thinner than 1 µm on
    average) has none — and its volume (0, 0 when empty)."""
    if shape.is_empty():
        return 0.0, 0.0
    vol = float(shape.volume())
    if vol <= 1e-9:
        return 0.0, vol
    best = 0.0
    for comp in shape.decompose():
        mesh = comp.to_mesh()
        v = np.asarray(mesh.vert_properties, dtype=float)[:, :3]
        t = np.asarray(mesh.tri_verts, dtype=int)
        if len(t) == 0:
            continue
        nn = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
        ln = np.linalg.norm(nn, axis=1)
        dirs = nn[ln > 1e-12] / ln[ln > 1e-12, None]
        if len(dirs) == 0:                      # no face with an area: a degenerate sliver, no depth
            continue
        keys, group = np.unique(np.round(dirs, 6), axis=0, return_inverse=True)
        proj = v @ keys.T
        width = float((proj.max(axis=0) - proj.min(axis=0)).min())
        # a piece thinner than a micrometre on average (volume over its largest face, the triangles of one normal
        # summed) is where two solids only touch: no depth, whatever its facets' directions say
        face = float(np.bincount(np.asarray(group).reshape(-1), weights=0.5 * ln[ln > 1e-12]).max())
        if abs(float(comp.volume())) >= 1e-3 * face:
            best = max(best, width)
    return best, vol


def welded_on(part: str, other: str) -> bool:
    """A glazing strip (``GS-U03-07``) or its gasket (``GK-U03-07``) against a plate of its own beam (``B-U03``,
    ``B-U03-S01``): parts in designed contact — the strip is lowered onto and welded to that plate's top edge.
    Their fit in place (the plate's lean under a flat strip) is the clash check's and glazing's business, not the
    order's, so the sweep does not measure the pair.

    >>> welded_on("GS-U03-07", "B-U03-S01"), welded_on("GK-U03-07", "B-U03"), welded_on("GS-U03-07", "B-W02")
    (True, True, False)
    """
    if not part.startswith(("GS-", "GK-")):
        return False
    beam = "B-" + part[3:].rsplit("-", 1)[0]
    return other == beam or other.startswith(beam + "-")


def drilled_through(part: str, other: str) -> bool:
    """A clamping screw of a plate (``SC-U03-07#2``, the second screw of ``SC-U03-07``) and the parts of its own
    strip it stands in by design: the strip's gasket, the pressure gasket and plate (drilled for it: the holes are
    not modelled) and the cover cap (its nut inside the cap's channel, drawn as the prism it fills).

    >>> drilled_through("SC-U03-07#2", "CP-U03-07"), drilled_through("CC-U03-07", "SC-U03-07#1")
    (True, True)
    >>> drilled_through("SC-U03-07#2", "CP-U03-08"), drilled_through("SC-U03-07#2", "P-U01-V02")
    (False, False)
    """
    a, b = (part, other) if part.startswith("SC-") else (other, part)
    if not a.startswith("SC-") or not b.startswith(("GK-", "CG-", "CP-", "CC-")):
        return False
    return a.split("#")[0][3:] == b[3:]


def screw_bodies(row: dict[str, Any]) -> dict[str, Body]:
    """The screws of one ``kind = "screw"`` row of parts.csv, each a :class:`Body` named ``<part_id>#<k>``
    (1-based), from the row's ``frame``, ``screw_stations_mm``, ``diameter_mm`` and ``length_mm``; none when a
    cell is missing or malformed (the parts check names it)."""
    import json

    try:
        cell = row.get("frame")
        f = json.loads(cell) if isinstance(cell, str) else cell
        o, ex, ey, n = (np.asarray(f[k], dtype=np.float64) for k in ("origin", "x_dir", "y_dir", "normal"))  # type: ignore[index]
        xs = [float(x) for x in str(row.get("screw_stations_mm", "")).split(";") if x]
        r, length = 0.5 * float(row["diameter_mm"]), float(row["length_mm"])
    except (TypeError, ValueError, KeyError):
        return {}
    t = np.linspace(0.0, 2.0 * np.pi, SCREW_SIDES, endpoint=False)
    out = {}
    for k, x in enumerate(xs, start=1):
        foot = o + np.multiply(x, ex) + r * (np.outer(np.cos(t), ex) + np.outer(np.sin(t), ey))
        pts = np.vstack([foot, foot + np.multiply(length, n)])
        out[f"{row['part_id']}#{k}"] = Body(pts, True, o + np.multiply(x, ex), ex, ey, n, length, None)
    return out


def _perp(d: np.ndarray) -> np.ndarray:
    a = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(d, a)
    e1 /= np.linalg.norm(e1)
    return np.stack([e1, np.cross(d, e1)])


def _holds(part: str, pane: str) -> bool:
    """Whether retention part ``part`` is a setting block or stop of pane ``pane`` (``SB-U07-V12-1`` and
    ``ST-U07-V12-1`` of ``P-U07-V12``); pressure plates, their gaskets and caps go on after the panes they clamp."""
    return part[:2] in ("SB", "ST") and part[2:].rsplit("-", 1)[0] == pane[1:]


def sweep_passes(order: list[tuple[str, int, np.ndarray]], bodies: dict[str, Body],
                 approach: dict[str, float] | None = None) -> list[Pass]:
    """Every part of ``order`` (id, step, unit direction) with a body, swept along its direction from beyond every
    part of an earlier step (from ``approach[id]`` mm beyond its place where given: a part fitted by hand), against
    those whose boxes (3D and seen along the direction) overlap its sweep: one :class:`Pass` per pair measured
    (depth and volume 0 when they do not intersect)."""
    out: list[Pass] = []
    names = [pid for pid, _, _ in order if pid in bodies]
    if not names:
        return out
    steps = np.array([step for pid, step, _ in order if pid in bodies])
    lo_all = np.array([bodies[q].lo for q in names])
    hi_all = np.array([bodies[q].hi for q in names])
    centre, half = 0.5 * (lo_all + hi_all), 0.5 * (hi_all - lo_all)
    for pid, step, d in order:
        body = bodies.get(pid)
        if body is None or not np.any(steps < step):
            continue
        earlier = steps < step
        reach = float((centre[earlier] @ -d + half[earlier] @ np.abs(d)).max())   # farthest earlier box along −d
        far = max(reach - float((body.points @ -d).min()) + 1.0, 1.0)
        if approach and pid in approach:
            far = min(far, approach[pid] + float(np.ptp(body.points @ d)))
        allp = np.vstack([body.points, body.points - far * d])
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        e = _perp(d)
        f2 = allp @ e.T
        flo, fhi = f2.min(axis=0), f2.max(axis=0)
        c2, h2 = centre @ e.T, half @ np.abs(e.T)                                  # the boxes seen along d
        near = earlier & np.all(lo_all <= hi + TOLERANCE, axis=1) & np.all(hi_all >= lo - TOLERANCE, axis=1) \
            & np.all(c2 - h2 <= fhi + TOLERANCE, axis=1) & np.all(c2 + h2 >= flo - TOLERANCE, axis=1)
        shape = None
        for k in np.flatnonzero(near):
            if welded_on(pid, names[k]) or drilled_through(pid, names[k]):
                continue
            b = bodies[names[k]]
            if shape is None:
                shape = body.swept(d, far)
            depth, vol = depth_of(shape ^ b.shape())
            static = depth_of(body.shape() ^ b.shape())[0] if depth > TOLERANCE else 0.0
            out.append(Pass(pid, names[k], depth, vol, static))
    return out


def _read_rows(v: Verification, rel: str) -> list[tuple[str, str, int, np.ndarray, str]] | None:
    """``(part_id, kind, step, direction, blocked spread)`` of the well-formed rows; findings for the others."""
    try:
        rows = read_csv(v.folder / rel)
    except (OSError, ValueError) as exc:
        v.error(rel, "", f"cannot be read ({exc})")
        return None
    out = []
    for k, r in enumerate(rows, start=2):
        pid, kind = r.get("part_id") or "", r.get("kind") or ""
        where = pid or f"row {k}"
        try:
            step, after = int(r.get("step") or ""), int(r.get("after") or "")
        except ValueError:
            v.error(rel, where, f"step {r.get('step')!r} or after {r.get('after')!r} is not a whole number")
            continue
        if kind not in KINDS:
            v.error(rel, where, f"kind {kind!r} is none of {', '.join(sorted(KINDS))}")
            continue
        if step < 1 or not 0 <= after < step:
            v.error(rel, where, f"step {step} must be ≥ 1 and after {after} below it")
        d = np.zeros(3)
        if kind != "weld":
            try:
                d = np.array([float(r.get(f"direction_{c}") or "") for c in "xyz"])
            except ValueError:
                v.error(rel, where, "insertion direction is not three numbers")
                continue
            if not np.all(np.isfinite(d)) or abs(float(np.linalg.norm(d)) - 1.0) > 1e-4:
                v.error(rel, where, f"insertion direction {d.tolist()} is not a unit vector")
                continue
        out.append((pid, kind, step, d, r.get("blocked_spread_deg") or ""))
    return out


def _bodies(v: Verification, files: dict[str, Any], wanted: set[str]) -> dict[str, Body]:
    from ._step_read import read_or_report

    solids: dict[str, Any] = dict(v.data.get("beam_solids") or {})
    keys = ["glazing_step", "splices_step", "panels_step"] + ([] if solids else ["beams_step"])
    for key in keys:
        rel = files.get(key)
        if rel:
            for s in read_or_report(v, rel) or []:
                if s.name in wanted:
                    solids.setdefault(s.name, s.solid)
    return {name: body_of(solid) for name, solid in solids.items() if name in wanted}


def _overlap_hint(a: str, b: str) -> str:
    """What to look at when parts of kinds ``a`` and ``b`` overlap in place."""
    pair = {a, b}
    if pair & {"strip", "gasket"} and pair & {"row", "column", "splice"}:
        return ("; the plate's bevel or notch does not clear the strip (docs/glazing.md): a splice cut keeps its "
                "plate's full top edge, so a cut beside a node may need another beams.max_length")
    if pair <= {"strip", "gasket"}:
        return "; strips meeting at a node should clear each other (docs/glazing.md, at the nodes)"
    return ""


def _same_line(a: str, b: str) -> bool:
    """Whether two part ids name the same mesh polyline (``GS-U03-06``, ``CC-U03-06`` and ``B-U03-S01``: ``U03``)."""
    ma, mb = re.search(r"-([UW]\d+)", a), re.search(r"-([UW]\d+)", b)
    return ma is not None and mb is not None and ma.group(1) == mb.group(1)


def _number(text: Any) -> float | None:
    """A cell's finite positive number, ``None`` otherwise (the parts check names a bad cell)."""
    try:
        x = float(text)
    except (TypeError, ValueError):
        return None
    return x if np.isfinite(x) and x > 0 else None


@check("erection", 68)
def check_erection(v: Verification) -> None:
    files = v.data.get("manifest", {}).get("files", {})
    rel = files.get("erection_csv")
    if rel is None:
        return
    rows = _read_rows(v, rel)
    if rows is None:
        return
    parts = v.data.get("parts")
    if parts is None:
        try:
            parts = read_csv(v.folder / files.get("parts_csv", "parts.csv"))
        except (OSError, ValueError) as exc:
            v.error(rel, "", f"cannot be checked: parts.csv cannot be read ({exc})")
            return
    wanted = [r["part_id"] for r in parts] + ["GK" + r["part_id"][2:] for r in parts if r.get("kind") == "strip"]
    seen: dict[str, int] = {}
    for pid, *_ in rows:
        seen[pid] = seen.get(pid, 0) + 1
    for pid in wanted:
        if seen.get(pid, 0) != 1:
            v.error(rel, pid, f"appears {seen.get(pid, 0)} times, expected once")
    known = set(wanted)
    for pid, kind, *_ in rows:
        if pid not in known and kind != "weld":
            v.error(rel, pid, "is not a part of parts.csv nor the gasket of a strip")
    order = [(pid, step, d) for pid, kind, step, d, _ in rows if kind != "weld" and pid in known]
    bodies = _bodies(v, files, {pid for pid, _, _ in order})
    screws = {r["part_id"]: screw_bodies(r) for r in parts if r.get("kind") == "screw"}
    for one in screws.values():
        bodies.update(one)
    order = [(name, step, d) for pid, step, d in order for name in (list(screws[pid]) if pid in screws else [pid])]
    blocked = {pid: spread for pid, _, _, _, spread in rows if spread}
    kind_of = {pid: kind for pid, kind, *_ in rows}
    beams = {r["part_id"] for r in parts if r.get("kind") == "beam"}
    passes = [replace(p, part=p.part.split("#")[0], through=p.through.split("#")[0])
              for p in sweep_passes(order, bodies, {name: HAND_APPROACH_MM for name, _, _ in order
                                                    if kind_of.get(name.split("#")[0]) in BY_HAND})]
    deep = [p for p in passes if p.excess > TOLERANCE]
    v.data["erection_passes"] = passes
    kinds = {pid: kind for pid, kind, *_ in rows}
    overlapping = [p for p in passes if p.static > TOLERANCE]
    # a plate leaning under a part it carries lifts one top corner into it by (t/2)·sin λ < t/2: an overlap in
    # place deeper than half the plate's thickness is no lean but a part placed inside the steel (strips hung
    # on the glass's side of the plates: 12 mm on a real mesh whose faces pointed inwards).  Only the parts of
    # the plate's own polyline: a strip of the other family crossing a plate at a node meets its top edge over
    # the strip's width (a fit at the crossing, warned below)
    half_t = {r["part_id"]: 0.5 * t for r in parts if r.get("kind") == "beam"
              for t in [_number(r.get("thickness_mm"))] if t is not None}
    inside = sorted((p for p in overlapping if _same_line(p.part, p.through)
                     and p.static > min(half_t.get(p.part, np.inf), half_t.get(p.through, np.inf)) + TOLERANCE),
                    key=lambda p: -p.static)
    for p in inside[:20]:
        plate = p.through if p.through in half_t else p.part
        v.error(rel, p.part, f"overlaps {p.through} in its final place by {p.static:.2f} mm, deeper than half the "
                             f"plate's thickness ({half_t[plate]:.2f} mm), which no lean of the plate explains: the part "
                             f"is inside the steel (is the glass on the side the beams hang? [panels] outside)")
    if len(inside) > 20:
        v.error(rel, "", f"{len(inside) - 20} more parts inside a beam plate in their final places")
    overlapping = [p for p in overlapping if p not in inside]
    # glass takes no steel: a retention part or another pane standing in a pane in its final place (a clamping
    # screw beside a joint a kink closes towards the glass's top) is a finding.  The structure under a pane is not
    # (a beam plate's leaning top corner under glass laid on the plates, [glazing] support = "none": the lean's
    # fit, warned below; strips and gaskets are the clash check's)
    def into_glass(p: Any) -> tuple[str, str] | None:
        for pane, other in ((p.part, p.through), (p.through, p.part)):
            if kinds.get(pane) == "panel" and kinds.get(other) in (*RETENTION, "panel"):
                return pane, other
        return None
    deepest: dict[tuple[str, str], Any] = {}
    for p in overlapping:
        pair = into_glass(p)
        if pair is not None and (pair not in deepest or p.static > deepest[pair].static):
            deepest[pair] = p
    in_glass = sorted(deepest.items(), key=lambda kv: -kv[1].static)
    for (pane, other), p in in_glass[:20]:
        v.error(rel, pane, f"has {other} {p.static:.2f} mm inside it in its final place (more than {TOLERANCE:g} mm): "
                           f"glass takes no steel; widen [panels] gap by twice that to clear a clamping screw")
    if len(in_glass) > 20:
        v.error(rel, "", f"{len(in_glass) - 20} more parts inside a pane in their final places")
    # every other overlap in place beyond the tolerance is a clash of the finished model: the plates' bevels and
    # notches take the lean under the strips, running strips meet on the mitre plane of their spans, so every
    # bundled example builds without one (the largest was 0.73 mm, a gasket in the next span's strip at a valley)
    overlapping = sorted((p for p in overlapping if into_glass(p) is None), key=lambda p: -p.static)
    # ... except glass laid straight on the steel ([glazing] support = "none", no strips: the glazing system is
    # someone else's), where a leaning plate's top corner rises (t/2)·sin λ into the pane and a splice's cover
    # plates, set under the top edge for strips that are not there, can reach it: said, as before
    bare = (v.data.get("manifest", {}).get("fabrication", {}).get("glazing", {}) or {}).get("support") == "none"

    def on_plates(p: Any) -> bool:
        return bare and {kinds.get(p.part), kinds.get(p.through)} in ({"panel", "row"}, {"panel", "column"},
                                                                      {"panel", "splice"})

    lean = [p for p in overlapping if on_plates(p)]
    if lean:
        logging.getLogger("ppfab").warning(
            "erection: %d pair(s) of a pane laid on the bare steel and a beam or cover plate overlap by up to %.2f mm "
            "(%s on %s): glass on bare plates needs a bed that takes the plates' lean and the splices "
            "([glazing] support = \"strip\" models one)", len(lean), lean[0].static, lean[0].part, lean[0].through)
    overlapping = [p for p in overlapping if not on_plates(p)]
    for p in overlapping[:20]:
        v.error(rel, p.part, f"overlaps {p.through} in its final place by {p.static:.2f} mm ({p.volume:.0f} mm³, "
                             f"more than {TOLERANCE:g} mm): two parts of the finished model in one another"
                             + _overlap_hint(kinds.get(p.part, ""), kinds.get(p.through, "")))
    if len(overlapping) > 20:
        v.error(rel, "", f"{len(overlapping) - 20} more pairs of parts overlapping in their final places")
    # the plan's way in for cover plates, strips, gaskets and panes past the steel (lowered in the beam's plane,
    # along the strip's down or the pane's inside normal) is not proven on leaning beams: said, not failed; the
    # rows (they go in first, into nothing) and the glazing and glass among themselves stay findings
    steel = beams | {pid for pid, kind, *_ in rows if kind == "splice"}
    glazing = {pid for pid, kind, *_ in rows if kind in ("strip", "gasket")}
    onto_steel = sorted({p.part for p in deep if (kinds.get(p.part) in ("column", "splice", "strip", "gasket", "panel",
                                                                        *RETENTION)
                                                  and p.through in steel)
                         or (kinds.get(p.part) == "panel" and p.through in glazing)})
    if onto_steel:
        logging.getLogger("ppfab").warning(
            "erection: %d column plate(s), cover plate(s), strip(s), gasket(s), pane(s) or retention part(s) pass a beam "
            "or cover plate "
            "on their way in (%s): no single straight way in past leaning steel; fit them before that plate, from the "
            "side, or split them", len(onto_steel), ", ".join(onto_steel[:6]))
    # a pane that has no straight way in past the steel or glazing of a fold above it meets the setting blocks,
    # stops and caps of that fold's panes on the same way: the same warning, not another finding (its own blocks
    # stay findings: they would be set where the pane cannot come down onto them)
    fitted = {pid for pid, kind, *_ in rows if kind in RETENTION}
    others = {(p.part, p.through) for p in deep if kinds.get(p.part) == "panel" and p.part in onto_steel
              and p.through in fitted and not _holds(p.through, p.part)}
    shown = 0
    for p in sorted(deep, key=lambda p: -p.depth):
        if (p.part in blocked and p.through in beams) or (p.part in onto_steel and p.through in steel | glazing) \
                or (p.part, p.through) in others:
            continue
        if shown < 20:
            v.error(rel, p.part, f"passes through {p.through} by {p.depth:.2f} mm ({p.volume:.0f} mm³) on its way in "
                                 f"(more than {TOLERANCE:g} mm"
                                 + (f" beyond their overlap in place, {p.static:.2f} mm)" if p.static > 0 else ")"))
        shown += 1
    if shown > 20:
        v.error(rel, "", f"{shown - 20} more passes of parts through parts of earlier steps")
    for pid, spread in blocked.items():
        # a blocked mark the sweep does not confirm is conservative for a column (its slots' play can hide the
        # sideways travel from the sweep), but always wrong for a row: rows go in first, into nothing
        if kinds.get(pid) == "row" and not any(p.part == pid for p in deep):
            v.error(rel, pid, f"is marked as having no single insertion direction (spread {spread}°) but slides in "
                              f"clear of every earlier part")
    v.checked.append("erection")
