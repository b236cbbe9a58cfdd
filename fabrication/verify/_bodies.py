"""The written solids rebuilt for the erection check (:mod:`.erection`) in manifold3d: each part as the hull of
its vertices or as its largest face's polygon extruded by its thickness (:func:`body_of`), the clamping screws
from their parts.csv row (:func:`screw_bodies`), and the depth of an intersection (:func:`depth_of`), which the
clash check (:mod:`.clash`) uses too."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ._shapes import cross3, cross_rows

_ONE_THREAD = False


def manifold3d() -> Any:
    """The ``manifold3d`` module, its task scheduler started on one thread.

    manifold3d runs its operations on oneTBB's workers, sized at their first use from the calling thread's CPU
    affinity.  The checks' solids are tens of triangles: on two cores the second worker doubled the CPU time of
    the erection check's booleans (24.6 against 16.6 CPU s on the bundled default) for the same wall time, and
    took its core from the second verify process.  So the scheduler is started once with this thread pinned to
    one core (a boolean of two spheres), the affinity then given back; where it had been started already, or
    the platform has no affinity, nothing changes."""
    global _ONE_THREAD
    import manifold3d as m3  # type: ignore[import-not-found]

    if not _ONE_THREAD:
        _ONE_THREAD = True
        import os

        if hasattr(os, "sched_getaffinity"):
            mask = os.sched_getaffinity(0)
            try:
                os.sched_setaffinity(0, {min(mask)})
                ball = m3.Manifold.sphere(1.0, 64)
                (ball ^ ball.translate([0.5, 0.0, 0.0])).volume()
            finally:
                os.sched_setaffinity(0, mask)
    return m3


SCREW_SIDES = 16
"""A clamping screw is rebuilt as the hull of two 16-gons of its diameter (its foot and its top)."""


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
    _corners: Any = None

    @property
    def lo(self) -> np.ndarray:
        return self.points.min(axis=0)

    @property
    def hi(self) -> np.ndarray:
        return self.points.max(axis=0)

    def prism(self, polygon: Any) -> Any:
        """A shapely polygon of this body's plane extruded like the body (a manifold3d ``Manifold``)."""
        m3 = manifold3d()
        from shapely.geometry import MultiPolygon

        polys = polygon.geoms if isinstance(polygon, MultiPolygon) else [polygon]
        rings = []
        for poly in polys:
            rings.append(np.asarray(poly.exterior.coords)[:-1])
            rings += [np.asarray(r.coords)[:-1] for r in poly.interiors]
        m = m3.Manifold.extrude(m3.CrossSection(rings, m3.FillRule.EvenOdd), self.thick)
        return m.transform(np.column_stack([self.ex, self.ey, self.n, self.origin]))

    @property
    def corners(self) -> np.ndarray:
        """``(k, 3)`` the vertices of the solid as rebuilt (:meth:`shape`): the points of a convex body, the rings
        of a prism's polygon (arcs as sampled) on both its faces; every extent of the rebuilt solid is theirs."""
        if self._corners is None:
            if self.convex or self.flat is None:
                self._corners = self.points
            else:
                import shapely

                q = shapely.get_coordinates(self.flat.exterior if hasattr(self.flat, "exterior")
                                            else [g.exterior for g in self.flat.geoms])
                base = self.origin + np.outer(q[:, 0], self.ex) + np.outer(q[:, 1], self.ey)
                self._corners = np.vstack([base, base + self.thick * self.n])
        return self._corners

    def moved(self, motion: np.ndarray, points: np.ndarray) -> "Body":
        """This body moved by the rigid motion ``motion (4, 4)``, whose vertices are then ``points (n, 3)`` (the
        moved solid's own, as read): its plane, frame and normal moved, polygon and thickness kept."""
        rot, shift = motion[:3, :3], motion[:3, 3]
        return Body(np.asarray(points, dtype=float), self.convex, rot @ self.origin + shift, rot @ self.ex,
                    rot @ self.ey, rot @ self.n, self.thick, self.flat)

    def apart_from(self, d: np.ndarray, far: float, others: list["Body"], gap: float = 1e-6) -> np.ndarray:
        """``(len(others),)`` bool: whether this body swept along ``[−far·d, 0]`` (:meth:`swept`) and each of
        ``others`` are separated by a plane with more than ``gap`` mm on either side (:meth:`overlaps` below
        ``−gap``: a separating axis proves that the two do not meet; finding none proves nothing)."""
        return self.overlaps(d, far, others) < -gap

    def overlaps(self, d: np.ndarray, far: float, others: list["Body"]) -> np.ndarray:
        """``(len(others),)`` the least overlap (mm) of this body swept along ``[−far·d, 0]`` (:meth:`swept`) and
        each of ``others`` projected on a candidate axis (the normals of either body's frame axes and of a frame
        normal crossed with ``d``): on an axis, with the intervals ``[lo, hi]`` of the sweep and ``[t_lo, t_hi]``
        of the other, ``min(hi − t_lo, t_hi − lo)``, how far the other must move along it, one way or the other,
        to clear the sweep.  Negative when they are that far apart, ``inf`` when no axis can be used; ``w`` ≥ 0 is
        an upper bound of how deep the two are in one another.  All pairs at once: the projections of all
        corners in a few array products."""
        k = len(others)
        if k == 0:
            return np.zeros(0)

        def unit(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            ln = np.sqrt(np.einsum("...j,...j->...", a, a))
            ok = ln > 1e-9
            return np.where(ok[..., None], a / np.where(ok, ln, 1.0)[..., None], 0.0), ok

        mine_axes, mine_ok = unit(np.array([self.n, self.ex, self.ey, cross3(self.n, d)]))          # (4, 3)
        frames = np.array([[o.n, o.ex, o.ey] for o in others])                                         # (k, 3, 3)
        nd = cross_rows(frames[:, 0], d[None, :])                                                       # (k, 3)
        their_axes, their_ok = unit(np.concatenate([frames, nd[:, None, :]], axis=1))                 # (k, 4, 3)
        axes = np.concatenate([np.broadcast_to(mine_axes, (k, 4, 3)), their_axes], axis=1)          # (k, 8, 3)
        ok = np.concatenate([np.broadcast_to(mine_ok, (k, 4)), their_ok], axis=1)                   # (k, 8)
        mine = self.corners @ axes.reshape(-1, 3).T                                                  # (m, 8k)
        shift = (-far * (axes @ d)).reshape(-1)
        lo = (mine.min(axis=0) + np.minimum(shift, 0.0)).reshape(k, 8)
        hi = (mine.max(axis=0) + np.maximum(shift, 0.0)).reshape(k, 8)
        sizes = np.array([len(o.corners) for o in others])
        starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
        corners = np.concatenate([o.corners for o in others])                                        # (Σm, 3)
        theirs = np.einsum("rj,raj->ra", corners, np.repeat(axes, sizes, axis=0))                    # (Σm, 8)
        t_lo, t_hi = np.minimum.reduceat(theirs, starts, axis=0), np.maximum.reduceat(theirs, starts, axis=0)
        return np.where(ok, np.minimum(hi - t_lo, t_hi - lo), np.inf).min(axis=1)

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
    m3 = manifold3d()

    return m3.Manifold.hull_points(np.ascontiguousarray(points, dtype=float))


def union(shapes: list[Any]) -> Any:
    m3 = manifold3d()

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


def bodies_of(solids: dict[str, Any]) -> dict[str, Body]:
    """:func:`body_of` of every solid, by name; solids of the text-level reader that place one B-rep (an instanced
    shape) are rebuilt once and the body moved by the rigid motion from one placement to the other."""
    out: dict[str, Body] = {}
    first: dict[tuple[int, int], tuple[Any, Body]] = {}
    for name, solid in solids.items():
        key = (id(solid.shared), solid.brep) if getattr(solid, "shared", None) is not None else None
        got = first.get(key) if key is not None else None
        if got is None:
            out[name] = body_of(solid)
            if key is not None:
                first[key] = (solid, out[name])
        else:
            motion = solid.transform @ np.linalg.inv(got[0].transform)
            out[name] = got[1].moved(motion, solid.points)
    return out


def body_of(solid: Any) -> Body:
    """A thin prism read from STEP as a :class:`Body`: its largest face gives the plane and the polygon (its outer
    and inner boundaries, :func:`_ring`), convex when the polygon fills its hull."""
    from shapely.geometry import MultiPoint, Polygon

    text = hasattr(solid, "face_area")                  # a record of the text-level reader
    if text:
        pts = solid.points
        faces = solid.faces()                           # unpacked once: the opposite face is sought among them
        planes = [f for f in faces if f.surface == "plane"]
        face = max(planes, key=solid.face_area)
        outer = solid.outer_loop(face)
        outer_ring = solid.ring(outer, 16)
        inner_rings = [solid.ring(lp, 16) for lp in face.loops if lp is not outer]
    else:
        pts = np.array([tuple(p) for p in solid.vertices()], dtype=float).reshape(-1, 3)
        faces = solid.faces()
        face = max(faces, key=lambda f: f.area)
        outer_ring = _ring(face.outer_wire())
        inner_rings = [_ring(w) for w in face.inner_wires()]
    c = pts.mean(axis=0)
    axes = np.linalg.svd(pts - c, full_matrices=False)[2]   # (3, 3); the (n, n) left factor is not wanted
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
    ey = cross3(n, ex)
    thick = float(off.max())

    def to2(q: np.ndarray) -> np.ndarray:
        return np.stack([(q - fo) @ ex, (q - fo) @ ey], axis=1)

    flat = Polygon(to2(outer_ring), [to2(r) for r in inner_rings]).buffer(0)
    other = _opposite_ring(solid, face, n, text, faces)
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


def _opposite_ring(solid: Any, face: Any, n: np.ndarray, text: bool,
                   faces: list | None = None) -> np.ndarray | None:
    """The outer boundary of the solid's other large face parallel to ``face`` (a plate's other side), ``None``
    when there is none; ``faces`` the solid's when already at hand.  A plate whose top edge is bevelled under its
    strip has two faces of different outline (:mod:`fabrication.beams.bevel_cut`); its body is the prism over what
    both hold, inside the solid by at most the bevel's wedge, so that a square plate's overlap with its strip is
    still measured in full."""
    if faces is None:
        faces = solid.faces()
    if text:
        area = solid.face_area(face)
        for f in faces:
            if f.index != face.index and f.surface == "plane" and abs(float(f.normal @ n)) >= 1.0 - 1e-9 \
                    and solid.face_area(f) > 0.5 * area:
                return solid.ring(solid.outer_loop(f), 16)
        return None
    for f in faces:
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


def normal_pair(d: np.ndarray) -> np.ndarray:
    """``(2, 3)`` two unit vectors normal to the unit vector ``d`` and to each other."""
    a = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = cross3(d, a)
    e1 /= np.linalg.norm(e1)
    return np.stack([e1, cross3(d, e1)])
