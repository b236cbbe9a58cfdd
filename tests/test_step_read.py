"""verify's STEP reader (``fabrication/verify/_step_read.py``) against build123d's ``import_step`` on every STEP
file of a real build, and the product trees of ``glazing.step`` and ``splices.step`` (design → beam → solids).

The reader walks the kernel's XCAF labels itself instead of build123d's Python assembly tree; both must give
the same solids: names, the assemblies above each, vertices, volumes and, for ``beams.step``, colours.
"""

from __future__ import annotations

import csv

import numpy as np
import pytest

from conftest import built_folder, small_vault
from fabrication.verify import verify
from fabrication.verify._step_read import read_step_solids

built = built_folder("step_read", small_vault("step read", max_length=3000.0))


def _build123d_solids(path) -> list[tuple[tuple[str, ...], object]]:
    """``(labels of the assemblies above, solid)`` of every solid, walking build123d's imported tree."""
    from build123d import Solid, import_step

    def walk(node, above):
        if isinstance(node, Solid):
            return [(above, node)]
        kids = list(getattr(node, "children", ()) or ())
        if not kids:
            return [(above, s) for s in node.solids()]
        return [pair for kid in kids for pair in walk(kid, above + (node.label,))]

    return walk(import_step(str(path)), ())


def _points(solid) -> np.ndarray:
    pts = np.array([tuple(p) for p in solid.vertices()])
    return pts[np.lexsort(pts.T[::-1])]


@pytest.mark.parametrize("name", ["beams.step", "glazing.step", "splices.step", "panels.step"])
def test_reader_gives_the_solids_build123d_gives(built, name):
    path = built / name
    assert path.exists(), f"the build wrote no {name}"
    theirs = _build123d_solids(path)
    ours = read_step_solids(path, colours=(name == "beams.step"))
    assert len(ours) == len(theirs) > 0
    for (above, solid), mine in zip(theirs, ours):
        if "_shape_" in solid.label:
            # a shape written once and placed per part (glazing.step, panels.step): build123d names the solid by
            # the shape's product ("SB shape 9"), verify's reader by its occurrence, the part id
            assert solid.label.startswith(mine.name.split("-")[0] + "_shape_"), (mine.name, solid.label)
        else:
            assert mine.name == solid.label
        # build123d folds " .()" of a label into "_"; below the root the labels are part and beam ids
        assert mine.path[1:] == above[1:] and len(mine.path) == len(above)
        assert np.abs(_points(mine.solid) - _points(solid)).max() <= 1e-9
        assert mine.solid.volume == pytest.approx(solid.volume, rel=1e-9)
        if name == "beams.step":
            assert mine.colour is not None
            assert np.allclose(mine.colour, tuple(solid.color), atol=1e-6)


def _rows(built) -> dict[str, dict[str, str]]:
    with open(built / "parts.csv", newline="", encoding="utf-8") as f:
        return {r["part_id"]: r for r in csv.DictReader(f)}


@pytest.mark.parametrize("name, kind", [("glazing.step", "strip"), ("splices.step", "splice")])
def test_glazing_and_splice_solids_sit_under_their_beam(built, name, kind):
    rows = _rows(built)
    read = read_step_solids(built / name)
    wanted = {pid for pid, r in rows.items() if r["kind"] == kind}
    assert wanted, f"the build has no {kind} parts"
    seen = set()
    retention = {}                                  # setting blocks, stops, pressure plates: rows of retention.csv
    if name == "glazing.step" and (built / "retention.csv").exists():
        with open(built / "retention.csv", newline="", encoding="utf-8") as f:
            retention = {r["part_id"]: r for r in csv.DictReader(f)}
    for s in read:
        if s.name in retention:
            assert len(s.path) == 2 and s.path[1] == retention[s.name]["beam"], (s.name, s.path)
            continue
        pid = "GS" + s.name[2:] if s.name.startswith("GK") else s.name      # a gasket belongs to its strip
        assert pid in rows, s.name
        assert len(s.path) == 2 and s.path[1] == rows[pid]["beam"], (s.name, s.path)
        seen.add(s.name)
    assert wanted <= seen
    groups = {s.path[1] for s in read}
    assert len(groups) == len({rows[pid]["beam"] for pid in wanted})        # one assembly per beam, no more


def test_unreadable_step_is_a_finding(built, tmp_path):
    import shutil

    out = tmp_path / "out"
    shutil.copytree(built, out)
    text = (out / "glazing.step").read_bytes()
    (out / "glazing.step").write_bytes(text[: len(text) // 3])                # cut off mid-file
    report = verify(out)
    assert not report.ok
    assert any(f.file == "glazing.step" and ("cannot be read by the CAD kernel" in f.message or
                                             "cannot be read at the text level (the DATA section does not end"
                                             in f.message)
               for f in report.findings), [str(f) for f in report.findings]


def test_panels_sit_in_glass_by_row(built):
    rows = _rows(built)
    read = read_step_solids(built / "panels.step")
    panels = {pid for pid, r in rows.items() if r["kind"] == "panel"}
    assert {s.name for s in read} == panels
    for s in read:
        assert s.path[1:] == ("glass", f"P-U{int(rows[s.name]['face_i']):02d}"), (s.name, s.path)


def test_panel_groups_of_a_general_mesh_are_blocks_of_consecutive_panels():
    from fabrication.writers.step import PANEL_BLOCK, panel_groups

    ids = [f"P-{k:04d}" for k in range(2 * PANEL_BLOCK + 7)]
    groups = panel_groups(ids)
    assert groups[0] == groups[PANEL_BLOCK - 1] == f"P-0000-{PANEL_BLOCK - 1:04d}"
    assert groups[-1] == f"P-{2 * PANEL_BLOCK:04d}-{2 * PANEL_BLOCK + 6:04d}"
    assert len(set(groups)) == 3
    assert panel_groups(["P-U03-V00", "P-U03-V01", "P-U04-V00"]) == ["P-U03", "P-U03", "P-U04"]


def test_reader_places_a_solid_by_the_locations_of_the_assemblies_above_it(tmp_path):
    """A box in an assembly placed 100 mm along x and turned 90° about z, inside a second assembly placed
    50 mm along z: its vertices are R·p + t of the box's own, composed by hand."""
    from build123d import Box, Compound, Location, export_step

    box = Box(10, 20, 30)
    box.label = "box"
    inner = Compound(children=[box], label="inner").moved(Location((100, 0, 0), (0, 0, 1), 90))
    inner.label = "inner"
    outer = Compound(children=[inner], label="outer").moved(Location((0, 0, 50)))
    outer.label = "outer"
    export_step(Compound(children=[outer], label="root"), str(tmp_path / "placed.step"))
    (solid,) = read_step_solids(tmp_path / "placed.step")
    assert solid.name == "box" and solid.path == ("root", "outer", "inner")
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    own = np.array([[x, y, z] for x in (-5, 5) for y in (-10, 10) for z in (-15, 15)], dtype=float)
    want = own @ turn.T + np.array([100.0, 0.0, 50.0])
    got = np.array([tuple(p) for p in solid.solid.vertices()])
    assert len(got) == 8
    assert max(np.linalg.norm(want - g, axis=1).min() for g in got) <= 1e-9


def test_the_kernel_floor_benchmark_reads_every_solid_and_touches_nothing(built):
    """``benchmarks/step_floor.py`` times the kernel's plain reader and writer on each STEP file: the plain
    reader must see exactly the solids the self-check's reader sees (else the floor would be of another
    file), every file of the build must be measured, and the build's files must be byte-identical after."""
    import hashlib
    import importlib.util

    from conftest import REPO

    spec = importlib.util.spec_from_file_location("step_floor", REPO / "benchmarks" / "step_floor.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    steps = sorted(p.name for p in built.glob("*.step"))
    before = {n: hashlib.sha256((built / n).read_bytes()).hexdigest() for n in steps}
    rows = mod.measure(built, 1)
    assert sorted(r["file"] for r in rows) == steps
    for r in rows:
        assert r["solids"] == r["ppfab_solids"] == len(read_step_solids(built / r["file"])) > 0, r
        assert r["read"] > 0 and r["write"] > 0 and r["ppfab"] > 0
    assert {n: hashlib.sha256((built / n).read_bytes()).hexdigest() for n in steps} == before


def test_the_read_memory_benchmark_reads_every_solid_in_a_fresh_process(built):
    """``benchmarks/step_read_memory.py`` measures verify's read of a file in a fresh process importing the tree
    it is given: it must read every solid the reader reads here, with no finding, its peak at or above the
    resident size before the read, and leave the file as it was."""
    import hashlib
    import importlib.util

    from conftest import REPO
    from fabrication.verify._step_text_read import read_text_solids

    spec = importlib.util.spec_from_file_location("step_read_memory", REPO / "benchmarks" / "step_read_memory.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    before = hashlib.sha256((built / "splices.step").read_bytes()).hexdigest()
    got = mod.measure(REPO, built, "splices.step")
    assert got["solids"] == len(read_text_solids(built / "splices.step")) > 0 and got["findings"] == 0
    assert got["peak"] >= got["before"] > 0 and got["cpu"] > 0
    assert hashlib.sha256((built / "splices.step").read_bytes()).hexdigest() == before
