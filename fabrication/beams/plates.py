"""Beam plates in their support planes: frames, top/bottom edges, pieces.

Each support plane carrying a mesh polyline becomes a planar plate (§3.1: the
planes ``U_i``/``W_j`` of a P or PP mesh are part of its support structure).
In the plate's plane the *top edge* is the polyline (projected into the plane,
which moves it at most ``plane_tolerance``) and the *bottom edge* is the top
edge moved by the beam depth along the node axes, each axis first brought into
the plane (``â = (a − (a·n)n)/|…|``), so the whole plate stays in its plane:

    top_k = v_k − (n·v_k + d) n,        bottom_k = top_k + depth · â_k.

Everything is drawn in the plate's own 2D frame (origin at the first top point,
``x`` along the chord, ``y`` up, away from the axes) and placed with the frame
afterwards — a CAD kernel accepts a face only if its polygon is exactly planar.

Polylines that are not planar (the transverse family of a P mesh, or with
``joint = "segmented"``) become one plate per edge, in the edge's support plane.
Long or closed planar polylines are cut into pieces inside edges, clear of the joints
(:mod:`fabrication.beams.splitting`).
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from dataclasses import dataclass, field

import numpy as np

from ppfab import planes as pl
from ppfab.errors import GeometryError
from ppfab.finding import Finding
from ppfab.frame import Frame
from ppfab.metrics import polygon_area
from ppfab.support.structure import SupportStructure

from .. import contract

from .params import BeamParams
from .splitting import Cut, plan_cuts

SpliceClearances = tuple[tuple[str, float], ...]
"""The splice kinds a split beam may get, in order, each with the extra clearance (mm) its cuts keep from the
joints: ``(("bolted", 240.0), ("welded", 50.0))``."""


@dataclass(frozen=True, eq=False)
class Slot:
    """A half-lap slot in a plate's 2D frame: a strip of ``width`` centred on the line
    ``origin + α·direction`` (``direction`` points from the top edge down), from the top
    edge down to ``α = length`` (``from_top``) or from ``α = length`` down through the bottom edge."""

    node: int
    partner: str
    from_top: bool
    origin: np.ndarray
    direction: np.ndarray
    width: float
    length: float
    depth: float

    def polygon(self) -> np.ndarray:
        """``(4, 2)`` CCW rectangle, overshooting the plate edge by half the depth."""
        s = self.direction
        t = np.array([-s[1], s[0]])
        a0, a1 = (-0.5 * self.depth, self.length) if self.from_top else (self.length, 1.5 * self.depth)
        w = 0.5 * self.width
        pts = np.array([self.origin + a0 * s - w * t, self.origin + a1 * s - w * t,
                        self.origin + a1 * s + w * t, self.origin + a0 * s + w * t])
        return pts if polygon_area(pts) > 0 else pts[::-1]

    def inner_corners(self) -> np.ndarray:
        """``(2, 2)`` the corners of the slot's closed end (where the mating plate's edge seats)."""
        t = np.array([-self.direction[1], self.direction[0]])
        return self.end_center + np.outer([-0.5 * self.width, 0.5 * self.width], t)

    def cutout(self, tool_radius: float = 0.0, segments: int = 8):
        """The material removed by the slot (shapely ``Polygon``): :meth:`polygon` and, with ``tool_radius``
        ``r > 0``, a dog-bone relief at each inner corner ``q``: the disc of radius ``r`` centred ``r`` from
        ``q`` along the corner's bisector into the slot, so the tool passes through the corner.  The disc is
        drawn circumscribed (``segments`` per quarter, vertex radius ``r / cos(π/(4·segments))``) so that it
        holds the true circle."""
        from shapely.geometry import Point, Polygon

        rect = Polygon(self.polygon())
        if tool_radius <= 0:
            return rect
        s = self.direction
        t = np.array([-s[1], s[0]])
        grow = 1.0 / np.cos(np.pi / (4 * segments))
        discs = []
        for q, side in zip(self.inner_corners(), (1.0, -1.0)):
            # into the slot: back along the slot line (towards the open end) and across towards its middle
            inward = (-s if self.from_top else s) + side * t
            c = q + tool_radius * inward / np.linalg.norm(inward)
            discs.append(Point(c).buffer(tool_radius * grow, quad_segs=segments))
        return rect.union(discs[0]).union(discs[1])

    @property
    def cut_length(self) -> float:
        """How far the slot reaches into the plate from the edge it opens on, mm (along its line)."""
        return self.length if self.from_top else self.depth - self.length

    @property
    def end_center(self) -> np.ndarray:
        """Centre of the slot's closed end (on the slot line at ``α = length``)."""
        return self.origin + self.length * self.direction


@dataclass(frozen=True, eq=False)
class BeamPlate:
    """One plate to cut: its place in the structure, its 2D outline and frame.

    Parameters
    ----------
    part_id : e.g. ``B-U03`` (row 3), ``B-W07-S03`` (segment 3 of column 7), ``B-R0012`` (polyline 12)
    beam_id : the polyline's id (equal for all pieces of one beam)
    polyline : index into ``support.polylines``; ``family`` 0 rows / 1 cols
    piece, n_pieces : which piece of the beam (0-based) and how many
    nodes : (k,) vertex ids on the plate, in order; ``through`` (k,) bool: the plate continues on both sides
    chain : (k,) index of each node in ``top``/``bottom``
    top, bottom : (p, 2) top edge (the polyline) and bottom edge in the frame, mm
    plane : (4,) unit support plane the plate is centred on
    frame : 2D ↔ 3D mapping of the plate
    outline : (q, 2) CCW outline with end cuts and slots; ``body``: before the slots
    slots : half-lap slots; ``trims``: ``(vertex, distance mm)`` end cuts set back from the node axis
    plane_deviation : largest distance of the plate's mesh vertices from ``plane``, mm
    holes : (h, 3) bolt holes cut in the plate: centre ``x, y`` in the frame and diameter, mm (the holes of the
        bolted splices at its ends, :func:`fabrication.beams.build.with_splice_holes`)
    bevels : the top-edge spans raised and bevelled to the glazing strip on them
        (:class:`fabrication.beams.bevel_cut.TopBevel`, in span order; empty: a square top edge)
    cut_outline : ``(r, 2)`` what is cut from the sheet when the plate has bevels (the outline raised by ``Δ``
        on the bevelled spans), else ``None``; ``outline`` stays the plate's section in its mid-plane
    notches : the notches of its top edge under the glazing strips of other beams that run over it
        (:class:`fabrication.beams.notch.Notch`; ``outline`` is already cut by them)
    """

    part_id: str
    beam_id: str
    polyline: int
    family: int
    piece: int
    n_pieces: int
    nodes: np.ndarray
    through: np.ndarray
    chain: np.ndarray
    top: np.ndarray
    bottom: np.ndarray
    plane: np.ndarray
    frame: Frame
    depth: float
    thickness: float
    plane_deviation: float
    outline: np.ndarray
    body: np.ndarray
    slots: tuple[Slot, ...] = ()
    trims: tuple[tuple[int, float], ...] = ()
    meta: dict = field(default_factory=dict)
    holes: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    bevels: tuple = ()
    cut_outline: np.ndarray | None = None
    notches: tuple = ()

    @property
    def flat_outline(self) -> np.ndarray:
        """``(r, 2)`` the outline cut from the sheet: :attr:`cut_outline` when bevelled, else :attr:`outline`."""
        return self.outline if self.cut_outline is None else self.cut_outline

    @property
    def raw_outline(self) -> np.ndarray:
        """``(p, 2)`` CCW polygon top + reversed bottom, before joints."""
        return _ccw(np.concatenate([self.top, self.bottom[::-1]], axis=0))

    @property
    def length(self) -> float:
        """Length of the top edge, mm."""
        return float(np.linalg.norm(np.diff(self.top, axis=0), axis=1).sum())

    @property
    def area(self) -> float:
        """Area of the final outline, mm²."""
        return float(polygon_area(self.outline))

    @property
    def net_area(self) -> float:
        """Area of the plate less its bolt holes, mm² (its solid's volume is this × thickness)."""
        return self.area - float(np.pi / 4.0 * np.sum(self.holes[:, 2] ** 2))

    def node_top(self, vertex: int) -> np.ndarray:
        """Top point (2D) of a node of this plate."""
        k = int(np.flatnonzero(self.nodes == vertex)[0])
        return self.top[self.chain[k]]

    def node_axis(self, vertex: int) -> np.ndarray:
        """Unit in-plane axis direction (2D, pointing down) at a node."""
        k = int(np.flatnonzero(self.nodes == vertex)[0])
        c = self.chain[k]
        d = self.bottom[c] - self.top[c]
        return d / np.linalg.norm(d)

    def body_direction(self, vertex: int, towards: int | None = None) -> np.ndarray:
        """Unit 2D direction from a node into the plate, perpendicular to the node's axis
        (for an end node: the side the plate lies on; ``towards``: the side of that neighbouring node)."""
        k = int(np.flatnonzero(self.nodes == vertex)[0])
        c = int(self.chain[k])
        s = self.node_axis(vertex)
        if towards is not None:
            b = self.node_top(towards) - self.top[c]
        else:
            b = self.top[c + 1] - self.top[c] if c + 1 < len(self.top) else self.top[c - 1] - self.top[c]
        b = b - (b @ s) * s
        return b / np.linalg.norm(b)


def _ccw(p: np.ndarray) -> np.ndarray:
    return p if polygon_area(p) >= 0 else p[::-1]


# -- naming ------------------------------------------------------------------------------------------

# -- plates ------------------------------------------------------------------------------------------

def _in_plane_axes(axes: np.ndarray, n: np.ndarray, where: str) -> np.ndarray:
    a = axes - np.outer(axes @ n, n)
    length = np.linalg.norm(a, axis=1)
    if np.any(length < 1e-6):
        raise GeometryError(f"{where}: a node axis is perpendicular to the beam plane "
                            f"(in-plane length {length.min():.1e}); the beam has no depth direction",
                            element=where, value=float(length.min()))
    return a / length[:, None]


@dataclass(frozen=True, eq=False)
class PlateChain:
    """What a plate is drawn through: its chain of top points ``points (p, 3)`` with their axes ``axes (p, 3)``
    (the nodes' top points and, where a piece ends at a cut inside an edge, the cut's point and interpolated
    axis); the mesh vertices it holds ``nodes (k,)``, their places in the chain ``chain (k,)`` and their top
    points ``node_points (k, 3)``; ``through (k,)``: the polyline goes on past that node (else it ends there)."""

    points: np.ndarray
    axes: np.ndarray
    nodes: np.ndarray
    chain: np.ndarray
    node_points: np.ndarray
    through: np.ndarray


@dataclass(frozen=True)
class PlateName:
    """Who a plate is: part id, beam id, polyline index and family, and its place among the beam's pieces."""

    part_id: str
    beam_id: str
    polyline: int
    family: int
    piece: int = 0
    n_pieces: int = 1


def make_plate(name: PlateName, plane: np.ndarray, chain: PlateChain, params: BeamParams) -> BeamPlate:
    """A plate drawn through ``chain`` in ``plane`` ``(4,)`` (see module doc)."""
    part_id = name.part_id
    pln = pl.normalize(plane)
    n, d = pln[:3], pln[3]
    top3 = chain.points - np.outer(chain.points @ n + d, n)
    ahat = _in_plane_axes(chain.axes, n, part_id)
    chord = top3[-1] - top3[0]
    if np.linalg.norm(chord) < 1e-9 * max(1.0, float(np.abs(top3).max())):
        chord = top3[1] - top3[0]
    ex = chord - (chord @ n) * n
    ex /= np.linalg.norm(ex)
    ey = np.cross(n, ex)
    if ahat.sum(axis=0) @ ey > 0:
        ey = -ey
    frame = Frame(top3[0].copy(), ex, ey)
    top = frame.to2d(top3)
    bottom = top + params.depth * frame.vec2d(ahat)
    raw = _ccw(np.concatenate([top, bottom[::-1]], axis=0))
    dev = float(np.abs(chain.node_points @ n + d).max())
    return BeamPlate(part_id, name.beam_id, name.polyline, name.family, name.piece, name.n_pieces,
                     np.asarray(chain.nodes, dtype=np.int64), np.asarray(chain.through, dtype=bool),
                     np.asarray(chain.chain, dtype=np.int64), top, bottom,
                     pln, frame, params.depth, params.thickness, dev, raw, raw)


def _continuous_family(support: SupportStructure, params: BeamParams) -> int:
    if params.continuous_family is not None:
        return params.continuous_family
    return support.planar_families[0] if support.planar_families else 0


BLOCKED_RULE = "blocked"
"""The ``[beams] segment`` rule for the column plates no single direction puts into their half-lap slots
(:mod:`fabrication.beams.insertion`), applied by :func:`fabrication.beams.build.build_beams` once the slots are
known."""


def segmented_polylines(support: SupportStructure, params: BeamParams) -> np.ndarray:
    """``(L,)`` bool: the polylines ``[beams] segment`` names (ids and rules of :mod:`ppfab.support.lines`;
    ``nonplanar`` here means further than ``plane_tolerance`` mm from the polyline's plane)."""
    from ppfab.support.lines import select_polylines

    mesh = support.mesh
    out = np.zeros(len(mesh.polylines), dtype=bool)
    if "nonplanar" in params.segment:
        out |= support.polyline_deviation > params.plane_tolerance
    rest = [s for s in params.segment if s not in ("nonplanar", BLOCKED_RULE)]   # blocked: the beams stage's
    if rest:
        out |= select_polylines(mesh, rest, "beams.segment")
    return out


def layout_plates(support: SupportStructure, params: BeamParams, max_height: float = 0.0,
                  splice_clearances: SpliceClearances = (("bolted", 0.0),),
                  node_breaks: Mapping[int, Collection[int]] | None = None) -> tuple[list[BeamPlate], list[Finding]]:
    """All plates of the structure before joints, and the problems found on the way.

    A polyline becomes continuous plates when its plane is a support plane
    (``support.polyline_planar``), it lies in that plane within ``params.plane_tolerance``
    and, with segmented joints, belongs to the continuous family; otherwise one plate per
    edge in the edge's support plane.  Polylines the support left out of the planar families
    (``support.left_out``) and those ``[beams] segment`` names are always cut into one-edge plates.
    ``max_height``: the widest flat piece the plate stock holds across its length (0 = no limit);
    ``splice_clearances``: the splice kinds a split beam may get, in order of preference, each with how much
    further (mm) than the joints need its cuts stay from a node (a bolted splice: half its cover plate; a
    welded one: room for the weld preparation); a beam takes the first kind its cuts fit with, and its pieces
    carry it in ``meta["splice"]``.  ``node_breaks``: polyline → the vertices at which its continuous plates are
    cut across the node axis, each part ending there against the plate that runs through (the
    ``[beams] segment = ["blocked"]`` rule, :func:`fabrication.beams.insertion.node_breaks`).  With half-lap
    joints every polyline must be planar; with segmented joints every polyline of the
    continuous family — a polyline that is not is reported (``not_planar``) and cut
    into edge plates so the rest can still be inspected.
    """
    from .joint_types import get_joint_type

    jt = get_joint_type(params.joint)
    v = support.vertices
    axes = support.axes
    ids = contract.beam_ids(support)
    epl_edges = support.edges
    nv = len(v)
    edge_key = epl_edges[:, 0] * nv + epl_edges[:, 1]
    cont = _continuous_family(support, params)
    planar_lines = support.polyline_planar
    assert planar_lines is not None, "SupportStructure.__post_init__ sets polyline_planar"
    left_out = {k for k, _ in support.left_out}
    cut = segmented_polylines(support, params)
    plates: list[BeamPlate] = []
    defects: list[Finding] = []
    for l, line in enumerate(support.polylines):
        vs = line.vertices
        if len(vs) < 2:
            continue
        dev = float(support.polyline_deviation[l])
        supported = bool(planar_lines[l]) or len(vs) == 2
        planar = supported and dev <= params.plane_tolerance
        segmented = (jt.segments and line.family != cont) or l in left_out or bool(cut[l])
        if not planar and not segmented and jt.planar_requirement is not None:
            why = (f"its vertices lie up to {dev:.3g} mm off the beam plane (tolerance {params.plane_tolerance:g} mm)"
                   if dev > params.plane_tolerance else
                   f"its plane is not a support plane of the '{support.kind}' support structure (the axes leave it)")
            defects.append(Finding("not_planar", "", ids[l], dev, params.plane_tolerance,
                                  f"{ids[l]}: {why}; {jt.planar_requirement}"))
        if planar and not segmented:
            breaks = frozenset(int(k) for k in (node_breaks or {}).get(l, ()))
            plates.extend(_continuous(support, params, l, ids[l], defects, max_height, splice_clearances, breaks))
        else:
            a, b = vs[:-1], vs[1:]
            if line.closed and len(vs) > 2:
                a, b = np.r_[a, vs[-1]], np.r_[b, vs[0]]
            lo, hi = np.minimum(a, b), np.maximum(a, b)
            eids = np.searchsorted(edge_key, lo * nv + hi)
            w = contract.digits(len(a))
            for k, (va, vb, e) in enumerate(zip(a, b, eids)):
                pid = ids[l] if len(a) == 1 else contract.piece_id(ids[l], k, w)
                pts = v[[va, vb]]
                plate = make_plate(PlateName(pid, ids[l], l, line.family, k, len(a)), support.edge_planes[e],
                                   PlateChain(pts, axes[[va, vb]], nodes=np.array([va, vb]), chain=np.array([0, 1]),
                                              node_points=pts, through=np.array([False, False])), params)
                plate.meta["segment"] = True        # one edge in its own support plane
                plates.append(plate)
    return plates, defects


def _node_clearance(support: SupportStructure, params: BeamParams, l: int) -> np.ndarray:
    """``(k,)`` how far (mm, along the edges) a cut of polyline ``l`` must stay from each of its nodes: half
    the widest half-lap slot or end set-back another plate there can need (:func:`~fabrication.beams.joint_types.
    halflap.slot_width` at the smallest angle between this plane and another support plane at the node) plus
    ``min_segment``."""
    line = support.polylines[l]
    vs = line.vertices
    n = pl.normalize(support.polyline_planes[l])[:3]
    edges = support.edges
    nv = len(support.vertices)
    key = edges[:, 0] * nv + edges[:, 1]
    own = set()
    a, b = vs[:-1], vs[1:]
    if line.closed and len(vs) > 2:
        a, b = np.r_[a, vs[-1]], np.r_[b, vs[0]]
    own.update(np.searchsorted(key, np.minimum(a, b) * nv + np.maximum(a, b)).tolist())
    at: dict[int, list[int]] = {}
    for e, (i, j) in enumerate(edges.tolist()):
        if e not in own:
            at.setdefault(i, []).append(e)
            at.setdefault(j, []).append(e)
    out = np.full(len(vs), params.min_segment)
    t, c = params.slot_thickness, params.fit
    for q, v in enumerate(vs.tolist()):
        others = at.get(v, [])
        if not others:
            continue
        cos = np.abs(support.edge_planes[others, :3] @ n)
        cmax = float(min(cos.max(), np.cos(np.radians(max(params.min_angle_deg, 1.0)))))
        width = t * (1.0 + cmax) / np.sqrt(1.0 - cmax * cmax) + c
        out[q] += 0.5 * width
    return out


def _spans(vs: np.ndarray, closed: bool, breaks: Collection[int]) -> list[tuple[np.ndarray, bool]]:
    """The runs of a polyline between the vertices of ``breaks``: ``(positions into vs, closed)``, in order,
    consecutive runs sharing their break node; without a break inside, the polyline itself.  A closed polyline
    cut at breaks is read from its first break round to it."""
    n = len(vs)
    at = [q for q in range(n) if int(vs[q]) in breaks and (closed or 0 < q < n - 1)]
    if not at:
        return [(np.arange(n), closed)]
    seq = [(at[0] + q) % n for q in range(n + 1)] if closed else list(range(n))
    out: list[tuple[np.ndarray, bool]] = []
    start = 0
    for i in range(1, len(seq)):
        if seq[i] in at or i == len(seq) - 1:
            out.append((np.asarray(seq[start:i + 1]), False))
            start = i
    return out


def _continuous(support: SupportStructure, params: BeamParams, l: int, beam_id: str,
                defects: list[Finding], max_height: float = 0.0,
                splice_clearances: SpliceClearances = (("bolted", 0.0),),
                breaks: Collection[int] = frozenset()) -> list[BeamPlate]:
    """The pieces of a planar polyline, cut where :func:`~fabrication.beams.splitting.plan_cuts` finds
    room: anywhere inside an edge, clear of the joints, each piece's flat length (extent along its chord,
    bottom-edge overhang at the ends included) at most ``max_length`` and its height across at most
    ``max_height``, and across the node axis at each vertex of ``breaks`` (:func:`_spans`; pieces meeting there
    end against the plate running through, not spliced).  The splice kinds of ``splice_clearances`` are tried in
    order; the beam takes the first whose clearance leaves room for all its cuts (a beam whose pieces meet only
    at breaks takes none)."""
    line = support.polylines[l]
    vs = line.vertices
    spans = _spans(vs, bool(line.closed and len(vs) > 2), breaks)
    joints = _node_clearance(support, params, l)
    # a plate's top edge raised by a bevel under its strips (fabrication.beams.bevel_cut) meets its end cuts
    # further out: the pieces are planned one thickness shorter (a conical example's piece grew 4.7 mm)
    max_length = max(params.max_length - params.thickness, 0.5 * params.max_length) if params.max_length else 0.0
    tried: list[str] = []
    problem, long_x, high_y = None, 0.0, 0.0
    pieces: list[BeamPlate] = []
    for kind, extra in splice_clearances:
        plans = [plan_cuts(support.vertices[vs[pos]], support.axes[vs[pos]], support.polyline_planes[l], closed,
                           params.depth, max_length, joints[pos] + extra, max_height) for pos, closed in spans]
        counts = [len(plan.cuts) if closed else len(plan.cuts) + 1 for plan, (_, closed) in zip(plans, spans)]
        pieces = []
        for plan, (pos, closed) in zip(plans, spans):
            pieces += _pieces(support, params, l, beam_id, list(plan.cuts), closed, pos, len(pieces), sum(counts))
        sizes = [(float(np.ptp(p.raw_outline[:, 0])), float(np.ptp(p.raw_outline[:, 1]))) for p in pieces]
        long_x = max((x for x, _ in sizes), default=0.0)
        high_y = max((y for _, y in sizes), default=0.0)
        problem = next((plan.problem for plan in plans if plan.problem), None)
        over = ((max_length > 0 and long_x > max_length + 1e-6)
                or (max_height > 0 and high_y > max_height + 1e-6))
        if not (problem or over):
            if any(plan.cuts for plan in plans):
                for p in pieces:
                    p.meta["splice"] = kind
            return pieces
        tried.append(f"{kind} splices {extra:.0f} mm")
    limit = f"{params.max_length:g} mm" + (f" × {max_height:g} mm" if max_height > 0 else "")
    why = problem or f"its largest piece is {long_x:.0f} × {high_y:.0f} mm"
    clear = f" (cuts kept from the joints by {' or '.join(tried)} more)" if any(e for _, e in splice_clearances) \
        else ""
    welded = "" if any(k == "welded" for k, _ in splice_clearances) else \
        "set splices.kind = \"welded\" or \"auto\" (welded splices need less room), "
    defects.append(Finding("too_long", "", beam_id, long_x, params.max_length,
                          f"{beam_id}: cannot be cut into pieces of at most {limit} clear of the joints{clear}: "
                          f"{why}; {welded}raise beams.max_length (up to the usable plate length), use wider plate "
                          "stock ([beam_nesting] sheet) or lower beams.depth"))
    return pieces


def _pieces(support: SupportStructure, params: BeamParams, l: int, beam_id: str, cuts: list[Cut],
            closed: bool, pos: np.ndarray, first: int, total: int) -> list[BeamPlate]:
    """The plates of one run of polyline ``l`` (``pos``: positions into its vertices, :func:`_spans`) between
    its ``cuts`` (inside edges of the run), numbered ``first, first + 1, …`` of the beam's ``total`` pieces; a
    node is an end only where the run ends (the polyline's end or a break)."""
    line = support.polylines[l]
    vs = line.vertices[pos]
    pts = support.vertices[vs]
    plane = support.polyline_planes[l]
    axes = support.axes[vs]
    nn = len(vs)
    pieces: list[tuple[Cut | None, list[int], Cut | None]] = []
    if closed:
        for r in range(len(cuts)):
            a, b = cuts[r], cuts[(r + 1) % len(cuts)]
            count = (b.edge - a.edge) % nn or nn
            pieces.append((a, [(a.edge + 1 + q) % nn for q in range(count)], b))
    else:
        starts: list[Cut | None] = [None, *cuts]
        ends: list[Cut | None] = [*cuts, None]
        for s, e in zip(starts, ends):
            lo = 0 if s is None else s.edge + 1
            hi = nn - 1 if e is None else e.edge
            pieces.append((s, list(range(lo, hi + 1)), e))
    out = []
    w = contract.digits(total)

    def cut_point(c: Cut) -> tuple[np.ndarray, np.ndarray]:
        i, j = c.edge, (c.edge + 1) % nn
        return (1 - c.t) * pts[i] + c.t * pts[j], (1 - c.t) * axes[i] + c.t * axes[j]

    for r, (s, idx, e) in enumerate(pieces, start=first):
        cp: list[np.ndarray] = []
        ca: list[np.ndarray] = []
        chain: list[int] = []
        if s is not None:
            point, axis = cut_point(s)
            cp.append(point)
            ca.append(axis)
        for k in idx:
            chain.append(len(cp))
            cp.append(pts[k])
            ca.append(axes[k])
        if e is not None:
            point, axis = cut_point(e)
            cp.append(point)
            ca.append(axis)
        ca_unit = np.asarray(ca)
        ca_unit /= np.linalg.norm(ca_unit, axis=1, keepdims=True)
        through = np.array([closed or (0 < k < nn - 1) for k in idx])
        pid = beam_id if total == 1 else contract.piece_id(beam_id, r, w)
        out.append(make_plate(PlateName(pid, beam_id, l, line.family, r, total), plane,
                              PlateChain(np.asarray(cp), ca_unit, nodes=vs[idx], chain=np.asarray(chain),
                                         node_points=pts[idx], through=through), params))
    return out
