"""The studio's model without a browser: handles keep the mesh PP (P for the conical vault), the edited
parameters are exact, saving round-trips the geometry, bad values leave the state alone with a message,
undo/redo, and the live figures against independent formulas."""

from __future__ import annotations

import json
import math
import socket
import time
import tomllib

import numpy as np
import pytest

from conftest import REPO
from fabrication.cli import main
from fabrication.studio.figures import face_corners, panel_boxes
from fabrication.studio.model import StudioModel, face_metric, solve

pytest.importorskip("tomli_w", reason="the studio extra is not installed")

CONICAL = REPO / "examples" / "conical_spheres.toml"


def _delta_p(vertices: np.ndarray, families) -> float:
    """δ_P (§3.3) by SVD: largest distance from the least-squares plane over the bounding-box diagonal."""
    worst = 0.0
    for fam in families:
        for line in (vertices if fam == "rows" else np.swapaxes(vertices, 0, 1)):
            c = line - line.mean(0)
            worst = max(worst, float(np.abs(c @ np.linalg.svd(c)[2][-1]).max() / np.linalg.norm(np.ptp(line, 0))))
    return worst


def _poly(coeffs, t):
    return np.array([np.polyval(np.asarray(c, dtype=float)[::-1], t) for c in coeffs])


@pytest.fixture(scope="module")
def default() -> StudioModel:
    return StudioModel.load(None)


def test_tangent_plane_handle_moves_one_node_and_keeps_pp(default):
    m = StudioModel(default.doc, default.base_dir)
    p0 = m.params
    h = {x.key: x for x in m.handles()}["g1"]
    target = h.position + np.array([0.0, 0.0, 0.4])                # display metres
    assert m.move_handle("g1", target)
    p1 = m.params
    assert p1["h"] == p0["h"] and p1["c"] == p0["c"]
    # the new face plane f(u_1, v̄) = g(u_1) + h(v̄) − c passes through the moved handle (construction units)
    # g's D + 1 interpolation nodes spread uniformly over u_range (D its largest degree: 4 in the default)
    u = np.linspace(p0["u_range"][0], p0["u_range"][1], max(len(c) for c in p0["g"]))
    assert len(u) == 5
    vbar = 0.5 * sum(p0["v_range"])
    plane = _poly(p1["g"], u[1]) + _poly(p1["h"], vbar) - np.asarray(p1["c"])
    x = target * 1000.0 / m.geometry["scale"]
    assert abs(plane[:3] @ x + plane[3]) / np.linalg.norm(plane[:3]) < 1e-9
    for k in (0, 2, 3, 4):                                         # the other nodes keep their values
        assert np.allclose(_poly(p1["g"], u[k]), _poly(p0["g"], u[k]), atol=1e-12)
    moved = np.abs(m.state.placed.vertices - default.state.placed.vertices).max()
    assert moved > 50.0                                            # mm
    assert _delta_p(m.state.placed.vertices, ("rows", "cols")) < 1e-9


def test_turning_a_tangent_plane_handle_keeps_pp(default):
    m = StudioModel(default.doc, default.base_dir)
    h = {x.key: x for x in m.handles()}["h2"]
    a = math.radians(3.0)
    rot = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    assert m.move_handle("h2", h.position, rot)
    assert m.params["g"] == default.params["g"]
    assert np.abs(m.state.placed.vertices - default.state.placed.vertices).max() > 10.0
    assert _delta_p(m.state.placed.vertices, ("rows", "cols")) < 1e-9


def test_sphere_and_profile_handles_of_the_conical_vault():
    m = StudioModel.load(CONICAL)
    before = m.state.placed.vertices.copy()
    hs = {x.key: x for x in m.handles()}
    assert {"s0", "s4", "p0"} <= set(hs)
    assert m.move_handle("s2", hs["s2"].position + np.array([0.0, 0.0, 0.8]))
    assert m.params["spheres"][2][:3] == pytest.approx([16.0, -0.6, 0.8])
    assert m.state.families == ("rows",)
    assert _delta_p(m.state.placed.vertices, ("rows",)) < 1e-9
    assert np.abs(m.state.placed.vertices - before).max() > 100.0
    p = {x.key: x for x in m.handles()}["p4"]
    assert m.move_handle("p4", p.position + np.array([0.0, 0.0, -0.3]))
    assert _delta_p(m.state.placed.vertices, ("rows",)) < 1e-9


def test_drag_is_relative_to_its_start_and_one_undo_step(default):
    m = StudioModel(default.doc, default.base_dir)
    h = {x.key: x for x in m.handles()}["g2"]
    m.begin_drag()
    for dz in (0.1, 0.2, 0.3):
        assert m.drag("g2", h.position + np.array([0.0, 0.0, dz]))
    m.end_drag()
    direct = StudioModel(default.doc, default.base_dir)
    direct.move_handle("g2", h.position + np.array([0.0, 0.0, 0.3]))
    assert np.abs(m.state.placed.vertices - direct.state.placed.vertices).max() < 1e-9
    assert len(m.history.undo) == 1
    assert m.undo() and np.array_equal(m.state.placed.vertices, default.state.placed.vertices)
    assert m.redo() and np.abs(m.state.placed.vertices - direct.state.placed.vertices).max() == 0.0


def test_bad_values_leave_the_state_and_say_why(default):
    m = StudioModel(default.doc, default.base_dir)
    before = m.state
    assert not m.set_param("faces_u", "many")
    assert "faces_u" in m.error and m.state is before
    assert not m.set_param("u_range", [3.0, -3.0])
    assert "u_range" in m.error and m.state is before
    assert not m.set_param("g", [[0.0]])
    assert "g" in m.error and m.state is before
    assert m.set_param("faces_u", 10) and m.error == ""
    c = StudioModel.load(CONICAL)
    assert not c.set_param("spheres", [[0, 0, 0, 7], [1, 0, 0, 20]])
    assert "spacelike" in c.error


def test_save_round_trip_and_only_where_asked(default, tmp_path):
    m = StudioModel(default.doc, default.base_dir)
    h = {x.key: x for x in m.handles()}["h0"]
    m.move_handle("h0", h.position + np.array([0.3, -0.2, 0.5]))
    m.set_param("faces_v", 19)
    out = m.save(tmp_path / "roof.toml")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["roof.toml"]
    again = solve(tomllib.loads(out.read_text(encoding="utf-8")), tmp_path)
    assert np.abs(again.placed.vertices - m.state.placed.vertices).max() <= 1e-9
    from fabrication import load_design
    from ppfab.geometry import build_geometry

    d = load_design(out)                                           # every section still valid
    g = build_geometry(d.geometry, base_dir=d.base_dir)
    assert np.abs(g.mesh.vertices - m.state.placed.vertices).max() <= 1e-9
    from ppfab.errors import DesignError

    for bad in (tmp_path / "roof.txt", tmp_path / "missing" / "a.toml", tmp_path):
        with pytest.raises(DesignError):
            m.save(bad)


def test_figures_against_independent_formulas(default):
    st = default.state
    v = st.placed.vertices
    m, n = v.shape[0] - 1, v.shape[1] - 1
    f = st.figures
    assert f.panels == m * n
    # a planar quad is two triangles
    c = face_corners(v)
    tri = 0.5 * (np.linalg.norm(np.cross(c[..., 1, :] - c[..., 0, :], c[..., 2, :] - c[..., 0, :]), axis=-1) +
                 np.linalg.norm(np.cross(c[..., 2, :] - c[..., 0, :], c[..., 3, :] - c[..., 0, :]), axis=-1))
    assert tri.sum() / 1e6 > f.glass_area_m2                     # the faces; the glass is the panes as cut
    # the panes as cut: each face (in its own plane) inset by half the gap, by shapely's mitred buffer
    from shapely.geometry import Polygon

    from fabrication.design import load_design

    gap = load_design(None).section("panels").gap
    cut = 0.0
    for q in c.reshape(-1, 4, 3):
        o, e1 = q[0], (q[1] - q[0]) / np.linalg.norm(q[1] - q[0])
        nrm = np.cross(q[1] - q[0], q[3] - q[0])
        e2 = np.cross(nrm / np.linalg.norm(nrm), e1)
        cut += Polygon((q - o) @ np.stack([e1, e2], axis=1)).buffer(-0.5 * gap, join_style="mitre").area
    assert f.glass_area_m2 == pytest.approx(cut / 1e6, rel=1e-6) and f.gap_mm == gap
    # the bound a nesting of the real panes reports: make_panels insets every face, lower_bound grows the panes
    from fabrication.design import load_design
    from fabrication.nesting import lower_bound
    from fabrication.panels import make_panels

    d = load_design(None)
    panes = [p.flat_part() for p in make_panels(st.placed, d.section("panels"))]
    assert f.glass_sheets_min == lower_bound(panes, d.section("nesting"))
    from fabrication.nesting.result import grown_area
    from fabrication.studio.figures import grown_pane_areas

    assert grown_pane_areas(c, 10.0, d.section("panels").gap) == pytest.approx(
        [grown_area(p.outline, 5.0) for p in panes], rel=1e-9)                # closed form = the real panes
    assert f.glass_sheets_min >= math.ceil(sum(p.area for p in panes) / (6000.0 * 3210.0))
    assert f.beams == (m + 1) + (n + 1)
    lengths = np.linalg.norm(np.diff(v, axis=1), axis=-1).sum() + np.linalg.norm(np.diff(v, axis=0), axis=-1).sum()
    assert f.beam_length_m == pytest.approx(lengths / 1000.0, rel=1e-12)
    assert f.torsion_mm < 1e-6                                     # PP: the axes lie in both support planes
    edges = np.linalg.norm(np.roll(c, -1, axis=-2) - c, axis=-1)
    assert f.largest_panel_mm[0] >= edges.max() - 1e-9
    # the box around a rectangle is the rectangle
    rect = np.array([[[0, 0, 0], [3, 0, 0], [3, 2, 0], [0, 2, 0]]], float)
    assert panel_boxes(rect)[0] == pytest.approx([3.0, 2.0])
    assert face_metric(st.placed, "corner angle").min() == pytest.approx(f.min_corner_deg)


@pytest.mark.parametrize("example", ["conical_spheres", "default_pp_gridshell"])
def test_figures_count_what_the_build_counts(example):
    """The studio's torsion is that of the support structure the build makes (here a P support of the conical
    vault, whose construction's cone axes are 14 mm off), and its glass area that of the panes as the build
    cuts them: both against the build's own stages (geometry, support, panels, summary's definition)."""
    from fabrication.design import load_design
    from fabrication.progress import Progress
    from fabrication.pipeline.stages import stage_geometry, stage_panels, stage_support

    path = REPO / "examples" / f"{example}.toml"
    figs = StudioModel.load(path).state.figures
    design = load_design(path)
    quiet = Progress(quiet=True)
    geometry = stage_geometry(design, quiet, allow_large=False)
    support = stage_support(design, geometry, quiet)
    build_torsion = float(np.max(support.torsion_offset(design.beams.depth), initial=0.0))
    assert figs.torsion_mm == pytest.approx(build_torsion, abs=1e-6)
    assert "support the build makes" in figs.torsion_of
    panels = stage_panels(design, geometry, quiet).panels
    assert figs.glass_area_m2 == pytest.approx(sum(p.flat_part().area for p in panels) / 1e6, rel=1e-6)
    assert f"faces inset by half the {design.panels.gap:g} mm gap" in figs.markdown()


@pytest.fixture
def studio(default):
    """A studio server on a free loopback port, editing a fresh model of the default design; stopped after."""
    pytest.importorskip("viser")
    from fabrication.studio.app import Studio

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    server = Studio(StudioModel(default.doc, default.base_dir), port=port)
    yield server
    server.stop()


def test_studio_server_survives_bad_input_and_binds_loopback(studio):
    from fabrication.studio.values import parse_list as _parse_list

    assert studio.server.get_host() == "127.0.0.1"
    studio._guard(lambda: studio._set("g", _parse_list("[[0.0, 1", "g")))
    assert studio.model.error.startswith("g: not a list")
    studio._guard(lambda: studio.model.save("/nonexistent-folder/x.toml"))
    assert "no such folder" in studio.model.error
    studio._guard(lambda: studio._set("faces_u", 12))
    assert studio.model.error == "" and studio.model.state.placed.vertices.shape[0] == 13
    with socket.create_connection(("127.0.0.1", studio.server.get_port()), timeout=5):
        pass


def test_a_refused_value_reverts_its_field_and_says_why_beside_it(studio):
    """A value the model refuses does not stay in its field as if applied: the field shows the model's value
    again and the reason appears right under that field (the next control comes after it); a value that is not a
    number is refused the same way; the next applied edit takes the message away."""
    scale = studio._controls["geometry.scale"][0]
    kept = float(studio.model.geometry["scale"])
    for bad in (-5.0, float("nan")):
        scale.value = bad                                  # as the page sends it: the callbacks run
        assert float(studio.model.geometry["scale"]) == kept
        assert scale.value == kept                         # the field shows what the model keeps
        msg = studio.field_message
        assert msg is not None and "not applied" in msg.content and f"stays {kept:g}" in msg.content
        later = [h.order for h, _ in studio._controls.values() if h.order > scale.order]
        assert scale.order < msg.order < min(later, default=float("inf"))
    scale.value = 2 * kept
    assert float(studio.model.geometry["scale"]) == 2 * kept and studio.field_message is None


def test_the_colour_legend_names_what_the_colours_show(studio):
    """The legend under "colour by" gives the ramp's two ends with the values there (min and max of the panel
    areas in m², δ_f's fixed 0 … 1e-3 scale) and the number of panel types when coloured by type."""
    area = face_metric(studio.model.state.placed, "panel area")
    text = studio.legend.content
    assert "panel area" in text and f"{area.min():.3g} m²" in text and f"{area.max():.3g} m²" in text
    studio.metric_dd.value = "planarity"
    assert "δ_f" in studio.legend.content and "0.001 and above" in studio.legend.content
    studio.metric_dd.value = "type"
    types = int(face_metric(studio.model.state.placed, "type").max()) + 1
    assert f"{types} types" in studio.legend.content


def test_plane_handles_are_drawn_as_labelled_planes():
    """The plane-spline design's tangent-plane handles (the paper's Fig. 12): each is drawn as a translucent
    square in its plane (normal and point from the handle set, placed like the mesh) and carries its label."""
    pytest.importorskip("viser")
    from fabrication.studio.app import Studio

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    model = StudioModel.load(REPO / "examples" / "pp_plane_splines.toml")
    studio = Studio(model, port=port)
    try:
        planes = [h for h in model.handles() if h.normal is not None]
        assert len(planes) >= 4
        for h in planes:
            mesh = studio._handles[f"{h.key}-plane"]
            v = np.asarray(mesh.vertices, dtype=float)
            n = np.cross(v[1] - v[0], v[3] - v[0])
            assert abs(abs(n @ h.normal) / np.linalg.norm(n) - 1.0) < 1e-5            # in the handle's plane
            assert np.allclose(v.mean(axis=0), h.position, atol=1e-5)
            assert studio._handles[f"{h.key}-label"].text == h.label
    finally:
        studio.stop()


def test_cli_studio_bad_input(capsys):
    assert main(["studio", "--port", "0", "--no-browser"]) == 2
    assert capsys.readouterr().err.strip().startswith("ppfab: error: --port")
    assert main(["studio", "missing-design.toml", "--no-browser"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("ppfab: error:")


@pytest.mark.slow
def test_build_job_writes_the_edited_design(default, tmp_path):
    from fabrication.studio.jobs import BuildJob

    m = StudioModel(default.doc, default.base_dir)
    for key, value in (("faces_u", 4), ("faces_v", 3), ("u_range", [-3.0, 3.0]), ("v_range", [-2.0, 2.0])):
        assert m.set_param(key, value), m.error
    seen: list[str] = []
    job = BuildJob(m.design(), tmp_path / "out", lambda text, fraction: seen.append(text)).start()
    job.join(600)
    assert job.status == "done", job.message
    assert job.report is not None and job.report.is_file()
    assert any(s.startswith("support") for s in seen)
    import json

    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text(encoding="utf-8"))
    assert manifest["summary"]["panels"] == 12


def test_optimize_job_runs_in_the_background_and_cancels():
    from fabrication.studio.jobs import OptimizeJob
    from ppfab.optimize.params import OptimizeParams
    from ppfab.schema import parse_params

    path = REPO / "examples" / "p_optimised_conical1.toml"
    m = StudioModel.load(path)
    assert m.state.families == ()                        # the mesh file before optimising
    params = parse_params(OptimizeParams, dict(m.doc["optimize"]), "optimize")
    told: list[str] = []
    job = OptimizeJob(m.state.raw, params, lambda text, fraction: told.append(text))
    job.start()
    t0 = time.monotonic()
    while not told and time.monotonic() - t0 < 120:
        time.sleep(0.05)
    assert told and told[0].startswith("iteration")
    job.cancel()
    job.join(120)
    assert job.status == "cancelled" and job.result is None
    assert told[-1] == "optimisation cancelled"


def test_figures_take_a_per_side_trim_and_refuse_a_bad_nesting_table(default):
    """``[nesting] margin`` may be one number or four (left, right, bottom, top): the live bound uses the usable
    sheet either way; a bad value is refused with the design error a build would give."""
    import copy

    from ppfab.errors import DesignError

    doc = copy.deepcopy(default.doc)
    doc.setdefault("nesting", {})["margin"] = [10.0, 10.0, 10.0, 10.0]
    same = solve(doc, default.base_dir).figures.glass_sheets_min
    assert same == default.state.figures.glass_sheets_min
    doc["nesting"]["margin"] = [400.0, 400.0, 300.0, 300.0]             # 5200 × 2610 usable: more sheets
    assert solve(doc, default.base_dir).figures.glass_sheets_min > same
    doc["nesting"]["margin"] = "wide"
    with pytest.raises(DesignError):
        solve(doc, default.base_dir)


def test_nested_list_parameters_have_a_field_per_number_and_rows_that_the_construction_checks(studio):
    """The default's curve coefficients ``g`` (four rows of 2, 4, 1 and 5 numbers) are edited in vector and
    number fields; a changed field sets exactly that coefficient, a row the construction refuses leaves the
    model and the fields as they were with the reason, bad JSON is refused in one line, undo restores."""
    from fabrication.studio.table_editor import TableEditor

    editor = studio._controls["g"][0]
    assert isinstance(editor, TableEditor)
    g0 = studio.model.params["g"]
    assert [(r, s) for r, s, _ in editor.fields] == [(r, s) for r, row in enumerate(g0) for s in range(0, len(row), 3)]
    field = next(h for r, s, h in editor.fields if (r, s) == (1, 3))    # g's y: its x³ coefficient alone
    assert field.value == g0[1][3]
    before = studio.snapshot()["vertices"].copy()
    field.value = 2.0 * g0[1][3]
    g1 = studio.model.params["g"]
    assert studio.model.error == "" and g1[1] == [*g0[1][:3], 2.0 * g0[1][3]]
    assert [g1[k] for k in (0, 2, 3)] == [g0[k] for k in (0, 2, 3)]
    after = studio.snapshot()
    assert np.abs(after["vertices"] - before).max() > 1.0
    assert _delta_p(after["vertices"], ("rows", "cols")) <= 1e-9
    assert json.loads(editor.text.value) == g1

    studio._apply_table("g", lambda: [*g1, [1.0]])                # a fifth row: refused by the construction
    assert studio.model.error and studio.model.params["g"] == g1
    editor = studio._controls["g"][0]
    assert len({r for r, _, _ in editor.fields}) == 4 and field.value == g1[1][3]

    editor.text.value = "[[0.0, 1"
    assert studio.model.error.startswith("g: not JSON")
    assert studio.model.params["g"] == g1 and json.loads(editor.text.value) == g1

    studio._guard(lambda: studio._history(studio.model.undo))
    assert studio.model.params["g"] == g0
    assert next(h for r, s, h in studio._controls["g"][0].fields if (r, s) == (1, 3)).value == g0[1][3]


def test_a_table_that_gains_a_row_is_drawn_anew():
    from fabrication.studio.table_editor import row_chunks, with_cells, with_rows

    assert row_chunks(4) == [(0, 3), (3, 4)] and row_chunks(2) == [(0, 2)] and row_chunks(7)[-1] == (6, 7)
    table = [[0.0, 1.0, 2.0, 3.0], [4.0]]
    assert with_cells(table, 0, 3, 9) == [[0.0, 1.0, 2.0, 9.0], [4.0]] and table[0][3] == 3.0
    assert with_rows(table, +1) == [[0.0, 1.0, 2.0, 3.0], [4.0], [4.0]]
    assert with_rows([[1.0]], -1) == [[1.0]]


def test_a_sphere_removed_by_its_table_button_redraws_the_table_with_one_row_less():
    pytest.importorskip("viser")
    from fabrication.studio.app import Studio

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    studio = Studio(StudioModel.load(CONICAL), port=port)
    try:
        spheres = studio.model.params["spheres"]
        studio._controls["spheres"][0]._rows(-1)
        assert studio.model.error == "" and studio.model.params["spheres"] == spheres[:-1]
        editor = studio._controls["spheres"][0]
        assert len({r for r, _, _ in editor.fields}) == len(spheres) - 1
        x, y, z, r = spheres[0]
        assert [h.value for row, _, h in editor.fields if row == 0] == [(x, y, z), r]   # [x, y, z] and r
        assert _delta_p(studio.snapshot()["vertices"], ("rows",)) <= 1e-9
    finally:
        studio.stop()
