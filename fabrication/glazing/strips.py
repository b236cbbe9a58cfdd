"""Glazing strips: one flat bar on the top edge of every beam span, and its gasket.

A span is a mesh edge ``a b`` with its beam plane ``(n, d)`` (``support.edge_planes``).  Its strip lies on the
beam's top edge, in the plane through the edge that bisects the one or two panes on it (the panes are
nearly coplanar across an edge, the beam plane need not be square to them: a PP support plane ``U_i``
can lean 20° off the glass), in the frame

    ex = (b − a) / |b − a|   (a, b projected into the beam plane),
    ez = up: N_1 + N_2 (the outside normals of the panes on the edge), made perpendicular to ex,
    ey = ez × ex,

so the strip is the rectangle ``x0 ≤ x ≤ x1, |y| ≤ w/2`` at ``0 ≤ z ≤ t_s`` (the gasket on it at
``t_s ≤ z ≤ t_s + t_g``), drawn in 2D and extruded once.

At every node one polyline *runs through*: the one with two spans there, of the lowest family (rows before
columns); where no polyline has two spans, two spans of one family that kink by at most 30°, rows before columns (a
re-entrant corner of a trimmed boundary, where the mesh's polylines stop but the beams go on),
else — at a corner — the span of the lowest family (:func:`running_spans`).  Its strips end at the node, each
on its own side of the *mitre plane* of the two spans (through the node, normal ``o_e − o_f``, the unit
directions from the node into the two spans), strip and gasket alike (:func:`mitre_setback`): square-cut,
set back by

    s = (max(0, H·(up·o_f)) + (w/2)·|ey·o_f|) / (1 − o_e·o_f),     H = t_s + t_g,

which is ``H·tan(κ/2)`` where the polyline kinks by κ towards the glass (a valley: the two boxes' top corners
meet on the mitre plane) and 0 where it kinks away (a ridge: their bottom edges would meet at the node) — and
at least ``t_s·tan(κ/2)``, the setback of before, which keeps the next span's gasket out from under the pane's
corner where the row also turns in plan (a recovered real grid's pane entered it by 0.17 mm at zero setback).
Before, the setback was ``t_s·tan(κ/2)`` either way, and in a valley each gasket ran ``t_g·tan(κ/2)`` into the
next span's strip (0.73 mm on ``smallest_roof``).  Every other strip at the node *stops* where its rectangle
clears the running strips' band
``|distance| ≤ w/2`` by the clearance ``c``: with ``θ`` the angle between the two spans,

    x_stop = (w/2 + c + (w/2)·|cos θ|) / sin θ.

Every strip end, running or stopping, then keeps out from under the corners of the panes at the node that it
does not carry (:func:`corner_cutback`): where a beam kinks towards the glass under an obtuse pane corner, the
next span's strip reaches under that corner and rises with the kink, and the pane would rest on it instead of on
its own edges' gaskets (on a 10 m patch of a real shell, five panes 4.8–6.5 mm above nominal).  The end moves to
the farthest point of the strip's band that lies in the corner (seen along the strip's ``up``) with its gasket top
more than :data:`CORNER_RISE_TOL` above the pane's nominal underside; on a ridge and under an acute corner that is
nowhere, and the end stays where the rules above put it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ppfab import planes as pl
from ppfab.frame import Frame
from ppfab.support.structure import SupportStructure, edge_polyline_index

from ..contract import strip_id
from .params import GlazingParams


@dataclass(frozen=True, eq=False)
class Strip:
    """The glazing strip of one span: part id ``GS-<beam>-<k>``, the mesh edge ``(a, b)`` it carries, its frame
    (origin at ``a``'s top point, normal = up), its extent ``x0 … x1`` along the span and its width."""

    part_id: str
    edge: int
    vertices: tuple[int, int]
    beam_id: str
    frame: Frame
    x0: float
    x1: float
    width: float
    thickness: float
    runs: tuple[bool, bool]

    @property
    def length(self) -> float:
        return self.x1 - self.x0

    def outline(self) -> np.ndarray:
        """``(4, 2)`` counter-clockwise rectangle in the strip frame."""
        b = 0.5 * self.width
        return np.array([[self.x0, -b], [self.x1, -b], [self.x1, b], [self.x0, b]])

    def top_corners(self, gasket: float) -> np.ndarray:
        """``(4, 3)`` corners of the gasket's top face (the surface the glass rests on), mm."""
        up = self.frame.normal
        return self.frame.to3d(self.outline()) + (self.thickness + gasket) * up


def _in_plane(v: np.ndarray, n: np.ndarray) -> np.ndarray:
    return v - np.outer(v @ n, n) if v.ndim == 2 else v - (v @ n) * n


STRAIGHT_ON_DEG = 30.0
"""At a node where no polyline has two spans (a re-entrant corner of a trimmed boundary, where the mesh's
polylines stop), two spans of one family that kink by at most this much run through as one line."""


def running_spans(node: int, spans: list[int], line_of: np.ndarray, family: np.ndarray, edges: np.ndarray,
                  direction: np.ndarray) -> set[int]:
    """The spans (edge indices) at ``node`` whose strips run through it: those of the polyline with two spans
    there (of the lowest family, rows before columns); where no polyline has two (a corner, a re-entrant corner
    of a trimmed boundary), two spans of one family that kink by at most :data:`STRAIGHT_ON_DEG` (rows before
    columns, then the straighter pair); else the span of the lowest family.  ``direction (E, 3)``: unit ``b − a`` of each
    edge ``(a, b)``; ``family (E,)``: 0 rows, 1 columns, 9 none."""
    count: dict[int, int] = {}
    for e in spans:
        count[int(line_of[e])] = count.get(int(line_of[e]), 0) + 1
    through = [k for k, m in count.items() if m >= 2 and k >= 0]
    if through:
        fam_of = {int(line_of[e]): int(family[e]) for e in spans}
        k = min(through, key=lambda q: (fam_of[q], q))
        return {e for e in spans if int(line_of[e]) == k}
    best: tuple[int, float, int, int] | None = None
    for a_i, e in enumerate(spans):
        for f in spans[a_i + 1:]:
            if family[e] != family[f] or family[e] == 9:
                continue
            oe = direction[e] if edges[e, 0] == node else -direction[e]
            of = direction[f] if edges[f, 0] == node else -direction[f]
            kink = float(np.degrees(np.arccos(np.clip(-(oe @ of), -1.0, 1.0))))
            if kink <= STRAIGHT_ON_DEG and (best is None or (int(family[e]), kink, min(e, f)) < best[:3]):
                best = (int(family[e]), kink, min(e, f), max(e, f))
    if best is not None:
        return {best[2], best[3]}
    first = min(spans, key=lambda e: (int(family[e]), int(line_of[e])))
    return {e for e in spans if int(line_of[e]) == int(line_of[first])}


def mitre_setback(own: np.ndarray, other: np.ndarray, up: np.ndarray, ey: np.ndarray, height: float,
                  half_width: float) -> float:
    """How far (mm) a running strip and its gasket, the box ``|y| ≤ half_width, 0 ≤ z ≤ height`` of the frame
    ``(own, ey, up)`` from the node, must start from the node to lie on its side of the mitre plane with the next
    span (unit direction ``other`` from the node): a point ``x·own + y·ey + z·up`` has ``(·)·(own − other)
    = x(1 − own·other) − y(ey·other) − z(up·other)``, so the box stays on its side from
    ``x = (max(0, height·up·other) + half_width·|ey·other|) / (1 − own·other)``.  Two strips so cut do not
    overlap (the mitre plane separates them); the square-cut ends leave a wedge between them that opens away
    from the kink."""
    return (max(0.0, height * float(up @ other)) + half_width * abs(float(ey @ other))) \
        / max(1.0 - float(own @ other), 1e-9)


CORNER_RISE_TOL = 0.05
"""mm a strip's gasket top may stand above the underside of a pane it does not carry (nominal seat) before the
strip end is cut back out from under that pane's corner (:func:`corner_cutback`)."""


def _clip(poly: np.ndarray, a: float, bx: float, by: float) -> np.ndarray:
    """The part of the convex polygon ``poly (k, 2)`` where ``a + bx·x + by·y ≥ 0`` (Sutherland–Hodgman, one
    half-plane); ``(0, 2)`` when nothing is left."""
    if len(poly) == 0:
        return poly
    val = a + poly @ np.array([bx, by])
    out = []
    for k in range(len(poly)):
        p, q, fp, fq = poly[k], poly[(k + 1) % len(poly)], val[k], val[(k + 1) % len(poly)]
        if fp >= 0.0:
            out.append(p)
        if (fp >= 0.0) != (fq >= 0.0):
            out.append(p + (fp / (fp - fq)) * (q - p))
    return np.array(out).reshape(-1, 2)


def corner_cutback(origin: np.ndarray, own: np.ndarray, ey: np.ndarray, up: np.ndarray, height: float,
                   half_width: float, reach: float, rays: tuple[np.ndarray, np.ndarray], centre: np.ndarray,
                   normal: np.ndarray) -> float:
    """How far (mm) from a node a strip must start so that its gasket top stays out from under the corner of a
    pane it does not carry, or at most :data:`CORNER_RISE_TOL` above that pane's nominal underside.

    The strip end at the node: points ``origin + x·own + y·ey`` (``origin (3,)`` the node in the strip's beam
    plane, ``own`` the unit direction into the span), ``0 ≤ x ≤ reach, |y| ≤ half_width``, its gasket top
    ``height`` above along ``up``.  The pane's face has its corner at the node with the edges along ``rays``
    (two ``(3,)`` vectors from the node to its neighbours on the face); seen along ``up`` its corner is the wedge
    between them.  The pane's underside is the plane through ``centre + height·normal`` (the face's centre and
    unit outside normal): the gasket top rises above it by ``rise(x, y) = r0 + x·(own·N) + y·(ey·N)``.  The
    cut-back is the largest ``x`` of the rectangle clipped to the wedge and to ``rise ≥ CORNER_RISE_TOL`` (0
    when that is empty): where a beam kinks towards the glass under an obtuse pane corner, the next span's strip
    end would otherwise lift the pane off its own gaskets (on a ridge, or where the corner is acute, it is 0).
    """
    u = np.array([rays[0] @ own, rays[0] @ ey])
    v = np.array([rays[1] @ own, rays[1] @ ey])
    turn = float(u[0] * v[1] - u[1] * v[0])
    if abs(turn) <= 1e-9 * float(np.linalg.norm(u) * np.linalg.norm(v)):
        return 0.0                                      # the corner seen edge-on: no wedge
    if turn < 0.0:
        u, v = v, u
    b = half_width
    poly = np.array([[0.0, -b], [reach, -b], [reach, b], [0.0, b]])
    poly = _clip(poly, 0.0, -u[1], u[0])                # cross(u, p) ≥ 0
    poly = _clip(poly, 0.0, v[1], -v[0])                # cross(p, v) ≥ 0
    r0 = float((origin + height * up - centre - height * normal) @ normal)
    poly = _clip(poly, r0 - CORNER_RISE_TOL, float(own @ normal), float(ey @ normal))
    return float(poly[:, 0].max()) if len(poly) else 0.0


def face_corners(faces: np.ndarray, vertices: np.ndarray, normals: np.ndarray
                 ) -> dict[int, list[tuple[int, int, np.ndarray, np.ndarray]]]:
    """Node → the corners of the faces there: ``(previous vertex, next vertex, face centre (3,), unit outside
    normal (3,))``, from ``faces (F, 4)`` and their outside normals ``normals (F, 3)`` (zero rows: faces without a
    pane, left out)."""
    out: dict[int, list[tuple[int, int, np.ndarray, np.ndarray]]] = {}
    for f, ring in enumerate(np.asarray(faces).tolist()):
        if not np.any(normals[f]):
            continue
        centre = vertices[ring].mean(axis=0)
        for k, node in enumerate(ring):
            out.setdefault(node, []).append((ring[k - 1], ring[(k + 1) % len(ring)], centre, normals[f]))
    return out


def make_strips(support: SupportStructure, beam_ids: list[str], params: GlazingParams,
                edge_normals: np.ndarray | None = None, face_normals: np.ndarray | None = None) -> list[Strip]:
    """One :class:`Strip` per mesh edge (see the module docstring); ``beam_ids`` per polyline;
    ``edge_normals (E, 3)`` the sum of the outside normals of the panes on each edge (zero rows, or ``None``:
    the strip lies square to its beam plane); ``face_normals (F, 3)`` the outside normal of the pane on each mesh
    face (zero rows where none; ``None``: no strip end is cut back from under a pane's corner)."""
    mesh = support.mesh
    edges = support.edges
    v = support.vertices
    axes = support.axes
    line_of = edge_polyline_index(mesh)
    lines = mesh.polylines
    family = np.array([lines[k].family if k >= 0 else 9 for k in line_of])
    b, c, ts = 0.5 * params.width, params.clearance, params.thickness
    at: dict[int, list[int]] = {}
    for e, (i, j) in enumerate(edges.tolist()):
        at.setdefault(i, []).append(e)
        at.setdefault(j, []).append(e)
    direction = v[edges[:, 1]] - v[edges[:, 0]]
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    running: dict[int, set[int]] = {}                  # node -> the spans that run through it
    for node, es in at.items():
        running[node] = running_spans(node, es, line_of, family, edges, direction)
    frames: list[tuple[Frame, float]] = []
    for e, (i, j) in enumerate(edges.tolist()):
        plane = pl.normalize(support.edge_planes[e])
        n, d = plane[:3], plane[3]
        pa, pb = (v[[i, j]] - np.outer(v[[i, j]] @ n + d, n))
        ex = pb - pa
        span = float(np.linalg.norm(ex))
        ex = ex / span
        down = _in_plane(axes[[i, j]], n).sum(axis=0)
        up = -down
        if edge_normals is not None and np.linalg.norm(edge_normals[e]) > 1e-9:
            up = edge_normals[e]
        up = up - (up @ ex) * ex
        up = up / np.linalg.norm(up)
        ey = np.cross(up, ex)
        frames.append((Frame(pa, ex, ey), span))
    height = ts + params.gasket_thickness
    corners = face_corners(mesh.faces, v, face_normals) if face_normals is not None else {}
    counters: dict[str, int] = {}
    out: list[Strip] = []
    for e, (i, j) in enumerate(edges.tolist()):
        frame, span = frames[e]
        ends = []
        runs = []
        for node, sign in ((i, 1.0), (j, -1.0)):
            own = sign * direction[e]                   # from the node into this span
            if e in running[node]:
                setback = 0.0
                into = sign * frame.ex                  # the frame's own axis (the span brought into its plane)
                for f in running[node] - {e}:
                    of = frames[f][0].ex if edges[f, 0] == node else -frames[f][0].ex
                    kink = float(np.arccos(np.clip(-(into @ of), -1.0, 1.0)))
                    setback = max(setback, mitre_setback(into, of, frame.normal, frame.ey, height, b),
                                  ts * float(np.tan(0.5 * kink)))
                ends.append(setback)
                runs.append(True)
            else:
                x = 0.0
                for f in sorted(running[node]):
                    of = direction[f] if edges[f, 0] == node else -direction[f]
                    cos = float(np.clip(own @ of, -1.0, 1.0))
                    sin = max(float(np.sqrt(1.0 - cos * cos)), 1e-3)
                    x = max(x, (b + c + b * abs(cos)) / sin)
                ends.append(x)
                runs.append(False)
            other = j if node == i else i
            origin = frame.origin if node == i else frame.origin + span * frame.ex
            for prev, nxt, centre, normal in corners.get(node, []):
                if other not in (prev, nxt):           # a pane this strip does not carry
                    ends[-1] = max(ends[-1], corner_cutback(origin, sign * frame.ex, frame.ey, frame.normal, height,
                                                            b, span, (v[prev] - v[node], v[nxt] - v[node]), centre,
                                                            normal))
        k = int(line_of[e])
        beam = beam_ids[k] if k >= 0 else "B-X"
        q = counters.get(beam, 0)
        counters[beam] = q + 1
        out.append(Strip(strip_id(beam, q), e, (i, j), beam, frame, ends[0], span - ends[1],
                         params.width, ts, (runs[0], runs[1])))
    return out
