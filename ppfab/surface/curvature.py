"""The fundamental forms of a height field and what a net's quads make of them: principal curvatures and
directions, and the twist of a quad's two directions in the second fundamental form (0: conjugate).

For ``z = f(x, y)`` with ``p = ∇f``: ``I = 1 + p pᵀ`` and ``II = ∇²f / sqrt(1 + |p|²)`` in the plan
coordinates; the principal curvatures and directions solve ``II v = κ I v``.

Examples
--------
>>> import numpy as np
>>> I = np.eye(2)[None]; II = np.array([[[0.02, 0.0], [0.0, -0.01]]])
>>> k1, k2, d1, d2 = principal(I, II)
>>> float(k1[0]), float(k2[0]), np.abs(d1[0]).tolist()
(0.02, -0.01, [1.0, 0.0])
"""

from __future__ import annotations

import numpy as np

from .heightfield import HeightField


def forms(hf: HeightField, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``I, II`` at plan points: each ``(..., 2, 2)`` (II in 1/mm per unit plan length squared)."""
    fx, fy = hf.fx(x, y), hf.fy(x, y)
    fxx, fxy, fyy = hf.fxx(x, y), hf.fxy(x, y), hf.fyy(x, y)
    w = np.sqrt(1.0 + fx * fx + fy * fy)
    first = np.stack([np.stack([1 + fx * fx, fx * fy], -1), np.stack([fx * fy, 1 + fy * fy], -1)], -2)
    second = np.stack([np.stack([fxx, fxy], -1), np.stack([fxy, fyy], -1)], -2) / w[..., None, None]
    return first, second


def principal(first: np.ndarray, second: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Principal curvatures ``k1 >= k2`` (``(...,)``) and their plan directions ``d1, d2`` (``(..., 2)``, unit
    in plan) of ``II v = κ I v``."""
    c = np.linalg.cholesky(first)                          # I = C Cᵀ
    ci = np.linalg.inv(c)
    sym = ci @ second @ np.swapaxes(ci, -1, -2)            # C⁻¹ II C⁻ᵀ, symmetric
    k, u = np.linalg.eigh(sym)                             # ascending
    v = np.swapaxes(ci, -1, -2) @ u                        # back to plan directions
    d1, d2 = v[..., :, 1], v[..., :, 0]
    d1 = d1 / np.linalg.norm(d1, axis=-1, keepdims=True)
    d2 = d2 / np.linalg.norm(d2, axis=-1, keepdims=True)
    return k[..., 1], k[..., 0], d1, d2


def quad_twist(hf: HeightField, local: np.ndarray) -> np.ndarray:
    """Per quad of plan-frame corners ``local (F, 4, 3)`` (order ``v[i,j], v[i+1,j], v[i+1,j+1], v[i,j+1]``):
    ``|II(a, b)| / (|a|_I |b|_I max|κ|)`` at its centre, ``a``, ``b`` its mean edges of the two families in
    plan; 0 for a conjugate pair, up to 1."""
    c = np.asarray(local, dtype=float)
    a = 0.5 * ((c[:, 3] - c[:, 0]) + (c[:, 2] - c[:, 1]))[:, :2]
    b = 0.5 * ((c[:, 1] - c[:, 0]) + (c[:, 2] - c[:, 3]))[:, :2]
    m = c.mean(axis=1)
    first, second = forms(hf, m[:, 0], m[:, 1])
    k1, k2, _, _ = principal(first, second)
    kmax = np.maximum(np.abs(k1), np.abs(k2))
    na = np.sqrt(np.einsum("fi,fij,fj->f", a, first, a))
    nb = np.sqrt(np.einsum("fi,fij,fj->f", b, first, b))
    twist = np.abs(np.einsum("fi,fij,fj->f", a, second, b))
    out: np.ndarray = twist / np.maximum(na * nb * kmax, 1e-300)
    return np.where(kmax > 0, out, 0.0)
