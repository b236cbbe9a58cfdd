"""Live fabrication figures from the placed grid alone (no support solve, no CAD, no nesting): what the studio
shows beside the view after every edit.

All lengths in mm (the placed mesh), angles in degrees.  For a grid ``v (m+1, n+1, 3)`` with faces
``f[i, j] = (v[i,j], v[i+1,j], v[i+1,j+1], v[i,j+1])``:

* panel area ``A = ½ |d₁ × d₂|`` (the diagonals ``d₁ = c₂ − c₀``, ``d₂ = c₃ − c₁``; exact for a planar quad);
  the glass area is that of the panes as cut, as the build counts it: each face inset by half the panel gap
  (:func:`pane_areas`), not the faces;
* the smallest rectangle around a panel has a side along one of its edges (rotating calipers), so the
  sheet it needs is the least-area of the four edge-aligned boxes in the panel's plane;
* glass sheets: at least :func:`sheets_lower_bound` — the panes (faces inset by half the panel gap) grown by
  half the nesting spacing, over the trimmed sheet grown alike: the bound a nesting reports
  (:func:`fabrication.nesting.lower_bound`), from the faces alone;
* beams: the polylines of the planar families, their length ``Σ |v_{k+1} − v_k|`` and pieces
  ``Σ ⌈L / max_length⌉``;
* torsion: the largest distance of a node axis's end ``v + depth · a`` from the plane of a beam through
  ``v`` (the least-squares plane of the polyline): 0 for a torsion-free support structure (§2.1); the studio
  replaces it by the torsion of the support structure the build makes (``[support]``, the offset of an axis at
  beam depth, as ``nodes.csv`` ``torsion_mm``) and says which (:attr:`Figures.torsion_of`);
* node angle: at every interior node the angle between the row and the column through it (central
  differences of the two polylines);
* panel types: panels whose sorted edge lengths and diagonals agree to 1 mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ppfab import planes as pl
from ppfab.metrics import corner_angles, nonconvex_faces


@dataclass(frozen=True)
class Figures:
    panels: int
    panel_types: int
    largest_panel_mm: tuple[float, float]
    sheet_mm: tuple[float, float]
    panels_over_sheet: int
    min_corner_deg: float
    glass_area_m2: float
    glass_sheets_min: int
    beams: int
    beam_length_m: float
    beam_pieces: int
    torsion_mm: float
    node_angle_deg: tuple[float, float]
    gap_mm: float = 0.0
    torsion_of: str = "the construction's node axes"

    def markdown(self) -> str:
        w, h = self.largest_panel_mm
        fit = "fits" if self.panels_over_sheet == 0 else f"**{self.panels_over_sheet} panels larger than the sheet**"
        return "\n".join([
            f"- panels: **{self.panels}** in {self.panel_types} types",
            f"- largest panel: {w:.0f} × {h:.0f} mm on {self.sheet_mm[0]:.0f} × {self.sheet_mm[1]:.0f} ({fit})",
            f"- min corner angle: {self.min_corner_deg:.1f}°",
            f"- glass as cut: {self.glass_area_m2:.1f} m² (faces inset by half the {self.gap_mm:g} mm gap), "
            f"at least {self.glass_sheets_min} sheets",
            f"- beams: {self.beams} ({self.beam_pieces} pieces), {self.beam_length_m:.1f} m",
            f"- torsion: {self.torsion_mm:.2e} mm ({self.torsion_of})",
            f"- node angles: {self.node_angle_deg[0]:.1f}° – {self.node_angle_deg[1]:.1f}°",
        ])


def face_corners(v: np.ndarray, closed: bool = False) -> np.ndarray:
    """``(m, n', 4, 3)`` corners of every face of a grid ``(m+1, n+1, 3)`` (closed rows wrap around)."""
    w = np.concatenate([v, v[:, :1]], axis=1) if closed else v
    return np.stack([w[:-1, :-1], w[1:, :-1], w[1:, 1:], w[:-1, 1:]], axis=-2)


def panel_boxes(corners: np.ndarray) -> np.ndarray:
    """``(..., 2)`` long and short side of the least-area rectangle around each planar quad ``(..., 4, 3)``."""
    c = np.asarray(corners, dtype=float)
    shape = c.shape[:-2]
    c = c.reshape(-1, 4, 3)
    normal = np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1])
    normal /= np.maximum(np.linalg.norm(normal, axis=-1, keepdims=True), 1e-300)
    e = np.roll(c, -1, axis=1) - c                                   # (F, 4 edges, 3)
    e /= np.maximum(np.linalg.norm(e, axis=-1, keepdims=True), 1e-300)
    f = np.cross(normal[:, None, :], e)
    x = np.matmul(e, np.swapaxes(c, 1, 2))                           # (F, edge, corner)
    y = np.matmul(f, np.swapaxes(c, 1, 2))
    a, b = x.max(2) - x.min(2), y.max(2) - y.min(2)                  # (F, 4)
    k = np.argmin(a * b, axis=1)
    a, b = np.take_along_axis(a, k[:, None], 1)[:, 0], np.take_along_axis(b, k[:, None], 1)[:, 0]
    return np.stack([np.maximum(a, b), np.minimum(a, b)], -1).reshape(shape + (2,))


def panel_types(corners: np.ndarray, tolerance: float = 1.0) -> np.ndarray:
    """``(...)`` type index of each quad: equal sorted edge lengths and diagonals to ``tolerance``."""
    c = np.asarray(corners, dtype=float).reshape(-1, 4, 3)
    edges = np.linalg.norm(np.roll(c, -1, axis=1) - c, axis=-1)
    diags = np.stack([np.linalg.norm(c[:, 2] - c[:, 0], axis=-1), np.linalg.norm(c[:, 3] - c[:, 1], axis=-1)], -1)
    key = np.ascontiguousarray(np.round(np.concatenate([np.sort(edges, 1), np.sort(diags, 1)], 1) / tolerance)
                               .astype(np.int64))
    _, inverse = np.unique(key.view(np.dtype((np.void, key.itemsize * key.shape[1]))).ravel(), return_inverse=True)
    return inverse.reshape(np.asarray(corners).shape[:-2])


def _polylines(v: np.ndarray, family: str, closed: bool) -> np.ndarray:
    """``(L, k, 3)`` polylines of a family; closed rows repeat their first vertex at the end."""
    if family == "rows":
        return np.concatenate([v, v[:, :1]], axis=1) if closed else v
    return np.swapaxes(v, 0, 1)


def _inset(corners: np.ndarray, gap: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(c (F, 4, 3), A' (F,), P' (F,))``: the quads and the area and perimeter of their panes, each face with
    every edge moved inward by ``d = gap/2`` — for a convex quad of perimeter ``P``, area ``A`` and interior angles
    ``θ_i`` the inner parallel polygon, ``A' = A − dP + d² Σ cot(θ_i/2)``, ``P' = P − 2d Σ cot(θ_i/2)``."""
    c = np.asarray(corners, dtype=float).reshape(-1, 4, 3)
    if len(c) == 0:
        return c, np.zeros(0), np.zeros(0)
    area = 0.5 * np.linalg.norm(np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1]), axis=-1)
    per = np.linalg.norm(np.roll(c, -1, axis=1) - c, axis=-1).sum(axis=1)
    cot = (1.0 / np.tan(0.5 * np.radians(corner_angles(c)))).sum(axis=1)
    d = 0.5 * gap
    return c, area - d * per + d * d * cot, per - 2.0 * d * cot


def pane_areas(corners: np.ndarray, gap: float) -> np.ndarray:
    """``(F,)`` area of each pane of the planar quads ``corners (F, 4, 3)``: the face inset by half the ``gap``
    (:func:`_inset`; 0 where the inset closes the face)."""
    return np.maximum(_inset(corners, gap)[1], 0.0)


def grown_pane_areas(corners: np.ndarray, spacing: float, gap: float) -> np.ndarray:
    """``(F,)`` area of each pane of the planar quads ``corners (F, 4, 3)`` grown by half the ``spacing``.

    A pane is its face inset by half the ``gap`` (area ``A'``, perimeter ``P'``: :func:`_inset`); grown by
    ``r = spacing/2`` (Steiner) it covers ``A' + rP' + πr²``.  A non-convex face (or one the inset would close)
    gives 0, which keeps a sum of these a lower bound.
    """
    c, pane_area, pane_per = _inset(corners, gap)
    if len(c) == 0:
        return np.zeros(0)
    r = 0.5 * spacing
    grown = pane_area + r * pane_per + math.pi * r * r
    keep = ~nonconvex_faces(c) & (pane_per > 0) & (pane_area > 0)
    return np.where(keep, grown, 0.0)


def sheets_lower_bound(corners: np.ndarray, usable: tuple[float, float], spacing: float, gap: float) -> int:
    """No nesting of the panes of the planar quads ``corners (..., 4, 3)`` on sheets of usable size ``usable``
    (after the trim) with ``spacing`` between parts uses fewer sheets: the grown panes
    (:func:`grown_pane_areas`) of a sheet fit disjointly in ``(W + spacing)(H + spacing)``."""
    total = float(grown_pane_areas(corners, spacing, gap).sum())
    return int(math.ceil(total / ((usable[0] + spacing) * (usable[1] + spacing)) - 1e-9)) if total > 0 else 0


def figures(v: np.ndarray, axes: np.ndarray | None, families: tuple[str, ...], closed: bool,
            sheet: tuple[float, float], usable: tuple[float, float], depth: float, max_length: float,
            spacing: float = 10.0, gap: float = 10.0) -> Figures:
    """The figures of a placed grid ``v (m+1, n+1, 3)`` (mm) with unit node axes ``(m+1, n+1, 3)`` (or ``None``);
    ``sheet`` is the stock sheet, ``usable`` its size after the trim, ``spacing`` the nesting's distance between
    parts and ``gap`` the joint between panels (mm)."""
    corners = face_corners(v, closed)
    area = 0.5 * np.linalg.norm(np.cross(corners[..., 2, :] - corners[..., 0, :],
                                         corners[..., 3, :] - corners[..., 1, :]), axis=-1)
    boxes = panel_boxes(corners).reshape(-1, 2)
    W, H = max(usable), min(usable)
    over = int(np.sum((boxes[:, 0] > W) | (boxes[:, 1] > H)))
    largest = boxes[int(np.argmax(boxes[:, 0] * boxes[:, 1]))]
    beams = pieces = 0
    length = torsion = 0.0
    for fam in families:
        lines = _polylines(v, fam, closed)
        seg = np.linalg.norm(np.diff(lines, axis=1), axis=-1).sum(axis=1)
        beams += len(lines)
        length += float(seg.sum())
        pieces += int(np.ceil(seg / max_length).sum()) if max_length > 0 else len(lines)
        if axes is not None and lines.shape[1] >= 3:
            ax = _polylines(axes, fam, closed)
            planes, _ = pl.fit_plane(lines)
            ends = lines + depth * ax
            torsion = max(torsion, float(np.abs(pl.signed_distance(planes[:, None, :], ends)).max()))
    w = np.concatenate([v[:, -1:], v, v[:, :1]], axis=1) if closed else v
    if min(w.shape[:2]) >= 3:
        tr = w[2:, 1:-1] - w[:-2, 1:-1]
        tc = w[1:-1, 2:] - w[1:-1, :-2]
        ang = np.degrees(pl.line_angle(tr, tc))
        node = (float(ang.min()), float(ang.max()))
    else:
        node = (math.nan, math.nan)
    sheets_min = sheets_lower_bound(corners, (max(W, 1e-9), max(H, 1e-9)), spacing, gap)
    return Figures(
        panels=int(area.size), panel_types=int(panel_types(corners).max()) + 1,
        largest_panel_mm=(float(largest[0]), float(largest[1])), sheet_mm=(float(max(sheet)), float(min(sheet))),
        panels_over_sheet=over, min_corner_deg=float(corner_angles(corners).min()),
        glass_area_m2=float(pane_areas(corners, gap).sum()) / 1e6, glass_sheets_min=sheets_min,
        beams=beams, beam_length_m=length / 1000.0, beam_pieces=pieces, torsion_mm=torsion, node_angle_deg=node,
        gap_mm=float(gap))
