"""glazing.step against the structure: every glazing strip and its gasket is the box the mesh, the node axes and
the beam planes put on its span (:mod:`fabrication.glazing.strips`), recomputed from the other files.

For the strip of ``parts.csv`` on mesh edge ``a b`` (``edge_nodes``) of beam ``beam``:

* the frame: origin ``a`` brought into the beam's plane (``plane`` of a plate of that beam holding the nodes),
  ``ex`` towards ``b`` so brought, ``up`` the sum of the outside normals of the panes on the edge (the faces of
  ``mesh.obj``, least-squares planes, outside as the build chooses it: the side the gaskets are on) made square
  to ``ex`` — or, on an edge without panes, against the node axes in the plane — and ``ey = up × ex``;
* its ends: where its polyline *runs through* a node (the polyline with two spans there, rows before columns;
  where none has two, two spans of one family kinking by at most 30°, rows before columns),
  each square-cut on its side of the mitre plane of the two spans (through the node, normal ``o_e − o_f``),
  strip and gasket together (``H = t_s + t_g``), and at least ``t_s·tan(κ/2)``: ``H·tan(κ/2)`` in a valley,
  ``t_s·tan(κ/2)`` on a ridge; where it *stops*,
  at ``(w/2 + c + (w/2)|cos θ|) / sin θ`` from the node against each span of the running polyline (``w`` width, ``c`` ``glazing.clearance``, ``t_s`` strip thickness);
  either way at least as far as the farthest point of its band, seen along ``up``, that lies in the corner of a
  face of ``mesh.obj`` at the node not holding its edge with the gasket top more than
  :data:`CORNER_RISE_TOL` above that pane's nominal underside (the face's centre moved ``H`` along its outside
  normal): found by vertex enumeration (:func:`_corner_reach`), not by the build's polygon clipping;
* the strip is the box ``x0 ≤ x ≤ x1, |y| ≤ w/2, 0 ≤ z ≤ t_s``, its gasket the same outline at
  ``t_s ≤ z ≤ t_s + t_g``: every vertex of each solid within :data:`GLAZING_TOL` of that box's corners.

Reads glazing.step through :func:`._step_read.read_or_report`, which keeps what it read for the bite check in
the same process (the file is read once).
"""

from __future__ import annotations

import numpy as np

from ..contract import RETENTION_PREFIXES, gasket_id
from . import Verification, check, shared_by_confined
from ._shapes import literal, number, set_distance, solid_points

STRAIGHT_ON_DEG = 30.0
"""Where no polyline has two spans at a node (a re-entrant corner of a trimmed boundary), two spans of one family
kinking by at most this much run through as one line (the build's rule, restated here)."""

GLAZING_TOL = 0.05
"""How far (mm) a strip's or gasket's vertex may be from the recomputed box (pane normals are least-squares
normals here and in the build, which may differ in the last digits)."""

_FAMILY = {"rows": 0, "cols": 1}

CORNER_RISE_TOL = 0.05
"""mm a strip's gasket top may stand above the nominal underside of a pane it does not carry before its end is
cut back out from under that pane's corner (the build's rule, restated here)."""


def _corner_reach(origin: np.ndarray, own: np.ndarray, ey: np.ndarray, up: np.ndarray, height: float, half: float,
                  span: float, a: np.ndarray, b: np.ndarray, centre: np.ndarray, normal: np.ndarray) -> float:
    """The largest ``x`` of the strip end ``{origin + x·own + y·ey : 0 ≤ x ≤ span, |y| ≤ half}`` that lies in the
    corner of a pane it does not carry — the wedge between the corner's edges ``a``, ``b`` (vectors from the node)
    seen along ``up`` — with its gasket top (``height`` up) at least :data:`CORNER_RISE_TOL` above the pane's
    nominal underside (the plane through ``centre + height·normal``); 0 where there is no such point.  By vertex
    enumeration: the largest ``x`` among the feasible pairwise crossings of the seven constraint lines
    ``g·(x, y) ≥ h``."""
    p2 = np.array([[a @ own, a @ ey], [b @ own, b @ ey]])
    det = float(p2[0, 0] * p2[1, 1] - p2[0, 1] * p2[1, 0])
    if abs(det) <= 1e-9 * float(np.linalg.norm(p2[0]) * np.linalg.norm(p2[1])):
        return 0.0
    first, second = (p2[0], p2[1]) if det > 0 else (p2[1], p2[0])
    lift = float((origin + height * up - centre - height * normal) @ normal)
    g = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0], [-first[1], first[0]], [second[1], -second[0]],
                  [float(own @ normal), float(ey @ normal)]])
    h = np.array([0.0, -span, -half, -half, 0.0, 0.0, CORNER_RISE_TOL - lift])
    k1, k2 = np.triu_indices(len(g), 1)
    m = np.stack([g[k1], g[k2]], axis=1)                                     # (21, 2, 2)
    dets = m[:, 0, 0] * m[:, 1, 1] - m[:, 0, 1] * m[:, 1, 0]
    ok = np.abs(dets) > 1e-12
    rhs = np.stack([h[k1], h[k2]], axis=1)[ok]
    pts = np.linalg.solve(m[ok], rhs[..., None])[..., 0]                    # (k, 2) crossings
    feasible = pts[(pts @ g.T - h >= -1e-9 * (1.0 + np.abs(h))).all(axis=1)]
    return float(feasible[:, 0].max()) if len(feasible) else 0.0


def _face_normals(mesh) -> np.ndarray:
    """``(F, 3)`` unit least-squares normals of the faces, oriented by corner order (Newell), then all turned to
    the outside the build takes by default (away from the centre of the faces)."""
    out = []
    for f in mesh.faces:
        c = mesh.vertices[np.asarray(f)]
        n = np.linalg.svd(c - c.mean(axis=0))[2][2]
        newell = np.cross(c, np.roll(c, -1, axis=0)).sum(axis=0)
        out.append(n if n @ newell >= 0 else -n)
    return np.array(out).reshape(-1, 3)


def _strip_boxes(v: Verification, rows: list[dict[str, str]], sign: float) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Part id → (strip corners ``(8, 3)``, gasket corners ``(8, 3)``) recomputed (module docstring); ``sign``
    turns the face normals to the outside."""
    mesh = v.mesh
    assert mesh is not None                             # the check reads nothing without it
    fab = v.manifest.get("fabrication", {})
    gl = fab.get("glazing", {})
    c_clear, tg = float(gl.get("clearance", 0.0)), float(gl.get("gasket_thickness", 0.0))
    verts = np.asarray(mesh.vertices, dtype=float)
    axes = {int(number(r.get("vertex"), -1)): np.array([number(r.get(k)) for k in ("axis_x", "axis_y", "axis_z")])
            for r in (v.nodes or [])}
    plates: dict[str, list[tuple[set[int], np.ndarray]]] = {}
    for r in (v.parts or []):
        pl, nodes = literal(r.get("plane", "")), literal(r.get("nodes", ""))
        if r["kind"] == "beam" and isinstance(pl, list) and len(pl) == 4 and isinstance(nodes, list):
            p = np.asarray(pl, dtype=float)
            plates.setdefault(r.get("beam_id", ""), []).append(({int(k) for k in nodes}, p / np.linalg.norm(p[:3])))
    normals = sign * _face_normals(mesh)
    on_edge: dict[tuple[int, int], np.ndarray] = {}
    for fi, f in enumerate(mesh.faces):
        f = [int(x) for x in f]
        for k in range(len(f)):
            key = (min(f[k], f[(k + 1) % len(f)]), max(f[k], f[(k + 1) % len(f)]))
            on_edge[key] = on_edge.get(key, np.zeros(3)) + normals[fi]
    spans: list[tuple[dict[str, str], int, int]] = []
    for r in rows:
        first, _, second = r.get("edge_nodes", "").partition(";")
        spans.append((r, int(first), int(second)))
    at: dict[int, list[int]] = {}
    for e, (_, i, j) in enumerate(spans):
        at.setdefault(i, []).append(e)
        at.setdefault(j, []).append(e)
    line = [r.get("beam", "") for r, _, _ in spans]
    fam = [_FAMILY.get(r.get("family", ""), 9) for r, _, _ in spans]
    direction = np.array([verts[j] - verts[i] for _, i, j in spans]).reshape(-1, 3)
    direction /= np.maximum(np.linalg.norm(direction, axis=1, keepdims=True), 1e-300)
    running: dict[int, set[int]] = {}
    for node, es in at.items():
        count: dict[str, int] = {}
        for e in es:
            count[line[e]] = count.get(line[e], 0) + 1
        pool = [e for e in es if count[line[e]] >= 2]
        if pool:
            first = line[min(pool, key=lambda e: (fam[e], line[e]))]
            running[node] = {e for e in es if line[e] == first}
            continue
        # no polyline with two spans: a same-family pair kinking by at most STRAIGHT_ON_DEG runs through, rows
        # before columns, then the straighter
        pairs = []
        for s1 in es:
            for s2 in es:
                if s1 < s2 and fam[s1] == fam[s2] != 9:
                    o1 = direction[s1] if spans[s1][1] == node else -direction[s1]
                    o2 = direction[s2] if spans[s2][1] == node else -direction[s2]
                    kink = float(np.degrees(np.arccos(np.clip(-(o1 @ o2), -1.0, 1.0))))
                    if kink <= STRAIGHT_ON_DEG:
                        pairs.append((fam[s1], kink, s1, s2))
        if pairs:
            running[node] = set(min(pairs)[2:])
        else:
            first = line[min(es, key=lambda e: (fam[e], line[e]))]
            running[node] = {e for e in es if line[e] == first}
    at_node: dict[int, list[tuple[int, int, int]]] = {}                   # node -> (face, previous, next)
    centres = []
    for fi, f in enumerate(mesh.faces):
        f = [int(x) for x in f]
        centres.append(verts[f].mean(axis=0))
        for k in range(len(f)):
            at_node.setdefault(f[k], []).append((fi, f[k - 1], f[(k + 1) % len(f)]))
    out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for e, (r, i, j) in enumerate(spans):
        plane = next((p for nodes, p in plates.get(r.get("beam", ""), []) if i in nodes and j in nodes),
                     next((p for nodes, p in plates.get(r.get("beam", ""), []) if i in nodes or j in nodes), None))
        if plane is None:
            continue
        n, d = plane[:3], plane[3]
        pa, pb = verts[[i, j]] - np.outer(verts[[i, j]] @ n + d, n)
        ex = pb - pa
        span = float(np.linalg.norm(ex))
        ex /= span
        up = on_edge.get((min(i, j), max(i, j)), np.zeros(3))
        if np.linalg.norm(up) <= 1e-9 and i in axes and j in axes:
            down = axes[i] + axes[j]
            up = -(down - (down @ n) * n)
        up = up - (up @ ex) * ex
        up /= max(float(np.linalg.norm(up)), 1e-300)
        ey = np.cross(up, ex)
        w = number(r.get("width_mm"), 0.0)
        ts = number(r.get("thickness_mm"), 0.0)
        b = 0.5 * w
        ends = []
        for node, sgn in ((i, 1.0), (j, -1.0)):
            own = sgn * direction[e]
            x = 0.0
            if e in running[node]:
                # square-cut on its side of the mitre plane (normal own − other through the node): the box's end
                # face at x from the node has its corners c = z·up + y·ey at x·own + c; each must have
                # (x·own + c)·(own − other) ≥ 0, so x ≥ c·other / (1 − own·other) for every corner
                into = sgn * ex
                corners = [z * up + y * ey for z in (0.0, ts + tg) for y in (-b, b)]
                for f in sorted(running[node] - {e}):
                    of = direction[f] if spans[f][1] == node else -direction[f]
                    x = max(x, max(float(c @ of) for c in corners) / max(1.0 - float(into @ of), 1e-9),
                            ts * float(np.tan(0.5 * np.arccos(np.clip(-(into @ of), -1.0, 1.0)))))
            else:
                for f in sorted(running[node]):
                    of = direction[f] if spans[f][1] == node else -direction[f]
                    cos = float(np.clip(own @ of, -1.0, 1.0))
                    sin = max(float(np.sqrt(1.0 - cos * cos)), 1e-3)
                    x = max(x, (b + c_clear + b * abs(cos)) / sin)
            # out from under the corner of every pane at the node that this strip does not carry
            far = j if node == i else i
            start = pa if node == i else pa + span * ex
            for fi, before, after in at_node.get(node, []):
                if far not in (before, after):
                    x = max(x, _corner_reach(start, sgn * ex, ey, up, ts + tg, b, span, verts[before] - verts[node],
                                             verts[after] - verts[node], centres[fi], normals[fi]))
            ends.append(x)
        x0, x1 = ends[0], span - ends[1]
        rect = np.array([[x0, -b], [x1, -b], [x1, b], [x0, b]])
        flat = pa + rect[:, :1] * ex + rect[:, 1:] * ey

        def box(z0: float, z1: float) -> np.ndarray:
            return np.concatenate([flat + z0 * up, flat + z1 * up])

        out[r["part_id"]] = (box(0.0, ts), box(ts, ts + tg))
    return out


def _bad_spans(v: Verification, rows: list[dict[str, str]]) -> list[str]:
    """The part ids of the strip rows whose ``edge_nodes`` are not two mesh vertices ``a;b``."""
    assert v.mesh is not None
    n, bad = len(v.mesh.vertices), []
    for r in rows:
        try:
            span = [int(x) for x in r.get("edge_nodes", "").split(";")]
        except ValueError:
            span = []
        if len(span) != 2 or not all(0 <= k < n for k in span):
            bad.append(r["part_id"])
    return bad


@shared_by_confined
def strip_places(v: Verification) -> dict[str, list[np.ndarray]]:
    """Part id → the corners ``(8, 3)`` of the strip's box recomputed from the structure (module docstring) for
    either outside — a file without the gaskets (model.3dm, model.ifc, model.glb) does not say which side is
    out; empty without the mesh or with a strip row whose span is not a mesh edge (the glazing.step check
    reports it).  Computed once per process."""
    if v.read.strip_places is None:
        places: dict[str, list[np.ndarray]] = {}
        rows = [r for r in (v.parts or []) if r["kind"] == "strip"]
        if v.mesh is not None and rows and not _bad_spans(v, rows):
            for sign in (1.0, -1.0):
                for pid, (strip, _gasket) in _strip_boxes(v, rows, sign).items():
                    places.setdefault(pid, []).append(strip)
        v.read.strip_places = places
    return v.read.strip_places


def check_strip_place(v: Verification, rel: str, row: dict[str, str], points: np.ndarray, eps: float) -> None:
    """A strip's solid (vertices ``points (n, 3)``) is its recomputed box (:func:`strip_places`, the nearer of
    the two sides) within ``max(eps, GLAZING_TOL)``."""
    boxes = strip_places(v).get(row["part_id"])
    if not boxes:
        return
    gap = min(set_distance(np.asarray(points, dtype=float).reshape(-1, 3), b) for b in boxes)
    if not gap <= max(eps, GLAZING_TOL):
        off = f"{gap:.3g} mm" if np.isfinite(gap) else f"({len(points)} vertices for 8)"
        v.error(rel, row["part_id"], f"strip is {off} from the box its span, node axes and beam plane put it in "
                                     f"(mesh edge {row.get('edge_nodes', '').replace(';', '-')})")


@check("glazing_step")
def check_glazing_step(v: Verification) -> None:
    m = v.manifest
    rel = m.get("files", {}).get("glazing_step")
    if rel is None or v.mesh is None:
        return
    from ._step_read import read_or_report

    read = read_or_report(v, rel)
    if read is None:
        return
    solids = {s.name: s.solid for s in read}
    rows = [r for r in (v.parts or []) if r["kind"] == "strip"]
    bad = _bad_spans(v, rows)
    if bad:
        v.error("parts.csv", bad[0], "edge_nodes is not two mesh vertices 'a;b'")
        return
    names = {n for n in solids if not n.startswith(RETENTION_PREFIXES)}     # the retention check's (retention.py)
    for r in rows:
        names.discard(r["part_id"])
        names.discard(gasket_id(r["part_id"]))
    for name in sorted(names):
        v.error(rel, name or "(unnamed)", "solid is neither a strip of parts.csv nor its gasket")
    points = {name: solid_points(s) for name, s in solids.items()}
    best: tuple[float, dict[str, tuple[np.ndarray, np.ndarray]]] | None = None
    for sign in (1.0, -1.0):                       # the outside: the side the gaskets are on
        boxes = _strip_boxes(v, rows, sign)
        score = sum(float(((points[gasket_id(p)].mean(axis=0) - points[p].mean(axis=0)) @
                           (g.mean(axis=0) - s.mean(axis=0)))) for p, (s, g) in boxes.items()
                    if p in points and gasket_id(p) in points)
        if best is None or score > best[0]:
            best = (score, boxes)
    assert best is not None
    for r in rows:
        pid = r["part_id"]
        box = best[1].get(pid)
        if box is None:
            v.error("parts.csv", pid, f"no beam plate of {r.get('beam')} holds the strip's nodes {r.get('edge_nodes')}")
            continue
        for name, want in ((pid, box[0]), (gasket_id(pid), box[1])):
            got = points.get(name)
            if got is None:
                v.error(rel, name, "strip or gasket has no solid")
                continue
            gap = set_distance(got, want)
            if not gap <= GLAZING_TOL:
                what = "strip" if name == pid else "gasket"
                off = f"{gap:.3g} mm" if np.isfinite(gap) else f"({len(got)} vertices for 8)"
                v.error(rel, name, f"{what} is {off} from the box its span, node axes and beam plane put it in "
                                   f"(mesh edge {r.get('edge_nodes', '').replace(';', '-')})")
    v.checked.append("glazing_step")
