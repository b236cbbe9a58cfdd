"""Transformations of PP meshes through their weighted face image (§2.2.3, §2.3.5, Remark 3.2).

A PP grid is rebuilt from its *extended* face image ``F (m+2, n+2, 4)`` (one
ghost face beyond each side, see :mod:`ppfab.faceimage`), a translation net
``F[a, b] = g_a + h_b − c`` (eq. 7).  Every transformation here maps that
image and rebuilds the vertices ``v[i, j] = F[i+1, j+1] ∩ U_i ∩ W_j`` with
``U_i = g_{i+1} − g_i``, ``W_j = h_{j+1} − h_j``:

* :func:`f_transform` — translate ``F`` by ``t ∈ R^4``: the result shares the
  support planes ``U_i, W_j`` (an F-transform, Fig. 4); with ``t = (0, 0, 0, τ)``
  the face normals are kept and it is a parallel mesh (§2.2.3).
* :func:`offset` — the parallel mesh whose vertices move a chosen distance
  along the node axes (least squares over ``τ``), for the second layer of a
  two-layer structure or the lower edge of the beams.
* :func:`projective_map` — a 4D projective map of ``M_F`` by a 5×5 matrix (§2.3.5,
  Fig. 5).  The planes ``T(f)`` depend only on the upper 4×5 block (the last row
  only re-weights them), so the rebuilt mesh is PP again; the re-weighted image
  defines a second torsion-free support structure of it, returned in ``meta``.
* :func:`delete_face_rows`, :func:`delete_face_cols`, :func:`multinet` — delete
  rows/columns of ``M_F``: a PP mesh again (the multi-net property, Remark 3.2).

The transforms accept any open PP :class:`~ppfab.mesh.QuadGrid`: one made by
:func:`~ppfab.faceimage.pp_from_face_image` carries its extended image in
``extended_face_image``; for any other PP grid the image is recovered
with :func:`~ppfab.faceimage.pp_face_image` and completed by ghost faces
(:func:`extended_face_image_of`).  Boundary vertices stay exactly where they are
under the identity transform either way.

Examples
--------
>>> from ppfab.faceimage import pp_from_face_image
>>> s = np.linspace(-0.5, 0.5, 6)          # a paraboloid: g, h quadratic in the 4th coordinate
>>> grid = pp_from_face_image(np.stack([s, 0 * s, 0.5 + 0 * s, -0.5 * s ** 2], 1),
...                           np.stack([0 * s, s, 0.5 + 0 * s, -0.5 * s ** 2], 1))
>>> lower = offset_along_axes(grid, 0.01)             # vertical node axes: an exact 0.01 offset
>>> bool(np.allclose(lower.vertices, grid.vertices + 0.01 * grid.axes))
True
>>> multinet(grid, 2, 2).face_shape, delete_face_rows(grid, [0]).shape
((2, 2), (4, 5))
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ppfab import planes as pl
from ppfab.errors import GeometryError
from ppfab.faceimage import pp_face_image, pp_from_face_image
from ppfab.mesh import QuadGrid

__all__ = ["extended_face_image_of", "grid_from_extended", "with_face_image", "f_transform", "parallel_mesh",
           "offset_along_axes", "projective_map", "reweighted_axes", "delete_face_rows", "delete_face_cols", "multinet"]


def _size(v: np.ndarray) -> float:
    return float(np.linalg.norm(v.reshape(-1, 3).max(axis=0) - v.reshape(-1, 3).min(axis=0))) or 1.0


def _stored_image_fits(grid: QuadGrid, F: np.ndarray, tol: float) -> bool:
    """Whether ``F`` is the extended image of ``grid``: right shape and every vertex on its four planes."""
    m1, n1 = grid.shape
    if not isinstance(F, np.ndarray) or F.shape != (m1 + 1, n1 + 1, 4) or not np.all(np.isfinite(F)):
        return False
    v = grid.vertices
    size = _size(v)
    for da in (0, 1):
        for db in (0, 1):
            planes = F[da:da + m1, db:db + n1]
            if np.any(np.linalg.norm(planes[..., :3], axis=-1) == 0):
                return False
            if np.abs(pl.signed_distance(planes, v)).max() > tol * size:
                return False
    return True


def _ghost(first: np.ndarray, step: np.ndarray | None, support: np.ndarray, scale: float) -> np.ndarray:
    """A ghost step ``λ · support`` beyond ``first``: as long as the neighbouring step ``step`` and
    turned the same way (any λ ≠ 0 gives the same boundary vertices)."""
    s = pl.normalize(support)
    if step is None or not np.any(step):
        return s * scale
    sign = 1.0 if float(s @ step) >= 0 else -1.0
    return sign * s * float(np.linalg.norm(step))


def extended_face_image_of(grid: QuadGrid, tol: float = 1e-6) -> np.ndarray:
    """The extended weighted face image ``F (m+2, n+2, 4)`` of an open PP grid, a translation net (eq. 7).

    Taken from ``grid.extended_face_image`` when it still fits the
    vertices, otherwise recovered with :func:`~ppfab.faceimage.pp_face_image`
    (face ``(0, 0)`` gets unit weight) and completed by ghost faces
    ``F[0, ·] = F[1, ·] − λ U_0`` etc.

    Parameters
    ----------
    grid : open :class:`QuadGrid` whose rows and columns are planar
    tol : relative tolerance (to the bounding-box diagonal) for "planar" and for
        the rebuilt vertices; a grid that is not PP within it raises :class:`GeometryError`.
    """
    if grid.closed:
        raise GeometryError("face-image transforms need an open patch; this grid is closed in j")
    stored = grid.extended_face_image
    if stored is not None and _stored_image_fits(grid, np.asarray(stored, dtype=float), tol):
        return np.array(stored, dtype=float)
    v = grid.vertices
    size = _size(v)
    F, U, W = pp_face_image(grid)
    m, n = F.shape[:2]
    for name, pts, planes in (("row", grid.rows(), U), ("column", grid.cols(), W)):
        dist = np.abs(pl.signed_distance(planes[:, None, :], pts)).max(axis=1)
        k = int(np.argmax(dist))
        if dist[k] > tol * size:
            raise GeometryError(f"the grid is not a PP mesh: {name} polyline {k} deviates {dist[k]:.3g} from its "
                                f"plane (> {tol:g} x size {size:.3g})", element=f"{name} {k}", value=float(dist[k]))
    scale = 0.1 * float(np.linalg.norm(F[0, 0]))
    du = F[1:, 0] - F[:-1, 0]
    dw = F[0, 1:] - F[0, :-1]
    g = np.concatenate([(F[0, 0] - _ghost(F[0, 0], du[0] if m > 1 else None, U[0], scale))[None],
                        F[:, 0],
                        (F[-1, 0] + _ghost(F[-1, 0], du[-1] if m > 1 else None, U[-1], scale))[None]])
    h0 = F[0, :] - F[0, 0]
    h = np.concatenate([(h0[0] - _ghost(h0[0], dw[0] if n > 1 else None, W[0], scale))[None],
                        h0,
                        (h0[-1] + _ghost(h0[-1], dw[-1] if n > 1 else None, W[-1], scale))[None]])
    ext = g[:, None, :] + h[None, :, :]
    moved = np.abs(pp_from_face_image(g, h).vertices - v).max(axis=-1)
    if moved.max() > tol * size:
        i, j = (int(k) for k in np.unravel_index(np.argmax(moved), moved.shape))
        raise GeometryError(f"the grid is not a PP mesh: rebuilding vertex ({i}, {j}) from its face image moves it "
                            f"by {moved[i, j]:.3g} (> {tol:g} x size {size:.3g})", element=f"vertex ({i}, {j})",
                            value=float(moved[i, j]))
    return ext


def grid_from_extended(F: np.ndarray, min_sine: float = 1e-9, tol: float = 1e-9) -> QuadGrid:
    """Rebuild a PP grid from an extended face image ``F (m+2, n+2, 4)`` (Prop. 2.5, eq. 7).

    ``F`` must be a translation net, ``F[a, b] = F[a, 0] + F[0, b] − F[0, 0]``
    within ``tol`` (relative to its largest entry).
    """
    F = pl.as_planes(F)
    if F.ndim != 3 or F.shape[0] < 3 or F.shape[1] < 3:
        raise GeometryError(f"an extended face image needs shape (m+2, n+2, 4) with m, n >= 1, got {F.shape}")
    g, h, c = F[:, 0], F[0, :], F[0, 0]
    dev = np.abs(F - (g[:, None] + h[None, :] - c)).max()
    if dev > tol * max(1.0, float(np.abs(F).max())):
        raise GeometryError(f"the face image is not a translation net (eq. 7): deviation {dev:.3g}", value=float(dev))
    return pp_from_face_image(g, h, c, min_sine=min_sine)


def with_face_image(grid: QuadGrid, tol: float = 1e-6) -> QuadGrid:
    """The same vertices with support planes, face image, node axes and the extended face image.

    Used by constructions that make PP grids directly from vertices (Cauchy
    data, translational surfaces) so that every transform applies to them.
    """
    F = extended_face_image_of(grid, tol)
    rebuilt = grid_from_extended(F)
    return QuadGrid(grid.vertices, closed=False, support_u=rebuilt.support_u, support_w=rebuilt.support_w,
                    face_image=rebuilt.face_image, axes=rebuilt.axes, vertex_ids=grid.vertex_ids,
                    extended_face_image=F, meta=grid.meta)


def f_transform(grid: QuadGrid, t: np.ndarray) -> QuadGrid:
    """F-transform by translating the face image, ``F' = F + t`` (§2.2.3, Fig. 4).

    Support planes ``U_i = g_{i+1} − g_i`` and ``W_j`` are differences, hence
    unchanged: corresponding edges of the two meshes are coplanar.  With
    ``t[:3] = 0`` the face normals are unchanged too and the result is a
    parallel (Combescure) mesh.

    Parameters
    ----------
    grid : open PP :class:`QuadGrid`
    t : (4,) float, in the weights of ``extended_face_image_of(grid)``
    """
    t = np.asarray(t, dtype=float)
    if t.shape != (4,) or not np.all(np.isfinite(t)):
        raise GeometryError(f"a face-image translation needs 4 finite numbers, got {t!r}")
    return grid_from_extended(extended_face_image_of(grid) + t)


def parallel_mesh(grid: QuadGrid, shift: float) -> QuadGrid:
    """Parallel mesh ``F' = F + (0, 0, 0, shift)``: face ``f`` moves by ``shift / |n_f|`` along its normal."""
    return f_transform(grid, np.array([0.0, 0.0, 0.0, float(shift)]))


def _adjacent_normal_dot_axis(F: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """``n_f · a`` at every vertex for the weighted normal of the face ``F[i+1, j+1]`` (the same for all
    four faces around it, since their differences contain the axis), ``(m+1, n+1)``."""
    return np.einsum("...i,...i->...", F[1:, 1:, :3], axes)


def offset_along_axes(grid: QuadGrid, distance: float, mode: str = "parallel") -> QuadGrid:
    """A mesh sharing the support planes whose vertices lie ``≈ distance`` along the node axes.

    A vertex can only move along its node axis ``U_i ∩ W_j`` (it must stay on
    both support planes), by ``s_v``.  The face image is translated by ``t``:

    * ``mode="parallel"``: ``t = (0, 0, 0, τ)``, a parallel mesh with
      ``s_v = −τ / (n_v · a_v)``; ``τ`` minimises ``Σ (s_v − distance)²``.
      The offset is exactly uniform when ``|n_v · a_v|`` is constant (e.g. unit
      face image with axes along the normals).
    * ``mode="f_transform"``: all four entries of ``t`` by weighted linear least
      squares of ``(n_v + t_n)·(v + distance·a_v) + d_v + t_d = 0``; an
      F-transform, usually closer to a uniform distance, faces no longer parallel.

    Positive distances go along the node axes as oriented by the grid (towards
    the beams, away from the panels' outer side).  The achieved offsets are in
    ``result.meta["offset"]`` (``target, min, max, mean``).
    """
    if mode not in ("parallel", "f_transform"):
        raise GeometryError(f"offset mode must be 'parallel' or 'f_transform', got {mode!r}")
    distance = float(distance)
    if not np.isfinite(distance):
        raise GeometryError(f"offset distance must be finite, got {distance}")
    F = extended_face_image_of(grid)
    axes = grid_from_extended(F).axes
    assert axes is not None, "pp_from_face_image sets the node axes"
    if grid.axes is not None and grid.axes.shape == axes.shape:
        axes = axes * np.where(np.einsum("...i,...i->...", axes, grid.axes) < 0, -1.0, 1.0)[..., None]
    v = grid.vertices
    na = _adjacent_normal_dot_axis(F, axes)
    if np.abs(na).min() <= 1e-12 * np.abs(F[..., :3]).max():
        i, j = (int(k) for k in np.unravel_index(np.argmin(np.abs(na)), na.shape))
        raise GeometryError(f"the node axis of vertex ({i}, {j}) lies in its face plane; no offset along it",
                            element=f"vertex ({i}, {j})")
    if mode == "parallel":
        k = (-1.0 / na).ravel()
        tau = distance * k.sum() / (k @ k)
        t = np.array([0.0, 0.0, 0.0, tau])
    else:
        x = np.concatenate([v + distance * axes, np.ones(v.shape[:2] + (1,))], axis=-1).reshape(-1, 4)
        rhs = -distance * na.ravel()
        w = 1.0 / np.abs(na.ravel())
        t = np.linalg.lstsq(x * w[:, None], rhs * w, rcond=None)[0]
    out = grid_from_extended(F + t)
    s = np.einsum("...i,...i->...", out.vertices - v, axes)
    stats = {"target": distance, "min": float(s.min()), "max": float(s.max()), "mean": float(s.mean()),
             "mode": mode, "t": t.tolist()}
    return QuadGrid(out.vertices, support_u=out.support_u, support_w=out.support_w, face_image=out.face_image,
                    axes=axes, meta={**out.meta, "offset": stats})


def _projective_image(grid: QuadGrid, matrix: np.ndarray, min_weight: float) -> tuple[np.ndarray, np.ndarray]:
    """``A f + b`` ``(m+2, n+2, 4)`` and the weights ``w = cᵀ f + e`` ``(m+2, n+2)`` of the extended face image."""
    T = np.asarray(matrix, dtype=float)
    if T.shape != (5, 5) or not np.all(np.isfinite(T)):
        raise GeometryError(f"a 4D projective map needs a finite 5x5 matrix, got shape {T.shape}")
    if abs(np.linalg.det(T)) <= 1e-12 * max(1.0, float(np.abs(T).max())) ** 5:
        raise GeometryError(f"the 5x5 matrix is singular (det = {np.linalg.det(T):.3g}); not a projective map")
    F = extended_face_image_of(grid)
    Fh = np.concatenate([F, np.ones(F.shape[:2] + (1,))], axis=-1) @ T.T
    Fa, w = Fh[..., :4], Fh[..., 4]
    wscale = float(np.abs(w).max())
    if np.abs(w).min() <= min_weight * wscale:
        a, b = (int(k) for k in np.unravel_index(np.argmin(np.abs(w)), w.shape))
        raise GeometryError(f"the projective map sends face image point F[{a}, {b}] to infinity "
                            f"(weight {w[a, b]:.3g})", element=f"face image {a},{b}", value=float(w[a, b]))
    return Fa, w


def projective_map(grid: QuadGrid, matrix: np.ndarray, min_weight: float = 1e-9) -> QuadGrid:
    """Apply a 4D projective map to the face image and rebuild the mesh (§2.3.5, Fig. 5).

    ``f' = (A f + b) / (cᵀ f + e)`` with ``matrix = [[A, b], [cᵀ, e]]`` (5×5,
    acting on ``(f, 1)``).  Planes are points of RP³, so ``f'`` and ``A f + b``
    are the same plane: the rebuilt mesh depends only on the upper 4×5 block,
    and since ``A f + b`` maps the translation net ``F`` to a translation net
    the result is again PP, with support planes ``A U_i`` and ``A W_j`` and axes ``U_i ∩ W_j``.
    The re-weighting by the last row gives the same mesh another torsion-free support structure:
    :func:`reweighted_axes`.

    Raises :class:`GeometryError` when a face (ghost faces included) is sent to
    infinity (``|w|`` below ``min_weight`` relative) or the new planes degenerate.
    """
    Fa, _ = _projective_image(grid, matrix, min_weight)
    reweighted_axes(grid, matrix, min_weight)                 # the re-weighted structure must not degenerate
    out = grid_from_extended(Fa)
    return QuadGrid(out.vertices, support_u=out.support_u, support_w=out.support_w, face_image=out.face_image,
                    axes=out.axes, extended_face_image=out.extended_face_image, meta=out.meta)


def reweighted_axes(grid: QuadGrid, matrix: np.ndarray, min_weight: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """The torsion-free support structure of :func:`projective_map`'s mesh given by the re-weighted image.

    The re-weighted image ``F' = (A f + b) / w``, ``w = cᵀ f + e``, is the face image of the *same* mesh with
    another torsion-free support structure (Prop. 2.4/2.5): its edge planes are the differences of ``F'``
    and its node axes their intersections.

    Returns
    -------
    axes : (m+1, n+1, 3) unit node axes
    weights : (m+2, n+2) ``w`` of every face, ghosts included
    """
    Fa, w = _projective_image(grid, matrix, min_weight)
    Fp = Fa / w[..., None]
    s_row = Fp[1:, :-1] - Fp[:-1, :-1]          # across row i: faces F[i, j], F[i+1, j]   (m+1, n+1, 4)
    s_col = Fp[:-1, 1:] - Fp[:-1, :-1]          # across column j: faces F[i, j], F[i, j+1]
    axes = np.cross(s_row[..., :3], s_col[..., :3])
    length = np.linalg.norm(axes, axis=-1, keepdims=True)
    if length.min() <= 1e-14 * max(1.0, float(np.abs(Fp[..., :3]).max())) ** 2:
        i, j = (int(k) for k in np.unravel_index(np.argmin(length[..., 0]), length.shape[:2]))
        raise GeometryError(f"the re-weighted support structure degenerates at vertex ({i}, {j})",
                            element=f"vertex ({i}, {j})")
    return axes / length, w


def _check_indices(idx: Sequence[int], count: int, what: str) -> np.ndarray:
    k = np.asarray(list(idx), dtype=np.int64)
    if k.ndim != 1:
        raise GeometryError(f"{what} indices must be a flat list")
    bad = k[(k < 0) | (k >= count)]
    if len(bad):
        raise GeometryError(f"{what} {int(bad[0])} does not exist (the mesh has {count} {what}s, 0..{count - 1})",
                            element=f"{what} {int(bad[0])}")
    if len(np.unique(k)) >= count:
        raise GeometryError(f"deleting all {count} {what}s leaves no mesh")
    return np.unique(k)


def delete_face_rows(grid: QuadGrid, rows: Sequence[int]) -> QuadGrid:
    """Delete rows of the face image (Remark 3.2): the mesh faces ``f[r, :]`` for ``r`` in ``rows``.

    The two vertex rows of a deleted face row merge into one row in the plane
    ``U_r + U_{r+1}`` (weighted sum); the rest of the face planes are kept and
    the result is a PP mesh with ``m − len(rows)`` rows of faces.
    """
    F = extended_face_image_of(grid)
    k = _check_indices(rows, F.shape[0] - 2, "face row")
    return grid_from_extended(np.delete(F, k + 1, axis=0))


def delete_face_cols(grid: QuadGrid, cols: Sequence[int]) -> QuadGrid:
    """Delete columns of the face image (Remark 3.2), see :func:`delete_face_rows`."""
    F = extended_face_image_of(grid)
    k = _check_indices(cols, F.shape[1] - 2, "face column")
    return grid_from_extended(np.delete(F, k + 1, axis=1))


def multinet(grid: QuadGrid, step_u: int = 2, step_v: int = 2) -> QuadGrid:
    """Keep every ``step_u``-th row and ``step_v``-th column of faces (from the first): a coarser PP
    mesh whose faces are a subset of the original face planes (Remark 3.2)."""
    for name, step in (("step_u", step_u), ("step_v", step_v)):
        if not isinstance(step, (int, np.integer)) or step < 1:
            raise GeometryError(f"{name} must be a positive integer, got {step!r}")
    F = extended_face_image_of(grid)
    m, n = F.shape[0] - 2, F.shape[1] - 2
    keep_a = np.concatenate([[0], 1 + np.arange(0, m, step_u), [m + 1]])
    keep_b = np.concatenate([[0], 1 + np.arange(0, n, step_v), [n + 1]])
    return grid_from_extended(F[keep_a][:, keep_b])
