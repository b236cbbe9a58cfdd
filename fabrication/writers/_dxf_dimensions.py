"""Dimensions of a pane in its per-type DXF: every edge and both diagonals, as DXF ``DIMENSION`` entities.

A glass processor checks a free-form pane by its edge lengths and diagonals.  Each edge ``c_k → c_k+1`` of the
counter-clockwise outline gets an aligned dimension on the outside, each diagonal ``c_1 c_3``, ``c_2 c_4`` one
along the diagonal itself.  The entities go on layer :data:`~fabrication.contract.DIM_LAYER` (never machined); ezdxf
renders each one's geometry block (``*D1`` …), as a DXF dimension needs, so a reader that ignores dimensions
still sees the lines.  The measured values (group code 42) are the exact distances of the outline's corners.
"""

from __future__ import annotations

import numpy as np

from ..contract import DIM_COLOUR, DIM_LAYER


def text_height(outline: np.ndarray) -> float:
    """Dimension text height for a pane, mm: 2 % of its larger extent, between 10 and 60 mm."""
    extent = float(np.ptp(np.asarray(outline, dtype=float), axis=0).max())
    return float(np.clip(0.02 * extent, 10.0, 60.0))


EDGE_OFFSET = 120.0
"""An edge's dimension line lies ``2.5 h + EDGE_OFFSET`` mm outside the edge (``h`` the text height)."""


def title_position(outline: np.ndarray, title_height: float = 40.0) -> tuple[float, float]:
    """Where a per-type DXF's title starts: below everything the edge dimensions draw (their lines ``2.5 h +``
    :data:`EDGE_OFFSET` outside the outline, extension lines ``0.6 h`` beyond, text above the line), so no
    extension line runs through it."""
    p = np.asarray(outline, dtype=float)
    h = text_height(p)
    lo = p.min(axis=0)
    return float(lo[0]), float(lo[1] - (2.5 * h + EDGE_OFFSET) - 3.0 * h - title_height)


def dimension_keep_out(outline: np.ndarray) -> tuple[np.ndarray, ...]:
    """What a pane's label keeps clear of inside a dimensioned quad ``(4, 2)``: its two diagonals (dimensioned
    along their length) and a box around each diagonal's text, a quarter of the way along it."""
    p = np.asarray(outline, dtype=float)
    if len(p) != 4:
        return ()
    h = text_height(p)
    out: list[np.ndarray] = []
    for a, b in ((p[0], p[2]), (p[1], p[3])):
        out.append(np.array([a, b]))
        c, u = 0.75 * a + 0.25 * b, (b - a) / np.linalg.norm(b - a)
        v = np.array([-u[1], u[0]])
        half = 4.0 * h                              # "1234.5" at height h, with its arrows' gap
        out.append(np.array([c - half * u - 1.5 * h * v, c + half * u - 1.5 * h * v, c + half * u + 1.5 * h * v,
                             c - half * u + 1.5 * h * v, c - half * u - 1.5 * h * v]))
    return tuple(out)


def add_pane_dimensions(doc, outline: np.ndarray) -> int:
    """Add the edge and diagonal dimensions of a counter-clockwise outline ``(k, 2)`` to ``doc``'s modelspace;
    returns the number added (``k`` edges, and 2 diagonals when ``k = 4``).

    Every dimension reads from left to right (its points ordered by increasing x, the offset side kept), an
    edge's dimension line lies ``2.5 h + 120`` mm outside the edge (``h`` the text height; clear of the title
    under the reference edge), a diagonal's text sits a quarter of the way along it from its first corner.
    """
    p = np.asarray(outline, dtype=float)
    if DIM_LAYER not in doc.layers:
        doc.layers.add(DIM_LAYER, color=DIM_COLOUR)
    h = text_height(p)
    style = {"dimtxt": h, "dimasz": 0.6 * h, "dimdec": 1, "dimdsep": ord("."), "dimexo": 0.3 * h,
             "dimexe": 0.6 * h, "dimgap": 0.3 * h, "dimtad": 1}
    msp = doc.modelspace()
    k = len(p)
    pairs = [(p[i], p[(i + 1) % k], -(2.5 * h + EDGE_OFFSET), None) for i in range(k)]
    if k == 4:
        pairs += [(p[0], p[2], 0.0, 0.75 * p[0] + 0.25 * p[2]), (p[1], p[3], 0.0, 0.75 * p[1] + 0.25 * p[3])]
    for a, b, distance, text_at in pairs:
        if (b[0], b[1]) < (a[0], a[1]):            # read left to right; the offset stays on the same side
            a, b, distance = b, a, -distance
        dim = msp.add_aligned_dim(p1=tuple(map(float, a)), p2=tuple(map(float, b)), distance=distance,
                                  dimstyle="Standard", override=style, dxfattribs={"layer": DIM_LAYER})
        if text_at is not None:
            dim.set_location(tuple(map(float, text_at)))
        dim.render()
    return len(pairs)
