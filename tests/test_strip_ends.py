"""Where glazing strips run through a node and where they stop (fabrication.glazing.strips.running_spans).

At a re-entrant corner of a trimmed net the mesh's polylines stop (ppfab.topology), but the beams of one row go
on nearly straight: their strips must run through there, or the strip of one of them stops where it clears the
other's band — which, for two spans 0.4° off straight, is metres from the node (a real shell patch had pane edges
669 mm without strip or pressure plate).  The rule is checked here on a node built by hand, with the stop
distance of the module docstring computed apart.
"""

from __future__ import annotations

import numpy as np
import pytest


def _node(directions: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Edges ``(k, 2)`` from node 0 to nodes 1..k along ``directions``; unit ``b − a`` per edge."""
    edges = np.array([[0, k + 1] for k in range(len(directions))])
    d = np.array([v / np.linalg.norm(v) for v in directions])
    return edges, d


def test_a_reentrant_corner_runs_a_nearly_straight_pair_through_rows_first():
    from fabrication.glazing.strips import running_spans

    a = np.radians(0.4)
    # row spans 0 (east) and 1 (west, 0.4° off straight), column spans 2 (north) and 3 (south, 2.1° off)
    edges, d = _node([np.array([1.0, 0, 0]), np.array([-np.cos(a), np.sin(a), 0]),
                      np.array([0, 1.0, 0]), np.array([np.sin(np.radians(2.1)), -np.cos(np.radians(2.1)), 0])])
    line_of = np.array([10, 11, 12, 13])                  # four polylines: none with two spans here
    family = np.array([0, 0, 1, 1])
    assert running_spans(0, [0, 1, 2, 3], line_of, family, edges, d) == {0, 1}
    # the columns straighter than the rows: still the rows (rows before columns, as where polylines run through)
    c = np.radians(5.0)
    edges_c, d_c = _node([np.array([1.0, 0, 0]), np.array([-np.cos(c), np.sin(c), 0]),
                          np.array([0, 1.0, 0]), np.array([0, -1.0, 0])])
    assert running_spans(0, [0, 1, 2, 3], line_of, family, edges_c, d_c) == {0, 1}
    # the rows kinked by 60° (no straight-on pair of rows): the columns, 2.1° off, run through
    b = np.radians(60.0)
    edges, d = _node([np.array([1.0, 0, 0]), np.array([-np.cos(b), np.sin(b), 0]),
                      np.array([0, 1.0, 0]), np.array([np.sin(np.radians(2.1)), -np.cos(np.radians(2.1)), 0])])
    assert running_spans(0, [0, 1, 2, 3], line_of, family, edges, d) == {2, 3}
    # a corner (one span of each family): the row's span, as before
    assert running_spans(0, [0, 2], line_of, family, edges, d) == {0}
    # a polyline with two spans wins, whatever else is straighter
    assert running_spans(0, [0, 1, 2, 3], np.array([10, 11, 12, 12]), family, edges, d) == {2, 3}


def test_the_stop_of_a_strip_next_to_a_nearly_straight_span_is_metres():
    """Why the rule matters: a strip that stops against a span 0.4° off straight would stop where its rectangle
    clears that span's band, ``(w/2 + c + (w/2)|cos θ|) / sin θ`` from the node — computed here for the default
    strip (60 mm wide, 2 mm clearance): over 8 m, longer than any span."""
    from fabrication.glazing.params import GlazingParams

    p = GlazingParams()
    theta = np.radians(180.0 - 0.4)
    stop = (0.5 * p.width + p.clearance + 0.5 * p.width * abs(np.cos(theta))) / np.sin(theta)
    assert stop > 8000.0


def _valley_corner(kink_deg: float, corner_deg: float) -> dict:
    """A strip end along +x from a node at the origin (``ey`` = +y, up = +z) and the corner of a pane it does not
    carry: the pane's plane through the node turned by ``kink_deg`` about y (positive: the strip rises towards
    the pane, a valley), one edge back along −x in that plane, the other at ``corner_deg`` from it."""
    k, a = np.radians(kink_deg), np.radians(corner_deg)
    t1, t2 = np.array([-np.cos(k), 0.0, np.sin(k)]), np.array([0.0, 1.0, 0.0])
    ray_a, ray_b = 1500.0 * t1, 1500.0 * (np.cos(a) * t1 + np.sin(a) * t2)
    return dict(origin=np.zeros(3), own=np.array([1.0, 0, 0]), ey=np.array([0, 1.0, 0]), up=np.array([0, 0, 1.0]),
                height=11.0, half_width=30.0, reach=1500.0, rays=(ray_a, ray_b), centre=0.4 * (ray_a + ray_b),
                normal=np.array([np.sin(k), 0.0, np.cos(k)]))


def _sampled_reach(c: dict, tol: float) -> float:
    """The largest x of a 0.01 mm grid over the strip end's band whose point lies in the pane's corner (its angle,
    seen from above, between those of the two edges) with the gasket top more than ``tol`` above the pane's
    underside (the plane through ``centre + height·normal``); 0 where none."""
    x, y = np.meshgrid(np.arange(0.0, 200.0, 0.01), np.linspace(-c["half_width"], c["half_width"], 121))
    top = np.stack([x, y, np.full_like(x, c["height"])], axis=-1)
    rise = (top - c["centre"] - c["height"] * c["normal"]) @ c["normal"]
    angle = np.arctan2(y, x)
    lo, hi = sorted(float(np.arctan2(r[1], r[0])) for r in c["rays"])
    if hi - lo > np.pi:                                   # the corner spans ±180° (it opens towards −x)
        inside = (angle >= hi) | (angle <= lo)
    else:
        inside = (angle >= lo) & (angle <= hi)
    hit = inside & (rise > tol)
    return float(x[hit].max()) if hit.any() else 0.0


def test_a_strip_end_is_cut_back_out_from_under_an_obtuse_corner_in_a_valley_only():
    """``corner_cutback`` against a sampled grid: under an obtuse corner (120°) in a valley (kink 10°) the strip
    end reaches the corner's edge at the band's side, ``(w/2)·cot φ`` with φ the edge's angle seen from above
    (17.0 mm); on a ridge, or under an acute corner, nothing is cut; with a small kink only where the gasket
    top stands more than the tolerance above the pane."""
    from fabrication.glazing.strips import CORNER_RISE_TOL, corner_cutback

    c = _valley_corner(10.0, 120.0)
    cut = corner_cutback(**c)
    b = c["rays"][1]
    assert cut == pytest.approx(30.0 * b[0] / b[1], abs=1e-9) and 16.5 < cut < 17.5
    assert cut == pytest.approx(_sampled_reach(c, CORNER_RISE_TOL), abs=0.02)
    assert corner_cutback(**_valley_corner(-10.0, 120.0)) == 0.0 == _sampled_reach(_valley_corner(-10.0, 120.0),
                                                                                   CORNER_RISE_TOL)
    assert corner_cutback(**_valley_corner(10.0, 80.0)) == 0.0 == _sampled_reach(_valley_corner(10.0, 80.0),
                                                                                 CORNER_RISE_TOL)
    for kink, corner in ((0.5, 135.0), (0.2, 150.0), (3.0, 100.0), (25.0, 170.0)):
        c = _valley_corner(kink, corner)
        assert corner_cutback(**c) == pytest.approx(_sampled_reach(c, CORNER_RISE_TOL), abs=0.02), (kink, corner)
