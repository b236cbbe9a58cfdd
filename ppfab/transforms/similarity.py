"""Scale, rotate, move and flip meshes together with their support structure.

A similarity ``x' = s R x + t`` acts on weighted planes linearly (so the face
image stays a translation net and PP meshes stay PP): ``(n, d) ↦ (R n, s d − (R n)·t)``,
i.e. ``f' = M f`` with ``M = [[R, 0], [−tᵀR, s]]`` (a special case of the 4D
projective maps of §2.3.5).
"""

from __future__ import annotations

from dataclasses import replace
from typing import overload

import numpy as np
from numpy.typing import ArrayLike

from ppfab.mesh import QuadGrid, QuadMesh




def rotation_z(deg: float) -> np.ndarray:
    a = np.radians(deg)
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def plane_map(scale: float, rot: np.ndarray, translate: np.ndarray) -> np.ndarray:
    """The 4×4 matrix acting on weighted planes ``(n, d)`` for ``x' = s R x + t``."""
    m = np.zeros((4, 4))
    m[:3, :3] = rot
    m[3, :3] = -(translate @ rot)
    m[3, 3] = scale
    return m


def _planes(p: np.ndarray | None, m: np.ndarray) -> np.ndarray | None:
    return None if p is None else np.asarray(p) @ m.T


@overload
def transform(mesh: QuadGrid, scale: float = 1.0, rotate_z_deg: float = 0.0,
              translate: ArrayLike = (0.0, 0.0, 0.0), flip: bool = False) -> QuadGrid: ...
@overload
def transform(mesh: QuadMesh, scale: float = 1.0, rotate_z_deg: float = 0.0,
              translate: ArrayLike = (0.0, 0.0, 0.0), flip: bool = False) -> QuadMesh: ...
@overload
def transform(mesh: QuadGrid | QuadMesh, scale: float = 1.0, rotate_z_deg: float = 0.0,
              translate: ArrayLike = (0.0, 0.0, 0.0), flip: bool = False) -> QuadGrid | QuadMesh: ...
def transform(mesh: QuadGrid | QuadMesh, scale: float = 1.0, rotate_z_deg: float = 0.0,
              translate: ArrayLike = (0.0, 0.0, 0.0), flip: bool = False) -> QuadGrid | QuadMesh:
    """Apply ``x' = s R_z x + t`` (and optionally reverse the orientation) to a mesh and its support data."""
    rot = rotation_z(rotate_z_deg)
    t = np.asarray(translate, dtype=float)
    m = plane_map(scale, rot, t)
    if isinstance(mesh, QuadMesh):
        v = mesh.vertices @ rot.T * scale + t
        faces = mesh.faces[:, ::-1] if flip else mesh.faces
        grid = None
        if mesh.grid is not None:
            grid = transform(mesh.grid, scale, rotate_z_deg, translate, flip)
            assert mesh.grid_ids is not None, "a mesh made from a grid carries its grid ids"
            ids = mesh.grid_ids[:, ::-1] if flip else mesh.grid_ids
            return QuadMesh(v, faces, grid=grid, grid_ids=ids)
        return QuadMesh(v, faces)
    g = mesh
    v = g.vertices @ rot.T * scale + t
    axes = None if g.axes is None else g.axes @ rot.T
    out = replace(g, vertices=v, support_u=_planes(g.support_u, m), support_w=_planes(g.support_w, m),
                  face_image=_planes(g.face_image, m), axes=axes,
                  extended_face_image=_planes(g.extended_face_image, m),
                  extended_face_planes=_planes(g.extended_face_planes, m))
    return flip_grid(out) if flip else out


def flip_grid(g: QuadGrid) -> QuadGrid:
    """Reverse a grid's orientation by reversing ``j`` (columns); node axes turn to the new inside."""
    def rev(a, axis=1):
        if a is None:
            return None
        a = np.flip(a, axis=axis)
        return np.roll(a, 1, axis=axis) if g.closed else a
    def ext(a):
        return None if a is None or g.closed else np.flip(a, axis=1)
    face_image = None if g.face_image is None else np.flip(g.face_image, axis=1)
    return replace(g, vertices=rev(g.vertices), support_w=None if g.support_w is None else g.support_w[::-1],
                   face_image=face_image, axes=None if g.axes is None else -rev(g.axes),
                   vertex_ids=rev(g.vertex_ids), extended_face_image=ext(g.extended_face_image),
                   extended_face_planes=ext(g.extended_face_planes))
