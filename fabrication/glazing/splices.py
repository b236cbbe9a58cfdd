"""Splices where a long beam is cut into pieces (:mod:`fabrication.beams.splitting`): bolted cover plates, or a
full-penetration butt weld where the edges are too short for a cover plate clear of the joints.

``[splices] kind`` chooses: ``"bolted"``, ``"welded"``, or ``"auto"`` (the default): each beam is cut for
bolted splices where its edges leave room for a cover plate clear of the joints, and for welded splices
otherwise (fine meshes: a 280 mm cover plate needs edges of about 550 mm, a weld about 140 mm).  A welded
cut keeps ``weld_clear`` from every joint, at the top and the bottom edge (:func:`~fabrication.beams.
splitting.plan_cuts`); its weld is a row of ``welds.csv`` (:func:`welded_splices`).

Bolted:

A cut runs down the (interpolated) node axis from a point inside an edge; both pieces share that line.  The
splice is a pair of cover plates, one on each face of the beam plate (double shear), centred on the cut
and squared to the beam's top edge there: in the beam plate's 2D frame, with ``c`` the cut's top point,
``t`` the unit top-edge direction and ``s`` the in-plane downward normal of the top edge,

    corner = c + α·s + β·t,   e_top ≤ α ≤ h − e_bot,   |β| ≤ L/2,

``h`` the depth of the plate under the top edge, the least over the cover plate's length (a ray down ``s``
through the joined pieces' outlines at nine stations).  Bolt holes lie in ``rows × 2·cols`` positions:
``cols`` columns each side of the cut at ``e1 + k·p1`` from it, rows evenly between ``e2`` from the cover
plate's edges.  Spacing and edge distances follow EN 1993-1-8 Table 3.3 (``e1, e2 ≥ 1.2 d0``,
``p1 ≥ 2.2 d0``, ``p2 ≥ 2.4 d0``, ``d0`` the hole diameter); the same holes are cut in the beam pieces,
each in the piece on its side of the cut (:func:`fabrication.beams.build.with_splice_holes`).  Two cover plates of
thickness ``t_c`` with ``2 t_c ≥ t`` carry at least the beam plate's section.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ppfab.errors import DesignError
from ppfab.frame import Frame
from ppfab.schema import param

from ..contract import splice_plate_ids
from .welds import Weld, splice_preparation


@dataclass(frozen=True)
class SpliceParams:
    """Bolted cover-plate splices of split beams (the ``[splices]`` table; mm)."""

    plate_thickness: float = param(10.0, doc="thickness of each of the two cover plates, mm (2 × this ≥ beam "
                                             "thickness)", exclusive_min=0)
    bolt: str = param("M20 8.8", doc="bolt size and grade, written to the parts list")
    hole: float = param(22.0, doc="hole diameter d0, mm (normal clearance, EN 1090-2: M20 → 22)",
                        exclusive_min=0)
    columns: int = param(2, doc="bolt columns on each side of the cut", min=1, max=6)
    e1: float = param(40.0, doc="distance of a bolt from the cut and from the cover plate's end, mm", exclusive_min=0)
    p1: float = param(60.0, doc="pitch of the bolt columns along the beam, mm", exclusive_min=0)
    e2: float = param(40.0, doc="distance of a bolt row from the cover plate's long edges, mm", exclusive_min=0)
    p2_min: float = param(55.0, doc="smallest pitch between bolt rows across the beam, mm", exclusive_min=0)
    top_clear: float = param(15.0, doc="gap between the cover plates and the beam's top edge (room for the "
                                       "glazing strip's fillet weld), mm", min=0)
    bottom_clear: float = param(10.0, doc="gap between the cover plates and the beam's bottom edge, mm", min=0)
    material: str = param("S355 plate", doc="material of the cover plates")
    category: str = param("A", doc="bolt category, EN 1993-1-8 §3.4.1: 'A' bearing type, non-preloaded (ISO 4014 "
                                   "bolt, ISO 4032 nut, ISO 7089 washers); 'B' or 'C' slip-resistant, preloaded "
                                   "(EN 14399-3 HR sets, EN 14399-6 washers; grade 8.8 or 10.9); bolts.csv",
                          choices=("A", "B", "C"))
    thread_projection: float = param(5.0, doc="thread standing out of the nut, mm, added to the grip, washers "
                                              "and nut before the bolt length is rounded up to a standard length "
                                              "(EN 1090-2 §8.2.2: at least one full thread)", min=0)
    kind: str = param("auto", doc="'bolted' (cover plates), 'welded' (full-penetration butt weld across the cut) "
                                  "or 'auto': bolted where a beam's edges leave room for a cover plate clear of "
                                  "the joints, welded elsewhere", choices=("auto", "bolted", "welded"))
    weld_clear: float = param(50.0, doc="distance of a welded splice from every slot and plate end, at the top and "
                                        "the bottom edge, mm (room for the weld preparation and run-off plates)",
                              min=0)

    def __post_init__(self):
        from .bolts import PRELOADED_GRADES, BoltSpec

        spec = BoltSpec.parse(self.bolt)
        if self.category in ("B", "C") and spec.grade not in PRELOADED_GRADES:
            raise DesignError("category", f"category {self.category} needs preloaded bolts of grade 8.8 or 10.9, "
                                          f"bolt is {self.bolt!r}")
        d0 = self.hole
        for key, value, factor in (("e1", self.e1, 1.2), ("e2", self.e2, 1.2), ("p1", self.p1, 2.2),
                                   ("p2_min", self.p2_min, 2.4)):
            if value < factor * d0 - 1e-9:
                raise DesignError(key, f"{value:g} mm is below {factor:g} × hole = {factor * d0:g} mm "
                                       "(EN 1993-1-8 Table 3.3)")

    @property
    def length(self) -> float:
        """Length of a cover plate along the beam, mm."""
        return 2.0 * (2.0 * self.e1 + (self.columns - 1) * self.p1)

    def clearances(self, depth: float) -> tuple[tuple[str, float], ...]:
        """The splice kinds a split beam may get, in order, with how much further than its joints need (mm) a cut
        stays from a node: half a cover plate plus half the depth (the plate is squared to a cut that may lean)
        for a bolted splice, ``weld_clear`` for a welded one (:func:`fabrication.beams.build_beams`)."""
        bolted = ("bolted", 0.5 * (self.length + depth))
        welded = ("welded", self.weld_clear)
        return {"bolted": (bolted,), "welded": (welded,), "auto": (bolted, welded)}[self.kind]


@dataclass(frozen=True, eq=False)
class Splice:
    """One splice: part ids of its two cover plates, the beam, the two pieces it joins, the cover plate's
    outline ``(4, 2)`` and holes ``(h, 2)`` in the beam plate frame (``frame``), thickness and the beam's."""

    part_ids: tuple[str, str]
    beam_id: str
    pieces: tuple[str, str]
    frame: Frame
    outline: np.ndarray
    holes: np.ndarray
    hole: float
    thickness: float
    beam_thickness: float
    fits: bool

    @property
    def flat_outline(self) -> np.ndarray:
        """The cover plate in its own frame: ``(4, 2)`` rectangle with the origin at its lower-left corner."""
        o = self.outline
        t = (o[1] - o[0]) / np.linalg.norm(o[1] - o[0])
        n = np.array([-t[1], t[0]])
        rel = o - o[0]
        q = np.stack([rel @ t, rel @ n], axis=1)
        return q - q.min(axis=0)

    @property
    def flat_holes(self) -> np.ndarray:
        o = self.outline
        t = (o[1] - o[0]) / np.linalg.norm(o[1] - o[0])
        n = np.array([-t[1], t[0]])
        rel_o = o - o[0]
        q0 = np.stack([rel_o @ t, rel_o @ n], axis=1).min(axis=0)
        rel = self.holes - o[0]
        return np.stack([rel @ t, rel @ n], axis=1) - q0


def cut_pairs(plates, kind: str) -> list[tuple]:
    """``(a, b)`` for every cut between consecutive pieces ``a``, ``b`` of a beam split for ``kind`` splices
    (``meta["splice"]``), in beam and piece order; a closed beam's last piece joins its first.  Pieces that share
    a node meet there and are welded to the plate running through it (one-edge segments, and the parts of a
    column cut at nodes by ``[beams] segment = ["blocked"]``; :func:`~fabrication.glazing.welds.butt_welds`)."""
    by_beam: dict[str, list] = {}
    for p in plates:
        if p.n_pieces > 1 and not p.meta.get("segment") and p.meta.get("splice", "bolted") == kind:
            by_beam.setdefault(p.beam_id, []).append(p)
    out: list[tuple] = []
    for pieces in by_beam.values():
        pieces = sorted(pieces, key=lambda p: p.piece)
        pairs = [(a, b) for a, b in zip(pieces[:-1], pieces[1:]) if b.piece == a.piece + 1]
        first3 = pieces[0].frame.to3d(pieces[0].top[0])
        last3 = pieces[-1].frame.to3d(pieces[-1].top[-1])
        if np.linalg.norm(first3 - last3) < 1e-6:                 # closed beam: the last cut joins back
            pairs.append((pieces[-1], pieces[0]))
        out.extend((a, b) for a, b in pairs if not set(a.nodes.tolist()) & set(b.nodes.tolist()))
    return out


def welded_splices(plates) -> list[Weld]:
    """The full-penetration butt weld across every cut of a beam split for welded splices: along the cut line
    (the interpolated node axis, length ``|bottom − top|`` at the cut), the pieces in line (dihedral 0),
    throat the plate thickness (:func:`~fabrication.glazing.welds.splice_preparation`)."""
    out = []
    for a, b in cut_pairs(plates, "welded"):
        length = float(np.linalg.norm(a.bottom[-1] - a.top[-1]))
        prep, throat = splice_preparation(a.thickness)
        out.append(Weld(-1, a.part_id, b.part_id, 0.0, length, prep, throat, "splice"))
    return out


EdgeUps = Mapping[tuple[int, int], np.ndarray]
"""The up of the glazing strip on each mesh edge ``(i, j)``, ``i < j``: the sum of the outside normals of the panes
on it (:func:`fabrication.glazing.bite.edge_normals`)."""


def edge_ups(edges: np.ndarray, normals: np.ndarray) -> dict[tuple[int, int], np.ndarray]:
    """:data:`EdgeUps` from the ``(E, 2)`` mesh edges and the ``(E, 3)`` sums of the pane normals on them (edges
    without panes left out)."""
    return {(min(int(i), int(j)), max(int(i), int(j))): n for (i, j), n in zip(edges.tolist(), normals)
            if float(np.linalg.norm(n)) > 1e-9}


DROP_SLACK = 0.25
"""mm a leaning strip's underside may come down into a cover plate's top (the overlap ``ppfab verify`` accepts
between parts in their final places, :data:`fabrication.verify.erection.TOLERANCE`): the drop under a leaning
strip is rounded up to whole millimetres from this much less."""


def strip_drop(thickness: float, cover: float, lean: float) -> float:
    """How far (whole mm) a cover plate is lowered under a glazing strip leaning by ``lean`` (radians) off a beam
    plate ``thickness`` thick: its underside comes ``(t/2 + t_c)·tan λ`` down over the cover plate's outer face
    (``cover`` = ``t_c``); rounded up from :data:`DROP_SLACK` less to whole millimetres, so that the plates of
    one cut size stay one type (their heights are whole millimetres apart) and none stands more than the slack
    in the strip (0 for a drop under the slack)."""
    exact = (0.5 * thickness + cover) * float(np.tan(lean))
    return float(np.ceil(exact - DROP_SLACK - 1e-9)) if exact > DROP_SLACK else 0.0


def strip_lean(a, b, ups: EdgeUps | None) -> float:
    """The largest lean (radians) off the beam plate of the glazing strips over the cut between pieces ``a`` and
    ``b``: the strips of the beam's edges with a node in each piece (their tops taken from the pieces), their up
    made square to the edge as the strip's frame makes it (:mod:`fabrication.glazing.strips`), against the plate's
    normal: ``sin λ = |up · n|``."""
    if not ups:
        return 0.0
    n = np.asarray(a.plane[:3], dtype=float)
    n = n / np.linalg.norm(n)
    lean = 0.0
    for i in (int(k) for k in a.nodes):
        for j in (int(k) for k in b.nodes):
            up = ups.get((min(i, j), max(i, j))) if i != j else None
            if up is None:
                continue
            ex = b.frame.to3d(b.node_top(j)[None])[0] - a.frame.to3d(a.node_top(i)[None])[0]
            ex = ex / np.linalg.norm(ex)
            up = up - (up @ ex) * ex
            lean = max(lean, float(np.arcsin(min(1.0, abs(float(up @ n)) / float(np.linalg.norm(up))))))
    return lean


def make_splices(plates, params: SpliceParams, ups: EdgeUps | None = None) -> list[Splice]:
    """The bolted splice at every cut between consecutive pieces of a beam split for bolted splices (closed
    beams: also last → first); ``fits`` says whether the cover plate lies on the two pieces' outlines (clear of
    slots and ends).

    The cover plate's top edge lies ``top_clear`` under the beam's top edge over its own length, lowered further
    by :func:`strip_drop` — ``(t/2 + t_c)·tan λ`` rounded up to whole millimetres — where the glazing strip over
    the cut leans by ``λ`` off the plate (``ups``, from the panes: :func:`strip_lean`): the strip's underside
    comes down that far over the cover plate's outer face on the side it leans to (conical_pp_rotational's
    strips stood 6.4 mm in cover plates 15 mm under a top edge with strips leaning 21°)."""
    from shapely.geometry import LineString, Polygon
    from shapely.ops import unary_union

    out: list[Splice] = []
    L = params.length
    for a, b in cut_pairs(plates, "bolted"):
        beam = a.beam_id
        f = a.frame
        c = a.top[-1]                                       # the cut's top point, in a's frame
        s = a.bottom[-1] - a.top[-1]                        # down the cut line (the node axis there)
        s = s / np.linalg.norm(s)
        t = np.array([-s[1], s[0]])                         # square to the cut, along the beam
        u = a.top[-1] - a.top[-2]                           # along the top edge
        u = u / np.linalg.norm(u)
        if t @ u < 0:
            t = -t
        m = np.array([u[1], -u[0]])                         # square to the top edge, down
        if m @ s < 0:
            m = -m
        to_xy = np.array([t, m])                            # P − c ↦ (x across the cut, y under the top edge)
        to_p = np.linalg.inv(to_xy)
        body = unary_union([Polygon(a.outline).buffer(1e-3),
                            Polygon(f.to2d(b.frame.to3d(b.outline))).buffer(1e-3)])
        depth = float(np.linalg.norm(a.bottom[-1] - a.top[-1]))
        corners = np.asarray(body.exterior.coords) if body.geom_type == "Polygon" else np.zeros((0, 2))

        def under_top_edge(*ys: float) -> tuple[float, float]:
            """The beam's top and bottom (depths under the top edge through ``c``) over the stretch of the top
            edge that the plate's edges at depths ``ys`` span, exact: at its ends and at every corner of the
            pieces' outline between them (the depth of the first material under the edge is linear between)."""
            reach = [float((to_p @ np.array([x, y])) @ u) for x in (-0.5 * L, 0.5 * L) for y in ys]
            ends = [min(reach), max(reach)]
            taus = [*ends, *(float(t) for t in (corners - c) @ u if ends[0] < t < ends[1])]
            top, bottom = -np.inf, np.inf
            for tau in taus:
                foot = c + tau * u
                ray = LineString([foot - 2.0 * depth * m, foot + 3.0 * depth * m])
                hit = ray.intersection(body)
                spans = [np.asarray(g.coords) for g in getattr(hit, "geoms", [hit]) if not g.is_empty]
                if not spans:
                    return np.inf, -np.inf
                main = max(spans, key=lambda q: float(np.linalg.norm(q[-1] - q[0])))
                yy = sorted(float((q - foot) @ m) for q in main)
                top, bottom = max(top, yy[0]), min(bottom, yy[-1])
            return top, bottom

        # the top clearance is kept over the plate's own top edge (a slot or notch beyond its end does not lower
        # it: a crossing slot a plate length from the cut lowered pp_cauchy's plates by 7 mm when the whole
        # depth's reach was sampled); the edge's stretch moves with its depth on a skew cut, so settle it
        under_strip = strip_drop(a.thickness, params.plate_thickness, strip_lean(a, b, ups))
        top = under_top_edge(params.top_clear + under_strip)[0]
        for _ in range(4):
            again = under_top_edge(top + params.top_clear + under_strip)[0]
            if not np.isfinite(again) or again <= top + 1e-9:
                break
            top = again
        bottom = under_top_edge(0.0, depth)[1]
        h = bottom - top
        lo, hi = top + params.top_clear + under_strip, bottom - params.bottom_clear
        if hi - lo < 2 * params.e2:
            raise DesignError("splices", f"{beam}: a cover plate needs {2 * params.e2 + params.top_clear + params.bottom_clear:g} mm "
                                         f"of beam depth at the cut, the beam has {h:.0f} mm; lower splices.e2 "
                                         "or the clearances")

        def at(x: float, y: float) -> np.ndarray:
            return c + to_p @ np.array([x, y])

        outline = np.array([at(-0.5 * L, lo), at(0.5 * L, lo), at(0.5 * L, hi), at(-0.5 * L, hi)])
        if (outline[1, 0] - outline[0, 0]) * (outline[2, 1] - outline[0, 1]) - \
                (outline[1, 1] - outline[0, 1]) * (outline[2, 0] - outline[0, 0]) < 0:
            outline = outline[::-1]
        usable = hi - lo - 2 * params.e2
        rows = 1 + int(usable // params.p2_min) if usable >= params.p2_min else 1
        rows = min(rows, 2) if usable < 2 * params.p2_min else rows
        ys = [lo + params.e2 + k * usable / max(rows - 1, 1) for k in range(rows)] if rows > 1 else \
            [0.5 * (lo + hi)]
        xs = sorted(sgn * (params.e1 + k * params.p1) for k in range(params.columns) for sgn in (-1.0, 1.0))
        holes = np.array([at(x, y) for y in ys for x in xs])
        fits = bool(body.contains(Polygon(outline)))
        ids = splice_plate_ids(beam, a.piece)
        out.append(Splice(ids, beam, (a.part_id, b.part_id), f, outline, holes, params.hole,
                          params.plate_thickness, a.thickness, fits))
    return out
