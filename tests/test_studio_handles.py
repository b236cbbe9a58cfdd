"""The studio's point and plane handles (translational, profile curves, principal sections, plane splines,
bisector, planar-spine spheres) on the bundled examples: a moved handle lands where it was dragged, the mesh
stays PP (and conical for the conical constructions) measured by SVD, one undo step, save/reload to 1e-9,
refused edits keep the last valid design, and a refused fold marks its faces."""

from __future__ import annotations

import math
import re
import tomllib

import numpy as np
import pytest

from conftest import REPO
from fabrication.studio.model import StudioModel, solve

pytest.importorskip("tomli_w", reason="the studio extra is not installed")

EX = REPO / "examples"


def _line_planarity(vertices: np.ndarray) -> float:
    """Largest distance of a row or column polyline from its least-squares plane (smallest right singular
    vector) over the polyline's bounding-box diagonal."""
    worst = 0.0
    for lines in (vertices, np.swapaxes(vertices, 0, 1)):
        for line in lines:
            c = line - line.mean(0)
            worst = max(worst, float(np.abs(c @ np.linalg.svd(c)[2][-1]).max() / np.linalg.norm(np.ptp(line, 0))))
    return worst


def _face_planarity(v: np.ndarray) -> float:
    """Largest distance of a quad's corners from their least-squares plane over the quad's longer diagonal."""
    q = np.stack([v[:-1, :-1], v[1:, :-1], v[1:, 1:], v[:-1, 1:]], axis=-2)
    c = q - q.mean(-2, keepdims=True)
    n = np.linalg.svd(c)[2][..., -1, :]
    dist = np.abs(np.einsum("...ki,...i->...k", c, n)).max(-1)
    diag = np.maximum(np.linalg.norm(q[..., 2, :] - q[..., 0, :], axis=-1), np.linalg.norm(q[..., 3, :] - q[..., 1, :], axis=-1))
    return float((dist / diag).max())


def _cone_defect(v: np.ndarray) -> float:
    """Largest ``|α1 − α2 + α3 − α4|`` (rad) of the four face angles at an interior vertex: zero exactly when
    the four face normals lie on a right circular cone (the angle criterion of conical meshes)."""
    p = v[1:-1, 1:-1]
    nb = [v[2:, 1:-1], v[1:-1, 2:], v[:-2, 1:-1], v[1:-1, :-2]]
    ang = []
    for a, b in zip(nb, nb[1:] + nb[:1]):
        x, y = a - p, b - p
        ang.append(np.arccos(np.clip(np.einsum("...i,...i", x, y) / (np.linalg.norm(x, axis=-1) *
                                                                      np.linalg.norm(y, axis=-1)), -1, 1)))
    return float(np.abs(ang[0] - ang[1] + ang[2] - ang[3]).max())


def _one_undo_step_and_the_same_after_reload(m: StudioModel, v0: np.ndarray, v: np.ndarray, tmp_path) -> None:
    """The edit is one undo step back to ``v0`` exactly and redo forward to ``v``; saved and read back, the
    design gives the same geometry to 1e-9 mm."""
    assert len(m.history.undo) == 1
    assert m.undo() and np.array_equal(m.state.placed.vertices, v0)
    assert m.redo() and np.array_equal(m.state.placed.vertices, v)
    out = m.save(tmp_path / "edited.toml")
    again = solve(tomllib.loads(out.read_text(encoding="utf-8")), tmp_path)
    assert np.abs(again.placed.vertices - v).max() <= 1e-9


def _rot(axis: int, deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    i, j = [k for k in range(3) if k != axis]
    R = np.eye(3)
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


# (example, handle key, move in display metres, rotation, conical)
CASES = [
    ("pp_translational", "a_points_2", [0.0, 0.0, 0.4], None, False),
    ("pp_translational", "b_points_3", [0.0, 0.2, 0.3], None, False),
    ("pp_profile_curves", "c_points_1", [0.0, 0.0, 0.3], None, False),      # off the crest: phi is moved
    ("pp_profile_curves", "d_points_4", [0.0, 0.0, 0.1], None, False),      # the crest point: eps is moved
    ("conical_sections", "section_a_0", [0.3, 0.0, 0.4], None, True),
    ("conical_sections", "section_b_8", [3.0, 0.0, 0.0], None, True),       # normal to B's plane: no change
    ("conical_sections", "section_b_0", [0.0, 0.2, 0.4], None, True),
    ("conical_sections", "section_a_4", [0.0, 0.0, 0.2], None, True),       # the crest: B is lifted with it
    ("pp_plane_splines", "u_planes_3", [0.0, 0.0, 0.5], None, False),
    ("pp_plane_splines", "v_tangents_1", [0.0, 0.0, 0.0], (2, 4.0), False),
    ("pp_plane_splines", "u_planes_0", [0.2, 0.0, 0.3], (0, 3.0), False),
    ("pp_bisector", "g_6", [0.0, 0.1, 0.05], None, False),
    ("conical_spheres_pp", "centers_2", [0.5, 0.0, 0.8], None, True),
]


@pytest.fixture(scope="module")
def models() -> dict[str, StudioModel]:
    return {name: StudioModel.load(EX / f"{name}.toml") for name in {c[0] for c in CASES}}


@pytest.mark.parametrize("example, key, move, turn, conical", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_handle_keeps_pp_lands_where_dragged_and_undoes(models, tmp_path, example, key, move, turn, conical):
    base = models[example]
    m = StudioModel(base.doc, base.base_dir)
    h = {x.key: x for x in m.handles()}[key]
    target = h.position + np.asarray(move)
    rot = np.eye(3) if turn is None else _rot(*turn)
    assert m.move_handle(key, target, rot), m.error
    v0, v = base.state.placed.vertices, m.state.placed.vertices
    moved = float(np.abs(v - v0).max())
    after = {x.key: x for x in m.handles()}
    if example == "conical_sections" and key == "section_b_8":
        # B lies in the plane x = x_crest: a drag normal to it is projected away and changes nothing (but
        # round-off in the crest heights)
        assert moved < 1e-6 and np.allclose(after[key].position, h.position, atol=1e-12)
        return
    assert moved > 20.0                                              # mm
    assert _line_planarity(v) < 1e-9 and _face_planarity(v) < 1e-9
    if conical:
        assert _cone_defect(base.state.placed.vertices) < 1e-9       # the example is conical …
        assert _cone_defect(v) < 1e-9                                # … and stays so
    if example == "pp_plane_splines":
        # the edited plane passes through the dragged point with the turned normal
        from ppfab.constructions.plane_splines import plane_from_entry

        name, k = key.rsplit("_", 1)
        x = target * 1000.0 / m.geometry["scale"]
        new = plane_from_entry(m.params[name][int(k)], key)
        old = plane_from_entry(base.params[name][int(k)], key) if base.params.get(name) else None
        assert abs(new[:3] @ x + new[3]) < 1e-12
        if old is not None:
            assert np.allclose(new[:3], rot @ old[:3], atol=1e-12)
        if key == "u_planes_0":
            assert m.params["v_planes"][0] == m.params["u_planes"][0]
    else:
        # a point handle lands exactly where it was dragged (the moves here lie in the handle's plane)
        assert np.abs(after[key].position - target).max() < 1e-9
    # one undo step back to the example exactly, redo forward again
    _one_undo_step_and_the_same_after_reload(m, v0, v, tmp_path)


def test_profile_edit_restores_the_meeting_point_by_moving_the_other_plane(models):
    """Moving a point of c off the crest tilts c there: the construction alone refuses the new c (no common
    normal), the handle translates phi onto c's new crest and the mesh is accepted."""
    base = models["pp_profile_curves"]
    m = StudioModel(base.doc, base.base_dir)
    h = {x.key: x for x in m.handles()}["c_points_1"]
    assert m.move_handle("c_points_1", h.position + np.array([0.0, 0.0, 0.3]))
    shift = np.asarray(m.params["phi_origin"], dtype=float)
    assert abs(shift[0]) > 1e-3 and m.params["eps_origin"] == base.params["eps_origin"]
    plain = StudioModel(base.doc, base.base_dir)
    assert not plain.set_param("c_points", m.params["c_points"])    # the same c without moving phi
    assert "common normal" in plain.error or "meet" in plain.error
    assert plain.state is not None and len(plain.history.undo) == 0


def test_section_edit_lifts_the_other_section_to_the_same_crest(models):
    base = models["conical_sections"]
    m = StudioModel(base.doc, base.base_dir)
    h = {x.key: x for x in m.handles()}["section_a_4"]
    assert m.move_handle("section_a_4", h.position + np.array([0.0, 0.0, 0.2]))
    dz = {p[1] - q[1] for p, q in zip(m.params["section_b"], base.params["section_b"])}
    assert len({round(x, 12) for x in dz}) == 1 and dz.pop() == pytest.approx(0.2, abs=1e-9)  # B lifted rigidly
    plain = StudioModel(base.doc, base.base_dir)
    assert not plain.set_param("section_a", m.params["section_a"])
    assert "do not meet" in plain.error


def test_a_sphere_centre_stays_in_the_plane_of_the_others(models):
    base = models["conical_spheres_pp"]
    m = StudioModel(base.doc, base.base_dir)
    h = {x.key: x for x in m.handles()}["centers_1"]
    assert m.move_handle("centers_1", h.position + np.array([0.2, 0.7, 0.3]))
    c = np.asarray(m.params["centers"], dtype=float)
    assert np.linalg.svd(c - c.mean(0), compute_uv=False)[-1] < 1e-12       # still coplanar
    assert c[1].tolist() == pytest.approx([8.2, 0.0, 7.3], abs=1e-12)       # y = 0 is the plane M here
    assert _line_planarity(m.state.placed.vertices) < 1e-9 and _cone_defect(m.state.placed.vertices) < 1e-9


def _three_step_drag_is_one_undo_step(base: StudioModel, key: str, step: np.ndarray, axis: int) -> None:
    """Dragging ``key`` three steps (``step`` and 1° about ``axis`` each) ends where one move of the whole way
    ends, to 1e-9, and is one undo step back to ``base``."""
    m = StudioModel(base.doc, base.base_dir)
    h = {x.key: x for x in m.handles()}[key]
    m.begin_drag()
    for a in (1.0, 2.0, 3.0):
        assert m.drag(key, h.position + a * step, _rot(axis, a))
    m.end_drag()
    direct = StudioModel(base.doc, base.base_dir)
    assert direct.move_handle(key, h.position + 3.0 * step, _rot(axis, 3.0))
    assert np.abs(m.state.placed.vertices - direct.state.placed.vertices).max() < 1e-9
    assert len(m.history.undo) == 1 and m.undo()
    assert np.array_equal(m.state.placed.vertices, base.state.placed.vertices)


def test_drag_of_a_plane_handle_is_one_undo_step(models):
    _three_step_drag_is_one_undo_step(models["pp_plane_splines"], "v_planes_3", np.array([0.0, 0.0, 0.1]), 0)


def test_refused_handle_edit_keeps_the_last_valid_design(models):
    base = models["pp_profile_curves"]
    m = StudioModel(base.doc, base.base_dir)
    h = {x.key: x for x in m.handles()}["c_points_2"]
    before = m.state
    assert not m.move_handle("c_points_2", h.position + np.array([0.0, 0.0, 0.3]))   # makes an inflection
    assert "inflection" in m.error and "\n" not in m.error
    assert m.state is before and m.doc == base.doc and not m.history.undo
    s = models["conical_sections"]
    c = StudioModel(s.doc, s.base_dir)
    h = {x.key: x for x in c.handles()}["section_b_8"]
    assert not c.move_handle("section_b_8", h.position + np.array([0.0, -6.0, 0.0]))
    assert "section_b" in c.error and c.doc == s.doc
    assert not c.move_handle("section_c_0", h.position) and "section_c_0" in c.error


def test_a_refused_fold_marks_the_faces_it_folds():
    m = StudioModel.load(EX / "conical_spheres.toml")
    before = m.state
    assert not m.set_param("spheres", [[0, 0, 0, 6.0], [6, 0, 0, 6], [8, 2, 0, 6], [8, 8, 0, 6]])
    assert "folds over" in m.error and m.state is before
    count, total = (int(x) for x in re.search(r"\((\d+) of (\d+) faces\)", m.error).groups())
    assert m.refused_folds is not None and m.refused_folds.shape == before.folded.shape
    assert m.refused_folds.size == total and int(m.refused_folds.sum()) == count > 0
    i, j = (int(x) for x in re.search(r"face \((\d+), (\d+)\)", m.error).groups())
    assert m.refused_folds[i, j]                                     # the face the message names
    assert m.set_param("faces_profile", 13) and m.refused_folds is None


# ----------------------------------------------------------------------------------------------------------
# cauchy: initial vertices slide on their node axes, support planes move and turn


def _unit_plane(e) -> np.ndarray:
    e = np.asarray(e, dtype=float)
    return e / np.linalg.norm(e[:3])


def _axis_direction(a, b) -> np.ndarray:
    """Unit direction of the line of planes ``a`` and ``b`` (the cross product of their normals)."""
    d = np.cross(np.asarray(a, float)[:3], np.asarray(b, float)[:3])
    return d / np.linalg.norm(d)


def _plane_residual(params: dict, v: np.ndarray) -> float:
    """Largest distance (construction units) of a row ``v[i, :]`` from ``U_i`` and of a column ``v[:, j]`` from
    ``W_j`` (so also of each initial vertex from the two planes of its node axis)."""
    U = np.stack([_unit_plane(e) for e in params["support_u"]])
    W = np.stack([_unit_plane(e) for e in params["support_w"]])
    rows = np.abs(np.einsum("ijk,ik->ij", v, U[:, :3]) + U[:, None, 3]).max()
    cols = np.abs(np.einsum("ijk,jk->ij", v, W[:, :3]) + W[None, :, 3]).max()
    return float(max(rows, cols))


def _off_axis(params: dict, name: str, k: int) -> float:
    """Distance of the stored initial vertex ``name[k]`` from the two planes of its node axis."""
    i, j = (k, 0) if name == "boundary_u" else (0, k)
    x = np.asarray(params[name][k], float)
    return max(abs(_unit_plane(params["support_u"][i]) @ np.r_[x, 1.0]),
               abs(_unit_plane(params["support_w"][j]) @ np.r_[x, 1.0]))


# (handle, along its node axis (m), across it (m), rotation)
CAUCHY = [
    ("boundary_u_5", 0.8, 0.3, None),
    ("boundary_w_3", -0.6, 0.5, None),
    ("boundary_u_0", 0.5, 0.2, None),                 # v_00: both lists
    ("support_u_4", None, [0.3, 0.0, 0.1], (1, 2.0)),
    ("support_w_9", None, [0.0, 0.2, 0.0], (0, -3.0)),
    ("support_u_0", None, [0.2, 0.0, 0.0], (2, 1.5)),   # U_0: every v_0j follows its axis
    ("support_w_0", None, [0.0, -0.3, 0.2], None),      # W_0: every v_i0 follows its axis
]


@pytest.fixture(scope="module")
def cauchy() -> StudioModel:
    return StudioModel.load(EX / "pp_cauchy.toml")


@pytest.mark.parametrize("key, along, across, turn", CAUCHY, ids=[c[0] for c in CAUCHY])
def test_cauchy_handle_keeps_the_initial_vertices_on_their_axes(cauchy, tmp_path, key, along, across, turn):
    m = StudioModel(cauchy.doc, cauchy.base_dir)
    p0 = cauchy.params
    h = {x.key: x for x in m.handles()}[key]
    name, k = key.rsplit("_", 1)
    k = int(k)
    rot = np.eye(3) if turn is None else _rot(*turn)
    if along is not None:
        # the node axis by the cross product of the normals; the drag has a part across the axis, which is dropped
        i, j = (k, 0) if name == "boundary_u" else (0, k)
        d = _axis_direction(p0["support_u"][i], p0["support_w"][j])
        off = np.cross(d, [0.0, 0.0, 1.0] if abs(d[2]) < 0.9 else [1.0, 0.0, 0.0])
        target = h.position + along * d + across * off / np.linalg.norm(off)
        expect = h.position + along * d
    else:
        target = expect = h.position + np.asarray(across)
    assert m.move_handle(key, target, rot), m.error
    v0, v = cauchy.state.placed.vertices, m.state.placed.vertices
    assert float(np.abs(v - v0).max()) > 20.0                          # mm
    assert _line_planarity(v) < 1e-9 and _face_planarity(v) < 1e-9
    # the rows lie in the (edited) planes U_i, the columns in W_j, the initial vertices on both of their planes
    size = float(np.linalg.norm(np.ptp(m.state.raw.vertices.reshape(-1, 3), 0)))
    assert _plane_residual(m.params, m.state.raw.vertices) < 1e-9 * size
    x = expect * 1000.0 / m.geometry["scale"]                           # display metres -> construction units
    if along is not None:
        # the point moved by the drag's component along its axis, and the mesh vertex is there
        after = {x.key: x for x in m.handles()}[key]
        assert np.abs(after.position - expect).max() < 1e-9
        assert np.abs(m.state.raw.vertices[i, j] - x).max() < 1e-9 * size
        assert _off_axis(m.params, name, k) < 1e-12 * size
        if k == 0:
            assert m.params["boundary_w"][0] == m.params["boundary_u"][0]
        others = [q for q in range(len(p0[name])) if q != k]
        assert all(m.params[name][q] == p0[name][q] for q in others)
    else:
        # the edited plane passes through the dragged point with the turned normal, of the same length
        new, old = np.asarray(m.params[name][k], float), np.asarray(p0[name][k], float)
        assert abs(new[:3] @ x + new[3]) < 1e-9 * np.linalg.norm(new[:3]) * size
        assert np.allclose(new[:3], rot @ old[:3], atol=1e-12 * np.linalg.norm(old[:3]))
        other = "support_w" if name == "support_u" else "support_u"
        assert m.params[other] == p0[other]
        # the initial vertices on the axes through the edited plane were moved onto the new axes, exactly
        if name == "support_u":
            moved = [("boundary_u", k)] + [("boundary_w", q) for q in range(len(p0["boundary_w"])) if k == 0]
        else:
            moved = [("boundary_w", k)] + [("boundary_u", q) for q in range(len(p0["boundary_u"])) if k == 0]
        if ("boundary_u", 0) in moved or ("boundary_w", 0) in moved:            # v_00 is in both lists
            moved += [("boundary_u", 0), ("boundary_w", 0)]
            assert m.params["boundary_w"][0] == m.params["boundary_u"][0]
        assert max(_off_axis(m.params, *e) for e in moved) < 1e-12 * size
        for list_name in ("boundary_u", "boundary_w"):                       # the others stay as they were
            assert all(m.params[list_name][q] == x for q, x in enumerate(p0[list_name]) if (list_name, q) not in moved)
    _one_undo_step_and_the_same_after_reload(m, v0, v, tmp_path)


def test_cauchy_refused_edits_keep_the_last_valid_design(cauchy):
    m = StudioModel(cauchy.doc, cauchy.base_dir)
    before = m.state
    h = {x.key: x for x in m.handles()}
    # v_10,0 up its axis to the dome's centre, where every node axis meets: the propagation breaks down
    p = h["boundary_u_10"].position.copy()
    p[2] = 40.0
    assert not m.move_handle("boundary_u_10", p)
    assert "breaks down at vertex (11, 1)" in m.error and "\n" not in m.error
    # W_3 turned onto U_0's normal: their node axis is undefined
    nw, nu = (np.asarray(cauchy.params[s][k][:3], float) for s, k in (("support_w", 3), ("support_u", 0)))
    a, b = nw / np.linalg.norm(nw), nu / np.linalg.norm(nu)
    c, ax = float(a @ b), np.cross(a, b)
    K = np.array([[0, -ax[2], ax[1]], [ax[2], 0, -ax[0]], [-ax[1], ax[0], 0]])
    R = np.eye(3) + K + K @ K / (1 + c)                                # Rodrigues: R a = b
    assert np.allclose(R @ a, b)
    assert not m.move_handle("support_w_3", h["support_w_3"].position, R)
    assert "nearly parallel" in m.error and "W_3" in m.error and "\n" not in m.error
    assert not m.move_handle("boundary_w_0", h["boundary_u_0"].position) and "boundary_u_0" in m.error
    assert not m.move_handle("boundary_u_99", p) and "boundary_u_99" in m.error
    assert m.state is before and m.doc == cauchy.doc and not m.history.undo


def test_cauchy_drag_is_one_undo_step(cauchy):
    _three_step_drag_is_one_undo_step(cauchy, "support_u_12", np.array([0.1, 0.0, 0.0]), 1)
