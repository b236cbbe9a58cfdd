"""Glass panels from the faces of a quad mesh: check, inset, flatten, identify, group.

One panel per face.  For every face (vectorised over all faces):

1. its least-squares plane and planarity deviation (mm); any face deviating by more than
   ``planarity_tolerance`` stops the run with :class:`~ppfab.errors.NonPlanarPanelError`
   listing every offender — before anything is written;
2. the corners projected onto that plane and flattened by an exact isometry into the
   panel's own frame (origin at the inset reference corner, ``X`` along the reference
   edge, ``Y = N × X`` with ``N`` the outside normal), so the outline is seen from the
   outside and is counter-clockwise;
3. the mitred inset by ``gap / 2`` along every edge (edge lines moved inwards and
   consecutive lines intersected); a collapsing inset is an error naming the panel;
4. identity (``P-U07-V12`` on a regular patch, else ``P-0042``), processing flags,
   measures, and the congruence type (``T001`` …).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np

from ppfab.errors import FabricationError, GeometryError, NonPlanarPanelError
from ppfab.finding import Finding
from ppfab.frame import Frame
from ppfab.mesh import QuadGrid, QuadMesh

from ..flatpart import FlatPart
from .. import contract
from . import geometry as geo
from .congruence import group_congruent
from .params import PanelParams

log = logging.getLogger("ppfab")

ROTATIONS: dict[str, tuple[float, ...] | None] = {"free": None, "grain": (0.0, 180.0), "quarter": (0.0, 90.0, 180.0, 270.0)}
"""Allowed rotations of each ``PanelParams.rotation`` (``None``: any angle)."""


@dataclass(frozen=True, eq=False)
class Panel:
    """One glass panel (all lengths mm, areas mm², weights kg).

    Attributes
    ----------
    part_id : ``P-U07-V12`` (face ``f[7, 12]`` of a regular patch) or ``P-0042`` (face 42)
    face : 0-based index of the face in the output OBJ: row-major ``i·n' + j`` for a :class:`QuadGrid`, the
        mesh's own face order for a :class:`QuadMesh` (also when it is a recovered regular patch)
    face_ij : ``(i, j)`` on a regular patch, else ``None``
    mesh_face : index of the face in the mesh that was passed in
    outline : (k, 2) inset outline in the panel frame, counter-clockwise seen from outside,
        starting at the reference corner (corner 0, ``v[i, j]`` on a grid).  With
        ``rotation = "free"`` it lies in its minimum-area rectangle (long side along +x, the
        rectangle's lower-left corner at the origin); otherwise the reference corner is at the
        origin and the reference edge runs along +x (face edge ``c0 → c1``, or ``c0 → c3`` when the
        face's normal points inside)
    corner_index : (k,) face corner (0..3 in the face's corner order) of each outline vertex
    corners_3d : (k, 3) the mesh face's corners (mm), in face order
    frame : :class:`Frame` mapping the flat outline back to 3D
    deviation_mm : largest distance of a face corner from the face's least-squares plane
    rotation : how the panel may turn on the stock sheet (:attr:`PanelParams.rotation`)
    """

    part_id: str
    face: int
    face_ij: tuple[int, int] | None
    mesh_face: int
    outline: np.ndarray
    corner_index: np.ndarray
    corners_3d: np.ndarray
    frame: Frame
    deviation_mm: float
    area_mm2: float
    perimeter_mm: float
    weight_kg: float
    corner_angles_deg: tuple[float, ...]
    bbox: tuple[float, float]
    min_rect: tuple[float, float, float]
    flags: tuple[str, ...]
    makeup: str
    thickness_mm: float
    mirror_allowed: bool
    type_id: str = ""
    marks: tuple = ()
    meta: dict = field(default_factory=dict)
    rotation: str = "free"

    def outline_3d(self) -> np.ndarray:
        """The inset outline in 3D, ``(k, 3)`` mm, on the face's least-squares plane."""
        return self.frame.to3d(self.outline)

    def flat_part(self, shape: "Panel | None" = None) -> FlatPart:
        """This panel as a :class:`~fabrication.flatpart.FlatPart` (``kind="panel"``) for nesting and DXF.

        ``shape``: the panel whose outline and marks are cut — the first panel of this panel's type, so every
        panel of a type is cut, listed and ordered as the same piece of glass (:func:`type_flat_parts`).
        """
        meta = {
            "face": self.face,
            "material": self.makeup,
            "thickness_mm": self.thickness_mm,
            "width_mm": round(self.min_rect[0], 3),
            "height_mm": round(self.min_rect[1], 3),
            "perimeter_mm": round(self.perimeter_mm, 3),
            "weight_kg": round(self.weight_kg, 3),
            "planarity_dev_mm": round(self.deviation_mm, 4),
            "min_angle_deg": round(min(self.corner_angles_deg), 3),
            "panel_flags": ";".join(self.flags),
            "outside": "up",
        }
        if self.face_ij is not None:
            meta["face_i"], meta["face_j"] = self.face_ij
        meta.update(self.meta)
        cut = shape or self
        if cut is not self and self.area_mm2 > 0:        # the glass as cut (its type's outline) is what weighs
            meta["weight_kg"] = round(self.weight_kg * cut.area_mm2 / self.area_mm2, 3)
        rotations = ROTATIONS[self.rotation]
        meta["rotation"] = self.rotation
        return FlatPart(part_id=self.part_id, kind="panel", outline=cut.outline, marks=cut.marks,
                        label=self.part_id, type_id=self.type_id, rotations=rotations,
                        mirror_allowed=self.mirror_allowed, meta=meta, free_rotation=rotations is None)


def _outside_signs(corners: np.ndarray, planes: np.ndarray, mode: str) -> np.ndarray:
    """``+1`` where the face normal points outside, ``−1`` where it points inside (one choice per mesh)."""
    F = len(corners)
    if mode == "normal":
        return np.ones(F)
    if mode == "reverse":
        return -np.ones(F)
    centre = corners.reshape(-1, 3).mean(axis=0)
    fc = corners.mean(axis=1)
    n = planes[:, :3]
    away = float(np.einsum("fi,fi->", n, fc - centre))
    spread = float(np.linalg.norm(fc - centre, axis=1).sum())
    if abs(away) < 1e-6 * max(spread, 1e-12):      # no clear inside (flat sheet): outside is up (+z)
        away = float(n[:, 2].sum())
    return np.full(F, 1.0 if away >= 0 else -1.0)


def outside_sign(mesh: QuadMesh | QuadGrid, mode: str = "auto") -> float:
    """``+1`` when the glass's outside is the side the mesh's face normals point to, ``−1`` when it is the other
    side — the one choice :func:`make_panels` makes for ``[panels] outside = mode``.  The support structure takes
    it too, so that the beams hang on the other side of the glass (a mesh whose faces point inwards would
    otherwise get its glazing strips inside its plates)."""
    corners = _face_layout(mesh)[0]
    if len(corners) == 0:
        return 1.0
    planes, _ = geo.oriented_planes(corners)
    return float(_outside_signs(corners, planes, mode)[0])


def _face_layout(mesh: QuadMesh | QuadGrid) -> tuple[np.ndarray, np.ndarray | None, np.ndarray, list[str]]:
    """Corners ``(F, 4, 3)``, grid indices ``(F, 2)`` or None, input-mesh face index ``(F,)``, part ids."""
    grid: QuadGrid | None
    qm: QuadMesh | None
    if isinstance(mesh, QuadGrid):
        grid, qm = mesh, None
    elif isinstance(mesh, QuadMesh):
        grid, qm = mesh.grid, mesh
    else:
        raise GeometryError(f"panels need a QuadMesh or QuadGrid, got {type(mesh).__name__}")
    if grid is None:
        assert qm is not None, "a QuadGrid input always has its grid"
        corners = np.asarray(qm.face_corners, dtype=float)
        F = len(corners)
        width = contract.digits(F, 4)
        return corners, None, np.arange(F), [contract.panel_id(f, width) for f in range(F)]
    fm, fn = grid.face_shape
    corners = np.asarray(grid.face_corners, dtype=float).reshape(-1, 4, 3)
    ij = np.stack(np.meshgrid(np.arange(fm), np.arange(fn), indexing="ij"), axis=-1).reshape(-1, 2)
    wi, wj = contract.digits(fm), contract.digits(fn)
    ids = [contract.panel_id_grid(int(i), int(j), wi, wj) for i, j in ij]
    mesh_face = np.arange(len(ij))
    if qm is not None and qm.grid_ids is not None:
        from ppfab.topology import grid_face_indices

        gf = np.sort(grid_face_indices(np.asarray(qm.grid_ids), grid.closed).reshape(-1, 4), axis=1)
        mf = np.sort(np.asarray(qm.faces), axis=1)
        lookup = {tuple(r): k for k, r in enumerate(mf.tolist())}
        mesh_face = np.array([lookup.get(tuple(r), -1) for r in gf.tolist()])
    return corners, ij, mesh_face, ids


def _mark_polylines(outline: np.ndarray, size: float) -> tuple:
    """An L at the reference corner (long leg along the reference edge), inside the outline.

    The L sits ``size / 4`` inside the corner; on a panel too small for that, ``size`` is reduced to the
    largest that fits (halving, then bisection), so every panel keeps its mark (:func:`mark_size_used`).
    """
    if size <= 0:
        return ()
    e = geo.edge_vectors(outline[None])[0]
    lengths = np.linalg.norm(e, axis=1)
    size = mark_size_used(outline, size)
    inner, shrink = geo.inset_polygons(outline[None], 0.25 * size)
    a = inner[0, 0]
    along = e[0] / lengths[0]
    back = -e[-1] / lengths[-1]
    long_leg = min(size, 0.3 * lengths[0])
    short_leg = min(0.5 * size, 0.3 * lengths[-1])
    return (np.array([a + long_leg * along, a, a + short_leg * back]),)


def mark_size_used(outline: np.ndarray, size: float) -> float:
    """``size``, or the largest mark size below it whose inset (``size / 4``) still leaves ``outline`` a polygon."""
    def fits(s: float) -> bool:
        return bool(geo.inset_polygons(outline[None], 0.25 * s)[1][0] > 0.5)

    if fits(size):
        return size
    lo, hi = 0.0, size
    while hi > 1e-6 and not fits(hi):
        lo, hi = hi / 2, hi / 2
    if hi <= 1e-6:
        return 0.0
    lo, hi = hi, 2 * hi                  # fits(lo), not fits(hi)
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    return lo


def make_panels(mesh: QuadMesh | QuadGrid, params: PanelParams | None = None, *, scale: float = 1.0) -> list[Panel]:
    """One glass panel per face of ``mesh`` (see the module docstring for the steps).

    Parameters
    ----------
    mesh : the (planar-quad) mesh; on a regular patch faces are numbered row-major ``f[i, j]``
    params : :class:`PanelParams` (defaults when ``None``)
    scale : mesh units → mm (the design file's ``geometry.scale``)

    Raises
    ------
    NonPlanarPanelError : faces deviate from their plane by more than ``planarity_tolerance`` mm
        (all offenders listed with their deviation)
    FabricationError : an inset by ``gap/2`` collapses (names the panel and its shortest edge)
    GeometryError : a degenerate face (zero-length reference edge, collinear corners)
    """
    p = params or PanelParams()
    if not (math.isfinite(scale) and scale > 0):
        raise GeometryError(f"scale must be a positive number, got {scale}", element="scale", value=scale)
    corners, ij, mesh_face, ids = _face_layout(mesh)
    corners = corners * scale
    if len(corners) == 0:
        return []
    planes, deviation = geo.oriented_planes(corners)
    bad = np.flatnonzero(~(deviation <= p.planarity_tolerance))
    if len(bad):
        raise NonPlanarPanelError([Finding("planarity", "", ids[f], float(deviation[f]), p.planarity_tolerance,
                                           f"{ids[f]} deviates {deviation[f]:.3g} mm from its plane")
                                   for f in bad], p.planarity_tolerance)
    edges = np.linalg.norm(corners - np.roll(corners, -1, axis=1), axis=2)
    if np.any(edges <= 1e-9):
        f = int(np.argmin(edges.min(axis=1)))
        raise GeometryError(f"panel {ids[f]}: face has a zero-length edge", element=ids[f], value=0.0)
    outside = _outside_signs(corners, planes, p.outside)
    # seen from N, the face's corner order is CCW when N = n, CW when N = −n: relabel to CCW from corner 0
    corner_index = np.where((outside > 0)[:, None], np.array([0, 1, 2, 3]), np.array([0, 3, 2, 1]))
    ordered = np.take_along_axis(corners, corner_index[:, :, None], axis=1)
    origin, X, Y, N, flat = geo.flat_frames(ordered, planes, outside)
    area0 = geo.polygon_area(flat)
    if np.any(area0 <= 0):
        f = int(np.argmin(area0))
        raise GeometryError(f"panel {ids[f]}: face is degenerate or folded (flat area {area0[f]:.3g} mm²)",
                            element=ids[f], value=float(area0[f]))
    inset, shrink = geo.inset_polygons(flat, 0.5 * p.gap)
    area = geo.polygon_area(inset)
    collapsed = np.flatnonzero(~((shrink > 0) & (area > 0)))
    if len(collapsed):
        f = int(collapsed[0])
        shortest = float(np.linalg.norm(geo.edge_vectors(flat[f:f + 1])[0], axis=1).min())
        names = ", ".join(ids[k] for k in collapsed[:8]) + (" …" if len(collapsed) > 8 else "")
        raise FabricationError(f"inset by gap/2 = {0.5 * p.gap:g} mm collapses {len(collapsed)} panel(s): {names} "
                               f"({ids[f]}: shortest edge {shortest:.3g} mm)")
    # final frame: origin at the inset reference corner, X unchanged ...
    ref = inset[:, 0, :]
    origin = origin + ref[:, :1] * X + ref[:, 1:2] * Y
    outline = inset - ref[:, None, :]
    if p.rotation == "free":          # ... or, for glass free to turn, the minimum-area rectangle frame
        origin, X, Y, outline = geo.min_area_frames(origin, X, Y, outline)
    perim = geo.perimeter(outline)
    angles = np.degrees(geo.corner_angles(outline))
    rects = geo.min_area_rectangles(outline)
    bbox = outline.max(axis=1) - outline.min(axis=1)
    weight = area * 1e-6 * p.mass_per_m2
    long_max, short_max = max(p.max_size), min(p.max_size)
    long_min, short_min = max(p.min_size), min(p.min_size)
    used = np.array([mark_size_used(o, p.mark_size) if p.mark_size > 0 else 0.0 for o in outline])
    if np.any(used < p.mark_size):
        small = np.flatnonzero(used < p.mark_size)
        k = int(small[np.argmin(used[small])])
        log.warning("panels.mark_size %g mm does not fit %d panel(s): their reference marks are drawn smaller, "
                    "down to %.3g mm on %s (the cutter still finds the corner; lower panels.mark_size to draw them all "
                    "alike)", p.mark_size, len(small), used[k], ids[k])
    types = group_congruent(list(outline), p.type_tol, p.mirror_allowed)
    wt = max(3, len(str(int(types.max()) + 1)))
    panels: list[Panel] = []
    for f in range(len(corners)):
        flags = []
        if rects[f, 0] > long_max + 1e-9 or rects[f, 1] > short_max + 1e-9:
            flags.append("too_large")
        if rects[f, 0] < long_min - 1e-9 or rects[f, 1] < short_min - 1e-9:
            flags.append("too_small")
        if angles[f].min() < p.min_corner_angle_deg:
            flags.append("acute_corner")
        o = outline[f]
        panels.append(Panel(
            part_id=ids[f],
            face=int(mesh_face[f]) if isinstance(mesh, QuadMesh) else f,     # the face of the OBJ written
            face_ij=None if ij is None else (int(ij[f, 0]), int(ij[f, 1])),
            mesh_face=int(mesh_face[f]),
            outline=o,
            corner_index=corner_index[f],
            corners_3d=corners[f],
            frame=Frame(origin[f], X[f], Y[f]),
            deviation_mm=float(deviation[f]),
            area_mm2=float(area[f]),
            perimeter_mm=float(perim[f]),
            weight_kg=float(weight[f]),
            corner_angles_deg=tuple(float(a) for a in angles[f]),
            bbox=(float(bbox[f, 0]), float(bbox[f, 1])),
            min_rect=(float(rects[f, 0]), float(rects[f, 1]), float(rects[f, 2])),
            flags=tuple(flags),
            makeup=p.layers.text(),
            thickness_mm=p.pane_thickness,
            mirror_allowed=p.mirror_allowed,
            type_id=f"T{int(types[f]) + 1:0{wt}d}",
            marks=_mark_polylines(o, float(used[f])),
            rotation=p.rotation,
        ))
    return panels


def type_flat_parts(panels: list[Panel]) -> list[FlatPart]:
    """The flat parts of the panels, each cut to the outline of the first panel of its type.

    Panels of one type are congruent within ``congruence_tolerance``; the glass order lists one outline per
    type (``glass/types/``), so the cutting sheets cut that outline too and ``x, y, rotation_deg, mirrored``
    of ``parts.csv`` map the type's outline exactly onto each CUT polyline.
    """
    first: dict[str, Panel] = {}
    for pnl in panels:
        first.setdefault(pnl.type_id, pnl)
    return [pnl.flat_part(first[pnl.type_id] if pnl.type_id else None) for pnl in panels]


def panel_types(panels: list[Panel]) -> dict[str, list[str]]:
    """``type_id → part ids`` in order of first appearance (the number of types is ``len(...)``)."""
    out: dict[str, list[str]] = {}
    for pnl in panels:
        out.setdefault(pnl.type_id, []).append(pnl.part_id)
    return out
