"""Editing conical P meshes by a Möbius transform of their normals plus parallelity (paper §4.3).

Every face ``f`` of a conical mesh has a homogeneous normal ``N_f = (n_f : 1)``
(``n_f`` unit, ``N_fᵀ J N_f = 0``) and the plane ``[x; d_f]ᵀ N_f = 0``.  A transform
moves vertex ``v`` to ``v̄`` and the face to ``d̄_f`` with (eq. 17)::

    [v̄; d̄_f]ᵀ · A N_f = 0   for every vertex v of face f,     Aᵀ J A = J.

For a fixed Lorentz matrix ``A`` this is linear.  Its solutions are exactly the
meshes whose faces have the Möbius-transformed normals: the Laguerre images of
the mesh and all meshes parallel to them — conical, with the same planar
polyline families (§4.2, §4.3).  :class:`ConicalEditor` imposes (17) as the
equality constraints of one sparse KKT solve — to the solver's rounding, not
exactly: :attr:`EditResult.constraint_residual` reports it (below 1e-12 of the
mesh size on the test grids), and the conical residual of the result is of the
same order on an exactly conical input (1e-13 … 5e-11 rad on the test grids; 5e-9 rad
has been measured on others); an input that is only nearly conical stays
only as conical as its normals (§4.3 keeps them, up to ``A``) — and
picks, among those meshes, the one closest to user handles plus
regularisers (proximity to the previous state, fairness).  Only ``d̄`` is
unknown: at each vertex the four face planes must be concurrent,
``λ_vᵀ d̄_v = 0`` with ``λ_v`` the left null vector of the 4×3 matrix of their unit
normals, and then ``v̄ = −N_v⁺ d̄_v``; the equality-constrained least-squares
problem is one sparse KKT solve.

With ``A`` free (:meth:`ConicalEditor.fit`), (17) becomes bilinear: damped
Gauss–Newton steps on ``(v̄, d̄, A)`` treat (17) as a weighted term; the step of
``A`` is taken in the tangent space of the Lorentz group (the paper fits ``A``
without the constraint; a full 16-entry step mostly scales ``A`` and stalls) and
the matrix is projected back onto ``Aᵀ J A = J`` by the Minkowski polar
decomposition (:func:`ppfab.laguerre.project_lorentz`); the result is finished by
the constrained fixed-``A`` solve.  :func:`fit_lorentz` is the paper's unconstrained
linear fit of ``A`` followed by the projection, for normals given directly.

Boundary vertices use the grid's ghost faces (:func:`ppfab.conical.extended_planes`),
so every vertex has four planes.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu, spsolve

from ppfab.conical.cones import laguerre_transform, _refit, axis_of_normals, extended_planes
from ppfab.errors import GeometryError
from ppfab.folds import check_folds
from ppfab.transforms.laguerre import J, LaguerreMap, lorentz_residual, project_lorentz
from ppfab.mesh import QuadGrid


@dataclass(frozen=True)
class EditResult:
    """Result of a §4.3 edit.

    ``A`` acts on the paper's homogeneous normals ``(n : 1)``; ``constraint_residual`` is the
    largest distance of a vertex from one of its (transformed) face planes (eq. 17, mesh units);
    ``handle_residual`` the largest distance of a handle vertex from its target.
    """

    grid: QuadGrid
    A: np.ndarray
    converged: bool
    iterations: int
    history: list = field(default_factory=list)
    message: str = ""
    constraint_residual: float = 0.0
    handle_residual: float = 0.0
    lorentz_residual: float = 0.0


_PAIRS = [(0, 1), (0, 2), (1, 2), (0, 3), (1, 3), (2, 3)]


def _antisymmetric(w: np.ndarray) -> np.ndarray:
    """The antisymmetric 4×4 matrix with entries ``w`` at ``_PAIRS`` (``J S`` spans the Lorentz algebra)."""
    S = np.zeros((4, 4))
    for k, (p, q) in enumerate(_PAIRS):
        S[p, q], S[q, p] = w[k], -w[k]
    return S


def _unit_normals(A: np.ndarray, n: np.ndarray) -> np.ndarray:
    """``(A N)[:3] / (A N)[3]`` for ``N = (n, 1)`` — the Möbius image of unit normals ``(..., 3)``."""
    N = np.concatenate([n, np.ones(n.shape[:-1] + (1,))], axis=-1) @ np.asarray(A, float).T
    if np.any(np.abs(N[..., 3]) <= 1e-12 * np.linalg.norm(N[..., :3], axis=-1)):
        raise GeometryError("the Möbius transform sends a face normal to infinity (A N has no 4th coordinate)")
    return N[..., :3] / N[..., 3:4]


class ConicalEditor:
    """The linear machinery of §4.3 for one conical grid (set up once, solved many times).

    Parameters
    ----------
    grid : a conical grid (P or PP); its extended face planes give four planes at every vertex
    proximity : weight of ``Σ |v̄ − v_prev|²`` (keeps the solution near the previous state)
    fairness : weight of the squared second differences along rows and columns
    """

    def __init__(self, grid: QuadGrid, proximity: float = 1e-3, fairness: float = 1e-3):
        self.grid = grid
        self.E = extended_planes(grid)
        rows, cols = grid.shape
        self.shape = (rows, cols)
        er, ec = self.E.shape[:2]
        if grid.closed:
            # column b of the extended array is face column (b − 1) mod cols: one unknown per face
            ids = np.arange(er * (ec - 1)).reshape(er, ec - 1)
            pid = ids[:, (np.arange(ec) - 1) % (ec - 1)]
            unique = self.E[:, 1:].reshape(-1, 4)
        else:
            pid = np.arange(er * ec).reshape(er, ec)
            unique = self.E.reshape(-1, 4)
        self.plane_index = pid
        self.idx = np.stack([pid[:-1, :-1], pid[1:, :-1], pid[1:, 1:], pid[:-1, 1:]], axis=-1).reshape(-1, 4)
        self.n0 = unique[:, :3]
        self.n_planes = len(self.n0)
        self.n_vertices = rows * cols
        self.proximity = float(proximity)
        self.fairness = float(fairness)
        self.D = self._second_differences()
        diag = np.linalg.norm(np.ptp(grid.vertices.reshape(-1, 3), axis=0))
        self.scale = float(diag) if diag > 0 else 1.0

    def _second_differences(self) -> sp.csr_matrix:
        """Sparse ``(k, V)`` second differences along rows and columns (rows wrap when closed)."""
        rows, cols = self.shape
        vid = np.arange(rows * cols).reshape(rows, cols)
        trip = []
        if cols >= 3 or self.grid.closed:
            c = vid if self.grid.closed else vid[:, 1:-1]
            left = np.roll(vid, 1, axis=1) if self.grid.closed else vid[:, :-2]
            right = np.roll(vid, -1, axis=1) if self.grid.closed else vid[:, 2:]
            trip.append((left.ravel(), c.ravel(), right.ravel()))
        if rows >= 3:
            trip.append((vid[:-2].ravel(), vid[1:-1].ravel(), vid[2:].ravel()))
        if not trip:
            return sp.csr_matrix((0, rows * cols))
        a = np.concatenate([t[0] for t in trip])
        b = np.concatenate([t[1] for t in trip])
        c = np.concatenate([t[2] for t in trip])
        k = np.arange(len(a))
        return sp.csr_matrix((np.concatenate([np.ones_like(k), -2 * np.ones_like(k), np.ones_like(k)]).astype(float),
                              (np.concatenate([k, k, k]), np.concatenate([a, b, c]))), shape=(len(a), rows * cols))

    # -- pieces -------------------------------------------------------------------------------
    def _targets(self, handles) -> tuple[np.ndarray, np.ndarray]:
        if handles is None:
            return np.zeros(0, dtype=np.int64), np.zeros((0, 3))
        if isinstance(handles, dict):
            keys = list(handles)
            ij = np.asarray(keys, dtype=np.int64).reshape(-1, 2)
            pos = np.asarray([handles[k] for k in keys], dtype=float).reshape(-1, 3)
        else:
            ij, pos = (np.asarray(handles[0], dtype=np.int64).reshape(-1, 2), np.asarray(handles[1], float).reshape(-1, 3))
        rows, cols = self.shape
        if len(ij) and (ij.min() < 0 or np.any(ij[:, 0] >= rows) or np.any(ij[:, 1] >= cols)):
            raise GeometryError(f"a handle names a vertex outside the {rows} × {cols} grid")
        return ij[:, 0] * cols + ij[:, 1], pos

    def _position_map(self, nbar: np.ndarray) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """``x = −N⁺ d`` (sparse ``(3V, P)``) and the concurrency constraints ``λᵀ d = 0`` (sparse ``(V, P)``)."""
        Nv = nbar[self.idx]                                          # (V, 4, 3)
        U, s, Vt = np.linalg.svd(Nv)
        if np.any(s[:, 2] <= 1e-9 * s[:, 0]):
            k = int(np.argmax(s[:, 2] <= 1e-9 * s[:, 0]))
            raise GeometryError(f"the four face normals at vertex {divmod(k, self.shape[1])} lie in one plane: "
                                f"the vertex is undefined", element=f"vertex {divmod(k, self.shape[1])}")
        pinv = np.einsum("vji,vj,vkj->vik", Vt[:, :3, :], 1.0 / s, U[:, :, :3])   # (V, 3, 4)
        lam = U[:, :, 3]                                                          # (V, 4)
        V = self.n_vertices
        r = np.repeat(np.arange(3 * V).reshape(V, 3), 4, axis=1)                  # (V, 12) rows
        c = np.tile(self.idx, (1, 3))                                              # (V, 12) cols
        Bm = sp.csr_matrix((-pinv.reshape(V, 12).ravel(), (r.ravel(), c.ravel())), shape=(3 * V, self.n_planes))
        K = sp.csr_matrix((lam.ravel(), (np.repeat(np.arange(V), 4), self.idx.ravel())), shape=(V, self.n_planes))
        return Bm, K

    def _objective(self, handles, x_prev: np.ndarray, w_handles: float):
        """``Σ w_i |R_i x − t_i|²`` as (sparse R, t, sqrt-weights) over stacked vertex coordinates ``x (3V,)``."""
        V = self.n_vertices
        hid, hpos = self._targets(handles)
        blocks, rhs = [], []
        if len(hid):
            sel = sp.csr_matrix((np.ones(3 * len(hid)), (np.arange(3 * len(hid)),
                                 (3 * hid[:, None] + np.arange(3)).ravel())), shape=(3 * len(hid), 3 * V))
            blocks.append(np.sqrt(w_handles) * sel)
            rhs.append(np.sqrt(w_handles) * hpos.ravel())
        if self.proximity > 0:
            blocks.append(np.sqrt(self.proximity) * sp.identity(3 * V, format="csr"))
            rhs.append(np.sqrt(self.proximity) * x_prev.ravel())
        if self.fairness > 0 and self.D.shape[0]:
            D3 = sp.kron(self.D, sp.identity(3), format="csr")
            blocks.append(np.sqrt(self.fairness) * D3)
            rhs.append(np.zeros(D3.shape[0]))
        if not blocks:
            raise GeometryError("nothing to solve for: give handles, proximity or fairness")
        return sp.vstack(blocks, format="csr"), np.concatenate(rhs)

    # -- solves ----------------------------------------------------------------------------------
    def solve_fixed(self, A: np.ndarray | None = None, handles=None, w_handles: float = 1.0,
                    previous: np.ndarray | None = None) -> EditResult:
        """(17) for a fixed Lorentz matrix ``A`` as hard constraints (to rounding, see the module docstring;
        identity: parallel meshes); closest to handles + regularisers.

        Parameters
        ----------
        A : (4, 4) Lorentz matrix acting on ``(n : 1)`` (default identity)
        handles : ``{(i, j): (x, y, z)}`` or ``(ij (k, 2), positions (k, 3))`` — target vertex positions
        w_handles : weight of the handles relative to proximity and fairness
        previous : (rows, cols, 3) previous state for the proximity term (default: the Laguerre image of
            the grid under the map whose Möbius part is ``A``, i.e. the grid itself for ``A = I``)
        """
        A = np.eye(4) if A is None else np.asarray(A, dtype=float)
        if lorentz_residual(A) > 1e-8 * max(1.0, float(np.abs(A).max()) ** 2):
            raise GeometryError(f"A is not a Lorentz matrix (|AᵀJA − J| = {lorentz_residual(A):.3g}); project it first")
        nbar = _unit_normals(A, self.n0)
        Bm, K = self._position_map(nbar)
        if previous is None:
            try:
                prev = laguerre_transform(self.grid, LaguerreMap(J @ A @ J), check=False).vertices
            except GeometryError:
                prev = self.grid.vertices
        else:
            prev = np.asarray(previous, float)
        R, t = self._objective(handles, prev.reshape(-1, 3), w_handles)
        RB = (R @ Bm).tocsr()
        Q = (RB.T @ RB).tocsc()
        c = RB.T @ t
        n = self.n_planes
        kkt = sp.bmat([[Q, K.T], [K, None]], format="csc")
        rhs = np.concatenate([c, np.zeros(K.shape[0])])
        sol = _solve_kkt(Q, K, kkt, rhs)
        d = sol[:n]
        x = (Bm @ d).reshape(self.shape + (3,))
        return self._result(A, nbar, d, x, handles, True, 1, [], "constrained solve of eq. (17) for fixed A")

    def fit(self, handles, A0: np.ndarray | None = None, w_handles: float = 1.0, w_planes: float = 1.0,
            iterations: int = 50, tol: float = 1e-12) -> EditResult:
        """Handles with ``A`` free (§4.3): damped Gauss–Newton steps on ``(v̄, d̄, A)`` with (17) as a
        weighted term; ``A`` moves along the Lorentz algebra (``A ← A (I + J S)``, ``S`` antisymmetric) and
        is projected back onto ``Aᵀ J A = J`` by the Minkowski polar decomposition after each step; then
        the constrained fixed-``A`` solve.

        ``d̄`` is the offset of the unit plane (the paper's homogeneous ``d_f``), so it keeps its meaning
        when ``A`` is rescaled or projected.
        """
        A = np.eye(4) if A0 is None else np.asarray(A0, float)
        start = self.solve_fixed(A, handles, w_handles)
        x = start.grid.vertices.reshape(-1, 3).copy()
        Eext = start.grid.extended_face_planes
        assert Eext is not None
        d = (Eext[:, 1:] if self.grid.closed else Eext).reshape(-1, 4)[:, 3].copy()
        V, P = self.n_vertices, self.n_planes
        N = np.concatenate([self.n0, np.ones((P, 1))], axis=1)                    # (P, 4) homogeneous normals
        f = self.idx.ravel()                                                       # plane of each incidence
        vv = np.repeat(np.arange(V), 4)
        R, t = self._objective(handles, self.grid.vertices.reshape(-1, 3), w_handles)
        Rz = sp.hstack([R, sp.csr_matrix((R.shape[0], P + 6))], format="csr")
        wp = np.sqrt(w_planes)
        history, converged, it, mu = [], False, 0, 1e-6

        def energy(x, d, A):
            AN = N @ A.T
            r = (np.einsum("ki,ki->k", AN[f, :3], x[vv]) + AN[f, 3] * d[f]) / AN[f, 3]
            e = R @ x.ravel() - t
            return float(w_planes * r @ r + e @ e)

        e_old = energy(x, d, A)
        for it in range(1, iterations + 1):
            AN = N @ A.T
            s = AN[f, 3]
            r = (np.einsum("ki,ki->k", AN[f, :3], x[vv]) + s * d[f]) / s
            y = np.concatenate([x[vv], d[f][:, None]], axis=1)                     # (4V, 4)
            # dA = A (J S), S antisymmetric: derivative of yᵀ A N along the six generators
            yAJ = y @ A @ J
            Ja = np.stack([yAJ[:, p] * N[f, q] - yAJ[:, q] * N[f, p] for p, q in _PAIRS], axis=1) / s[:, None]
            Jx = sp.csr_matrix(((AN[f, :3] / s[:, None]).ravel(),
                                (np.repeat(np.arange(4 * V), 3), (3 * vv[:, None] + np.arange(3)).ravel())),
                               shape=(4 * V, 3 * V))
            Jd = sp.csr_matrix((np.ones(4 * V), (np.arange(4 * V), f)), shape=(4 * V, P))
            Jp = wp * sp.hstack([Jx, Jd, sp.csr_matrix(Ja)], format="csr")
            Jall = sp.vstack([Rz, Jp], format="csr")
            res = np.concatenate([Rz[:, :3 * V] @ x.ravel() - t, wp * r])
            H = (Jall.T @ Jall).tocsc()
            g = Jall.T @ res
            while True:
                step = spsolve(H + mu * sp.diags(np.maximum(H.diagonal(), 1e-12)), -g)
                x2 = x + step[:3 * V].reshape(-1, 3)
                d2 = d + step[3 * V:3 * V + P]
                try:
                    A2 = project_lorentz(A @ (np.eye(4) + J @ _antisymmetric(step[3 * V + P:])))
                    e_new = energy(x2, d2, A2)
                except GeometryError:
                    e_new = np.inf
                if e_new <= e_old or mu > 1e8:
                    break
                mu *= 10.0
            if not np.isfinite(e_new):
                break
            change = float(np.abs(A2 - A).max())
            x, d, A, mu = x2, d2, A2, max(mu / 3.0, 1e-9)
            history.append(e_new)
            done = abs(e_old - e_new) <= tol * max(e_old, 1e-300) or change <= tol
            e_old = e_new
            if done:
                converged = True
                break
        fixed = self.solve_fixed(A, handles, w_handles, previous=x.reshape(self.shape + (3,)))
        msg = (f"converged after {it} Gauss-Newton steps (energy {history[-1]:.3e})" if converged else
               f"stopped after {it} Gauss-Newton steps without converging")
        return replace(fixed, converged=converged, iterations=it, history=history, message=msg)

    def _result(self, A, nbar, d, x, handles, converged, iterations, history, message) -> EditResult:
        planes = np.concatenate([nbar, d[:, None]], axis=1)
        Pv = planes[self.idx]                                                    # (V, 4, 4)
        xv = x.reshape(-1, 3)
        cres = float(np.abs(np.einsum("vki,vi->vk", Pv[..., :3], xv) + Pv[..., 3]).max())
        hid, hpos = self._targets(handles)
        hres = float(np.linalg.norm(xv[hid] - hpos, axis=1).max()) if len(hid) else 0.0
        E = planes[self.plane_index]
        g = self.grid
        inner = E[1:-1, 1:] if g.closed else E[1:-1, 1:-1]
        a, _, _ = axis_of_normals(Pv[..., :3].reshape(self.shape + (4, 3)))
        out = QuadGrid(x, closed=g.closed, support_u=_refit(x, g.support_u, True), support_w=_refit(x, g.support_w, False),
                       face_image=inner, axes=-a, vertex_ids=g.vertex_ids, extended_face_planes=E, meta=g.meta)
        return EditResult(out, A, converged, iterations, history, message, cres, hres, lorentz_residual(A))


def _solve_kkt(Q: sp.spmatrix, K: sp.spmatrix, kkt: sp.spmatrix, rhs: np.ndarray) -> np.ndarray:
    """Solve the KKT system ``[[Q, Kᵀ], [K, 0]]``: a direct LU with iterative refinement; when that
    fails or leaves the constraints unmet (redundant concurrency constraints, e.g. on closed grids) a
    quasi-definite regularisation ``[[Q + εI, Kᵀ], [K, −εI]]`` refined against the exact system."""
    n, m = Q.shape[0], K.shape[0]

    def refine(lu, sol, steps):
        for _ in range(steps):
            sol = sol + lu.solve(rhs - kkt @ sol)
        return sol

    def good(sol):
        d = sol[:n]
        return np.all(np.isfinite(sol)) and np.abs(K @ d).max() <= 1e-12 * max(1.0, np.abs(d).max()) and \
            np.abs(kkt @ sol - rhs).max() <= 1e-8 * max(1.0, np.abs(rhs).max())

    try:
        with np.errstate(all="ignore"):
            lu = splu(kkt)
            sol = refine(lu, lu.solve(rhs), 3)
        if good(sol):
            return sol
    except RuntimeError:
        pass
    reg = 1e-10 * float(abs(Q.diagonal()).max() or 1.0)
    lu = splu(sp.bmat([[Q + reg * sp.identity(n), K.T], [K, -reg * sp.identity(m)]], format="csc"))
    return refine(lu, lu.solve(rhs), 20)


def edit_conical(grid: QuadGrid, handles=None, A: np.ndarray | None = None, fit_A: bool = False,
                 w_handles: float = 1.0, proximity: float = 1e-3, fairness: float = 1e-3,
                 iterations: int = 50, check: bool = True) -> EditResult:
    """One-shot §4.3 edit of a conical P (or PP) grid.

    Parameters
    ----------
    grid : the conical grid
    handles : target positions of some vertices, ``{(i, j): (x, y, z)}`` or ``(ij, positions)``
    A : Lorentz matrix on homogeneous normals ``(n : 1)`` (identity: parallel meshes only); with
        ``fit_A`` the starting value
    fit_A : let ``A`` vary (alternating fits, Minkowski-polar projection)
    w_handles, proximity, fairness : weights of the least-squares terms
    check : raise :class:`~ppfab.errors.FoldError` when the edited mesh folds (handles pulled too far
        for the regularisers)

    Returns
    -------
    EditResult — its grid satisfies (17) to the solver's rounding (``constraint_residual``; conical, planar
    faces and polylines kept to that precision on a conical input), not exactly.

    Examples
    --------
    >>> from ppfab.constructions.conical_pp import Series, conical_pp_grid
    >>> g = conical_pp_grid(Series(cos=[-10.0]), Series(cosh=[-20.0]), np.linspace(-.3, .3, 4), np.linspace(-.2, .2, 4))
    >>> r = edit_conical(g, handles={(0, 0): g.vertices[0, 0] + [0.0, 0.0, 0.1]})
    >>> bool(r.constraint_residual < 1e-9)
    True
    """
    ed = ConicalEditor(grid, proximity=proximity, fairness=fairness)
    if fit_A:
        res = ed.fit(handles, A, w_handles=w_handles, iterations=iterations)
    else:
        res = ed.solve_fixed(A, handles, w_handles)
    if check:
        E = res.grid.extended_face_planes
        assert E is not None
        check_folds(res.grid, reference=E[1:-1, 1:] if grid.closed else E[1:-1, 1:-1],
                    context="the edited conical mesh (§4.3)")
    return res


def fit_lorentz(normals_from: np.ndarray, normals_to: np.ndarray) -> np.ndarray:
    """Lorentz matrix ``A`` with ``A (n : 1) ∝ (n' : 1)`` in least squares, projected (§4.3).

    Linear fit disregarding ``Aᵀ J A = J``: ``(n' : 1)`` parallel to ``A (n : 1)`` means
    ``P_⊥(n'_h) A N = 0`` for the projector orthogonal to ``n'_h = (n', 1)``; the smallest right
    singular vector of the stacked system gives ``A`` up to scale, which the Minkowski polar
    decomposition turns into a Lorentz matrix.  Needs at least 5 normals in general position.
    """
    a = np.asarray(normals_from, float).reshape(-1, 3)
    b = np.asarray(normals_to, float).reshape(-1, 3)
    if len(a) < 5 or a.shape != b.shape:
        raise GeometryError(f"fit_lorentz needs at least 5 pairs of normals, got {len(a)}")
    Na = np.concatenate([a, np.ones((len(a), 1))], axis=1)
    Nb = np.concatenate([b, np.ones((len(b), 1))], axis=1)
    Nb = Nb / np.linalg.norm(Nb, axis=1, keepdims=True)
    Pp = np.eye(4)[None] - np.einsum("ki,kj->kij", Nb, Nb)                     # (k, 4, 4)
    G = np.einsum("kij,kl->kijl", Pp, Na).reshape(-1, 16)                        # rows: (P A N)_i = Σ P_ij A_jl N_l
    _, _, vt = np.linalg.svd(G)
    return project_lorentz(vt[-1].reshape(4, 4))


def mobius_of_laguerre(A_laguerre: np.ndarray) -> np.ndarray:
    """The §4.3 matrix on ``(n : 1)`` induced by the sphere map ``X ↦ λ A X + T`` (our contact convention): ``J A J``."""
    return J @ np.asarray(A_laguerre, float) @ J
