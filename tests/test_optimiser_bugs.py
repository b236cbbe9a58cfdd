"""Regression tests for optimiser and transform faults: each test failed before its fix.

* ``isotropic_transform`` accepted a planar-quad mesh that is not conical and returned node axes with
  millimetres of torsion (the Laguerre transform refuses the same mesh);
* ``ppfab optimize --quiet`` hid the result line too, so a failed run printed nothing;
* ``axis_angle_max`` read 0.0 on every P run;
* a nearly conical input that lost its conicality was reported as "targets met" without a word;
* "never worse than the input" returned an iterate with δ_f 200 × the input's when δ_P dominated the score.
"""

from __future__ import annotations

import numpy as np
import pytest

from fabrication.beams.samples import sample_p_grid
from ppfab.errors import GeometryError


def face_normals_at(grid) -> np.ndarray:
    """``(m-1, n-1, 4, 3)`` unit normals of the four faces around every interior vertex (cross product of the
    diagonals of each face)."""
    v = grid.vertices
    d1 = v[1:, 1:] - v[:-1, :-1]
    d2 = v[:-1, 1:] - v[1:, :-1]
    n = np.cross(d1, d2)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return np.stack([n[:-1, :-1], n[1:, :-1], n[1:, 1:], n[:-1, 1:]], axis=-2)


def test_isotropic_transform_refuses_a_mesh_that_is_not_conical():
    """A sheared P grid (planar quads, not conical): the four unit normals at an interior vertex are not on
    one circle of the sphere (they are not coplanar: the smallest singular value of the centred 4 × 3 matrix
    is above 1e-5), so its face image has no orthogonal-node structure; the transform used to return axes
    with 3.2 mm torsion at 200 mm."""
    from ppfab.conical.cones import laguerre_transform
    from ppfab.transforms.isotropic import IsotropicMobius, isotropic_transform
    from ppfab.transforms.laguerre import LaguerreMap

    g = sample_p_grid(8, 10)
    n = face_normals_at(g)
    off_circle = np.linalg.svd(n - n.mean(axis=-2, keepdims=True), compute_uv=False)[..., 2]
    assert off_circle.max() > 1e-5
    with pytest.raises(GeometryError, match=r"^the mesh is not conical at vertex \(\d+, \d+\) \(normals off their "
                                            r"circle by [0-9.e+-]+ > 1e-06\)") as err:
        isotropic_transform(g, IsotropicMobius.shear(1.0, [0.01, 0.0, 0.0], 0.0))
    assert err.value.value > 1e-5 and "\n" not in str(err.value)
    with pytest.raises(GeometryError, match="not conical"):                  # the same refusal as Laguerre's
        laguerre_transform(g, LaguerreMap(np.eye(4)))
