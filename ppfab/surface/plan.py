"""The plan frame of a surface: the section planes are ``x = const`` in it, the surface a height field over it.

``x`` is the normal of the section planes, ``z`` the height (the world's vertical made orthogonal to ``x``),
``y = z × x``.  Without a given normal, ``x`` is the longer principal direction of the plan (the sections
are vertical planes across the longer direction).

Examples
--------
>>> import numpy as np
>>> pts = np.array([[0, 0, 0], [10, 0, 1], [10, 2, 0], [0, 2, 1.0]])
>>> f = plan_frame(pts)
>>> np.round(np.abs(f.axes[0]), 6).tolist(), np.allclose(f.to_world(f.to_local(pts)), pts)
([1.0, 0.0, 0.0], True)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..errors import DesignError


@dataclass(frozen=True)
class PlanFrame:
    """An orthonormal frame: ``origin (3,)`` and ``axes (3, 3)`` with rows ``x``, ``y``, ``z``."""

    origin: np.ndarray
    axes: np.ndarray

    def to_local(self, p: np.ndarray) -> np.ndarray:
        """World points ``(..., 3)`` → frame coordinates ``(..., 3)``."""
        return (np.asarray(p, dtype=float) - self.origin) @ self.axes.T

    def to_world(self, q: np.ndarray) -> np.ndarray:
        """Frame coordinates ``(..., 3)`` → world points ``(..., 3)``."""
        return np.asarray(q, dtype=float) @ self.axes + self.origin

    def section_plane(self, x: float) -> np.ndarray:
        """The plane ``x = const`` as a unit weighted plane ``(n, d)``, ``n·p + d = 0`` (world)."""
        n = self.axes[0]
        return np.concatenate([n, [-(float(n @ self.origin) + x)]])


def plan_frame(points: np.ndarray, plane_normal: Sequence[float] | None = None) -> PlanFrame:
    """The frame whose ``x`` is ``plane_normal`` (or the longer plan direction of ``points (N, 3)``)."""
    p = np.asarray(points, dtype=float)
    up = np.array([0.0, 0.0, 1.0])
    if plane_normal is None:
        xy = p[:, :2] - p[:, :2].mean(axis=0)
        w, vec = np.linalg.eigh(xy.T @ xy)
        d = vec[:, int(np.argmax(w))]
        x = np.array([d[0], d[1], 0.0])
        k = int(np.argmax(np.abs(x)))
        x = x if x[k] > 0 else -x                       # a stable sign
    else:
        x = np.asarray(plane_normal, dtype=float)
        if x.shape != (3,) or not np.all(np.isfinite(x)) or np.linalg.norm(x) == 0:
            raise DesignError("surface.plane_normal", "must be three finite numbers, not all zero")
        x = x / np.linalg.norm(x)
        if abs(x @ up) > np.cos(np.radians(10.0)):
            raise DesignError("surface.plane_normal", "is within 10° of vertical: the section planes would be "
                                                      "nearly horizontal; give a normal across the plan, e.g. "
                                                      "[1, 0, 0]")
    x = x / np.linalg.norm(x)
    z = up - (up @ x) * x
    z = z / np.linalg.norm(z)
    y = np.cross(z, x)
    axes = np.stack([x, y, z])
    origin = np.zeros(3)
    local = (p - origin) @ axes.T
    origin = axes.T @ np.array([local[:, 0].mean(), local[:, 1].mean(), 0.0])
    for a in (axes, origin):
        a.flags.writeable = False
    return PlanFrame(origin, axes)
