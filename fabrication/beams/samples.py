"""Sample meshes in millimetres for tests, benchmarks and examples of the beam layer.

* :func:`sample_pp_grid` — a genuine PP vault built from its face image (eq. 7/8):
  the tangent planes of the translational paraboloid ``z = H − x²/(2R_x) − y²/(2R_y)``
  plus small terms that turn and tilt the support planes.
* :func:`sample_p_grid` — an exact P mesh (planar faces, rows planar, columns not):
  the same face image with trapezoid faces ``F[i+1, j] = F[i, j] + λ_ij U_i``
  instead of parallelograms (Prop. 3.1).
* :func:`sample_conical_grid` — a surface of revolution (conical, and PP with
  horizontal and meridian planes).
"""

from __future__ import annotations

import numpy as np

from ppfab import planes as pl
from ppfab.faceimage import pp_from_curves, sample_extended
from ppfab.mesh import QuadGrid
from ppfab.transforms.similarity import transform


def _vault(faces_u: int, faces_v: int, spacing: float, bend: float, tilt: float):
    s = spacing / 1000.0
    lx, ly = faces_u * s / 2.0, faces_v * s / 2.0
    rx, ry = 2.7 * lx, 2.7 * ly
    h0 = 0.3 * (lx * lx / (2 * rx) + ly * ly / (2 * ry)) + 4.0
    bx, by = bend * 0.0015 / lx, bend * 0.0015 / ly
    cx, cy = bend * 0.005 / lx ** 2, bend * 0.005 / ly ** 2
    tx, ty = -tilt * 0.025 / lx ** 2, -tilt * 0.025 / ly ** 2

    def g(u):
        return np.stack([u / rx, bx * u * u, 0.5 + tx * u * u, -u * u / (2 * rx) + cx * u ** 3], axis=1)

    def h(v):
        return np.stack([by * v * v, v / ry, 0.5 + ty * v * v, -h0 - v * v / (2 * ry) - cy * v ** 3], axis=1)

    u = np.linspace(-lx + s / 2, lx - s / 2, faces_u)
    v = np.linspace(-ly + s / 2, ly - s / 2, faces_v)
    return g, h, u, v


def sample_pp_grid(faces_u: int = 20, faces_v: int = 30, spacing: float = 1500.0, bend: float = 1.0,
                   tilt: float = 1.0) -> QuadGrid:
    """A PP vault of ``faces_u × faces_v`` faces about ``spacing`` mm apart (rows ``v[i, :]`` in ``U_i``).

    Parameters
    ----------
    faces_u, faces_v : number of faces along ``i`` and ``j``
    spacing : approximate vertex spacing, mm
    bend : scale of the terms that turn the support planes about the vertical (0 and ``tilt`` 0 give
        a translational surface whose ``U_i`` are all parallel, like its ``W_j``)
    tilt : scale of the terms that tilt the support planes out of the vertical, so that the node
        axes fan out (about ±13° at the edges for ``tilt = 1``) instead of being all vertical

    Returns
    -------
    QuadGrid in mm with ``support_u``, ``support_w`` and axes; face normals (corner order) point up.
    """
    g, h, u, v = _vault(faces_u, faces_v, spacing, bend, tilt)
    return transform(pp_from_curves(g, h, u, v), scale=1000.0)


def sample_p_grid(faces_u: int = 8, faces_v: int = 10, spacing: float = 1500.0, shear: float = 0.3) -> QuadGrid:
    """An exact P mesh in mm: planar faces, rows ``v[i, :]`` in planes ``U_i``, columns not planar.

    Face image (extended by ghost faces, Prop. 3.1): ``F[0, :]`` and ``U_i`` from the vault of
    :func:`sample_pp_grid`; ``F[i+1, j] = F[i, j] + λ_ij U_i`` with
    ``λ_ij = 1 + shear·sin(π j/(n+1))·(i − m/2)/m`` (``shear = 0`` gives the PP vault back);
    vertex ``v[i, j] = F[i, j] ∩ F[i, j+1] ∩ U_i``.  The grid carries ``support_u``.
    """
    g, h, u, v = _vault(faces_u, faces_v, spacing, 1.0, 1.0)
    ge, he = sample_extended(g, u), sample_extended(h, v)
    U = ge[1:] - ge[:-1]                                # (m+1, 4)
    m1, nb = len(U), len(he)
    ii = np.arange(m1)[:, None]
    jj = np.arange(nb)[None, :]
    lam = 1.0 + shear * np.sin(np.pi * jj / (nb - 1)) * (ii - (m1 - 1) / 2) / (m1 - 1)
    F = np.zeros((m1 + 1, nb, 4))
    F[0] = ge[0] + he
    for i in range(m1):
        F[i + 1] = F[i] + lam[i][:, None] * U[i]
    verts = pl.intersect_three(F[:-1, :-1], F[:-1, 1:], np.broadcast_to(U[:, None, :], (m1, nb - 1, 4)))
    return transform(QuadGrid(verts, support_u=U), scale=1000.0)


def sample_conical_grid(rows: int = 8, cols: int = 12, radius: float = 6000.0, sweep_deg: float = 120.0
                        ) -> QuadGrid:
    """A surface of revolution in mm (``rows × cols`` faces): rows are parallel circles, columns
    meridians.  Every such planar-quad mesh is conical (by symmetry the four faces at a vertex touch a
    cone whose axis lies in the meridian plane).  Face normals point away from the rotation axis.
    ``sweep_deg = 360`` gives a closed grid (rows are loops, ``cols`` columns)."""
    closed = abs(sweep_deg - 360.0) < 1e-9
    t = np.linspace(-1.0, 1.0, rows + 1)
    r = radius * (1.0 + 0.25 * np.cos(1.3 * t))
    z = radius * (0.8 * t + 0.15 * t * t)
    phi = np.radians(np.linspace(0.0, sweep_deg, cols + 1))
    if closed:
        phi = phi[:-1]
    v = np.stack([r[:, None] * np.cos(phi)[None], r[:, None] * np.sin(phi)[None],
                  np.broadcast_to(z[:, None], (rows + 1, len(phi)))], axis=-1)
    grid = QuadGrid(v, closed=closed)
    c = grid.face_corners[0, 0]
    n = np.cross(c[2] - c[0], c[3] - c[1])
    centre = c.mean(axis=0)
    if n @ np.array([centre[0], centre[1], 0.0]) < 0:
        grid = QuadGrid(v[:, ::-1].copy(), closed=closed)
    return grid
