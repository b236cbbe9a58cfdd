"""Where glazing strips run through a node and where they stop (fabrication.glazing.strips.running_spans).

At a re-entrant corner of a trimmed net the mesh's polylines stop (ppfab.topology), but the beams of one row go
on nearly straight: their strips must run through there, or the strip of one of them stops where it clears the
other's band — which, for two spans 0.4° off straight, is metres from the node (a real shell patch had pane edges
669 mm without strip or pressure plate).  The rule is checked here on a node built by hand, with the stop
distance of the module docstring computed apart.
"""

from __future__ import annotations

import numpy as np


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
