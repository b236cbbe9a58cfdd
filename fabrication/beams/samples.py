"""Sample meshes in millimetres for tests, benchmarks and examples of the beam layer.

:func:`sample_pp_grid` is a genuine PP vault built from its face image (eq. 7/8),
the same family of shapes as the bundled default design: the tangent planes of
the translational paraboloid ``z = H − x²/(2R_x) − y²/(2R_y)`` plus small bending
terms so that neither family of support planes is parallel.
"""

from __future__ import annotations

import numpy as np

from ppfab.faceimage import pp_from_curves
from ppfab.mesh import QuadGrid
from ppfab.similarity import transform


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
        axes fan out (about ±8° at the edges for ``tilt = 1``) instead of being all vertical

    Returns
    -------
    QuadGrid in mm with ``support_u``, ``support_w`` and axes; face normals (corner order) point up.
    """
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
    return transform(pp_from_curves(g, h, u, v), scale=1000.0)
