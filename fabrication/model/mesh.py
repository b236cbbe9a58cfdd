"""The record of the build's quad mesh: :class:`MeshData`."""

from __future__ import annotations

from dataclasses import dataclass

from .part import Point3


@dataclass(frozen=True)
class MeshData:
    """The mesh in mm as ``mesh.obj`` holds it (0-based face indices; OBJ vertex ``k`` is node ``N{k:04d}``),
    with the grid shape ``(rows, cols)`` and ``closed`` of a regular patch (``mesh.json``; ``None`` without)."""

    vertices: tuple[Point3, ...]
    faces: tuple[tuple[int, ...], ...]
    grid_shape: tuple[int, int] | None = None
    closed: bool = False

    def arrays(self):  # noqa: ANN201 - numpy is imported here only
        """``(vertices (n, 3), faces (f, k))`` as numpy arrays (faces padded with -1 when of mixed size)."""
        import numpy as np

        width = max((len(f) for f in self.faces), default=4)
        faces = np.full((len(self.faces), width), -1, dtype=int)
        for k, f in enumerate(self.faces):
            faces[k, :len(f)] = f
        return np.array(self.vertices, dtype=float).reshape(-1, 3), faces
