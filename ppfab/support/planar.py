"""Support structures whose planar beams are chosen polylines (the PP and P methods on any quad mesh).

:func:`planar_support` takes the polylines that should be planar beams (both families for PP, one for P),
leaves out those that cannot be (the ``[support] exclude`` selectors, :mod:`ppfab.support.lines`), finds the
node axes (:func:`ppfab.support.axes.solve_axes`) and assembles the :class:`SupportStructure`.

The selector ``"auto"`` (the default) stands for the polylines that cannot be planar beams:

1. ``"tangent"`` — a polyline whose plane is further than ``max_normal_angle_deg`` from the surface normal at
   one of its vertices (no axis in it could be near the normal: a curve in a flat part of the surface);
2. then, only while the support exceeds ``max_torsion`` at beam depth on some edge: at every vertex where
   more than two planes meet (singular vertices, corners of a jagged boundary) and the axis leaves one of
   them by more than the tolerance, the polylines ending there except two (those running through the
   vertex, then the longest), repeated up to :data:`CONFLICT_ROUNDS` times; if that is not enough, the same
   again after leaving out the polylines ending at singular vertices (``"singular"``), the boundary
   polylines (``"boundary"``), or both — the first that brings every edge within ``max_torsion``; if none
   does, the one with the smallest torsion (which the build then refuses, listing the edges);
3. once the torsion is within the tolerance, a planar beam whose node axes, brought into its plane, cross
   less than the beam depth below it (the plate would fold; its axes are fixed by its own and the crossing
   planes), up to :data:`CONFLICT_ROUNDS` times: leaving it out frees its axes to turn apart.

Every polyline left out is recorded with its reason (:attr:`SupportStructure.left_out`), so ``ppfab check``
and the report can list it; its edges become beams of one edge each in their own support planes.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ppfab.mesh import QuadMesh

from .axes import AxisSolution, solve_axes
from .lines import PolylinePlanes, polyline_planes, select_polylines
from .params import BeamContext
from .structure import SupportStructure, _assemble, torsion_offset

ESCALATION: tuple[tuple[str, ...], ...] = ((), ("singular",), ("boundary",), ("singular", "boundary"))
"""What ``"auto"`` adds to ``"tangent"``, in order, when the support is not within the torsion tolerance."""

TORSION_SHARE = 0.25
"""The axes that are solved for stop at this share of ``max_torsion`` (keeping them nearer the normals)."""

EXACT = 1e-13
"""With exact strips (the P method) the penalty solve of what the combinatorics leave goes on until every
``|det(ê, a_i, a_j)|`` is below this (torsion-free to rounding where a solution exists), not only to the
share of the tolerance above."""

CONFLICT_ROUNDS = 3
"""How often ``"auto"`` leaves out the polylines ending at the vertices whose planes do not share a line (and,
as often again, the beams whose axes cross within the depth)."""


def _conflicts(mesh: QuadMesh, sol: AxisSolution, planar: np.ndarray, sine: float) -> np.ndarray:
    """``(L,)`` bool: at every vertex where more than two planes meet with a misfit above ``sine`` (the
    torsion tolerance over the depth), the planar polylines ending there, except the two kept: polylines
    running through the vertex first, then the longest."""
    out = np.zeros(len(planar), dtype=bool)
    bad = np.flatnonzero((sol.planes_at >= 3) & (sol.misfit > sine))
    if not len(bad):
        return out
    at: dict[int, list[int]] = {int(v): [] for v in bad}
    for k, p in enumerate(mesh.polylines):
        if planar[k]:
            for v in set(p.vertices.tolist()) & at.keys():
                at[v].append(k)
    for v, ks in at.items():
        lines = mesh.polylines

        def ends(k: int) -> bool:
            p = lines[k]
            return not p.closed and v in (int(p.vertices[0]), int(p.vertices[-1]))

        order = sorted(ks, key=lambda k: (ends(k), -len(lines[k]), k))
        for k in order[2:]:
            if ends(k):
                out[k] = True
    return out


def _reasons(planes: PolylinePlanes, left: np.ndarray, masks: dict[str, np.ndarray]) -> dict[int, str]:
    """Why each polyline of ``left`` is not a planar beam (the first selector that took it)."""
    text = {
        "exclude": lambda k: "left out by support.exclude",
        "tangent": lambda k: (f"its plane is {planes.tilt_deg[k]:.0f}° from the surface normal at vertex "
                              f"{int(planes.tilt_vertex[k])} (> support.max_normal_angle_deg): no axis in it can "
                              "be near the normal"),
        "singular": lambda k: ("it ends at a singular vertex where the planes of the polylines ending there do "
                               "not share a line"),
        "boundary": lambda k: "it runs along the boundary, whose corners join more planes than can share a line",
        "conflict": lambda k: ("it ends at a vertex where more polyline planes meet than share a line (the two "
                               "polylines running through or longest there are kept)"),
        "crossing": lambda k: ("the node axes in its plane cross less than the beam depth below it (the plate "
                               "would fold)"),
    }
    out: dict[int, str] = {}
    for k in (int(x) for x in np.flatnonzero(left)):
        name = next((n for n in text if n in masks and masks[n][k]), None)
        if name is not None:
            out[k] = text[name](k)
    return out


def _crossing(mesh: QuadMesh, axes: np.ndarray, planes: np.ndarray, planar: np.ndarray, depth: float) -> np.ndarray:
    """``(L,)`` bool: planar beams with an edge whose two node axes, brought into the beam's plane, cross less
    than ``depth`` below it (the plate would fold: ``T_i + α s_i = T_j + β s_j`` with ``0 < α, β`` and
    ``min(α, β) < depth``)."""
    out = np.zeros(len(planar), dtype=bool)
    v = mesh.vertices
    for k in np.flatnonzero(planar):
        p = mesh.polylines[int(k)]
        vs = p.vertices
        i, j = (np.r_[vs[:-1], vs[-1]], np.r_[vs[1:], vs[0]]) if p.closed and len(vs) > 2 else (vs[:-1], vs[1:])
        n = planes[k, :3] / np.linalg.norm(planes[k, :3])
        s = axes - np.outer(axes @ n, n)
        s /= np.maximum(np.linalg.norm(s, axis=1, keepdims=True), 1e-300)
        si, sj, d = s[i], s[j], v[j] - v[i]
        # least squares of α s_i − β s_j = d (exact when all lie in the plane)
        a11, a12, a22 = np.einsum("ij,ij->i", si, si), -np.einsum("ij,ij->i", si, sj), np.einsum("ij,ij->i", sj, sj)
        b1, b2 = np.einsum("ij,ij->i", si, d), -np.einsum("ij,ij->i", sj, d)
        det = a11 * a22 - a12 * a12
        ok = np.abs(det) > 1e-12
        alpha = np.where(ok, (b1 * a22 - a12 * b2) / np.where(ok, det, 1.0), np.inf)
        beta = np.where(ok, (a11 * b2 - a12 * b1) / np.where(ok, det, 1.0), np.inf)
        out[k] = bool(np.any(ok & (alpha > 0) & (beta > 0) & (np.minimum(alpha, beta) < depth)))
    return out


def _max_offset(mesh: QuadMesh, sol: AxisSolution, depth: float) -> float:
    return float(torsion_offset(mesh, sol.axes, depth).max()) if len(mesh.topology.edges) else 0.0


def _penalty_torsion_deg(mesh: QuadMesh, sol: AxisSolution) -> float:
    """Largest torsion (degrees: the angle between the planes spanned by the edge and each end's axis) of
    the free edges whose axes the penalty solve found (not both ends propagated exactly): what the
    combinatorics left, reported."""
    e = mesh.topology.edges
    exact = sol.exact if sol.exact is not None else np.zeros(len(mesh.vertices), dtype=bool)
    pick = sol.free_edges & ~(exact[e[:, 0]] & exact[e[:, 1]])
    if not pick.any():
        return 0.0
    d = mesh.vertices[e[pick, 1]] - mesh.vertices[e[pick, 0]]
    ni, nj = np.cross(d, sol.axes[e[pick, 0]]), np.cross(d, sol.axes[e[pick, 1]])
    ang = np.arctan2(np.linalg.norm(np.cross(ni, nj), axis=1), np.abs(np.einsum("ij,ij->i", ni, nj)))
    return float(np.degrees(ang.max()))


def planar_support(mesh: QuadMesh, normals: np.ndarray, candidates: np.ndarray, exclude: Sequence[int | str],
                   kind: str, families: tuple[int, ...], flip: bool = False, max_normal_angle_deg: float = 30.0,
                   planar_tolerance: float = 1e-6, beams: BeamContext | None = None,
                   planes: np.ndarray | None = None, key: str = "support.exclude",
                   strips: bool = False) -> SupportStructure:
    """The support structure whose planar beams are the ``candidates`` (``(L,)`` bool over
    ``mesh.polylines``) minus the polylines ``exclude`` selects (module docstring).

    ``planes``: the planes of the polylines, ``(L, 4)`` (finite rows override the least-squares planes);
    ``beams``: beam depth and torsion tolerance (mesh units) for the crossing term and for ``"auto"``;
    ``families``: the families reported as planar when all their candidate polylines stay planar beams;
    ``strips``: solve the transverse strips exactly by propagation (:mod:`ppfab.support.strips`, the P method).
    """
    pp = polyline_planes(mesh, normals, straight_tolerance=planar_tolerance)
    if planes is not None:
        given = np.asarray(planes, dtype=float)
        ok = np.all(np.isfinite(given), axis=1)
        plane_arr = pp.planes.copy()
        plane_arr[ok] = given[ok] / np.linalg.norm(given[ok, :3], axis=1, keepdims=True)
        pp = PolylinePlanes(plane_arr, pp.deviation, pp.relative, pp.straight, pp.tilt_deg, pp.tilt_vertex)
    lengths = np.array([len(p) for p in mesh.polylines])
    cand = np.asarray(candidates, dtype=bool) & (lengths >= 3) & np.all(np.isfinite(pp.planes), axis=1)
    sel = [s for s in exclude if s != "auto"]
    auto = "auto" in exclude
    none = np.zeros(len(lengths), dtype=bool)
    base = {"exclude": select_polylines(mesh, sel, key, pp, max_normal_angle_deg, planar_tolerance),
            "tangent": select_polylines(mesh, ["tangent"], key, pp, max_normal_angle_deg) if auto else none}
    depth = beams.depth if beams is not None else None
    limit = beams.max_torsion if beams is not None else 0.0
    best: tuple[tuple[bool, int, float], np.ndarray, AxisSolution, dict[str, np.ndarray]] | None = None
    for step in (ESCALATION if auto and beams is not None else ((),)):
        masks = {**base, **{name: select_polylines(mesh, [name], key) for name in step}}
        out = np.logical_or.reduce(list(masks.values()))
        if step and not (cand & out & ~(base["exclude"] | base["tangent"])).any():
            continue                                     # this step would leave nothing more out
        masks["conflict"] = none.copy()
        masks["crossing"] = none.copy()
        for _ in range(2 * CONFLICT_ROUNDS + 1):
            planar = cand & ~out
            sol = solve_axes(mesh, normals, pp.planes, planar, flip, depth,
                             EXACT if strips else TORSION_SHARE * limit / depth if depth and limit > 0 else 1e-10,
                             strips)
            worst = _max_offset(mesh, sol, depth) if depth else float(np.abs(sol.torsion_det).max(initial=0.0))
            crossing = _crossing(mesh, sol.axes, pp.planes, planar, depth) if auto and depth else none
            score = (worst > limit, int(crossing.sum()), worst)
            if best is None or score < best[0]:
                best = (score, planar, sol, {k: m.copy() for k, m in masks.items()})
            if (worst <= limit and not crossing.any()) or not auto or beams is None:
                break
            if worst > limit:                        # torsion first: the planes that do not share a line
                more = _conflicts(mesh, sol, planar, limit / beams.depth) & ~out
                masks["conflict"] |= more
            else:                                    # then the beams whose axes cross within the depth
                more = crossing & ~out
                masks["crossing"] |= more
            if not more.any():
                break
            out |= more
        if best is not None and not best[0][0] and not best[0][1]:
            break
    assert best is not None
    _, planar, sol, used = best
    reasons = _reasons(pp, cand & ~planar, used)
    fam = np.array([p.family for p in mesh.polylines], dtype=np.int64)
    kept = tuple(f for f in families if np.any(cand & (fam == f)) and not np.any(cand & ~planar & (fam == f)))
    meta = {"planes": "least squares", "iterations": sol.iterations, "stages": sol.stages,
            "normal_weight": sol.normal_weight, "misfit_max": float(sol.misfit.max(initial=0.0)), "left_out": len(reasons),
            "straight_polylines": int(pp.straight.sum()), "exact_strips": sol.strips,
            "penalty_strips": sol.forced,
            "exact_vertices": int(sol.exact.sum()) if sol.exact is not None else 0,
            "penalty_torsion_max_deg": _penalty_torsion_deg(mesh, sol)}
    return _assemble(mesh, sol.axes, pp.planes, planar, kept, kind, meta,
                     left_out=tuple(sorted(reasons.items())), planes_at=sol.planes_at, misfit=sol.misfit)
