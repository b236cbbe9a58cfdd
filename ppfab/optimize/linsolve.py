"""The damped normal equations of Levenberg–Marquardt, solved sparsely.

Each LM step solves ``(JᵀJ + μI) h = −Jᵀr`` [Madsen et al. 2004, eq. 3.13].
The face normals are the last ``3F`` unknowns and every residual touches at
most one of them, so their block ``A_zz`` of ``JᵀJ`` is block-diagonal with
``3 × 3`` blocks.  They are eliminated exactly (Schur complement, as in
bundle adjustment)::

    S = A_yy + μI − A_yz (A_zz + μI)⁻¹ A_zy,      S h_y = −g_y + A_yz (A_zz + μI)⁻¹ g_z,
    h_z = (A_zz + μI)⁻¹ (−g_z − A_zy h_y),

leaving a symmetric positive definite system ``S (n_y, n_y)`` in the vertices
(and support-plane normals, if they are unknowns) only.

How ``S`` is solved (:class:`FactorCache`):

* **Ordering.** A nested-dissection ordering of the graph of ``3 × 3`` blocks
  (level structures, :mod:`ppfab.optimize.ordering`; each vertex's three coordinates stay together) is
  computed once per problem — the sparsity pattern of ``S`` never changes — and
  reused for every factorisation.  No factorisation is spent on finding it.
* **Factorisation.** ``S`` is factorised by MKL PARDISO as a real symmetric positive definite matrix (its
  upper triangle, PARDISO's own METIS ordering) when ``pypardiso`` is installed (``pip install
  ppfab[fast]``), else by SuperLU (``scipy.sparse.linalg.splu``
  in symmetric mode, natural order on the permuted matrix, no pivoting: ``S`` is
  SPD).  Measured on single factorisations of the benchmark systems (one thread, CPU s): 30 × 30 PP with the
  support normals exact 0.050 → 0.033, 45 × 45 0.147 → 0.080, 100 × 100 projected 0.697 → 0.402 — the same
  solutions to 1e-14.  ``linear_solver`` (``[optimize]``) chooses; a PARDISO error falls back to SuperLU.
  PARDISO analyses a sparsity pattern once (phase 11, about half of a factorisation) and factorises later
  matrices of that pattern numerically only (:class:`_PardisoFactor`): the benchmark grids' runs 20–30 % faster,
  the meshes bit for bit the same.  Its settings are ppfab's (:func:`_own_settings`): no iterative refinement,
  minimum degree ordering for a system with the exact support normals, METIS otherwise (:data:`ORDERINGS`).  A sparse Cholesky was measured instead, side by side on the systems of
  the 100 × 100 and 150 × 150 benchmark grids: CHOLMOD as packaged by
  ``cholespy`` (AMD ordering) took 1.6–2.4× the time of this SuperLU
  factorisation, so it is not used (``docs/optimisation.md``).
* **Reuse after a rejected step.** A rejected step changes only ``μ`` (``JᵀJ`` and
  ``Jᵀr`` are kept), and ``S(μ')`` differs from ``S(μ)`` by ``(μ' − μ) I`` plus a change
  of the Schur term.  The factor of ``S(μ)`` is then used as the preconditioner of
  conjugate gradients on ``S(μ')`` (Saad, *Iterative methods for sparse linear
  systems*, Alg. 9.1); only when CG does not reach the relative residual
  ``cg_tol`` within ``cg_maxiter`` iterations is ``S(μ')`` factorised afresh.
* **Inexact steps on a new linearisation** (systems of at least :data:`INEXACT_MIN_UNKNOWNS` unknowns).  The
  first system of a new linearisation is solved by CG preconditioned with the kept factor of an earlier one,
  to the forcing term ``‖S h − b‖ ≤ η ‖b‖``, ``η =`` :data:`FORCING` (an inexact Newton step: Dembo,
  Eisenstat & Steihaug, *Inexact Newton methods*, SIAM J. Numer. Anal. 19, 1982; Nocedal & Wright §7.1), within
  :data:`FORCING_MAXITER` iterations, else it is factorised.  The gain ratio judges the step as any other (its
  predicted decrease is computed from ``J h``, exact for any ``h``).  A failed attempt, or a rejected inexact
  step (the solver tells, :attr:`FactorCache.inexact_ok`), stops inexact steps until the next continuation
  stage.  Measured (``benchmarks/optimize.py``, docs/optimisation.md): the 200 × 200 grid takes 3 factorisations
  instead of 9 in the same 9 iterations; on the 1,000–2,000-vertex real meshes the extra iterations inexact
  steps cost were not repaid (DOI rot4 took 189–500 iterations instead of 226 depending on ``η``), hence the
  size threshold.
A rejected step only changes ``μ``: ``JᵀJ`` and ``Jᵀr`` are kept.
"""

from __future__ import annotations

import os
import sys
import threading
from pathlib import Path
from typing import Any

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import splu

from ..errors import GeometryError
from .ordering import level_set_dissection

LINEAR_SOLVERS = ("auto", "pardiso", "superlu")

FORCING = 0.1
"""Forcing term ``η`` of the inexact Newton steps (Dembo, Eisenstat & Steihaug 1982): the first system of a new
linearisation is accepted from CG when ``‖S h − b‖ ≤ η ‖b‖``."""
FORCING_MAXITER = 6
"""CG iterations (each one solve with the kept factor) tried before a new linearisation's system is factorised."""
INEXACT_MIN_UNKNOWNS = 30_000
"""Inexact steps only for systems ``S`` of at least this many unknowns (10,000 vertices): below it a factorisation
costs few solves, and the extra iterations inexact steps can cost are not repaid."""


def _point_at_mkl() -> None:
    """Tell pypardiso where MKL's runtime library is, when it sits where pip puts it (``<prefix>/lib`` or
    ``<prefix>/Library/bin``) and nobody said otherwise: without ``PYPARDISO_MKL_RT`` pypardiso searches the
    whole installation tree for it when it is imported and for every solver it makes (0.3 s each here)."""
    if os.environ.get("PYPARDISO_MKL_RT"):
        return
    for folder, pattern in (("lib", "libmkl_rt.so*"), ("lib", "libmkl_rt*.dylib"), ("Library/bin", "mkl_rt*.dll")):
        found = sorted(Path(sys.prefix, folder).glob(pattern), key=lambda q: len(str(q)))
        if found:
            os.environ["PYPARDISO_MKL_RT"] = str(found[0])
            return


def pardiso_available() -> bool:
    """Whether MKL PARDISO can be loaded (``pypardiso`` installed with its MKL)."""
    _point_at_mkl()
    try:
        import pypardiso  # type: ignore[import-untyped]  # noqa: F401
    except Exception:                     # ImportError, or an MKL that fails to load
        return False
    return True


def resolve_solver(name: str) -> str:
    """``"pardiso"`` or ``"superlu"`` for a :data:`LINEAR_SOLVERS` name (``auto``: PARDISO when available).

    Raises :class:`GeometryError` when ``pardiso`` is asked for and cannot be loaded."""
    if name == "superlu":
        return name
    if pardiso_available():
        return "pardiso"
    if name == "pardiso":
        raise GeometryError("linear_solver = \"pardiso\" needs pypardiso (pip install ppfab[fast]); use \"auto\" "
                            "or \"superlu\"", element="linear_solver")
    return "superlu"


_LOCAL = threading.local()


def _thread_pardiso() -> Any:
    """This thread's ``pypardiso.PyPardisoSolver(mtype=2)`` (real SPD), made once (making one loads MKL).  One
    per thread, because PARDISO keeps its factor in the solver's handle (the studio's live relaxation runs beside
    other solves); a cache whose factor another solve in the thread replaced gets it refactorised by pypardiso,
    which compares the matrix before it solves."""
    solver = getattr(_LOCAL, "pardiso", None)
    if solver is None:
        from pypardiso import PyPardisoSolver

        solver = _LOCAL.pardiso = PyPardisoSolver(mtype=2)
        _one_mkl_thread(solver.libmkl)
        _own_settings(solver)
    return solver


def _own_settings(solver: Any) -> None:
    """PARDISO with its settings in ppfab's hands: with ``iparm(1) = 0`` (pypardiso's start) PARDISO fills in
    its defaults on every call and ignores any other value, so an analysis of a 1 × 1 matrix fills them once and
    ``iparm(1) = 1`` keeps them; then no iterative refinement (``iparm(8) = 0``: the default's two refinement
    steps doubled the cost of a solve on the 100² system, 19.2 against 8.7 ms, for a residual of 2e-13 instead
    of 5e-13 relative — an LM step needs neither) and :data:`ORDERINGS` chosen per system (``iparm(2)``)."""
    one = sparse.csr_matrix(np.ones((1, 1)))
    for phase in (11, -1):
        solver.set_phase(phase)
        solver._call_pardiso(one, np.zeros(1))
    solver.ppfab_metis = int(solver.get_iparm(2))          # PARDISO's default: its nested dissection (METIS)
    solver.set_iparm(1, 1)
    solver.set_iparm(8, 0)


ORDERINGS = {"metis": None, "minimum degree": 0}
"""PARDISO's fill-reducing orderings ppfab uses (``iparm(2)``; ``None``: PARDISO's default, METIS nested
dissection).  Minimum degree for a system with long-range rows (the exact support normals: each couples every
vertex of its polyline), where it factorises 1.6–2.0× faster than METIS (the 30² benchmark system 7.2 against
14.3 ms, DOS conical1 10.4 against 16.6 ms, one thread, idle machine); METIS otherwise (100²: 0.144–0.163 s
against minimum degree's 0.141–0.157 s in four runs, no difference; minimum degree fills 17 % more)."""


def _one_mkl_thread(libmkl: Any) -> None:
    """MKL on one thread in this thread (``mkl_set_num_threads_local``): PARDISO's factor depends on how many
    threads reduce it, and MKL picks that count by the machine's load (``MKL_DYNAMIC``), so an optimised mesh
    differed by 1e-10 mm between two builds of one design on a busy machine.  On one thread every build of a
    design is byte-identical, on any machine; the optimiser's benchmarks count CPU time, which one thread does
    not raise."""
    import ctypes

    fn = getattr(libmkl, "MKL_Set_Num_Threads_Local", None) or getattr(libmkl, "mkl_set_num_threads_local", None)
    if fn is not None:
        fn.argtypes = [ctypes.c_int]
        fn(1)


class _PardisoFactor:
    """A PARDISO factorisation of an SPD matrix from its upper triangle ``a (n, n)`` CSR; ``solve(b)``.

    ``solver`` is the thread's ``pypardiso.PyPardisoSolver`` (:func:`_thread_pardiso`).  PARDISO's analysis
    (phase 11: METIS ordering and symbolic factorisation, about half of a factorisation) depends only on the
    sparsity pattern, which the normal matrix keeps from one iteration to the next: the solver remembers the
    pattern it analysed and a matrix of that pattern is factorised numerically only (phase 22) — the same factor
    as a full factorisation (phase 12), bit for bit.  A pattern that differs (a barrier row switched on or off)
    is analysed afresh.  The solver holds one factor: each factorisation takes a number, and a factor whose number
    is no longer the solver's (another solve in the thread factorised since) is computed again before it solves.
    """

    def __init__(self, upper: sparse.csr_matrix, solver: Any, ordering: str = "metis"):
        self.a = upper
        self.solver = solver
        self.ordering = ordering
        self.generation = -1
        self._factorise()

    def _factorise(self) -> None:
        a, solver = self.a, self.solver
        pattern = getattr(solver, "ppfab_pattern", None)
        same = pattern is not None and pattern[2] == self.ordering and np.array_equal(pattern[0], a.indptr) \
            and np.array_equal(pattern[1], a.indices)
        if not same:
            code = ORDERINGS[self.ordering]
            solver.set_iparm(2, getattr(solver, "ppfab_metis", 2) if code is None else code)
        solver.set_phase(22 if same else 12)
        solver._call_pardiso(a, np.zeros(a.shape[0]))
        if not same:
            solver.ppfab_pattern = (a.indptr.copy(), a.indices.copy(), self.ordering)
        solver.ppfab_generation = self.generation = getattr(solver, "ppfab_generation", 0) + 1

    def solve(self, b: np.ndarray) -> np.ndarray:
        if getattr(self.solver, "ppfab_generation", None) != self.generation:
            self._factorise()
        self.solver.set_phase(33)
        return np.asarray(self.solver._call_pardiso(self.a, np.ascontiguousarray(b, dtype=float)), dtype=float)

    def free(self) -> None:
        """Nothing: the next factorisation of the same pattern reuses the solver's analysis, which releasing the
        factor's memory (phase 0) would not keep reliably; the factor's memory is taken over by the next one."""


def nested_dissection(s: sparse.spmatrix, block: int = 3, last: int = 0) -> np.ndarray:
    """Fill-reducing permutation ``p`` of ``S (n, n)`` (``S[p][:, p]`` has little fill).

    Nested dissection (:func:`~ppfab.optimize.ordering.level_set_dissection`) on the graph whose nodes are
    consecutive groups of ``block`` unknowns
    (a vertex's coordinates, a normal) and whose edges are the nonzero ``block × block`` blocks of ``S``.
    A trailing group smaller than ``block`` keeps its own node.

    The trailing ``last`` unknowns (the support normals of ``plane_solver = "exact"``, each coupled to every
    vertex of its polyline: long-range, nearly dense rows) are left out of the dissection and ordered after
    everything else, as AMD treats dense rows; the dissection would put them among the separators, where each
    joins its polyline's vertices into one clique.  Measured on the 30 × 30 and 45 × 45 PP benchmark systems:
    L + U 1.69 M → 1.01 M and 4.51 M → 2.76 M nonzeros, the factorisation 2.2–2.4× faster.
    """
    n = s.shape[0]
    if 0 < last < n:
        head = sparse.csr_matrix(s)[: n - last][:, : n - last]
        return np.concatenate([nested_dissection(head, block), np.arange(n - last, n)])
    nb = -(-n // block)
    coo = sparse.coo_matrix(s)
    g = sparse.coo_matrix((np.ones(coo.nnz), (coo.row // block, coo.col // block)), shape=(nb, nb)).tocsr()
    g = (g + g.T).tocsr()
    g.setdiag(0.0)
    g.eliminate_zeros()
    g.sort_indices()
    if nb < 2 or g.nnz == 0:
        order = np.arange(nb)
    else:
        order = level_set_dissection(g)
    p = (block * order[:, None] + np.arange(block)).ravel()
    return p[p < n]


class FactorCache:
    """The ordering and the last factorisation of ``S``, shared by the iterations of one solve.

    Parameters
    ----------
    cg_tol : relative residual ``‖S h − b‖ / ‖b‖`` at which CG on a new damping's system is accepted
    cg_maxiter : CG iterations before ``S`` is factorised afresh
    reuse : keep factors for preconditioned CG (``False``: factorise every system, the direct method)
    last : the trailing unknowns ordered last (:func:`nested_dissection`)
    solver : ``"superlu"`` or ``"pardiso"`` (:func:`resolve_solver`)
    forcing, forcing_maxiter : the inexact step's relative residual and CG iterations on a new linearisation
    inexact_min : the fewest unknowns of ``S`` for which a new linearisation may be solved inexactly

    Counters ``factorisations``, ``cg_solves`` (``inexact_solves`` of them on a new linearisation) and
    ``cg_iterations`` say how the systems were solved; ``inexact_ok`` is cleared by a failed inexact attempt
    (and by the solver after a rejected inexact step) and set again by the solver at a new stage.
    """

    def __init__(self, cg_tol: float = 1e-10, cg_maxiter: int = 12, reuse: bool = True, last: int = 0,
                 solver: str = "superlu", forcing: float = FORCING, forcing_maxiter: int = FORCING_MAXITER,
                 inexact_min: int = INEXACT_MIN_UNKNOWNS):
        self.cg_tol = cg_tol
        self.cg_maxiter = cg_maxiter
        self.reuse = reuse
        self.forcing = forcing
        self.forcing_maxiter = forcing_maxiter
        self.inexact_min = inexact_min
        self.last = last
        self.solver = solver
        self.perm: np.ndarray | None = None
        self.lu: Any = None                  # SuperLU or _PardisoFactor of the last factorised system
        self.owner: object = None            # the linearisation of the last solve
        self.factor_owner: object = None     # the linearisation whose system ``lu`` factorised
        self.factorisations = 0
        self.cg_solves = 0
        self.cg_iterations = 0
        self.inexact_solves = 0
        self.inexact_ok = True               # inexact steps allowed (until one fails; the solver allows them again)

    def _ordering(self, s: sparse.csr_matrix) -> np.ndarray:
        if self.perm is None or len(self.perm) != s.shape[0]:
            self.perm = nested_dissection(s, last=self.last)
            self.lu = None
        return self.perm

    def solve(self, s: sparse.spmatrix, rhs: np.ndarray, owner: object = None) -> np.ndarray:
        """``h`` with ``S h = rhs`` for SPD ``S (n, n)``.

        ``owner`` identifies the linearisation.  Its first system is solved inexactly by CG preconditioned with
        the kept factor of an earlier linearisation when that reaches the forcing term (below); a later system
        of the same owner (a new damping) by CG preconditioned with the factor of that owner's own system, to
        ``cg_tol``; otherwise ``S`` is factorised.
        """
        s = sparse.csr_matrix(s)
        have = self.reuse and self.lu is not None and owner is not None
        first = owner is not self.owner
        inexact = (have and first and self.inexact_ok and self.forcing_maxiter > 0     # a new linearisation
                   and s.shape[0] >= self.inexact_min)
        if have and not first and self.factor_owner is owner:
            tol, maxiter = self.cg_tol, self.cg_maxiter       # a new damping: its own factor, (nearly) exact
        elif inexact:
            tol, maxiter = self.forcing, self.forcing_maxiter
        else:
            tol, maxiter = 0.0, -1
        self.owner = owner
        if self.solver == "pardiso":                          # PARDISO orders the matrix itself
            x = self._pcg(s, rhs, tol, maxiter) if maxiter >= 0 else None
            if x is not None:
                self.inexact_solves += int(inexact)
                return x
            self.inexact_ok = self.inexact_ok and not inexact
            upper = sparse.triu(s, format="csr")
            upper.sort_indices()
            self._drop()
            try:
                self.lu = _PardisoFactor(upper, _thread_pardiso(), "minimum degree" if self.last else "metis")
            except Exception:                                 # a PARDISO error: SuperLU from now on
                self.solver, self.lu = "superlu", None          # no factor: the SuperLU path factorises
            else:
                self.factorisations += 1
                self.factor_owner = owner
                return self.lu.solve(rhs)
        p = self._ordering(s)
        sp = sparse.csr_matrix(s[p][:, p])
        b = rhs[p]
        x = self._pcg(sp, b, tol, maxiter) if maxiter >= 0 and self.lu is not None else None
        if x is None:
            self.inexact_ok = self.inexact_ok and not inexact
            self._drop()
            self.lu = splu(sparse.csc_matrix(sp), permc_spec="NATURAL", diag_pivot_thresh=0.0,
                           options={"SymmetricMode": True})
            self.factorisations += 1
            self.factor_owner = owner
            x = self.lu.solve(b)
        else:
            self.inexact_solves += int(inexact)
        out = np.empty_like(rhs)
        out[p] = x
        return out

    def _drop(self) -> None:
        """Release the kept factor (PARDISO holds its memory until told)."""
        if isinstance(self.lu, _PardisoFactor):
            self.lu.free()
        self.lu = None

    def _pcg(self, a: sparse.csr_matrix, b: np.ndarray, tol: float, maxiter: int) -> np.ndarray | None:
        """Conjugate gradients on ``a x = b`` preconditioned by the kept factor, to the relative residual ``tol``
        within ``maxiter`` iterations; ``None`` if it does not get there."""
        bn = float(np.linalg.norm(b))
        if bn == 0.0:
            return np.zeros_like(b)
        lu = self.lu
        x = lu.solve(b)                                   # the old factor's solution as the start
        r = b - a @ x
        z = lu.solve(r)
        d = z.copy()
        rz = float(r @ z)
        for k in range(maxiter + 1):
            if np.linalg.norm(r) <= tol * bn:
                self.cg_solves += 1
                self.cg_iterations += k
                return x
            if k == maxiter or not rz > 0:
                break
            ad = a @ d
            alpha = rz / float(d @ ad)
            x += alpha * d
            r -= alpha * ad
            z = lu.solve(r)
            rz_new = float(r @ z)
            d = z + (rz_new / rz) * d
            rz = rz_new
        self.cg_iterations += maxiter
        return None


class DampedSystem:
    """``JᵀJ``, ``Jᵀr`` of one linearisation, solvable for any damping ``μ``.

    Parameters
    ----------
    jac : (R, n) sparse Jacobian, the last ``n_block`` columns being ``3 × 3``-block-separable unknowns
    r : (R,) residual
    n_block : number of trailing unknowns eliminated by the Schur complement (multiple of 3)
    cache : :class:`FactorCache` shared across linearisations (ordering, factor for reuse)
    """

    def __init__(self, jac: sparse.spmatrix, r: np.ndarray, n_block: int = 0, cache: FactorCache | None = None):
        jac = sparse.csc_matrix(jac)
        jac.eliminate_zeros()            # inactive barrier rows add no coupling to the factorised system
        self.jac = jac
        self.cache = cache or FactorCache()
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
        h_y = self.cache.solve(s, rhs, owner=self) if ny else np.zeros(0)
        if not self.nz:
            return h_y
        h_z = -np.einsum("fij,fj->fi", binv, (self.g[ny:] + self.a_yz.T @ h_y).reshape(-1, 3)).ravel()
        return np.concatenate([h_y, h_z])

    def predicted_decrease(self, h: np.ndarray, mu: float = 0.0) -> float:
        """``L(0) − L(h) = ‖r‖² − ‖r + J h‖² = −2 gᵀh − ‖J h‖²`` (Madsen et al. eq. 3.14, doubled).

        Computed from ``J h`` rather than from the normal equations, so it is exact also for a step
        from an iterative solve.  (``mu`` is accepted for the old signature and not used.)
        """
        jh = self.jac @ h
        return float(-2.0 * (self.g @ h) - jh @ jh)
