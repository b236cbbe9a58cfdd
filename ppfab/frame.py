"""An orthonormal frame of a plane: the one frame type of ppfab (panels, beam plates, profile planes).

A point of the plane is ``X = origin + x·ex + y·ey`` (shapes: ``origin, ex, ey (3,)``); the frame's normal is
``ex × ey``.  :meth:`Frame.to2d` projects ``(..., 3)`` points orthogonally into frame coordinates ``(..., 2)``,
:meth:`Frame.to3d` maps them back.

Examples
--------
>>> import numpy as np
>>> f = Frame(np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 0, 1.0]))
>>> f.normal.tolist(), f.to3d(np.array([2.0, 3.0])).tolist()
([0.0, -1.0, 0.0], [2.0, 0.0, 3.0])
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .errors import DesignError


@dataclass(frozen=True, eq=False)
class Frame:
    """``X = origin + x·ex + y·ey``; ``origin, ex, ey (3,)`` with ``ex ⟂ ey`` unit; normal ``ex × ey``."""

    origin: np.ndarray
    ex: np.ndarray
    ey: np.ndarray

    @property
    def normal(self) -> np.ndarray:
        """``(3,)`` unit normal ``ex × ey`` — the products and differences ``np.cross`` takes, bit for bit, on
        Python floats: ``np.cross`` of two 3-vectors costs ten times as much, and writers ask for a frame's normal
        per part."""
        (a0, a1, a2), (b0, b1, b2) = np.asarray(self.ex).tolist(), np.asarray(self.ey).tolist()
        return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])

    @property
    def plane(self) -> np.ndarray:
        """The frame's plane ``(n, d)``, ``n·x + d = 0``, unit normal ``(4,)``."""
        n = self.normal
        return np.r_[n, -float(n @ self.origin)]

    def to2d(self, points: np.ndarray) -> np.ndarray:
        """``(..., 3)`` points → ``(..., 2)`` frame coordinates (the normal component is dropped)."""
        d = np.asarray(points, dtype=float) - self.origin
        return np.stack([d @ self.ex, d @ self.ey], axis=-1)

    def to3d(self, points: np.ndarray) -> np.ndarray:
        """``(..., 2)`` frame coordinates → ``(..., 3)`` points in the plane."""
        q = np.asarray(points, dtype=float)
        return self.origin + q[..., :1] * self.ex + q[..., 1:2] * self.ey

    def vec2d(self, vectors: np.ndarray) -> np.ndarray:
        """``(..., 3)`` vectors → their ``(..., 2)`` in-plane components."""
        v = np.asarray(vectors, dtype=float)
        return np.stack([v @ self.ex, v @ self.ey], axis=-1)

    def vec3d(self, vectors: np.ndarray) -> np.ndarray:
        """``(..., 2)`` in-plane components → ``(..., 3)`` vectors."""
        q = np.asarray(vectors, dtype=float)
        return q[..., :1] * self.ex + q[..., 1:2] * self.ey

    def as_dict(self) -> dict[str, list[float]]:
        """``origin, x_dir, y_dir, normal`` as lists (the ``frame`` of parts in the output files)."""
        return {"origin": [float(x) for x in self.origin], "x_dir": [float(x) for x in self.ex],
                "y_dir": [float(x) for x in self.ey], "normal": [float(x) for x in self.normal]}

    @classmethod
    def from_axes(cls, origin: ArrayLike, axes: ArrayLike, key: str = "frame") -> "Frame":
        """Frame from an origin ``(3,)`` and two axes ``(2, 3)`` (Gram–Schmidt); parallel or zero axes raise
        :class:`~ppfab.errors.DesignError` under ``key``."""
        o = np.asarray(origin, dtype=float)
        a = np.asarray(axes, dtype=float)
        if o.shape != (3,):
            raise DesignError(key, f"origin needs 3 numbers, got {o.shape}")
        if a.shape != (2, 3):
            raise DesignError(key, f"needs two axes of 3 numbers each, got shape {a.shape}")
        n1 = np.linalg.norm(a[0])
        if n1 == 0:
            raise DesignError(key, "the first axis is the zero vector")
        e1 = a[0] / n1
        rest = a[1] - (a[1] @ e1) * e1
        n2 = np.linalg.norm(rest)
        if n2 <= 1e-9 * max(float(np.linalg.norm(a[1])), 1e-300):
            raise DesignError(key, "the two axes are parallel: they do not span a plane")
        return cls(o, e1, rest / n2)
