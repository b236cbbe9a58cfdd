"""The optimiser's sparse solves: the support normals ordered last, MKL PARDISO beside SuperLU, the fallback.

Each solve is checked against a dense solve with numpy on the same damped normal equations of a real mesh
(WWmore/DOS ``objs/obj_pq/conical1.obj`` made PP with its support normals among the unknowns).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import sparse
from scipy.sparse.linalg import splu

from conftest import shared_file
from ppfab.errors import GeometryError
from ppfab.io import load_mesh
from ppfab.optimize import build_problem, optimize
from ppfab.optimize import linsolve
from ppfab.optimize.linsolve import DampedSystem, FactorCache, nested_dissection


@pytest.fixture(scope="module")
def system():
    """``(S, rhs, n_normals)``: the Schur system of the first LM step of conical1 PP, exact support normals."""
    mesh = load_mesh(shared_file("DOS__conical1.obj"))
    prob = build_problem(mesh, families="both", plane_solver="exact")
    res = prob.residuals
    z = res.project_normals(prob.z0)
    ds = DampedSystem(res.jacobian(z), res.residual(z), res.n_face_unknowns)
    mu = 1e-3 * ds.diag_max
    nb = ds.nz // 3
    binv = np.linalg.inv(ds.blocks + mu * np.eye(3))
    bd = sparse.bsr_matrix((binv, np.arange(nb), np.arange(nb + 1)), shape=(ds.nz, ds.nz)).tocsr()
    s = (ds.a_yy + mu * sparse.identity(ds.ny) - ds.a_yz @ bd @ ds.a_yz.T).tocsr()
    rhs = np.random.default_rng(1).normal(size=ds.ny)
    return s, rhs, 3 * res.n_planes


def test_normals_last_solve_correctly_with_less_fill(system):
    s, rhs, last = system
    dense = np.linalg.solve(s.toarray(), rhs)
    fills = []
    for p in (nested_dissection(s), nested_dissection(s, last=last)):
        assert sorted(p.tolist()) == list(range(s.shape[0]))
        lu = splu(sparse.csc_matrix(s[p][:, p]), permc_spec="NATURAL", diag_pivot_thresh=0.0,
                  options={"SymmetricMode": True})
        x = np.empty_like(rhs)
        x[p] = lu.solve(rhs[p])
        assert np.linalg.norm(x - dense) <= 1e-9 * np.linalg.norm(dense)
        fills.append(lu.L.nnz + lu.U.nnz)
    assert np.all(nested_dissection(s, last=last)[-last:] == np.arange(s.shape[0] - last, s.shape[0]))
    assert fills[1] < 0.8 * fills[0]                    # the normals among the separators fill more


def test_pardiso_and_superlu_solve_the_same_system(system):
    pytest.importorskip("pypardiso")
    s, rhs, last = system
    dense = np.linalg.solve(s.toarray(), rhs)
    for name in ("superlu", "pardiso"):
        cache = FactorCache(last=last, solver=name)
        x = cache.solve(s, rhs)
        assert cache.factorisations == 1 and cache.solver == name
        assert np.linalg.norm(x - dense) <= 1e-9 * np.linalg.norm(dense)


def test_a_kept_pardiso_factor_preconditions_cg(system):
    pytest.importorskip("pypardiso")
    s, rhs, last = system
    owner = object()
    cache = FactorCache(last=last, solver="pardiso")
    cache.solve(s, rhs, owner=owner)
    s2 = (s + 1e-8 * sparse.identity(s.shape[0])).tocsr()
    x2 = cache.solve(s2, rhs, owner=owner)
    assert cache.factorisations == 1 and cache.cg_solves == 1
    assert np.linalg.norm(s2 @ x2 - rhs) <= 1e-9 * np.linalg.norm(rhs)


def _upper(a: sparse.spmatrix) -> sparse.csr_matrix:
    u = sparse.triu(a, format="csr")
    u.sort_indices()
    return u


def test_a_pattern_pardiso_has_analysed_is_factorised_numerically_only(system):
    """A second matrix of the same pattern is factorised without PARDISO's analysis (phase 22), a matrix of
    another pattern with it (phase 12): each solve is its own system's (against numpy's dense solve), and the
    numeric-only factor is bitwise the factor a fresh analysis gives."""
    pytest.importorskip("pypardiso")
    s, rhs, _ = system
    solver = linsolve._thread_pardiso()
    solver.ppfab_pattern = None
    phases: list[int] = []
    call = solver._call_pardiso

    def spy(a, b):
        phases.append(solver.phase)
        return call(a, b)

    solver._call_pardiso = spy
    try:
        linsolve._PardisoFactor(_upper(s), solver)
        s2 = (s + 0.37 * sparse.diags(np.linspace(1.0, 2.0, s.shape[0]))).tocsr()       # same pattern
        second = linsolve._PardisoFactor(_upper(s2), solver)
        x2 = second.solve(rhs)
        assert phases == [12, 22, 33]
        assert np.linalg.norm(x2 - np.linalg.solve(s2.toarray(), rhs)) <= 1e-9 * np.linalg.norm(x2)
        solver.ppfab_pattern = None                                   # forget the analysis: phase 12 again
        fresh = linsolve._PardisoFactor(_upper(s2), solver).solve(rhs)
        assert phases[-2:] == [12, 33] and np.array_equal(fresh, x2)
        keep = s2.tolil()                                             # another pattern: one more entry
        keep[0, s.shape[0] - 1] = keep[s.shape[0] - 1, 0] = 1e-3
        s3 = keep.tocsr()
        x3 = linsolve._PardisoFactor(_upper(s3), solver).solve(rhs)
        assert phases[-2:] == [12, 33]
        assert np.linalg.norm(x3 - np.linalg.solve(s3.toarray(), rhs)) <= 1e-9 * np.linalg.norm(x3)
    finally:
        del solver._call_pardiso


def test_a_pardiso_factor_replaced_by_another_solve_in_the_thread_is_computed_again(system):
    """Two factors kept in one thread (PARDISO holds one): solving with the older recomputes it, and each solve
    is its own system's."""
    pytest.importorskip("pypardiso")
    s, rhs, _ = system
    solver = linsolve._thread_pardiso()
    a = linsolve._PardisoFactor(_upper(s), solver)
    s2 = (s + 5.0 * sparse.identity(s.shape[0])).tocsr()
    b = linsolve._PardisoFactor(_upper(s2), solver)
    for f, m in ((a, s), (b, s2), (a, s)):
        x = f.solve(rhs)
        assert np.linalg.norm(m @ x - rhs) <= 1e-9 * np.linalg.norm(rhs)


def test_pardiso_keeps_ppfab_s_settings_and_orders_long_rows_by_minimum_degree(system):
    """PARDISO's settings are ppfab's (``iparm(1) = 1``: otherwise PARDISO refills its defaults on every call),
    without iterative refinement; a system with the support normals among its unknowns (long-range rows) is
    ordered by minimum degree, one without by METIS — a change of ordering analysed afresh — and each solve is
    its own system's (numpy's dense solve)."""
    pytest.importorskip("pypardiso")
    s, rhs, last = system
    solver = linsolve._thread_pardiso()
    assert solver.get_iparm(1) == 1 and solver.get_iparm(8) == 0
    dense = np.linalg.solve(s.toarray(), rhs)
    for cache_last, code in ((last, 0), (0, solver.ppfab_metis), (last, 0)):
        cache = FactorCache(last=cache_last, solver="pardiso")
        x = cache.solve(s, rhs)
        assert solver.get_iparm(2) == code and solver.ppfab_pattern[2] == ("minimum degree" if code == 0 else "metis")
        assert solver.get_iparm(7) == 0                                     # no refinement steps taken
        assert np.linalg.norm(x - dense) <= 1e-9 * np.linalg.norm(dense)


def test_a_pardiso_error_falls_back_to_superlu(system, monkeypatch):
    s, rhs, last = system

    class Broken:
        def __init__(self, *args):
            raise RuntimeError("pardiso error -4: zero pivot")

    monkeypatch.setattr(linsolve, "_PardisoFactor", Broken)
    monkeypatch.setattr(linsolve, "_thread_pardiso", lambda: None)
    cache = FactorCache(last=last, solver="pardiso")
    x = cache.solve(s, rhs)
    assert cache.solver == "superlu" and cache.factorisations == 1
    assert np.linalg.norm(s @ x - rhs) <= 1e-9 * np.linalg.norm(rhs)


def test_asking_for_pardiso_without_it_is_one_clear_error(monkeypatch):
    monkeypatch.setattr(linsolve, "pardiso_available", lambda: False)
    assert linsolve.resolve_solver("auto") == "superlu"
    with pytest.raises(GeometryError, match=r"pip install ppfab\[fast\]"):
        linsolve.resolve_solver("pardiso")


def test_both_solvers_reach_the_same_mesh():
    pytest.importorskip("pypardiso")
    mesh = load_mesh(shared_file("DOS__enneper2.obj"))
    a = optimize(mesh, families="both", linear_solver="superlu")
    b = optimize(mesh, families="both", linear_solver="pardiso")
    assert a.targets_met and b.targets_met and a.iterations == b.iterations
    va, vb = np.asarray(a.mesh.vertices).reshape(-1, 3), np.asarray(b.mesh.vertices).reshape(-1, 3)
    diag = np.linalg.norm(np.ptp(va, axis=0))
    assert np.abs(va - vb).max() < 1e-8 * diag


@pytest.mark.skipif(not linsolve.pardiso_available(), reason="MKL PARDISO (pypardiso) is not installed")
def test_a_pardiso_optimisation_is_bitwise_the_same_whatever_threads_mkl_may_use(tmp_path):
    """PARDISO's factor depends on how many threads reduce it, and MKL picks that by the machine's load: two
    builds of one design on a busy machine differed by 1e-10 mm.  The optimiser keeps MKL on one thread, so the
    same optimisation (the real DOS enneper2 made PP, 6 steps) in fresh processes told to use 1, 2 or (unset)
    any number of threads gives the same bytes; without it the 1- and 2-thread runs differ."""
    import os
    import subprocess
    import sys

    from conftest import REPO

    code = ("import hashlib, numpy as np\n"
            "from ppfab.io import load_mesh\nfrom ppfab.optimize import optimize\n"
            f"m = load_mesh({str(shared_file('DOS__enneper2.obj'))!r})\n"
            "r = optimize(m, families='both', linear_solver='pardiso', max_iterations=6)\n"
            "print(hashlib.sha256(np.ascontiguousarray(r.mesh.vertices).tobytes()).hexdigest())\n")
    digests = set()
    for threads in (None, "1", "2"):
        env = {k: v for k, v in os.environ.items() if k not in ("MKL_NUM_THREADS", "OMP_NUM_THREADS")}
        if threads:
            env["MKL_NUM_THREADS"] = threads
        run = subprocess.run([sys.executable, "-c", code], cwd=REPO, env=env, capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        digests.add(run.stdout.strip().splitlines()[-1])
    assert len(digests) == 1
