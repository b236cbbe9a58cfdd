"""The families of section planes of the ``sections`` net: parallel planes, or a pencil through a vertical axis.

The net is built in coordinates ``(s, t)`` of the plan (the plan frame of :mod:`.plan`) in which the section
planes are ``s = const`` and ``t`` runs along a section:

* :class:`ParallelPlanes` — ``(s, t) = (x, y)``: the planes ``x = const`` of the frame;
* :class:`PencilPlanes` — ``(s, t) = (θ, r)``, polar about the plan point ``c`` of a vertical axis:
  ``(x, y) = c + r (cos θ, sin θ)``; the planes ``θ = const`` contain the axis.

On the height field ``z = f(x, y)`` with plan Hessian ``H`` (``II`` is ``H / sqrt(1 + |∇f|²)``, so the same
directions are conjugate), a section has the plan tangent ``e`` (``∂y``, or ``e_r = (cos θ, sin θ)``) and a
curve of the other family the plan tangent ``w``; they are conjugate when ``eᵀ H w = 0``.  With the curve
written ``t(s)``:

* parallel: ``w = (1, t')``, ``H_xy + H_yy t' = 0``, so ``dy/dx = −H_xy / H_yy``;
* pencil: ``w = t' e_r + r e_θ`` (``e_θ = (−sin θ, cos θ)``), ``t' H_rr + r H_rθ = 0``, so
  ``dr/dθ = −r H_rθ / H_rr`` with ``H_rr = e_rᵀ H e_r``, ``H_rθ = e_rᵀ H e_θ``.

Both are regularised where the section's own second derivative vanishes (``H_yy``, ``H_rr``: a parabolic line
along the sections, where the conjugate direction turns into the section) and clipped so that the curve stays
within :data:`~ppfab.surface.sections.MAX_ANGLE_DEG` of the planes' normal.  Every vertex of row ``i`` has
``s = s_i``, so it lies in the plane ``s_i`` by construction (to rounding).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..errors import GeometryError
from .heightfield import HeightField
from .plan import PlanFrame


@dataclass(frozen=True)
class ParallelPlanes:
    """The planes ``x = const`` of ``frame``."""

    frame: PlanFrame
    kind: str = "parallel"

    def to_plan(self, s: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Plan coordinates ``(x, y)`` of ``(s, t)`` (arrays of one shape)."""
        return np.broadcast_to(s, np.shape(t)), t

    def slope(self, hf: HeightField, s: np.ndarray, t: np.ndarray, floor: float, limit: float) -> np.ndarray:
        """``dt/ds`` of the curves conjugate to the sections (module docstring), regularised by ``floor`` and
        clipped to ``±limit``."""
        fxy, fyy = hf.fxy(s, t), hf.fyy(s, t)
        return np.clip(-fxy * fyy / (fyy * fyy + floor * floor), -limit, limit)

    def second(self, hf: HeightField, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(H_ee, H_ew)`` at plan points: the second derivative along the section and the mixed one."""
        return hf.fyy(x, y), hf.fxy(x, y)

    def plane(self, s: float) -> np.ndarray:
        """The section plane ``s`` as a unit ``(n, d)``, ``n·p + d = 0`` (world)."""
        return self.frame.section_plane(s)

    def box(self, hf: HeightField, loops: Sequence[np.ndarray]) -> tuple[float, float, float, float]:
        """``(s_lo, s_hi, t_lo, t_hi)`` of the region: :func:`region_box`."""
        return region_box(hf, loops)

    def reach(self, hf: HeightField, spacing: float, box: tuple[float, float, float, float]) -> tuple[float, ...]:
        """``(s_lo, s_hi, t_lo, t_hi)`` over which planes and seeds are placed: the region and about one spacing
        beyond, within the fit's box."""
        s_lo, s_hi, t_lo, t_hi = box
        return (max(hf.x[0], s_lo - spacing), min(hf.x[-1], s_hi + spacing),
                max(hf.y[0], t_lo - spacing), min(hf.y[-1], t_hi + spacing))

    def s_step(self, spacing: float, box: tuple[float, float, float, float]) -> float:
        """About one ``spacing`` of arc length as a step of ``s`` (for the integration's step size)."""
        return spacing


@dataclass(frozen=True)
class PencilPlanes:
    """The vertical planes through the axis at plan point ``centre (2,)`` (frame coordinates), ``s = θ``."""

    frame: PlanFrame
    centre: np.ndarray
    kind: str = "pencil"

    def to_plan(self, s: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        s = np.broadcast_to(s, np.shape(t))
        return self.centre[0] + t * np.cos(s), self.centre[1] + t * np.sin(s)

    def _h(self, hf: HeightField, x: np.ndarray, y: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        c, sn = np.cos(theta), np.sin(theta)
        fxx, fxy, fyy = hf.fxx(x, y), hf.fxy(x, y), hf.fyy(x, y)
        h_rr = fxx * c * c + 2.0 * fxy * c * sn + fyy * sn * sn
        h_rt = (fyy - fxx) * c * sn + fxy * (c * c - sn * sn)
        return h_rr, h_rt

    def slope(self, hf: HeightField, s: np.ndarray, t: np.ndarray, floor: float, limit: float) -> np.ndarray:
        x, y = self.to_plan(s, t)
        h_rr, h_rt = self._h(hf, x, y, np.broadcast_to(s, np.shape(t)))
        return t * np.clip(-h_rt * h_rr / (h_rr * h_rr + floor * floor), -limit, limit)

    def second(self, hf: HeightField, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        theta = np.arctan2(y - self.centre[1], x - self.centre[0])
        return self._h(hf, x, y, theta)

    def plane(self, s: float) -> np.ndarray:
        ax = self.frame.axes
        normal = -np.sin(s) * ax[0] + np.cos(s) * ax[1]            # e_θ in the world: the plane holds e_r and z
        point = self.frame.to_world(np.array([self.centre[0], self.centre[1], 0.0]))
        return np.concatenate([normal, [-float(normal @ point)]])

    def box(self, hf: HeightField, loops: Sequence[np.ndarray]) -> tuple[float, float, float, float]:
        """``(θ_lo, θ_hi, r_lo, r_hi)`` of the region seen from the axis; refused when the axis lies inside it
        or the region spans half a turn or more about it."""
        if loops:
            pts = np.concatenate([densify_loop(np.asarray(lp, dtype=float), 50.0) for lp in loops])
        else:
            X, Y = np.meshgrid(hf.x, hf.y, indexing="ij")
            pts = np.stack([X.ravel(), Y.ravel()], axis=1)
        d = pts - self.centre
        mid = float(np.arctan2(*(d.mean(axis=0)[::-1])))
        theta = mid + np.angle(np.exp(1j * (np.arctan2(d[:, 1], d[:, 0]) - mid)))
        span = float(np.degrees(theta.max() - theta.min()))
        r = np.hypot(d[:, 0], d[:, 1])
        from .trim import inside

        if (loops and bool(inside(self.centre[None, :], loops)[0])) or span >= 179.0 or float(r.min()) <= 0.0:
            w = self.frame.to_world(np.array([self.centre[0], self.centre[1], 0.0]))
            raise GeometryError(f"sections net: the pencil's axis at ({w[0]:.0f}, {w[1]:.0f}) mm lies inside the "
                                f"outline or sees it over {span:.0f}° (half a turn or more); put the axis outside "
                                "the outline ([surface] pencil_axis) or use parallel planes",
                                element=f"({w[0]:.0f}, {w[1]:.0f})")
        return float(theta.min()), float(theta.max()), float(r.min()), float(r.max())

    def reach(self, hf: HeightField, spacing: float, box: tuple[float, float, float, float]) -> tuple[float, ...]:
        s_lo, s_hi, t_lo, t_hi = box
        ds = spacing / max(t_lo, spacing)                          # one spacing at the nearest radius, at most 1 rad
        return (s_lo - ds, s_hi + ds, max(0.5 * t_lo, t_lo - spacing), t_hi + spacing)

    def s_step(self, spacing: float, box: tuple[float, float, float, float]) -> float:
        return spacing / box[3]                                    # one spacing of arc at the farthest radius


PlaneFamily = ParallelPlanes | PencilPlanes


def region_box(hf: HeightField, loops: Sequence[np.ndarray]) -> tuple[float, float, float, float]:
    """``(x_lo, x_hi, y_lo, y_hi)``: the plan box of the trim loops within the box of the fit (the fit's box
    without loops)."""
    if loops:
        allp = np.concatenate(loops)
        return (max(hf.x[0], allp[:, 0].min()), min(hf.x[-1], allp[:, 0].max()),
                max(hf.y[0], allp[:, 1].min()), min(hf.y[-1], allp[:, 1].max()))
    return float(hf.x[0]), float(hf.x[-1]), float(hf.y[0]), float(hf.y[-1])


def densify_loop(loop: np.ndarray, step: float) -> np.ndarray:
    """Points along a closed plan loop ``(k, 2)`` at most ``step`` apart."""
    a, b = loop, np.roll(loop, -1, axis=0)
    n = np.maximum(1, np.ceil(np.linalg.norm(b - a, axis=1) / step)).astype(int)
    return np.concatenate([a[k] + (b[k] - a[k]) * (np.arange(n[k])[:, None] / n[k]) for k in range(len(a))])
