"""The damped normal equations of Levenberg–Marquardt, solved sparsely.

Each LM step solves ``(JᵀJ + μI) h = −Jᵀr`` [Madsen et al. 2004, eq. 3.13].
The face normals are the last ``3F`` unknowns and every residual touches at
most one of them, so their block ``A_zz`` of ``JᵀJ`` is block-diagonal with
``3 × 3`` blocks.  They are eliminated exactly (Schur complement, as in
bundle adjustment)::

    S = A_yy + μI − A_yz (A_zz + μI)⁻¹ A_zy,      S h_y = −g_y + A_yz (A_zz + μI)⁻¹ g_z,
    h_z = (A_zz + μI)⁻¹ (−g_z − A_zy h_y),

leaving a system in the vertices (and support-plane normals, if they are
unknowns) only, which is factorised with SuperLU (``scipy.sparse.linalg.splu``,
no pivoting since ``S`` is symmetric positive definite).  The fill-reducing
ordering is computed once per problem on the graph of 3 × 3 blocks (minimum
degree on ``Aᵀ + A`` of the block graph, each vertex's three coordinates kept
together), which gives less fill than ordering the scalar matrix, and reused
for every factorisation since the sparsity pattern never changes.
A rejected step only changes ``μ``: ``JᵀJ`` and ``Jᵀr`` are kept.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import splu

from ..errors import GeometryError


class BlockOrdering:
    """A fill-reducing symmetric permutation of ``S``, computed on first use and then reused."""

    def __init__(self):
        self.perm: np.ndarray | None = None

    def get(self, s: sparse.spmatrix) -> np.ndarray:
        if self.perm is None or len(self.perm) != s.shape[0]:
            self.perm = block_ordering(s)
        return self.perm


def block_ordering(s: sparse.spmatrix, block: int = 3) -> np.ndarray:
    """Permutation ``p`` (``S[p][:, p]`` has little fill) from minimum degree on the block graph of ``S``.

    Unknowns are grouped in consecutive blocks of ``block`` (a vertex's coordinates, a normal); a
    trailing group smaller than ``block`` keeps its own node.
    """
    n = s.shape[0]
    nb = -(-n // block)
    coo = sparse.coo_matrix(s)
    g = sparse.coo_matrix((np.ones(coo.nnz), (coo.row // block, coo.col // block)), shape=(nb, nb)).tocsr()
    g.data[:] = -1.0
    g = g + g.T
    g.setdiag(0.0)
    deg = -np.asarray(g.sum(axis=1)).ravel()
    lap = sparse.csc_matrix(g + sparse.diags(deg + 1.0))          # SPD with the block graph's pattern
    lu = splu(lap, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    order = np.argsort(lu.perm_c)
    p = (block * order[:, None] + np.arange(block)).ravel()
    return p[p < n]


class DampedSystem:
    """``JᵀJ``, ``Jᵀr`` of one linearisation, solvable for any damping ``μ``.

    Parameters
    ----------
    jac : (R, n) sparse Jacobian, the last ``n_block`` columns being ``3 × 3``-block-separable unknowns
    r : (R,) residual
    n_block : number of trailing unknowns eliminated by the Schur complement (multiple of 3)
    """

    def __init__(self, jac: sparse.spmatrix, r: np.ndarray, n_block: int = 0,
                 ordering: BlockOrdering | None = None):
        jac = sparse.csc_matrix(jac)
        self.ordering = ordering or BlockOrdering()
        n = jac.shape[1]
        self.n = n
        self.ny = ny = n - n_block
        self.nz = n_block
        self.g = np.asarray(jac.T @ r).ravel()
        jy = jac[:, :ny]
        self.a_yy = (jy.T @ jy).tocsr()
        self.diag_max = float(self.a_yy.diagonal().max()) if ny else 0.0
        if n_block:
            jz = jac[:, ny:]
            self.a_yz = (jy.T @ jz).tocsr()
            a_zz = (jz.T @ jz).tobsr(blocksize=(3, 3))
            nb = n_block // 3
            if a_zz.nnz // 9 != nb or not np.array_equal(a_zz.indices, np.arange(nb)):
                raise GeometryError("internal: the face-normal block of JᵀJ is not block-diagonal")
            self.blocks = np.array(a_zz.data)
            self.diag_max = max(self.diag_max, float(np.einsum("fii->fi", self.blocks).max()))

    def solve(self, mu: float) -> np.ndarray:
        """The step ``h (n,)`` with ``(JᵀJ + μI) h = −Jᵀr``."""
        ny = self.ny
        g_y = self.g[:ny]
        s = self.a_yy + mu * sparse.identity(ny, format="csr")
        rhs = -g_y
        if self.nz:
            nb = self.nz // 3
            binv = np.linalg.inv(self.blocks + mu * np.eye(3))
            bd = sparse.bsr_matrix((binv, np.arange(nb), np.arange(nb + 1)), shape=(self.nz, self.nz)).tocsr()
            a_yz = self.a_yz
            s = s - (a_yz @ bd @ a_yz.T)
            g_z = self.g[ny:]
            rhs = rhs + a_yz @ (bd @ g_z)
        h_y = self._factor_solve(s, rhs) if ny else np.zeros(0)
        if not self.nz:
            return h_y
        h_z = -np.einsum("fij,fj->fi", binv, (self.g[ny:] + self.a_yz.T @ h_y).reshape(-1, 3)).ravel()
        return np.concatenate([h_y, h_z])

    def _factor_solve(self, s: sparse.spmatrix, rhs: np.ndarray) -> np.ndarray:
        s = sparse.csr_matrix(s)
        p = self.ordering.get(s)
        sp = sparse.csc_matrix(s[p][:, p])
        lu = splu(sp, permc_spec="NATURAL", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        out = np.empty_like(rhs)
        out[p] = lu.solve(rhs[p])
        return out

    def predicted_decrease(self, h: np.ndarray, mu: float) -> float:
        """``L(0) − L(h) = hᵀ(μh − g)`` for the energy ``‖r‖²`` (Madsen et al. eq. 3.14, doubled)."""
        return float(h @ (mu * h - self.g))
