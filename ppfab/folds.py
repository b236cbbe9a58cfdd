"""Fold detection for constructed grids: a mesh that passes through a cuspidal edge.

Explicit constructions (face images eqs. 11–13, principal sections, sphere
families) never fail numerically when their input is unsuitable: they return
a mesh that folds over itself.  Near a cuspidal edge of the smooth surface the
vertex order of the faces reverses, so a face's corner-order normal
``(c2 − c0) × (c3 − c1)`` points against the normal of the plane it was built
in.  A face is *folded* when

* its corner-order normal disagrees in sign with its reference plane normal
  (compared with the majority of the faces, so a consistently reversed mesh is
  not a fold), or
* its corners do not all turn the same way (a butterfly or non-convex quad,
  :func:`ppfab.metrics.nonconvex_faces`), or
* it has (numerically) zero area.

:func:`check_folds` raises :class:`~ppfab.errors.FoldError` naming the first
folded face, its parameters, and the largest block of face parameters that
stays valid, so the caller can resample instead of receiving a folded mesh.
"""

from __future__ import annotations

import numpy as np

from .errors import FoldError
from .mesh import QuadGrid
from .metrics import nonconvex_faces


def corner_normals(corners: np.ndarray) -> np.ndarray:
    """Corner-order normals ``(c2 − c0) × (c3 − c1)`` (not normalised) of quads ``(..., 4, 3)``."""
    c = np.asarray(corners, dtype=float)
    return np.cross(c[..., 2, :] - c[..., 0, :], c[..., 3, :] - c[..., 1, :])


def orientation_sign(grid: QuadGrid, reference: np.ndarray) -> np.ndarray:
    """``sign((c2 − c0) × (c3 − c1) · n_ref)`` per face, ``(m, n')`` in {−1, 0, 1}.

    Parameters
    ----------
    grid : the mesh
    reference : (m, n', 3) or (m, n', 4) float — the normals (or planes) the faces were built in
    """
    ref = np.asarray(reference, dtype=float)[..., :3]
    return np.sign(np.einsum("...i,...i->...", corner_normals(grid.face_corners), ref))


def folded_faces(grid: QuadGrid, reference: np.ndarray | None = None,
                 area_tol: float = 1e-12) -> np.ndarray:
    """Boolean ``(m, n')``: faces that are flipped, non-convex or degenerate (see module doc).

    ``reference`` defaults to the grid's ``face_image``; without either only
    non-convex and degenerate faces are found.
    """
    ref = grid.face_image if reference is None else reference
    corners = grid.face_corners
    cn = corner_normals(corners)
    area = 0.5 * np.linalg.norm(cn, axis=-1)
    edges = np.linalg.norm(np.roll(corners, -1, axis=-2) - corners, axis=-1)
    scale = max(float(np.median(edges)) ** 2, 1e-300)
    bad = nonconvex_faces(corners) | (area <= area_tol * scale)
    if ref is not None:
        s = np.sign(np.einsum("...i,...i->...", cn, np.asarray(ref, dtype=float)[..., :3]))
        majority = 1.0 if (s > 0).sum() >= (s < 0).sum() else -1.0
        bad |= s != majority
    return bad


def largest_valid_block(bad: np.ndarray) -> tuple[int, int, int, int]:
    """The largest axis-aligned block of ``False`` entries in a boolean ``(m, n)`` array.

    Returns ``(i0, i1, j0, j1)`` (half-open face index ranges); ``(0, 0, 0, 0)``
    when every entry is bad.  Classic maximal-rectangle scan over row histograms
    (only used on the error path).
    """
    bad = np.asarray(bad, dtype=bool)
    m, n = bad.shape
    heights = np.zeros(n, dtype=np.int64)
    best = (0, (0, 0, 0, 0))
    for i in range(m):
        heights = np.where(bad[i], 0, heights + 1)
        stack: list[int] = []
        for j in range(n + 1):
            h = heights[j] if j < n else 0
            while stack and heights[stack[-1]] >= h:
                top = stack.pop()
                left = stack[-1] + 1 if stack else 0
                area = int(heights[top]) * (j - left)
                if area > best[0]:
                    best = (area, (i - int(heights[top]) + 1, i + 1, left, j))
            stack.append(j)
    return best[1]


def check_folds(grid: QuadGrid, u: np.ndarray | None = None, v: np.ndarray | None = None,
                reference: np.ndarray | None = None, context: str = "the mesh",
                names: tuple[str, str] = ("u", "v")) -> None:
    """Raise :class:`FoldError` when the grid folds (see :func:`folded_faces`).

    Parameters
    ----------
    grid : the constructed mesh
    u : (m,) float, optional — parameter of each row of faces (for the message)
    v : (n',) float, optional — parameter of each column of faces
    reference : (m, n', 3|4) float, optional — normals the faces were built in
    context : what to call the mesh in the message (e.g. the method name)
    names : names of the two parameters

    The message names the first folded face (row-major), how many faces fold,
    and the largest block of face parameters ``[u_a, u_b] × [v_c, v_d]`` that
    stays fold-free; the error's ``mask`` is the boolean ``(m, n')`` of the folded faces.
    """
    bad = folded_faces(grid, reference)
    if not bad.any():
        return
    i, j = (int(k) for k in np.argwhere(bad)[0])
    i0, i1, j0, j1 = largest_valid_block(bad)

    def at(name, t, k):
        return f"{name} = {float(t[k]):.6g}" if t is not None else None

    where = ", ".join(x for x in (at(names[0], u, i), at(names[1], v, j)) if x)
    where = f" at {where}" if where else ""
    def span(name, t, k0, k1, what):
        if t is None:
            return f"{what} {k0}..{k1 - 1}"
        a, b = sorted((float(t[k0]), float(t[k1 - 1])))
        return f"{name} in [{a:.6g}, {b:.6g}]"

    if i1 > i0:
        ru = span(names[0], u, i0, i1, "face rows")
        rv = span(names[1], v, j0, j1, "face columns")
        valid = f"the face parameters {ru}, {rv} stay valid (faces [{i0}:{i1}, {j0}:{j1}])"
    else:
        valid = "no block of faces stays valid"
    err = FoldError(f"{context} folds over (passes through a cuspidal edge): face ({i}, {j}){where} is flipped "
                    f"({int(bad.sum())} of {bad.size} faces); {valid}",
                    element=f"face ({i}, {j})", value=float(bad.sum()))
    err.mask = bad
    raise err
