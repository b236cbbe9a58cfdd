"""The faces of a B-rep read at the text level, packed (:class:`ShellCode`: a few arrays per B-rep, shared by every
solid placing it) and unpacked into records when a check asks (:class:`Face` with its :class:`Loop` s and their
:class:`Arc` s).  Made by :mod:`._step_breps`, measured by :mod:`._step_brep_facts`, placed and read by
:mod:`._step_text_read`.

Not a check (the leading underscore keeps it out of the registry).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, slots=True)
class Arc:
    """A circular edge: centre, unit axis about which it runs counter-clockwise from its start to its end vertex,
    radius and sweep (radians, in (0, 2π])."""

    centre: np.ndarray
    axis: np.ndarray
    radius: float
    sweep: float


@dataclass(frozen=True, slots=True)
class Loop:
    """A boundary loop of a face: indices into the solid's vertices, edge ``k`` running from ``vertices[k]`` to
    ``vertices[k + 1]`` (cyclic), straight or ``arcs[k]``; ``edges[k]`` the id of its EDGE_CURVE and ``forward[k]``
    whether the loop runs along it."""

    vertices: np.ndarray
    arcs: tuple[Arc | None, ...]
    edges: tuple[int, ...]
    forward: tuple[bool, ...]


@dataclass(frozen=True, slots=True)
class Face:
    """A face: ``surface`` ``"plane"`` or ``"cylinder"``; ``origin`` a point of the surface (on the axis of a
    cylinder); ``normal`` the outward unit normal of a plane (the axis of a cylinder); ``outward`` whether the
    face's normal is the surface's (for a cylinder: away from its axis); ``radius`` a cylinder's; its loops."""

    surface: str
    origin: np.ndarray
    normal: np.ndarray
    ref_dir: np.ndarray
    outward: bool
    radius: float
    loops: tuple[Loop, ...]
    index: int = -1
    """Its place in the solid's shell (:attr:`TextSolid.shell`)."""


@dataclass(frozen=True, slots=True)
class ShellCode:
    """The faces of one B-rep in its own coordinates, packed into a few arrays (kept once per B-rep, shared by
    every solid placing it): :meth:`faces` unpacks them into :class:`Face` records, placed, when a check asks.

    Why packed: at 88 × 60 faces glazing.step has 74,160 solids, and a shell kept as records (a face with its
    loops, arcs, edge tuples and small arrays: about 30 Python objects) held about 1 kB per face.

    ``planes (f, 10)``: per face its surface's origin, normal (outward for a plane; a cylinder's axis), reference
    direction and radius (0 for a plane); ``kinds (f, 2)``: whether it is a cylinder, whether the face's normal is
    the surface's; ``face_loops (f + 1,)``: face ``i``'s loops are ``face_loops[i]`` … ``face_loops[i + 1] - 1``;
    ``loop_steps (L + 1,)``: loop ``j``'s edges are the rows ``loop_steps[j]`` … of ``steps (V, 4)`` (the vertex
    it starts from, the EDGE_CURVE's id, 1 when the loop runs along it, the row of ``arcs`` or -1 when straight);
    ``arcs (A, 8)``: centre, unit axis, radius and sweep of each circular edge (as :class:`Arc`)."""

    planes: np.ndarray
    kinds: np.ndarray
    face_loops: np.ndarray
    loop_steps: np.ndarray
    steps: np.ndarray
    arcs: np.ndarray

    def faces(self, rot: np.ndarray | None = None, shift: np.ndarray | None = None) -> list[Face]:
        """The faces, moved by the rigid motion ``x ↦ rot x + shift`` when given (a proper rotation: arcs keep
        their sweep)."""
        planes, arcs = self.planes, self.arcs
        origin, normal, ref_dir = planes[:, 0:3], planes[:, 3:6], planes[:, 6:9]
        centre, axis = arcs[:, 0:3], arcs[:, 3:6]
        if rot is not None:
            move = rot.T
            origin, normal, ref_dir = origin @ move + shift, normal @ move, ref_dir @ move
            centre, axis = centre @ move + shift, axis @ move
        arc_records = [Arc(centre[k], axis[k], float(arcs[k, 6]), float(arcs[k, 7])) for k in range(len(arcs))]
        steps, bounds = self.steps, self.loop_steps.tolist()
        loops: list[Loop] = []
        for j in range(len(bounds) - 1):
            rows = steps[bounds[j]:bounds[j + 1]]
            which = rows[:, 3].tolist()
            loops.append(Loop(rows[:, 0], tuple(None if k < 0 else arc_records[k] for k in which),
                              tuple(rows[:, 1].tolist()), tuple(bool(x) for x in rows[:, 2].tolist())))
        first = self.face_loops.tolist()
        cylinder, outward = self.kinds[:, 0].tolist(), self.kinds[:, 1].tolist()
        radius = planes[:, 9].tolist()
        return [Face("cylinder" if cylinder[i] else "plane", origin[i], normal[i], ref_dir[i], bool(outward[i]),
                     radius[i], tuple(loops[first[i]:first[i + 1]]), i) for i in range(len(first) - 1)]

    def key(self) -> tuple:
        """Per face its surface and the edge counts and arcs of its loops, sorted (:meth:`TextSolid.shape_key`)."""
        bounds = self.loop_steps
        arcs: list[int] = (np.add.reduceat((self.steps[:, 3] >= 0).astype(int), bounds[:-1]).tolist()
                           if len(self.steps) else [])
        counts = list(zip(np.diff(bounds).tolist(), arcs))
        first = self.face_loops.tolist()
        cylinder = self.kinds[:, 0].tolist()
        return tuple(sorted(("cylinder" if cylinder[i] else "plane", tuple(sorted(counts[first[i]:first[i + 1]])))
                            for i in range(len(first) - 1)))
