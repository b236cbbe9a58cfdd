"""What a rigid motion does not change of a B-rep read at the text level (:class:`BrepFacts`), worked out for
many B-reps at once from their packed faces (:class:`~._step_shell.ShellCode`): whether the shell is
closed and oriented, how far a vertex is off its surface, the volume, and the faces' and loops' areas.

Volume by the divergence theorem, ``V = ⅓ Σ_faces ∫ (x − c)·n dA`` with ``c`` the B-rep's vertex centroid (no
cancellation far from the origin):

- a plane's flux is ``((o − c)·n) A`` with ``A`` its signed area, the sum of its loops' ``½ (∮ x × dx)·n``
  taken about the centre of its first loop: ``p × q`` for a straight edge ``p → q``, ``c_a × (q − p) + r² θ k``
  for an arc of centre ``c_a``, radius ``r``, sweep ``θ`` about ``k``;
- a cylinder band of axis ``(o, a)``, radius ``r`` and height ``h`` (the extent of its vertices along ``a``)
  has flux ``± r h (o·∫u dθ + r Δθ)`` over the arcs at its lower end, ``∫u dθ = e₁ sin θ + e₂ (1 − cos θ)``
  for an arc starting along ``e₁`` with ``e₂ = k × e₁`` — exact for the round holes ppfab drills.

Not a check (the leading underscore keeps it out of the registry).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ._step_shell import ShellCode


@dataclass(frozen=True)
class BrepFacts:
    """What a rigid motion does not change of a solid, so one B-rep placed many times is measured once:
    ``bad_edges`` the edges not used exactly twice in opposite senses (``first_bad_edge`` the id of the first
    one the loops reach, else 0), ``off_surface`` the largest distance (mm) of a vertex from its face's plane or
    cylinder or of a circle's end from its circle, ``volume`` mm³, ``face_areas`` mm² per face of the shell in
    its order (a plane's area, outer loop less holes; 0 for a cylinder) and ``loop_areas`` mm² per loop in the
    shell's order (signed about its face's normal: negative for a hole, or for a face turned inside out)."""

    bad_edges: int
    first_bad_edge: int
    off_surface: float
    volume: float
    face_areas: tuple[float, ...] = ()
    loop_areas: tuple[float, ...] = ()


def _starts(counts: np.ndarray) -> np.ndarray:
    """``(len(counts) + 1,)`` the offsets of consecutive runs of these lengths."""
    return np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)


def _group_sum(values: np.ndarray, group: np.ndarray, size: int) -> np.ndarray:
    """Rows of ``values`` summed by ``group`` (``size`` groups)."""
    out = np.zeros((size,) + values.shape[1:])
    np.add.at(out, group, values)
    return out


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1], a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)


def facts_of(shapes: Sequence[tuple[np.ndarray, ShellCode]]) -> list[BrepFacts]:
    """:class:`BrepFacts` of each B-rep given as its vertices ``(n, 3)`` and packed faces, all at once: the
    B-reps' tables are put end to end and every sum is grouped by face, loop or B-rep."""
    nb = len(shapes)
    if nb == 0:
        return []
    codes = [c for _, c in shapes]
    v_first = _starts(np.array([len(p) for p, _ in shapes]))
    points = np.concatenate([p for p, _ in shapes]).reshape(-1, 3)
    f_count = np.array([len(c.planes) for c in codes])
    l_count = np.array([len(c.loop_steps) - 1 for c in codes])
    s_count = np.array([len(c.steps) for c in codes])
    a_count = np.array([len(c.arcs) for c in codes])
    planes = np.concatenate([c.planes for c in codes]).reshape(-1, 10)
    kinds = np.concatenate([c.kinds for c in codes]).reshape(-1, 2)
    arcs = np.concatenate([c.arcs for c in codes]).reshape(-1, 8)
    steps = np.concatenate([c.steps for c in codes]).reshape(-1, 4)
    loops_per_face = np.concatenate([np.diff(c.face_loops) for c in codes]).astype(np.int64)
    steps_per_loop = np.concatenate([np.diff(c.loop_steps) for c in codes]).astype(np.int64)
    n_faces, n_loops, n_steps = len(planes), len(steps_per_loop), len(steps)
    face_brep = np.repeat(np.arange(nb), f_count)
    loop_face = np.repeat(np.arange(n_faces), loops_per_face)
    step_loop = np.repeat(np.arange(n_loops), steps_per_loop)
    step_face = loop_face[step_loop]
    step_brep = np.repeat(np.arange(nb), s_count)
    loop_first = _starts(steps_per_loop)
    at = v_first[step_brep] + steps[:, 0]                       # each step's start vertex, in ``points``
    after = np.arange(n_steps) + 1                              # the next step of the loop, cyclic
    ends = loop_first[1:] - 1
    after[ends[steps_per_loop > 0]] = loop_first[:-1][steps_per_loop > 0]
    p, q = points[at], points[at[after]]
    is_arc = steps[:, 3] >= 0
    arc_rows = (np.repeat(_starts(a_count)[:-1], s_count) + steps[:, 3])[is_arc]
    arc = arcs[arc_rows]
    # shell closed and oriented: each edge of a B-rep used twice, once each way
    edge_key = step_brep * (int(steps[:, 1].max(initial=0)) + 1) + steps[:, 1]
    _, first_use, which, uses = np.unique(edge_key, return_index=True, return_inverse=True, return_counts=True)
    forward = np.bincount(which.ravel(), weights=steps[:, 2], minlength=len(uses))
    bad = (uses != 2) | (forward != 1)
    bad_count = np.bincount(step_brep[first_use[bad]], minlength=nb)
    first_bad = np.full(nb, n_steps, dtype=np.int64)
    np.minimum.at(first_bad, step_brep[first_use[bad]], first_use[bad])
    # off the surfaces: each loop vertex from its face's plane or cylinder, each arc's ends from its circle
    origin, normal, radius = planes[step_face, 0:3], planes[step_face, 3:6], planes[step_face, 9]
    rel = p - origin
    along = _dot(rel, normal)
    cylinder = kinds[step_face, 0]
    radial = np.linalg.norm(rel - along[:, None] * normal, axis=1)
    off = np.where(cylinder, np.abs(radial - radius), np.abs(along))
    off_brep = np.zeros(nb)
    np.maximum.at(off_brep, step_brep, off)
    for end in (p[is_arc], q[is_arc]):
        e = end - arc[:, 0:3]
        worst = np.maximum(np.abs(np.linalg.norm(e, axis=1) - arc[:, 6]), np.abs(_dot(e, arc[:, 3:6])))
        np.maximum.at(off_brep, step_brep[is_arc], worst)
    # loop areas about the centre of their face's first loop
    loop_centre = _group_sum(p, step_loop, n_loops) / np.maximum(steps_per_loop, 1)[:, None]
    face_centre = loop_centre[_starts(loops_per_face)[:-1]]
    about = face_centre[step_face]
    pa, qa = p - about, q - about
    term = _cross(pa, qa)
    ca = arc[:, 0:3] - about[is_arc]
    term[is_arc] = _cross(ca, qa[is_arc] - pa[is_arc]) + (arc[:, 6] ** 2 * arc[:, 7])[:, None] * arc[:, 3:6]
    loop_area = 0.5 * _dot(_group_sum(term, step_loop, n_loops), planes[loop_face, 3:6])
    face_area = np.bincount(loop_face, weights=loop_area, minlength=n_faces)
    is_cyl = kinds[:, 0].astype(bool)
    face_area[is_cyl] = 0.0
    # volume: the planes' flux, then the cylinder bands'
    centroid = _group_sum(points, np.repeat(np.arange(nb), np.diff(v_first)), nb) \
        / np.maximum(np.diff(v_first), 1)[:, None]
    flux = _dot(planes[:, 0:3] - centroid[face_brep], planes[:, 3:6]) * face_area
    flux[is_cyl] = _band_flux(planes, kinds, centroid[face_brep], step_face, along, p, is_arc, arc, n_faces)[is_cyl]
    volume = np.bincount(face_brep, weights=flux, minlength=nb) / 3.0
    f_first, l_first = _starts(f_count), _starts(l_count)
    areas, signed = np.abs(face_area).tolist(), loop_area.tolist()
    first_edges = steps[np.minimum(first_bad, max(n_steps - 1, 0)), 1].tolist() if n_steps else [0] * nb
    return [BrepFacts(int(bad_count[b]), int(first_edges[b]) if bad_count[b] else 0, float(off_brep[b]),
                      float(volume[b]), tuple(areas[f_first[b]:f_first[b + 1]]),
                      tuple(signed[l_first[b]:l_first[b + 1]])) for b in range(nb)]


def _band_flux(planes: np.ndarray, kinds: np.ndarray, centroid: np.ndarray, step_face: np.ndarray,
               along: np.ndarray, p: np.ndarray, is_arc: np.ndarray, arc: np.ndarray, n_faces: int) -> np.ndarray:
    """``(n_faces,)`` ``∫ (x − c)·n dA`` of each face taken as a cylinder band (meaningful at the cylinders):
    ``± r h (o·∫u dθ + r Δθ)`` over the arcs at the band's lower end (within 1e-6 of its height), ``o`` the axis
    origin from the B-rep's centroid ``c``; 0 for a band without arcs."""
    low_s, high_s = np.full(n_faces, np.inf), np.full(n_faces, -np.inf)
    np.minimum.at(low_s, step_face, along)
    np.maximum.at(high_s, step_face, along)
    height = np.where(np.isfinite(low_s), high_s - low_s, 0.0)
    arc_face = step_face[is_arc]
    axial = _dot(arc[:, 0:3] - planes[arc_face, 0:3], planes[arc_face, 3:6])
    lowest = np.full(n_faces, np.inf)
    np.minimum.at(lowest, arc_face, axial)
    keep = np.abs(axial - lowest[arc_face]) <= 1e-6 * np.maximum(1.0, height[arc_face])
    e1 = (p[is_arc] - arc[:, 0:3]) / arc[:, 6:7]
    e2 = _cross(arc[:, 3:6], e1)
    sweep = arc[:, 7]
    u = e1 * np.sin(sweep)[:, None] + e2 * (1.0 - np.cos(sweep))[:, None]
    integral = _group_sum(u[keep], arc_face[keep], n_faces)
    turned = np.bincount(arc_face[keep], weights=sweep[keep], minlength=n_faces)
    o = planes[:, 0:3] - centroid
    r = planes[:, 9]
    sign = np.where(kinds[:, 1], 1.0, -1.0)
    has_arcs = np.bincount(arc_face, minlength=n_faces) > 0
    return np.where(has_arcs, sign * r * height * (_dot(o, integral) + r * turned), 0.0)
