"""Tamper matrix: each realistic mistake in a delivered folder, made after the build and with the manifest's
sha256 updated (so only the geometric and cross-file checks can catch it), is named by ``ppfab verify`` —
file and element."""

from __future__ import annotations

import json
import re
import shutil

import numpy as np
import pytest

from fabrication.cli import main

from tamper import copy, findings, read_rows, reseal, write_rows  # noqa: F401

from conftest import built_folder, small_vault

DESIGN = small_vault("tamper", max_length=5000.0, joint="halflap")
built = built_folder("tamper", DESIGN)


def set_node(folder, rows, row, columns, key, value):
    """Give the node of ``row`` the vector ``value`` in nodes.csv (``columns``) and nodes.json (``key``)."""
    for c, x in zip(columns, value):
        row[c] = repr(float(x))
    write_rows(folder / "nodes.csv", rows)
    nodes = json.loads((folder / "nodes.json").read_text())
    nodes["nodes"][int(row["vertex"])][key] = np.asarray(value, dtype=float).tolist()
    (folder / "nodes.json").write_text(json.dumps(nodes, indent=1))


def manifest(folder):
    return json.loads((folder / "manifest.json").read_text())


def cut_outline(folder, kind):
    """(sheet file, doc, entity) of the first CUT outline of a panel ("glass") or plate ("beam") sheet."""
    import ezdxf

    rel = manifest(folder)["files"]["glass_sheets" if kind == "glass" else "beam_sheets"][0]
    doc = ezdxf.readfile(folder / rel)
    ent = next(e for e in doc.modelspace() if e.dxftype() == "LWPOLYLINE" and e.dxf.layer == "CUT")
    return rel, doc, ent


def shift_first_cut_point(folder, kind, dx):
    """Move the first vertex of the first CUT outline of a glass or plate sheet by ``dx`` mm in x; the sheet file."""
    rel, doc, ent = cut_outline(folder, kind)
    pts = [(x, y) for x, y, *_ in ent.get_points("xyseb")]
    pts[0] = (pts[0][0] + dx, pts[0][1])
    ent.set_points(pts, format="xy")
    doc.saveas(folder / rel)
    return rel


def part_of(ent):
    return next(v.split("=", 1)[1] for c, v in ent.get_xdata("PPFAB") if v.startswith("part_id="))


def test_untampered_copy_verifies(copy, capsys):
    assert main(["verify", str(copy), "--quiet"]) == 0


def test_panel_outline_moved_half_a_millimetre_in_a_dxf(copy, capsys):
    rel, doc, ent = cut_outline(copy, "glass")
    pid = part_of(ent)
    ent.set_points([(x + 0.5, y) for x, y, *_ in ent.get_points("xyseb")], format="xy")
    doc.saveas(copy / rel)
    reseal(copy, rel)
    err = findings(copy, capsys)
    assert f"{rel}: {pid}: parts.csv placement" in err and "0.5 mm from the CUT polyline" in err


@pytest.mark.parametrize("change", ["rotation+180,x+100", "mirrored"])
def test_parts_csv_placement_changed(copy, capsys, change):
    rows = read_rows(copy / "parts.csv")
    row = next(r for r in rows if r["kind"] == "panel")
    if change == "mirrored":
        row["mirrored"] = "1" if row["mirrored"] == "0" else "0"
    else:
        row["rotation_deg"] = str(float(row["rotation_deg"]) + 180.0)
        row["x"] = str(float(row["x"]) + 100.0)
    write_rows(copy / "parts.csv", rows)
    reseal(copy, "parts.csv")
    err = findings(copy, capsys)
    assert f": {row['part_id']}: parts.csv placement" in err and "from the CUT polyline" in err


def _turn(a, degrees, about):
    about = about / np.linalg.norm(about)
    t = np.radians(degrees)
    return a * np.cos(t) + np.cross(about, a) * np.sin(t) + about * (about @ a) * (1 - np.cos(t))


def test_node_axis_turned_five_degrees(copy, capsys):
    rows = read_rows(copy / "nodes.csv")
    r = rows[len(rows) // 2]
    a = np.array([float(r[c]) for c in ("axis_x", "axis_y", "axis_z")])
    b = _turn(a, 5.0, np.cross(a, [1.0, 0.3, 0.0]))
    for c, x in zip(("axis_x", "axis_y", "axis_z"), b):
        r[c] = f"{x:.9f}"
    write_rows(copy / "nodes.csv", rows)
    reseal(copy, "nodes.csv")
    err = findings(copy, capsys)
    node = r["node_id"]
    assert f"nodes.csv: {node}: axis differs from nodes.json" in err
    assert f"mesh.json: {node}: axis" in err
    assert f"{node}" in err and "leaves the plate's plane" in err


def test_node_beam_list_replaced(copy, capsys):
    rows = read_rows(copy / "nodes.csv")
    inner = [r for r in rows if r["boundary"] == "0"]
    r, other = inner[0], inner[-1]
    assert r["beams"] != other["beams"]
    r["beams"] = other["beams"]
    write_rows(copy / "nodes.csv", rows)
    reseal(copy, "nodes.csv")
    err = findings(copy, capsys)
    assert f"nodes.csv: {r['node_id']}: beam list does not match the plates of parts.csv" in err


def test_per_type_dxf_scaled(copy, capsys):
    import ezdxf

    rel = manifest(copy)["files"]["panel_type_dxfs"][0]
    doc = ezdxf.readfile(copy / rel)
    for e in doc.modelspace():
        if e.dxftype() == "LWPOLYLINE":
            e.set_points([(1.01 * x, 1.01 * y) for x, y, *_ in e.get_points("xyseb")], format="xy")
    doc.saveas(copy / rel)
    reseal(copy, rel)
    err = findings(copy, capsys)
    tid = rel.rsplit("_", 1)[1].removesuffix(".dxf")
    assert f"{rel}: {tid}: outline is not congruent with face" in err


def test_order_quantity_changed(copy, capsys):
    rows = read_rows(copy / "glass_order.csv")
    rows[0]["quantity"] = str(int(rows[0]["quantity"]) + 5)
    write_rows(copy / "glass_order.csv", rows)
    reseal(copy, "glass_order.csv")
    err = findings(copy, capsys)
    assert f"glass_order.csv: {rows[0]['type_id']}: quantity" in err


def test_parts_json_changed(copy, capsys):
    doc = json.loads((copy / "parts.json").read_text())
    part = doc["parts"][3]
    part["area_mm2"] += 1000.0
    (copy / "parts.json").write_text(json.dumps(doc, indent=1, sort_keys=True))
    reseal(copy, "parts.json")
    err = findings(copy, capsys)
    assert f"parts.json: {part['part_id']}: area_mm2 is" in err


def _rewrite_step(folder, name, change):
    from build123d import Compound, export_step

    from fabrication.verify._step_read import read_step_solids

    pairs = [(s.name, s.solid) for s in read_step_solids(folder / name)]     # named by occurrence (part id)
    target = next(n for n, _ in pairs if n.startswith("B-W") or n.startswith("P-")) if name == "panels.step" \
        else next(n for n, _ in pairs if n.startswith("B-W"))
    solids = []
    for n, s in pairs:
        if n == target:
            s = change(s)
        s.label = n
        solids.append(s)
    export_step(Compound(children=solids), str(folder / name))
    reseal(folder, name)
    return target


@pytest.mark.parametrize("change", ["moved 50 mm", "rotated 3°"])
def test_step_beam_solid_moved_or_rotated(copy, capsys, change):
    from build123d import Axis, Pos

    def move(s):
        if change == "moved 50 mm":
            return s.moved(Pos(30.0, 40.0, 0.0))
        c = s.center()
        return s.rotate(Axis((c.X, c.Y, c.Z), (0.3, 0.2, 1.0)), 3.0)

    from fabrication.verify import verify

    pid = _rewrite_step(copy, "beams.step", move)
    err = findings(copy, capsys) + "\n".join(str(f) for f in verify(copy).findings)   # all, not the first few
    assert f"beams.step: {pid}: solid is not the plate of its frame" in err or f"beams.step: {pid} at N" in err


def test_panels_step_changed(copy, capsys):
    from build123d import Pos

    pid = _rewrite_step(copy, "panels.step", lambda s: s.moved(Pos(0.0, 0.0, 5.0)))
    err = findings(copy, capsys)
    assert f"panels.step: {pid}: solid is " in err                   # off its face's normal by the slope …
    assert f"panels.step: {pid}: bears on no gasket" in err          # … and lifted off its gaskets


def test_plate_outline_changed_by_two_millimetres(copy, capsys):
    rel, doc, ent = cut_outline(copy, "beam")
    pid = part_of(ent)
    pts = [(x, y) for x, y, *_ in ent.get_points("xyseb")]
    # the vertex with the largest y: on the plate's outer edge, where no neighbour is near
    k = max(range(len(pts)), key=lambda i: pts[i][1])
    pts[k] = (pts[k][0], pts[k][1] + 2.0)
    ent.set_points(pts, format="xy")
    doc.saveas(copy / rel)
    reseal(copy, rel)
    err = findings(copy, capsys)
    assert f"{rel}: {pid}: parts.csv placement" in err and "2 mm from the CUT polyline" in err


def test_torsion_beyond_tolerance(copy, capsys):
    """One axis turned by 0.5° in every file that carries it (nodes.csv, nodes.json, mesh.json): the files
    agree, only the torsion of its edges (0.5° at 150 mm depth is 1.3 mm) shows it; a design tolerance
    ``beams.max_torsion_mm`` above that accepts it."""
    rows = read_rows(copy / "nodes.csv")
    r = rows[len(rows) // 2]
    k = int(r["vertex"])
    a = np.array([float(r[c]) for c in ("axis_x", "axis_y", "axis_z")])
    b = _turn(a, 0.5, np.cross(a, [1.0, 0.3, 0.0]))
    set_node(copy, rows, r, ("axis_x", "axis_y", "axis_z"), "axis", b)
    grid = json.loads((copy / "mesh.json").read_text())
    grid["axes"][int(r["i"])][int(r["j"])] = b.tolist()
    (copy / "mesh.json").write_text(json.dumps(grid, indent=2))
    reseal(copy, "nodes.csv", "nodes.json", "mesh.json")
    err = findings(copy, capsys)
    assert f"edge N{k:04d}-" in err or f"-N{k:04d}: torsion" in err
    assert "(> beams.max_torsion_mm 0.5 mm)" in err
    assert "axis differs" not in err
    m = manifest(copy)
    m["fabrication"]["beams"]["max_torsion_mm"] = 2.0
    (copy / "manifest.json").write_text(json.dumps(m, indent=2))
    capsys.readouterr()
    main(["verify", str(copy), "--quiet"])
    assert "at beam depth 150 mm (>" not in capsys.readouterr().err


def test_bite_overstated_in_bites_csv(copy, capsys):
    """bites.csv edited to claim 5 mm more bite for one pane than glazing.step and mesh.obj give: verify
    recomputes the bite from the files and names the pane."""
    rows = read_rows(copy / "bites.csv")
    r = rows[0]
    for x in rows:
        if x["panel"] == r["panel"]:
            x["bite_mm"] = f"{float(x['bite_mm']) + 5.0:.3f}"
    write_rows(copy / "bites.csv", rows)
    reseal(copy, "bites.csv")
    err = findings(copy, capsys)
    assert re.search(rf"bites\.csv: row \d+ column bite_mm: {r['panel']} over mesh edge \d+-\d+ \(GS-\S+\): "
                     r"\d+\.?\d* written, \d+\.\d+ measured", err), err[:2000]


def test_min_bite_raised_above_what_the_panes_have(copy, capsys):
    """A manifest whose panels.min_bite is raised to 40 mm (the panes bite about 20 mm): every pane edge below
    it is a finding naming pane, mesh edge and bite."""
    m = manifest(copy)
    m["fabrication"]["panels"]["min_bite"] = 40.0
    (copy / "manifest.json").write_text(json.dumps(m, indent=2))
    err = findings(copy, capsys)
    assert re.search(r"glazing\.step: P-\S+: the pane edge over mesh edge \d+-\d+ bites \d+\.\d\d mm on its gasket, "
                     r"less than panels\.min_bite = 40 mm", err)


def test_splice_cover_plate_removed_from_parts_csv(copy, capsys):
    """One splice's two cover plates deleted from parts.csv: verify names the two beam pieces left unjoined."""
    rows = read_rows(copy / "parts.csv")
    splice = next(r for r in rows if r["kind"] == "splice")
    joins = splice["joins"]
    write_rows(copy / "parts.csv", [r for r in rows if not (r["kind"] == "splice" and r["joins"] == joins)])
    reseal(copy, "parts.csv")
    err = findings(copy, capsys)
    a, b = joins.split(";")
    assert f"parts.csv: {a}/{b}: the cut between these pieces of" in err and "has 0 splice cover plate(s)" in err


def _in_metres(grid, pos) -> bool:
    """Whether mesh.json's vertices are in metres where mesh.obj's are in mm (compared at one vertex)."""
    v = np.asarray(grid["vertices"], dtype=float).reshape(-1, 3)
    return bool(np.abs(v).max() < 0.01 * np.abs(pos).max())


def test_node_moved_down_its_axis_into_the_plates(copy, capsys):
    """One interior vertex moved 30 mm down its own node axis in every file that carries it: the node stays in
    both its beams' planes and its axis is unchanged, but its top point now lies inside the plates, 30 mm
    under their top edges.  The row plate's half-lap slot opens from above, so the point lies in its slot,
    within half the slot width (about 6.5 mm) of the outline, which is right; the column plate's slot opens
    from below, so the point lies in solid plate 30 mm from the outline, where the slot (about 13 mm wide,
    square to the top edge, and the notch under the row's strips crossing there) allows about 10 mm: verify
    names that plate at that node."""
    lines = (copy / "mesh.obj").read_text().splitlines()
    vs = [i for i, s in enumerate(lines) if s.startswith("v ")]
    rows = read_rows(copy / "nodes.csv")
    r = next(r for r in rows if r["boundary"] == "0" and int(r["valence"]) == 4)
    k = int(r["vertex"])
    pos = np.array([float(x) for x in lines[vs[k]].split()[1:4]])
    axis = np.array([float(r[c]) for c in ("axis_x", "axis_y", "axis_z")])
    moved = pos + 30.0 * axis / np.linalg.norm(axis)
    lines[vs[k]] = "v " + " ".join(repr(float(x)) for x in moved)
    (copy / "mesh.obj").write_text("\n".join(lines) + "\n")
    set_node(copy, rows, r, ("x", "y", "z"), "position", moved)   # every file that carries the node agrees
    grid = json.loads((copy / "mesh.json").read_text())
    at = grid.get("obj_vertex", list(range(len(grid["vertices"])))).index(k)
    grid["vertices"][at] = (moved / 1000.0 if _in_metres(grid, pos) else moved).tolist()
    (copy / "mesh.json").write_text(json.dumps(grid, indent=2))
    reseal(copy, "mesh.obj", "nodes.csv", "nodes.json", "mesh.json")
    from fabrication.verify import verify

    # every finding, not the first 50 the command prints: the plates' node axis marks on the cutting sheets,
    # no longer on the moved axis, are named too
    err = "\n".join(str(f) for f in verify(copy).findings)
    assert re.search(rf"beams/plates_\d+\.dxf: B-\S+: MARK line is \d+\.?\d* mm from where its node axes put it", err)
    hit = re.search(rf"beams\.step: (B-\S+) at N{k:04d}: the node's top point is (\d+\.?\d*) mm from the plate's "
                    r"outline \(at most (\d+\.?\d*) mm", err)
    assert hit, err[:2000]
    assert float(hit.group(2)) > 25.0 > 2 * float(hit.group(3))
    plates = set(re.findall(rf"beams\.step: (B-\S+) at N{k:04d}: the node's top point", err))
    assert len(plates) == 1 and plates.pop().startswith("B-W") and "from the plate's plane" not in err


def test_the_strip_bound_follows_the_angle_of_the_top_edge_to_the_axis():
    """The verify bound for a node's top point inside an end cut or slot is ``r / sin θ``: a top edge 24° off
    the in-plane axis (as at the valence-6 nodes of a real P mesh, DOS planarizednormalized_six_quad) puts the
    corner 2.46 r from the node; only neighbours in the plate's plane count, and the smallest angle wins."""
    from fabrication.verify.step_geometry import _smallest_sine

    frame = {"origin": np.zeros(3), "x_dir": np.array([1.0, 0, 0]), "y_dir": np.array([0, 0, 1.0]),
             "normal": np.array([0, -1.0, 0])}
    plane = np.array([0.0, 1.0, 0.0, 0.0])                        # y = 0: the plate's plane
    theta = np.radians(24.0)
    s = np.array([np.cos(theta), -np.sin(theta)])                  # the axis, 24° below the top edge (+x)
    verts = np.array([[0.0, 0, 0], [650.0, 0, 0], [-500.0, 0, 40.0], [0.0, 300.0, 0]])
    ahead = _smallest_sine(np.zeros(2), s, frame, plane, verts, {1, 3}, 0.5)   # vertex 3: 300 mm off the plane
    assert ahead == pytest.approx(np.sin(theta), rel=1e-12) and 12.467 / ahead == pytest.approx(30.65, abs=0.05)
    back = np.arctan2(40.0, 500.0)               # the edge to vertex 2 runs back, rising 4.6°: 19.4° off the axis
    both = _smallest_sine(np.zeros(2), s, frame, plane, verts, {1, 2, 3}, 0.5)
    assert both == pytest.approx(np.sin(theta - back), rel=1e-12)
    assert _smallest_sine(np.zeros(2), s, frame, plane, verts, {3}, 0.5) == 1.0


def test_verify_on_two_cores_finds_what_one_core_finds(copy):
    """Findings on both sides of the split (a cover plate row gone: the splices check, this process; a plate
    outline moved in its cutting sheet: the dxf check here and the placement check in the second process) come
    out the same, in the same order, whether the checks run in one process or two; a check that raises in the
    second process is run again here and raises its own error."""
    from fabrication import verify as verify_mod

    rows = read_rows(copy / "parts.csv")
    splice = next(r for r in rows if r["kind"] == "splice")
    write_rows(copy / "parts.csv", [r for r in rows if r["part_id"] != splice["part_id"]])
    rel = shift_first_cut_point(copy, "beam", 3.0)
    reseal(copy, "parts.csv", rel)
    one = verify_mod.verify(copy, parallel=False)
    two = verify_mod.verify(copy, parallel=True)
    assert [str(f) for f in one.findings] == [str(f) for f in two.findings]
    assert one.checked == two.checked
    files = {f.file for f in two.findings}
    assert "parts.csv" in files and rel in files
    codes = {f.code for f in two.findings}
    assert codes & set(verify_mod.SECOND_PROCESS) and codes - set(verify_mod.SECOND_PROCESS)   # both halves found

    def broken(v):
        raise RuntimeError("the ifc check broke")

    ifc = verify_mod.CHECKS["ifc"]
    verify_mod._TABLE.entries["ifc"] = verify_mod.Check("ifc", broken)
    try:
        with pytest.raises(RuntimeError, match="the ifc check broke"):
            verify_mod.verify(copy, parallel=True)
    finally:
        verify_mod._TABLE.entries["ifc"] = ifc


def test_the_exchange_model_checks_run_in_processes_that_end(copy, monkeypatch, tmp_path):
    """IfcOpenShell and openNURBS keep what they read until the process ends, so the ifc, rhino and glb checks
    each run in a forked process of their own (on two cores, below the second process): never in this process
    and never two in one.  Without fork they run here.  A model.3dm and a model.glb cut short are found the same
    either way, and what the second process's checks found comes back in report order."""
    import os

    from fabrication import verify as verify_mod
    from fabrication.writers import _parallel

    for name in ("model.3dm", "model.glb"):
        data = (copy / name).read_bytes()
        (copy / name).write_bytes(data[: len(data) // 2])
    reseal(copy, "model.3dm", "model.glb")
    confined = verify_mod.CONFINED
    assert set(confined) == {"ifc", "rhino", "glb"}
    table = verify_mod.load_table()

    def recording(log):
        for name in confined:
            original = table[name]

            def run(v, _name=name, _run=original.run):
                with open(log, "a") as f:
                    f.write(f"{_name} {os.getpid()}\n")
                _run(v)

            monkeypatch.setitem(verify_mod._TABLE.entries, name, verify_mod.Check(name, run))

    def pids(log):
        runs = [line.split() for line in log.read_text().splitlines()]
        assert sorted(n for n, _ in runs) == sorted(confined)           # each ran once
        return {n: int(p) for n, p in runs}

    from fabrication.verify import glazing_step

    boxes = glazing_step._strip_boxes

    def strip_boxes(v, rows, sign, _log=tmp_path / "strips.pids"):
        with open(_log, "a") as f:
            f.write(f"{os.getpid()}\n")
        return boxes(v, rows, sign)

    monkeypatch.setattr(glazing_step, "_strip_boxes", strip_boxes)
    results = {}
    for mode, parallel in (("serial", False), ("two", True)):
        recording(tmp_path / f"{mode}.pids")
        (tmp_path / "strips.pids").write_text("")
        results[mode] = verify_mod.verify(copy, parallel=parallel)
        got = pids(tmp_path / f"{mode}.pids")
        assert os.getpid() not in got.values() and len(set(got.values())) == len(confined)
        # the strips' boxes, which all three read, are worked out before they fork, not in each of them
        strips = {int(p) for p in (tmp_path / "strips.pids").read_text().split()}
        assert strips and not strips & set(got.values())
    monkeypatch.setattr(_parallel, "fork_available", lambda: False)
    recording(tmp_path / "here.pids")
    results["here"] = verify_mod.verify(copy, parallel=False)
    assert set(pids(tmp_path / "here.pids").values()) == {os.getpid()}
    found = {mode: [str(f) for f in v.findings] for mode, v in results.items()}
    assert found["serial"] == found["two"] == found["here"]
    assert {"model.3dm", "model.glb"} <= {f.file for f in results["here"].findings}
    assert results["serial"].checked == results["two"].checked == results["here"].checked


def test_checks_get_what_they_read_in_any_order_and_either_process(copy, monkeypatch):
    """The checks have no order among themselves: a check reads what another check reads from the folder
    through :class:`~fabrication.verify.Verification`'s properties, which run that check first when it has not
    run.  Forked right after the manifest (nothing else read yet), run in reverse name order, or serially, a
    tampered folder gives the same findings, each once and under the check that found it."""
    from fabrication import verify as verify_mod

    rows = read_rows(copy / "parts.csv")
    beam = next(r for r in rows if r["kind"] == "beam")
    beam["nest_tag"] = "X" + beam["nest_tag"]                    # parts.csv and the plate's sheet disagree
    write_rows(copy / "parts.csv", rows)
    rel = shift_first_cut_point(copy, "glass", 3.0)
    reseal(copy, "parts.csv", rel)
    serial = verify_mod.verify(copy, parallel=False)
    assert not serial.ok and {f.code for f in serial.findings} >= {"dxf"}
    assert len({str(f) for f in serial.findings}) == len(serial.findings)       # none reported twice
    monkeypatch.setattr(verify_mod, "READ_FIRST", ("manifest",))
    early_fork = verify_mod.verify(copy, parallel=True)
    table = verify_mod.load_table()
    monkeypatch.setattr(verify_mod, "load_checks",
                        lambda: [table["manifest"]] + sorted((c for c in table.values() if c.name != "manifest"),
                                                             key=lambda c: c.name, reverse=True))
    reverse = verify_mod.verify(copy, parallel=False)
    key = lambda v: sorted(str(f) for f in v.findings)            # noqa: E731 - the same findings, any order
    assert key(early_fork) == key(serial) == key(reverse)
    assert [str(f) for f in early_fork.findings] == [str(f) for f in serial.findings]    # in REPORT_ORDER
    assert sorted(early_fork.checked) == sorted(serial.checked) == sorted(reverse.checked)
    by_code = lambda v: sorted((f.code, str(f)) for f in v.findings)   # noqa: E731
    assert by_code(reverse) == by_code(serial)


def _sheet_entities(folder, kind, dxftype, layer):
    """(sheet file, doc, entities) of the first glass ("glass") or plate ("beam") cutting sheet."""
    import ezdxf

    rel = manifest(folder)["files"]["glass_sheets" if kind == "glass" else "beam_sheets"][0]
    doc = ezdxf.readfile(folder / rel)
    return rel, doc, [e for e in doc.modelspace() if e.dxftype() == dxftype and e.dxf.layer == layer]


def test_glass_sheet_label_names_another_panel(copy, capsys):
    """The id text of one pane on a glass sheet changed to the id of the next pane on that sheet: verify names
    the sheet, the pane the text lies on and the id it wrongly carries."""
    rel, doc, labels = _sheet_entities(copy, "glass", "TEXT", "LABEL")
    ids = [e for e in labels if e.dxf.text.startswith("P-")]
    first, other = ids[0], ids[1]
    pid, wrong = first.dxf.text, other.dxf.text
    first.dxf.text = wrong
    doc.saveas(copy / rel)
    reseal(copy, rel)
    err = findings(copy, capsys)
    assert f"{rel}: {pid}: LABEL text '{wrong}' on the outline of {pid} is another part's id" in err
    assert f"{rel}: {pid}: part carries its id on LABEL 0 times, expected once" in err


def test_glass_sheet_label_that_is_no_id(copy, capsys):
    """A label text that is no id at all (control-free garbage) is a finding naming sheet and pane, no error."""
    rel, doc, labels = _sheet_entities(copy, "glass", "TEXT", "LABEL")
    first = next(e for e in labels if e.dxf.text.startswith("P-"))
    pid = first.dxf.text
    first.dxf.text = "%%not an id"
    doc.saveas(copy / rel)
    reseal(copy, rel)
    err = findings(copy, capsys)
    assert f"{rel}: {pid}: LABEL text '%%not an id' on the outline of {pid} is not this part's id or nest tag" in err


@pytest.mark.parametrize("kind", ["glass", "beam"])
def test_mark_line_moved_30_mm(copy, capsys, kind):
    """One MARK line (a pane's reference L, a plate's node axis line) moved 30 mm along the sheet's x: verify
    names the sheet and the part whose mark it no longer is."""
    from shapely.geometry import Point, Polygon

    rel, doc, marks = _sheet_entities(copy, kind, "LWPOLYLINE", "MARK")
    cuts = [e for e in doc.modelspace() if e.dxftype() == "LWPOLYLINE" and e.dxf.layer == "CUT"]
    mark = marks[0]
    pts = [(x, y) for x, y, *_ in mark.get_points("xyseb")]
    owner = next(part_of(c) for c in cuts
                 if Polygon([(x, y) for x, y, *_ in c.get_points("xyseb")]).contains(Point(*np.mean(pts[:2], axis=0))))
    mark.set_points([(x + 30.0, y) for x, y in pts], format="xy")
    doc.saveas(copy / rel)
    reseal(copy, rel)
    err = findings(copy, capsys)
    assert f"{rel}: {owner}: 1 MARK line(s) missing" in err
    assert re.search(rf"{re.escape(rel)}: [^:]+: MARK line (is 30 mm from where|1: lies at)", err) or \
        re.search(rf"{re.escape(rel)}: MARK line \d+: lies at \(", err), err[:2000]


def test_per_type_dimension_text_overridden(copy, capsys):
    """A DIMENSION of a per-type DXF given a text override of 1234.5 mm: verify names the file, the type and the
    dimension (its handle) and the length it really measures."""
    import ezdxf

    rel = manifest(copy)["files"]["panel_type_dxfs"][2]
    doc = ezdxf.readfile(copy / rel)
    dim = [e for e in doc.modelspace() if e.dxftype() == "DIMENSION"][1]
    dim.dxf.text = "1234.5"
    doc.saveas(copy / rel)
    reseal(copy, rel)
    err = findings(copy, capsys)
    tid = rel.rsplit("_", 1)[1].removesuffix(".dxf")
    assert re.search(rf"{re.escape(rel)}: {tid} DIMENSION #{dim.dxf.handle}: text is overridden to '1234.5'; the "
                     r"dimension measures \d+\.\d mm", err), err[:2000]


def _rewrite_named(folder, name, target, change):
    """Rewrite the STEP file ``name`` with the solid ``target`` changed (flat, every solid keeps its name)."""
    from build123d import Compound, export_step

    from fabrication.verify._step_read import read_step_solids

    solids = []
    for n, s in [(r.name, r.solid) for r in read_step_solids(folder / name)]:   # named by occurrence (part id)
        if n == target:
            s = change(s)
        s.label = n
        solids.append(s)
    assert target in [s.label for s in solids]
    export_step(Compound(children=solids), str(folder / name))
    reseal(folder, name)


def test_splice_cover_plate_moved_4_mm(copy, capsys):
    """One splice cover plate moved 4 mm along its beam (across the cut) in splices.step: verify names the
    plate and how far off the cut it is."""
    from build123d import Pos

    rows = read_rows(copy / "parts.csv")
    plate = next(r for r in rows if r["kind"] == "splice")
    piece = next(r for r in rows if r["part_id"] == plate["joins"].split(";")[0])
    along = np.asarray(json.loads(piece["frame"])["x_dir"]) * 4.0
    _rewrite_named(copy, "splices.step", plate["part_id"], lambda s: s.moved(Pos(*along)))
    err = findings(copy, capsys)
    hit = re.search(rf"splices\.step: {plate['part_id']}: cover plate is (\d+\.?\d*) mm off the cut between", err)
    assert hit, err[:2000]
    assert 3.0 < float(hit.group(1)) <= 4.0 + 1e-6


def test_key_plan_polygon_moved(copy, capsys):
    """One pane's polygon on the key plan moved 25 mm: verify names the drawing and the pane."""
    rel = next(f for f in manifest(copy)["files"]["drawings"] if f.endswith("key_plan.svg"))
    text = (copy / rel).read_text()
    pts = re.search(r'<polygon points="([^"]*)"', text).group(1)
    moved = " ".join(f"{float(x) + 25.0:.1f},{y}" for x, y in (p.split(",") for p in pts.split()))
    (copy / rel).write_text(text.replace(pts, moved, 1))
    reseal(copy, rel)
    err = findings(copy, capsys)
    assert re.search(rf"{re.escape(rel)}: P-\S+: polygon 1 nearest this pane is 25 mm from where its mesh face", err), \
        err[:2000]


def test_key_plan_polygon_that_is_no_number(copy, capsys):
    """A polygon whose points are not numbers is a finding naming the drawing and the polygon, no error."""
    rel = next(f for f in manifest(copy)["files"]["drawings"] if f.endswith("key_plan.svg"))
    text = (copy / rel).read_text()
    (copy / rel).write_text(re.sub(r'<polygon points="[^"]*"', '<polygon points="1,2 x,4 5,6"', text, count=1))
    reseal(copy, rel)
    err = findings(copy, capsys)
    assert f"{rel}: polygon 1: points '1,2 x,4 5,6' are not x,y numbers" in err
    assert "pane is drawn nowhere its outline projects" in err


def test_extra_dxf_not_in_the_manifest(copy, capsys):
    """A cutting sheet copied into the folder after the build, listed nowhere: verify names it."""
    src = copy / manifest(copy)["files"]["glass_sheets"][0]
    shutil.copy(src, src.with_name("glass_99.dxf"))
    err = findings(copy, capsys)
    rel = src.with_name("glass_99.dxf").relative_to(copy).as_posix()
    assert f"{rel}: is in the folder but not listed in manifest.json (sha256)" in err


@pytest.mark.parametrize("which", ["strip", "gasket"])
def test_glazing_strip_or_gasket_moved_3_mm(copy, capsys, which):
    """One glazing strip (or the gasket on it) moved 3 mm in glazing.step: verify recomputes each strip's box from
    its mesh edge, the node axes, the beam plane and the panes, and names the solid that left it."""
    from build123d import Pos

    rows = read_rows(copy / "parts.csv")
    strip = [r for r in rows if r["kind"] == "strip"][5]
    name = strip["part_id"] if which == "strip" else "GK" + strip["part_id"][2:]
    _rewrite_named(copy, "glazing.step", name, lambda s: s.moved(Pos(3.0, 0.0, 0.0)))
    err = findings(copy, capsys)
    hit = re.search(rf"glazing\.step: {name}: {which} is (\d+\.?\d*) mm from the box its span, node axes and beam "
                    rf"plane put it in \(mesh edge {strip['edge_nodes'].replace(';', '-')}\)", err)
    assert hit, err[:2000]
    assert float(hit.group(1)) == pytest.approx(3.0, abs=0.01)


def test_every_file_of_a_build_is_read_by_a_check(built, monkeypatch):
    """Every file a real build writes is opened by at least one verify check other than the two that only hash
    or list files (manifest, files): the checks run one by one under an audit hook that records, per check, the
    files of the folder it opened (Python's ``open`` event; the STEP reader raises ``fabrication.verify.read``
    itself, and the IFC and Rhino readers, which open files in C++, are wrapped here to raise it)."""
    import os
    import sys

    import ifcopenshell
    import rhino3dm

    from fabrication.verify import Verification, load_checks

    folder = built.resolve()
    current: list[str | None] = [None]
    opened: dict[str, set[str]] = {}

    def hook(event, args):
        if current[0] is None or event not in ("open", "fabrication.verify.read") or not args:
            return
        if isinstance(args[0], (str, bytes, os.PathLike)):
            path = os.path.realpath(os.fsdecode(args[0]))
            if path.startswith(str(folder) + os.sep):
                opened.setdefault(current[0], set()).add(os.path.relpath(path, folder).replace(os.sep, "/"))

    def audited(fn):
        def wrapper(path, *a, **k):
            sys.audit("fabrication.verify.read", str(path))
            return fn(path, *a, **k)
        return wrapper

    monkeypatch.setattr(ifcopenshell, "open", audited(ifcopenshell.open))
    monkeypatch.setattr(rhino3dm.File3dm, "Read", staticmethod(audited(rhino3dm.File3dm.Read)))
    sys.addaudithook(hook)            # hooks cannot be removed: this one records nothing once current is None
    v = Verification(folder)
    try:
        for c in load_checks():
            current[0] = c.name
            c.run(v)
    finally:
        current[0] = None
    assert v.ok, [str(f) for f in v.findings[:5]]
    files = sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())
    assert len(files) > 60 and "glazing.step" in files and "drawings/key_plan.svg" in files
    assert set(files) <= opened["manifest"] | {"manifest.json"}          # the manifest check hashes them all
    assert "model.ifc" in opened["ifc"] and "model.3dm" in opened["rhino"]
    content = set().union(*(fs for name, fs in opened.items() if name not in ("manifest", "files")))
    assert "splices.step" in content                # read once per process, by whichever check asks first
    content.add("manifest.json")                    # its keys, units and digests are what the manifest check reads
    unread = [f for f in files if f not in content]
    assert unread == [], f"files no check reads: {unread}"


def test_a_verify_reads_each_step_file_once_and_lets_its_solids_go(built):
    """A serial verify of a real build reads every STEP file once (the text reader's ``fabrication.verify.read``
    events, the kernel's reads of its samples being of temporary files), and once the last check reading solids
    (:data:`~fabrication.verify.SOLID_READERS`) has run they are let go: the memo of STEP files is empty after
    the verify and the beam solids are gone.  A check reading solids that the set does not name would run after
    the release and read its file a second time.  Asked for again, the beam solids are read again."""
    import collections
    import os
    import sys

    from fabrication.verify import SOLID_READERS, load_checks, verify

    folder = os.path.realpath(built)
    reads: collections.Counter[str] = collections.Counter()
    recording = [True]

    def hook(event, args):
        if recording[0] and event == "fabrication.verify.read" and args:
            path = os.path.realpath(os.fsdecode(args[0]))
            if path.startswith(folder + os.sep):
                reads[os.path.relpath(path, folder)] += 1

    sys.addaudithook(hook)            # hooks cannot be removed: this one records nothing once recording is off
    try:
        v = verify(built, parallel=False)
    finally:
        recording[0] = False
    assert v.ok, [str(f) for f in v.findings[:5]]
    steps = sorted(p.name for p in built.glob("*.step"))
    assert len(steps) >= 4 and set(reads) == set(steps), (reads, steps)
    assert all(n == 1 for n in reads.values()), reads
    assert v.read.step_read == {} and v.read.beam_solids is None and v.read.erection_passes is None
    names = [c.name for c in load_checks()]
    assert max(names.index(n) for n in SOLID_READERS) < names.index("ifc")     # the models come after
    beams = {r["part_id"] for r in v.parts or [] if r.get("kind") == "beam"}
    assert len(beams) >= 20 and set(v.beam_solids or {}) == beams


def test_every_shared_field_is_filled_by_the_check_named_for_it(built, monkeypatch):
    """:data:`~fabrication.verify.PRODUCERS` is true: on a real build each field of ``FolderData`` it names is
    filled once that check has run on a fresh verification; asking for it runs the producer once, and the
    producer's own turn then reports what it found without running it again."""
    from fabrication import verify as verify_mod

    verify_mod.load_checks()
    runs: dict[str, int] = {}
    for producer in set(verify_mod.PRODUCERS.values()):
        check = verify_mod.CHECKS[producer]

        def counted(v, run=check.run, name=producer):
            runs[name] = runs.get(name, 0) + 1
            run(v)
        monkeypatch.setitem(verify_mod.CHECKS, producer, verify_mod.Check(producer, counted))
    for name, producer in verify_mod.PRODUCERS.items():
        runs.clear()
        v = verify_mod.Verification(built)
        assert getattr(v.read, name) in (None, {}, [])                # nothing read yet
        assert getattr(v, name), f"{name}: {producer} left it empty"  # the property ran the producer
        found, _ = v.run_check(verify_mod.CHECKS[producer])
        assert runs[producer] == 1 and found == [] and v.findings == []
