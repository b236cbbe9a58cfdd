"""The surface a designer brings, as the geometry core sees it: dense samples in millimetres.

A reader of the fabrication layer (a Rhino ``.3dm`` NURBS surface or trimmed face, a triangle mesh from
OBJ/OFF/STL/PLY) turns a file into a :class:`SurfaceSamples`: points on the surface, a triangulation of them
(the closeness reference of the optimiser and the deviation check), and the boundary loops that trim it.
The core never reads a file format itself.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import GeometryError


@dataclass(frozen=True)
class SurfaceSamples:
    """A surface sampled densely, in millimetres.

    Parameters
    ----------
    points : (N, 3) float — points on the surface, mm
    triangles : (T, 3) int — a triangulation of ``points`` (the original mesh's triangles, or the NURBS
        sampled on a parameter grid, each cell split in two)
    boundary : loops ``(k, 3)`` of points on the trim boundary (outer loops and holes; which is which is
        decided in plan by nesting)
    units : the unit the file was in (``"mm"``, ``"m"``, …) before the conversion to mm
    source : a short text saying where the samples came from (file and object)
    """

    points: np.ndarray
    triangles: np.ndarray
    boundary: tuple[np.ndarray, ...] = field(default_factory=tuple)
    units: str = "mm"
    source: str = ""

    def __post_init__(self) -> None:
        p = np.asarray(self.points, dtype=float)
        t = np.asarray(self.triangles, dtype=np.int64)
        if p.ndim != 2 or p.shape[1] != 3 or len(p) < 3:
            raise GeometryError(f"surface samples need shape (N >= 3, 3), got {p.shape}")
        if not np.all(np.isfinite(p)):
            raise GeometryError("a surface sample is not finite (NaN or inf)")
        if t.ndim != 2 or t.shape[1] != 3 or (len(t) and (t.min() < 0 or t.max() >= len(p))):
            raise GeometryError(f"surface triangles need shape (T, 3) indexing the points, got {t.shape}")
        loops = tuple(np.asarray(b, dtype=float).reshape(-1, 3) for b in self.boundary)
        for a in (p, t, *loops):
            a.flags.writeable = False
        object.__setattr__(self, "points", p)
        object.__setattr__(self, "triangles", t)
        object.__setattr__(self, "boundary", loops)

    @property
    def extent(self) -> float:
        """Diagonal of the bounding box, mm."""
        return float(np.linalg.norm(self.points.max(axis=0) - self.points.min(axis=0)))
