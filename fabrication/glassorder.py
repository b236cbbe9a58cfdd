"""The glass order a processor can check: the shape of every pane type by its corners, edges, diagonals, angles.

A glass processor checks a free-form pane by its edge lengths and both diagonals (a quadrilateral is fixed by its
four edges and one diagonal; the second diagonal checks the first), and cuts it from the corner coordinates.
For each type the representative pane's flat outline — seen from outside, counter-clockwise, moved into the
order's reference frame: corner 1 (the reference corner) at the origin, edge 12 along +x (the per-type DXF draws
the same outline in its nesting frame, which is only a rigid motion away) — gives

* corners ``c_k = (x_k, y_k)``, ``k = 1 … 4``;
* edges ``e_k,k+1 = |c_{k+1} − c_k|`` and diagonals ``d_13 = |c_3 − c_1|``, ``d_24 = |c_4 − c_2|``;
* interior angles ``α_k = atan2(a × b, a · b) mod 360°`` with ``a = c_{k−1} − c_k``, ``b = c_{k+1} − c_k``
  (counter-clockwise outline: the angle inside the pane, above 180° at a reflex corner);

plus the weight of one pane, the perimeter and, from ``[panels]``, the edge work and the coated side.  The
columns are :data:`fabrication.contract.ORDER_COLUMNS` then :data:`~fabrication.contract.ORDER_SHAPE_COLUMNS`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ppfab.errors import FabricationError

from .contract import ORDER_CORNERS
from .flatpart import FlatPart
from .parts import _num as _r
from .parts import order_rows

if TYPE_CHECKING:  # pragma: no cover
    from .panels.makeup import Makeup
    from .panels.params import PanelParams


def pane_shape(outline: np.ndarray) -> dict[str, np.ndarray]:
    """Corners, edge lengths, diagonals and interior angles of a counter-clockwise quadrilateral.

    Parameters
    ----------
    outline : (4, 2) float, counter-clockwise, mm

    Returns
    -------
    ``corners (4, 2)``, ``edges (4,)`` (12, 23, 34, 41), ``diagonals (2,)`` (13, 24), ``angles_deg (4,)``

    Examples
    --------
    >>> s = pane_shape(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0], [0.0, 4.0]]))
    >>> s["edges"].tolist(), s["diagonals"].tolist(), s["angles_deg"].tolist()
    ([3.0, 4.0, 3.0, 4.0], [5.0, 5.0], [90.0, 90.0, 90.0, 90.0])
    """
    c = np.asarray(outline, dtype=float)
    if c.shape != (ORDER_CORNERS, 2):
        raise FabricationError(f"a pane of the glass order needs {ORDER_CORNERS} corners, got outline {c.shape}")
    nxt, prv = np.roll(c, -1, axis=0), np.roll(c, 1, axis=0)
    edges = np.linalg.norm(nxt - c, axis=1)
    diagonals = np.array([np.linalg.norm(c[2] - c[0]), np.linalg.norm(c[3] - c[1])])
    a, b = prv - c, nxt - c
    cross = b[:, 0] * a[:, 1] - b[:, 1] * a[:, 0]
    angles = np.degrees(np.arctan2(cross, np.einsum("ki,ki->k", a, b))) % 360.0
    return {"corners": c, "edges": edges, "diagonals": diagonals, "angles_deg": angles}


def reference_frame(outline: np.ndarray) -> np.ndarray:
    """``outline (n, 2)`` moved rigidly so that its corner 1 is the origin and its edge 12 runs along +x.

    >>> reference_frame(np.array([[1.0, 1.0], [1.0, 3.0], [0.0, 3.0]])).round(9).tolist()
    [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0]]
    """
    c = np.asarray(outline, dtype=float) - np.asarray(outline, dtype=float)[0]
    t = np.arctan2(c[1, 1], c[1, 0])
    rot = np.array([[np.cos(t), np.sin(t)], [-np.sin(t), np.cos(t)]])
    out = c @ rot.T
    out[0] = 0.0
    out[1, 1] = 0.0
    return out


def shape_columns(part: FlatPart) -> dict[str, float]:
    """The corner, edge, diagonal and angle columns of one pane (lengths to 0.01 mm, angles to 0.001°)."""
    s = pane_shape(reference_frame(part.outline))
    row: dict[str, float] = {}
    for k in range(ORDER_CORNERS):
        row[f"c{k + 1}_x_mm"], row[f"c{k + 1}_y_mm"] = (_r(v, 2) for v in s["corners"][k])
    for k in range(ORDER_CORNERS):
        row[f"edge_{k + 1}{(k + 1) % ORDER_CORNERS + 1}_mm"] = _r(s["edges"][k], 2)
    row["diag_13_mm"], row["diag_24_mm"] = (_r(v, 2) for v in s["diagonals"])
    for k in range(ORDER_CORNERS):
        row[f"angle_{k + 1}_deg"] = _r(s["angles_deg"][k], 3)
    return row


def glass_order_rows(parts: list[FlatPart], rotations: list[float], type_files: dict[str, str],
                     panels: "PanelParams") -> list[dict]:
    """One row per pane type (:func:`fabrication.parts.order_rows`) with the shape columns of its representative
    pane, its weight and perimeter, the edge work and the coated side."""
    first: dict[str, FlatPart] = {}
    for p in parts:
        first.setdefault(p.type_id or p.part_id, p)
    rows = order_rows(parts, rotations, type_files)
    for row in rows:
        rep = first[row["type_id"]]
        row.update({"weight_kg": rep.meta.get("weight_kg", ""), "perimeter_mm": rep.meta.get("perimeter_mm", ""),
                    "edge_finish": panels.edge_finish, "coated_side": panels.coated_side})
        row.update(shape_columns(rep))
        row.update(makeup_columns(panels.layers, panels.coated_side, max(float(row["width_mm"]),
                                                                         float(row["height_mm"]))))
    return rows


SIZE_TOLERANCE_MM = ((2000.0, 2.0), (3000.0, 3.0), (float("inf"), 4.0))
"""± tolerance of a pane's cut size by its longest side (mm): our order figure for heat-treated panes; the
processor confirms it against the product standard of the glass (EN 1863-1, EN 12150-1)."""


def makeup_columns(makeup: "Makeup", coated_side: str, longest_mm: float) -> dict[str, object]:
    """The make-up columns (:data:`fabrication.contract.ORDER_MAKEUP_COLUMNS`) of a pane type whose longest side is
    ``longest_mm``.

    >>> from fabrication.panels.makeup import parse_makeup
    >>> c = makeup_columns(parse_makeup("6 FT / 1.52 PVB / 6 HS"), "inside", 1800.0)
    >>> c["laminated"], c["heat_soak"], c["thickness_tolerance_mm"], c["size_tolerance_mm"], c["coated_face"]
    ('yes', 'EN 14179-1', 0.5, 2.0, '4')
    """
    faces = 2 * len(makeup.glass)
    coated = {"none": "none", "outside": "1", "inside": str(faces)}[coated_side]
    size_tol = next(tol for limit, tol in SIZE_TOLERANCE_MM if longest_mm <= limit)
    return {"makeup": makeup.text(), "glass": makeup.description(), "laminated": "yes" if makeup.laminated else "no",
            "heat_soak": "EN 14179-1" if makeup.heat_soak else "no",
            "thickness_tolerance_mm": makeup.thickness_tolerance_mm, "size_tolerance_mm": size_tol,
            "stamp_corner": 1, "stamp_face": "inside", "coated_face": coated}
