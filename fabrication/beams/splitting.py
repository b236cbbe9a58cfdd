"""Where a long (or closed) planar beam is cut into pieces that fit the plate stock.

A beam is the chain of its nodes' top points ``p_0 … p_{k−1}`` (closed: ``p_{k−1}`` joins ``p_0``) with the
axes ``a_i`` brought into its plane.  A cut lies anywhere inside an edge ``p_e p_{e+1}``, at
``c(t) = (1 − t) p_e + t p_{e+1}`` with the axis ``(1 − t) a_e + t a_{e+1}`` (normalised), and runs down that
axis: the two pieces share the cut line.  A cut must stay clear of the joints: at least
``clear_i`` (half the widest slot or end set-back a node can get, plus ``min_segment``) from each node
along the edge.

A piece's *flat extent* is what the stock must hold: the extent, along its chord (first to last top
point) and across it in its plane, of its top and bottom points (``top + depth · â``), as
:func:`fabrication.beams.plates.make_plate` draws it; it fits when the length is at most ``max_length`` and
the height at most ``max_height`` (a curved beam's sagitta plus its depth must fit the plate's width).
:func:`plan_cuts` walks along the beam and puts each cut as far on as the piece still fits (the fewest
pieces: the extent only grows as a piece gets longer), then evens the pieces out by bisection on a common
share of the limits (the same number of pieces, the largest as small as possible).  A closed
beam is cut at least twice.  When a stretch of the beam has no place for a cut that leaves the piece short
enough — an edge too short to hold a cut clear of both its nodes, a node whose joints alone are longer than
``max_length`` — the beam is refused, saying where and why.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Cut:
    """A cut inside edge ``edge`` (between chain nodes ``edge`` and ``edge + 1``, modulo the count when
    closed) at the fraction ``t`` (0 < t < 1) of its length."""

    edge: int
    t: float


@dataclass(frozen=True)
class CutPlan:
    """The cuts in order along the beam, the longest piece's flat extent (mm), and why the beam cannot be
    cut to ``max_length`` (``""`` when it can)."""

    cuts: tuple[Cut, ...]
    longest: float
    problem: str = ""


class _Beam:
    """The chain of a beam in its plane: top points ``(k, 3)``, unit in-plane axes ``(k, 3)``."""

    def __init__(self, points: np.ndarray, axes: np.ndarray, plane: np.ndarray, closed: bool, depth: float,
                 max_length: float = 0.0, max_height: float = 0.0):
        n = plane[:3] / np.linalg.norm(plane[:3])
        self.n = n
        self.top = points - np.outer(points @ n + plane[3], n)
        a = axes - np.outer(axes @ n, n)
        self.axes = a / np.linalg.norm(a, axis=1, keepdims=True)
        self.closed = closed
        self.depth = depth
        self.k = len(points)
        self.n_edges = self.k if closed else self.k - 1
        nxt = np.roll(self.top, -1, axis=0)[: self.n_edges]
        self.edge_len = np.linalg.norm(nxt - self.top[: self.n_edges], axis=1)
        self.ix = 1.0 / max_length if max_length > 0 else 0.0
        self.iy = 1.0 / max_height if max_height > 0 else 0.0
        if not (self.ix or self.iy):                        # no limit: measure by length (closed beams)
            self.ix = 1.0 / max(float(self.edge_len.sum()), 1e-300)

    def cut_point(self, c: Cut) -> tuple[np.ndarray, np.ndarray]:
        i, j = c.edge, (c.edge + 1) % self.k
        p = (1 - c.t) * self.top[i] + c.t * self.top[j]
        a = (1 - c.t) * self.axes[i] + c.t * self.axes[j]
        return p, a / np.linalg.norm(a)

    def nodes_between(self, start: Cut | None, end: Cut | None) -> list[int]:
        """Chain nodes of the piece from ``start`` (``None``: the beam's first node) to ``end`` (``None``: the last)."""
        lo = 0 if start is None else start.edge + 1
        if end is None:
            hi = self.k - 1
        else:
            hi = end.edge
            if self.closed and start is not None and (end.edge < start.edge or
                                                     (end.edge == start.edge and end.t <= start.t)):
                hi += self.k
        return [q % self.k for q in range(lo, hi + 1)]

    def size(self, start: Cut | None, end: Cut | None) -> tuple[float, float]:
        """Flat extent of the piece between two cuts along its chord and across it (module docstring), mm."""
        idx = self.nodes_between(start, end)
        pts = [self.top[idx]]
        ax = [self.axes[idx]]
        if start is not None:
            p, a = self.cut_point(start)
            pts.insert(0, p[None])
            ax.insert(0, a[None])
        if end is not None:
            p, a = self.cut_point(end)
            pts.append(p[None])
            ax.append(a[None])
        top = np.concatenate(pts)
        bottom = top + self.depth * np.concatenate(ax)
        chord = top[-1] - top[0]
        if np.linalg.norm(chord) < 1e-9 * max(1.0, float(np.abs(top).max())):
            chord = top[1] - top[0]
        ex = chord - (chord @ self.n) * self.n
        ex /= np.linalg.norm(ex)
        ey = np.cross(self.n, ex)
        both = np.concatenate([top, bottom])
        x, y = both @ ex, both @ ey
        return float(x.max() - x.min()), float(y.max() - y.min())

    def extent(self, start: Cut | None, end: Cut | None) -> float:
        """How much of the stock the piece takes: ``max(length / max_length, height / max_height)`` (≤ 1 fits)."""
        x, y = self.size(start, end)
        return max(x * self.ix, y * self.iy)


def _windows(beam: _Beam, clear: np.ndarray) -> list[tuple[int, float, float]]:
    """Per edge the allowed cut fractions ``(edge, t_lo, t_hi)`` (only edges with room for a cut).

    A cut at ``t`` runs from ``c(t)`` down the interpolated axis to ``c(t) + D·â(t)``; a node's joint runs
    down its own axis from ``p_e`` to ``p_e + D·a_e``.  The cut keeps ``clear`` from both nodes of its edge,
    measured along the edge ``u = (p_{e+1} − p_e)/L``, at the top edge and at the bottom edge alike (the
    separation is nearly linear in the depth, so the two ends bound it): a cut line leaning towards a node
    does not come closer to its slot at the bottom than ``clear``.  The limits are found by bisection on
    every edge at once: ``sep_0(t)`` grows with ``t`` and ``sep_1(t)`` shrinks.
    """
    m = beam.n_edges
    if m == 0:
        return []
    i = np.arange(m)
    j = (i + 1) % beam.k
    p0, p1 = beam.top[i], beam.top[j]
    a0, a1 = beam.axes[i], beam.axes[j]
    L = beam.edge_len
    u = (p1 - p0) / np.maximum(L, 1e-300)[:, None]
    D = beam.depth
    q0, q1 = p0 + D * a0, p1 + D * a1
    c0, c1 = clear[i], clear[j]

    def seps(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        c = p0 + t[:, None] * (p1 - p0)
        a = (1 - t)[:, None] * a0 + t[:, None] * a1
        b = c + D * a / np.linalg.norm(a, axis=1, keepdims=True)
        s0 = np.minimum(np.einsum("ij,ij->i", c - p0, u), np.einsum("ij,ij->i", b - q0, u))
        s1 = np.minimum(np.einsum("ij,ij->i", p1 - c, u), np.einsum("ij,ij->i", q1 - b, u))
        return s0, s1

    # t_lo: the first t with sep_0 ≥ clear_e; t_hi: the last with sep_1 ≥ clear_{e+1}
    lo_a, lo_b = np.zeros(m), np.ones(m)
    hi_a, hi_b = np.zeros(m), np.ones(m)
    for _ in range(40):
        lo_m, hi_m = 0.5 * (lo_a + lo_b), 0.5 * (hi_a + hi_b)
        s0, _ = seps(lo_m)
        _, s1 = seps(hi_m)
        ok0, ok1 = s0 >= c0, s1 >= c1
        lo_b = np.where(ok0, lo_m, lo_b)
        lo_a = np.where(ok0, lo_a, lo_m)
        hi_a = np.where(ok1, hi_m, hi_a)
        hi_b = np.where(ok1, hi_b, hi_m)
    lo, hi = lo_b, hi_a
    s0_lo, _ = seps(lo)
    _, s1_hi = seps(hi)
    good = (L > 0) & (hi > lo) & (s0_lo >= c0 - 1e-9) & (s1_hi >= c1 - 1e-9)
    return [(int(e), float(lo[e]), float(hi[e])) for e in np.flatnonzero(good)]


def _furthest(beam: _Beam, start: Cut | None, windows: list[tuple[int, float, float]], limit: float,
              stop: Cut | None) -> Cut | None:
    """The furthest cut after ``start`` (before ``stop`` on a closed beam) whose piece fits ``limit``.

    The candidates are the windows in order along the beam; the extent grows along the beam, so the last
    window whose earliest cut fits holds the answer, found there by bisection."""
    order = _after(beam, start, windows, stop)
    best: Cut | None = None
    for e, lo, hi in order:
        c_lo = Cut(e, lo)
        if beam.extent(start, c_lo) > limit:
            break
        c_hi = Cut(e, hi)
        if beam.extent(start, c_hi) <= limit:
            best = c_hi
            continue
        a, b = lo, hi
        for _ in range(25):
            m = 0.5 * (a + b)
            if beam.extent(start, Cut(e, m)) <= limit:
                a = m
            else:
                b = m
        best = Cut(e, a)
        break
    return best


def _after(beam: _Beam, start: Cut | None, windows: list[tuple[int, float, float]], stop: Cut | None
           ) -> list[tuple[int, float, float]]:
    """The windows after ``start`` in order along the beam (a piece must hold at least one node), those of
    edges before ``stop``'s edge only; on a closed beam they wrap around."""
    if start is None:
        seq = list(windows)
    else:
        later = [w for w in windows if w[0] > start.edge]
        seq = later + ([w for w in windows if w[0] <= start.edge] if beam.closed else [])
    out = []
    for e, lo, hi in seq:
        if stop is not None and e == stop.edge:
            break                          # the piece from this cut back to ``stop`` needs a node too
        out.append((e, lo, hi))
    return out


def _greedy(beam: _Beam, windows: list[tuple[int, float, float]], limit: float, first: Cut | None
            ) -> tuple[list[Cut], str]:
    """Cuts from ``first`` (``None``: the open beam's start) on, each as far as ``limit`` allows."""
    cuts: list[Cut] = [] if first is None else [first]
    start = first
    for _ in range(beam.k + 1):
        if beam.closed:
            assert first is not None
            if len(cuts) > 1 and beam.extent(start, first) <= limit:
                return cuts, ""
        elif beam.extent(start, None) <= limit:
            return cuts, ""
        nxt = _furthest(beam, start, windows, limit, first if beam.closed else None)
        if nxt is None:
            return cuts, _why(beam, start, windows, limit)
        cuts.append(nxt)
        start = nxt
    return cuts, "the cuts do not advance along the beam"


def _why(beam: _Beam, start: Cut | None, windows: list[tuple[int, float, float]], limit: float) -> str:
    node = 0 if start is None else (start.edge + 1) % beam.k
    later = [w for w in windows if start is None or w[0] > start.edge or beam.closed]
    if not later:
        return (f"after chain node {node} no edge is long enough to hold a cut clear of the joints at both its "
                "ends")
    e, lo, _ = later[0]
    x, y = beam.size(start, Cut(e, lo))
    return (f"the piece from {'its start' if start is None else 'the cut before chain node ' + str(node)} to the "
            f"nearest place a cut clears the joints (edge {e}) is already {x:.0f} × {y:.0f} mm")


def plan_cuts(points: np.ndarray, axes: np.ndarray, plane: np.ndarray, closed: bool, depth: float,
              max_length: float, clear: np.ndarray, max_height: float = 0.0) -> CutPlan:
    """Cuts of a beam into pieces of at most ``max_length`` flat extent along their chords and ``max_height``
    across (module docstring).

    Parameters
    ----------
    points, axes : (k, 3) top points (the polyline's vertices) and node axes of the beam
    plane : (4,) the beam's unit plane
    closed : the polyline closes (then at least two pieces)
    depth : beam depth, mm
    max_length : longest flat piece, mm (0 = no limit: only a closed beam is cut, in two)
    clear : (k,) distance a cut keeps from each node along the edges, mm
    max_height : widest flat piece across its chord, mm (the plate stock's width; 0 = no limit)
    """
    beam = _Beam(np.asarray(points, dtype=float), np.asarray(axes, dtype=float), np.asarray(plane, dtype=float),
                 closed, depth, max_length, max_height)
    windows = _windows(beam, np.asarray(clear, dtype=float))
    whole = beam.size(None, None)[0]
    limited = max_length > 0 or max_height > 0
    if not closed and (not limited or beam.extent(None, None) <= 1.0):
        return CutPlan((), whole)
    if closed and not windows:
        return CutPlan((), whole, "no edge of the closed beam is long enough to hold a cut clear of the joints")
    limit = 1.0 if limited else np.inf
    if closed:
        # start at the window nearest the middle of edge 0's side of the ring; try a few and keep the best
        starts = [Cut(e, 0.5 * (lo + hi)) for e, lo, hi in windows[:: max(1, len(windows) // 4)]]
        plans = []
        for s in starts:
            cuts, problem = _greedy(beam, windows, limit, s)
            plans.append((len(cuts) if not problem else np.inf, cuts, problem, s))
        plans.sort(key=lambda p: p[0])
        _, cuts, problem, first = plans[0]
        if problem:
            return CutPlan(tuple(cuts), _longest(beam, cuts), problem)
        cuts = _balanced(beam, windows, cuts, first, max(len(cuts), 2))
        return CutPlan(tuple(sorted(cuts, key=lambda c: (c.edge, c.t))), _longest(beam, cuts))
    cuts, problem = _greedy(beam, windows, limit, None)
    if problem:
        return CutPlan(tuple(cuts), _longest(beam, cuts), problem)
    cuts = _balanced(beam, windows, cuts, None, len(cuts) + 1)
    return CutPlan(tuple(cuts), _longest(beam, cuts))


def _pieces_of(beam: _Beam, cuts: list[Cut]) -> list[tuple[Cut | None, Cut | None]]:
    if beam.closed:
        ordered = sorted(cuts, key=lambda c: (c.edge, c.t))
        return [(ordered[r], ordered[(r + 1) % len(ordered)]) for r in range(len(ordered))]
    return list(zip([None, *cuts], [*cuts, None]))


def _longest(beam: _Beam, cuts: list[Cut]) -> float:
    """Flat length along the chord of the piece that takes most of the stock, mm."""
    pieces = _pieces_of(beam, cuts) if cuts else [(None, None)]
    a, b = max(pieces, key=lambda ab: beam.extent(*ab))
    return beam.size(a, b)[0]


def _largest(beam: _Beam, cuts: list[Cut]) -> float:
    pieces = _pieces_of(beam, cuts) if cuts else [(None, None)]
    return max(beam.extent(a, b) for a, b in pieces)


def _balanced(beam: _Beam, windows: list[tuple[int, float, float]], cuts: list[Cut], first: Cut | None,
              pieces: int) -> list[Cut]:
    """The same number of pieces with the largest as small as bisection on the common limit finds."""
    hi = _largest(beam, cuts)
    lo = 0.0
    best = cuts
    for _ in range(8):
        mid = 0.5 * (lo + hi)
        trial, problem = _greedy(beam, windows, mid, first)
        count = len(trial) if beam.closed else len(trial) + 1
        if not problem and count <= pieces:
            best, hi = trial, mid
        else:
            lo = mid
    return best
