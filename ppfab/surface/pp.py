"""The ``pp`` net: two families of planar sections, both planar before any optimisation.

In the plan frame (:mod:`.plan`) the rows are the sections by the planes ``x = x_i`` and the columns the
sections by the vertical planes ``a·x + b·y = c_j`` (default ``(a, b) = (0, 1)``: the two plan axes); a
vertex is where a row plane, a column plane and the surface meet: ``(x_i, (c_j − a·x_i)/b, f)``.  Both
families lie in their planes exactly.  The planes are spaced by ``spacing`` along the arc length of the
middle row and the middle column.

A PP mesh's panels are planar only if the two families are conjugate; two arbitrary section families are
not, and an optimisation that makes the quads planar then moves the net away from the surface.  The twist
of each quad in the second fundamental form (:func:`.curvature.quad_twist`) is measured and the net refused
when it is too far from conjugate, with advice.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..errors import GeometryError
from .curvature import quad_twist
from .families import region_box
from .heightfield import HeightField
from .plan import PlanFrame
from .sections import SUBSTEPS_PER_SPACING, SectionsNet, _arc_positions, trim_grid

MIN_ANGLE_DEG = 30.0
"""The two plane families must cross at this angle or more in plan."""

MAX_TWIST = 0.35
"""Largest median twist (``|II(a, b)| / (|a||b| max|κ|)``) of the kept quads a PP optimisation is asked
to close; beyond it the planar quads it reaches lie far from the surface."""


def quad_warp(corners: np.ndarray) -> np.ndarray:
    """Per quad ``(F, 4, 3)``: ``|n · (c0 − c1 + c2 − c3)|``, mm — the normal part of its mixed difference
    (``n`` across the diagonals), ≈ ``|II(a, b)|``: what making it planar must move its corners by, in sum."""
    c = np.asarray(corners, dtype=float)
    n = np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1])
    n = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    out: np.ndarray = np.abs(np.einsum("ij,ij->i", n, c[:, 0] - c[:, 1] + c[:, 2] - c[:, 3]))
    return out


def column_direction(frame: PlanFrame, second_normal: Sequence[float] | None) -> np.ndarray:
    """``(a, b)``: the unit plan normal of the column planes in the frame (default ``(0, 1)``).

    Raises
    ------
    GeometryError : the normal is not horizontal in the frame, or crosses the rows at less than
        :data:`MIN_ANGLE_DEG`
    """
    if second_normal is None:
        return np.array([0.0, 1.0])
    n = frame.axes @ np.asarray(second_normal, dtype=float)
    if not np.all(np.isfinite(n)) or np.linalg.norm(n) == 0:
        raise GeometryError("[surface] second_normal must be three finite numbers, not all zero")
    n = n / np.linalg.norm(n)
    if abs(n[2]) > 1e-6:
        raise GeometryError(f"[surface] second_normal is {np.degrees(np.arcsin(abs(n[2]))):.1f}° out of the "
                            "plan: give a horizontal normal (the column planes are vertical)")
    ab = n[:2] / np.linalg.norm(n[:2])
    if abs(ab[1]) < np.sin(np.radians(MIN_ANGLE_DEG)):
        raise GeometryError(f"[surface] second_normal crosses the section planes at "
                            f"{np.degrees(np.arcsin(abs(ab[1]))):.0f}° in plan; give one at {MIN_ANGLE_DEG:g}° "
                            "or more from plane_normal")
    return ab if ab[1] > 0 else -ab


def suggested_normals(hf: HeightField, frame: PlanFrame, x: float, y: float) -> tuple[np.ndarray, np.ndarray]:
    """World normals of two vertical plane families whose sections run along the principal directions at the
    plan point ``(x, y)`` (frame coordinates): each plane's normal is across the other family's direction."""
    from .curvature import forms, principal

    _, _, d1, d2 = principal(*forms(hf, np.array([x]), np.array([y])))
    out = []
    for d in (d2[0], d1[0]):            # planes along d2 have the normal across it, and vice versa
        n = np.array([-d[1], d[0], 0.0]) @ frame.axes
        n = n / np.linalg.norm(n)
        k = int(np.argmax(np.abs(n)))
        out.append(np.round(n if n[k] > 0 else -n, 3) + 0.0)       # + 0.0: no "-0.000" in the advice
    return out[0], out[1]


def pp_net(hf: HeightField, frame: PlanFrame, loops: Sequence[np.ndarray], spacing: float,
           min_face: float = 0.25, second_normal: Sequence[float] | None = None,
           max_warp: float = float("inf")) -> tuple[SectionsNet, np.ndarray, np.ndarray]:
    """Build the pp net, trimmed to the plan region, and the twist of each kept quad.

    Returns
    -------
    net : rows in the planes ``planes``, columns in ``planes_cols`` (``planar_family = "both"``)
    twist : (F,) float — per kept face (row-major), 0 for conjugate directions
    warp : (F,) float — per kept face, :func:`quad_warp` in mm

    Raises
    ------
    GeometryError : the two families are far from conjugate (median twist above :data:`MAX_TWIST`, or a
        quad warped more than ``max_warp`` mm), with the place of the worst quad
    """
    ab = column_direction(frame, second_normal)
    a, b = float(ab[0]), float(ab[1])
    loops = [np.asarray(lp, dtype=float)[:, :2] for lp in loops]
    x_lo, x_hi, y_lo, y_hi = region_box(hf, loops)
    xc, yc = 0.5 * (x_lo + x_hi), 0.5 * (y_lo + y_hi)
    cc = a * xc + b * yc
    h = spacing / SUBSTEPS_PER_SPACING
    corners_c = [a * x + b * y for x in (hf.x[0], hf.x[-1]) for y in (hf.y[0], hf.y[-1])]
    # the column planes: along the middle row (x = xc)
    cs = np.linspace(min(corners_c), max(corners_c), max(50, int((max(corners_c) - min(corners_c)) / h) + 1))
    ys = (cs - a * xc) / b
    keep = (ys >= hf.y[0]) & (ys <= hf.y[-1])
    cs = cs[keep]
    c_planes = _arc_positions(cs, _row_points(a, b, xc, cs, hf), cc, spacing)
    # the row planes: along the middle column (c = cc)
    xs = np.linspace(hf.x[0], hf.x[-1], max(50, int((hf.x[-1] - hf.x[0]) / h) + 1))
    yx = (cc - a * xs) / b
    keep = (yx >= hf.y[0]) & (yx <= hf.y[-1])
    xs, yx = xs[keep], yx[keep]
    col = np.stack([xs, yx, hf.f(xs, yx)], axis=1)
    x_planes = _arc_positions(xs, col, xc, spacing)
    if len(x_planes) < 2 or len(c_planes) < 2:
        raise GeometryError(f"the surface is smaller than two panels of spacing {spacing:g} mm in one "
                            "direction; give a smaller [surface] spacing", value=spacing)
    X = np.broadcast_to(x_planes[:, None], (len(x_planes), len(c_planes)))
    Y = (c_planes[None, :] - a * X) / b
    valid = hf.inside_box(X, Y)
    local = np.stack([X, Y, hf.f(X, Y)], axis=-1)
    world = frame.to_world(local)
    planes = np.stack([frame.section_plane(float(x)) for x in x_planes])
    n2 = np.array([a, b, 0.0]) @ frame.axes
    planes_cols = np.stack([np.concatenate([n2, [-(float(n2 @ frame.origin) + float(c))]]) for c in c_planes])
    net = trim_grid(world, local, valid, planes, loops, spacing, min_face, planes_cols, "both", "pp")
    kept = np.argwhere(net.grid_faces)
    i, j = kept[:, 0], kept[:, 1]
    corners = np.stack([local[i, j], local[i + 1, j], local[i + 1, j + 1], local[i, j + 1]], axis=1)
    twist = quad_twist(hf, corners)
    warp = quad_warp(frame.to_world(corners))
    n1, n2 = suggested_normals(hf, frame, xc, yc)
    advice = (f"turn the planes towards the principal directions (at the middle: [surface] plane_normal = "
              f"[{n1[0]:.3f}, {n1[1]:.3f}, {n1[2]:.3f}], second_normal = [{n2[0]:.3f}, {n2[1]:.3f}, {n2[2]:.3f}]), "
              "or use net = 'sections'")
    if len(twist) and float(np.median(twist)) > MAX_TWIST:
        k = int(np.argmax(twist))
        w = frame.to_world(corners[k].mean(axis=0))
        raise GeometryError(
            f"pp net: the two plane families are far from conjugate on this surface (median twist "
            f"{np.median(twist):.2f} > {MAX_TWIST:g}, worst {twist[k]:.2f} at (x, y) = ({w[0]:.0f}, {w[1]:.0f}) mm): "
            f"planar panels would leave the surface; {advice}", value=float(np.median(twist)))
    if len(warp) and float(warp.max()) > max_warp:
        k = int(np.argmax(warp))
        w = frame.to_world(corners[k].mean(axis=0))
        raise GeometryError(
            f"pp net: a quad at (x, y) = ({w[0]:.0f}, {w[1]:.0f}) mm is warped {warp[k]:.0f} mm > [surface] "
            f"max_warp {max_warp:g} mm (median twist {np.median(twist):.2f}): planar panels would leave the "
            f"surface by about that much; {advice}, or give a smaller spacing", value=float(warp[k]))
    return net, twist, warp


def _row_points(a: float, b: float, x: float, cs: np.ndarray, hf: HeightField) -> np.ndarray:
    """The middle row ``x = const`` sampled at the column parameters ``cs``: ``(k, 3)`` plan-frame points."""
    y = (cs - a * x) / b
    return np.stack([np.full_like(y, x), y, hf.f(np.full_like(y, x), y)], axis=1)
