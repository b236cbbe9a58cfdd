"""Reading a finished build back: ``open_build(folder)`` gives the records ``package_of(build)`` makes in memory
(a small vault and a patch of a real mesh), every part kind with its outline where the files draw it, unknown
kinds and columns kept, older builds read, one-line errors naming file, row and column, the folder untouched.

Tolerances of the round trip (``differences``): the parts table and the node table are exact; a cutting outline
comes back within 2e-8 mm (``parts.json`` rounds ``x, y`` of the placement to 8 decimals); a strip's length and
width and the welds' values within 5e-4 (3 and 4 decimals in the files); the mesh is exact (``repr`` floats).
"""

from __future__ import annotations

import csv
import hashlib
import json
import re
import shutil
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from fabrication import build, open_build, package_of, parse_design
from fabrication.flatpart import Placement as FlatPlacement
from fabrication.flatpart import place_points
from fabrication.model import PanelData, differences
from fabrication.readers import BuildReadError
from fabrication.writers.dxf import read_sheet_dxf
from ppfab.errors import FabricationError

from conftest import REPO, shared_file, small_vault, write_patch_obj

LIGHT = "\n[output]\npanels_step = false\nreport = false\nifc = false\nrhino = false\nglb = false\n"
"""The exchange models and the report are not read back: leaving them out keeps the builds cheap."""


@pytest.fixture(scope="module")
def vault(tmp_path_factory):
    """The small vault built in memory and written: ``(build, folder)``."""
    b = build(parse_design(tomllib.loads(small_vault("read_back") + LIGHT)))
    out = b.write(tmp_path_factory.mktemp("vault") / "out")
    return b, out


def _copy(folder: Path, dest: Path) -> Path:
    """The files a reader reads, copied to ``dest`` (to be altered there)."""
    shutil.copytree(folder, dest, ignore=shutil.ignore_patterns("*.step", "drawings", "*.svg"))
    return dest


def _sha(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def _area(outline) -> float:
    """Shoelace area of a polygon (an independent formula, not the project's)."""
    x, y = np.asarray(outline, dtype=float).T
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def _round_trip(b, out: Path) -> None:
    """``open_build`` of the folder against ``package_of`` of the build, with the tolerances of the module
    docstring, and a shift of 0.01 mm found."""
    disk, mem = open_build(out), package_of(b)
    assert differences(disk, mem) == []
    cut = [(tuple(p for p in pk.parts if p.kind != "strip")) for pk in (disk, mem)]
    assert differences(*cut, abs_tol=2e-8, rel_tol=0.0) == []
    assert differences(disk.parts, mem.parts, abs_tol=5e-4, rel_tol=0.0) == []
    assert differences(disk.nodes, mem.nodes, abs_tol=0.0, rel_tol=0.0) == []
    assert differences(disk.mesh, mem.mesh, abs_tol=0.0, rel_tol=0.0) == []
    assert differences(disk.sheets, mem.sheets, abs_tol=0.0, rel_tol=0.0) == []
    assert differences(disk.welds, mem.welds, abs_tol=5e-4, rel_tol=0.0) == []
    first = mem.parts[0]
    assert first.outline is not None
    shifted = replace(mem, parts=(replace(first, outline=tuple((x + 0.01, y) for x, y in first.outline)),)
                      + mem.parts[1:])
    found = differences(disk, shifted)
    assert len(found) == len(first.outline) and all(d.startswith(f".parts[{first.part_id}].outline[") for d in found)


def test_a_written_vault_reads_back_as_the_build_in_memory(vault):
    b, out = vault
    before = _sha(out)
    _round_trip(b, out)
    assert _sha(out) == before                            # reading wrote, moved or touched nothing


def test_every_kind_of_the_parts_table_is_read_with_its_geometry(vault):
    b, out = vault
    package = open_build(out)
    rows = json.loads((out / "parts.json").read_text())["parts"]
    counts: dict[str, int] = {}
    for r in rows:
        counts[r["kind"]] = counts.get(r["kind"], 0) + 1
    assert package.kinds == counts and set(counts) >= {"panel", "beam", "strip", "splice"}
    assert [p.part_id for p in package.parts] == [r["part_id"] for r in rows]
    for p in package.parts:
        if p.kind in ("panel", "beam", "strip", "splice"):
            assert p.outline is not None and len(p.outline) >= 4, p.part_id
            # a cover plate has its type's outline (the type DXF draws one plate; plates of a type agree to the
            # whole millimetre of its name), every other part its own
            rel = 1e-3 if p.kind == "splice" else 1e-6
            assert _area(p.outline) == pytest.approx(p.area_mm2, rel=rel, abs=1e-2), p.part_id
    # a sheet part's outline, placed again by the project's own mapping, is the CUT polyline of its sheet
    beam = next(p for p in package.of_kind("beam") if p.placement and p.placement.mirrored and p.holes)
    pl = beam.placement
    cut = next(c for c in read_sheet_dxf(out / pl.sheet_file).parts if c.part_id == beam.part_id)
    again = place_points(beam.outline_array(), FlatPlacement(beam.part_id, pl.sheet - 1, pl.x, pl.y, pl.rotation_deg,
                                                             pl.mirrored))
    assert np.abs(again[::-1] - cut.points).max() < 1e-6
    # a beam plate's outline, set in the model by its frame, lies in its support plane
    n, d = np.asarray(beam.plane[:3]), beam.plane[3]
    corners = np.array([beam.frame.to_model(x, y) for x, y in beam.outline])
    assert np.abs(corners @ n + d).max() < 1e-6
    assert beam.details.joins and beam.details.splices and len(beam.holes) == beam.details.holes
    splice = package.part(beam.details.splices[0])
    assert splice.kind == "splice" and len(splice.holes) == splice.details.holes == 4
    assert {h.diameter for h in splice.holes} == {splice.details.hole_mm}
    strip = package.of_kind("strip")[0]
    assert strip.placement is None and strip.details.bar >= 1 and len(strip.details.edge_nodes) == 2
    # nodes, welds, sheets and the mesh agree with their own files
    assert len(package.nodes) == len(package.mesh.vertices) == b.summary.nodes
    node = package.nodes[7]
    assert np.allclose(node.position, package.mesh.vertices[node.vertex]) and abs(np.linalg.norm(node.axis) - 1) < 1e-9
    with open(out / "welds.csv", newline="") as fh:
        assert len(package.welds) == len(list(csv.DictReader(fh))) > 0
    placed = {p.part_id for p in package.parts if p.placement}
    assert sorted(pid for s in package.sheets for pid in s.parts) == sorted(placed)
    assert len(package.sheets) == b.summary.glass_sheets + b.summary.plate_sheets
    assert package.mesh.grid_shape == (7, 5) and len(package.mesh.faces) == b.summary.panels


def test_unknown_kinds_and_columns_are_kept(vault, tmp_path):
    """A kind and a column added later (a bracket under a pane's edge, say) come through in ``extra``, nothing
    dropped."""
    _, out = vault
    folder = _copy(out, tmp_path / "b")
    doc = json.loads((folder / "parts.json").read_text())
    doc["parts"][0]["edge_seal"] = "silicone"
    doc["parts"].append({"part_id": "BR-0001", "kind": "bracket", "type_id": "BR100", "material": "S355",
                         "thickness_mm": 4.0, "area_mm2": 400.0, "sheet": "", "block_length_mm": 100.0,
                         "panel": "P-U00-V00"})
    (folder / "parts.json").write_text(json.dumps(doc))
    package = open_build(folder)
    block = package.parts[-1]
    assert block.kind == "bracket" and block.details is None and block.outline is None
    assert block.extra == {"block_length_mm": 100.0, "panel": "P-U00-V00"} and block.thickness_mm == 4.0
    assert package.parts[0].extra == {"edge_seal": "silicone"}
    assert package.kinds["bracket"] == 1


def test_an_older_build_reads_as_the_current_one(vault, tmp_path):
    """The layout before docs/migration.md's changes: ``flags`` instead of ``panel_flags``, structured cells of
    ``parts.csv`` as Python literals (read when there is no ``parts.json``), ``welds.csv`` without ``joint``."""
    _, out = vault
    current = open_build(out)
    folder = _copy(out, tmp_path / "old")
    (folder / "parts.json").unlink()
    text = (folder / "parts.csv").read_text().replace("panel_flags", "flags", 1)
    rows = list(csv.reader(text.splitlines()))
    header = rows[0]
    for r in rows[1:]:
        for k, cell in enumerate(r):
            if cell.startswith(("[", "{")):
                r[k] = repr(json.loads(cell))          # 0.1.0 wrote Python literals (single quotes)
    drop = header.index("sheet_file")                  # and a table without sheet_file: the manifest's lists
    rows = [r[:drop] + r[drop + 1:] for r in rows]
    with open(folder / "parts.csv", "w", newline="") as fh:
        csv.writer(fh, lineterminator="\n").writerows(rows)
    assert "'origin'" in (folder / "parts.csv").read_text() and "flags" in rows[0] and "sheet_file" not in rows[0]
    with open(out / "welds.csv", newline="") as fh:
        welds = list(csv.reader(fh))
    assert welds[0][-1] == "joint" and "T" in {w[-1] for w in welds[1:]}
    with open(folder / "welds.csv", "w", newline="") as fh:             # 0.1.0 listed the T joints only
        csv.writer(fh, lineterminator="\n").writerows([w[:-1] for w in welds if w[-1] in ("joint", "T")])
    old = open_build(folder)
    t_joints = tuple(w for w in current.welds if w.joint == "T")
    assert 0 < len(t_joints) < len(current.welds)
    assert differences(replace(old, welds=()), replace(current, welds=()), abs_tol=0.0, rel_tol=0.0) == []
    assert differences(old.welds, t_joints, abs_tol=0.0, rel_tol=0.0) == []
    assert any(isinstance(p.details, PanelData) for p in old.parts)


def test_nodes_csv_reads_as_nodes_json_to_its_decimals(vault, tmp_path):
    """Without ``nodes.json`` the nodes come from ``nodes.csv``: the same records to the CSV's decimals (positions
    4, angles 4), without what only the JSON holds (beam planes, per-panel angles, pairs, axis to normal)."""
    _, out = vault
    folder = _copy(out, tmp_path / "n")
    (folder / "nodes.json").unlink()
    full, brief = open_build(out).nodes, open_build(folder).nodes

    def json_only_dropped(n):
        return replace(n, beams=tuple(replace(b, plane=None, panel_angles_deg=()) for b in n.beams), pairs=(),
                       axis_normal_deg=None)

    assert differences(tuple(json_only_dropped(n) for n in full), brief, abs_tol=5e-4, rel_tol=0.0) == []
    assert any(b.trim_mm for n in brief for b in n.beams)           # the set-backs land on the ending plates
    assert all(b.trim_mm is None for n in brief for b in n.beams if b.role == "through")
    lines = (folder / "nodes.csv").read_text().splitlines()
    lines[3] = lines[3].replace(",through;", ",through;through;", 1).replace(",end;", ",end;end;", 1)
    (folder / "nodes.csv").write_text("\n".join(lines) + "\n")
    assert re.search(r"nodes\.csv, row 3, column roles: 2 beams but 3 roles", _error(folder))


def _error(folder: Path) -> str:
    with pytest.raises(BuildReadError) as exc:
        open_build(folder)
    assert isinstance(exc.value, FabricationError) and isinstance(exc.value, ValueError)
    text = str(exc.value)
    assert "\n" not in text
    return text


def test_missing_and_malformed_files_are_one_line_naming_file_row_and_column(vault, tmp_path):
    _, out = vault
    assert "no such folder" in _error(tmp_path / "nowhere")
    folder = _copy(out, tmp_path / "c")
    doc = json.loads((folder / "parts.json").read_text())
    doc["parts"][2]["x"] = "left"
    (folder / "parts.json").write_text(json.dumps(doc))
    msg = _error(folder)
    assert msg.startswith(f"{folder / 'parts.json'}, row 3, column x: expected a number"), msg
    doc["parts"][2]["x"] = 0.0
    doc["parts"][4]["frame"] = {"origin": [0, 0, 0]}
    (folder / "parts.json").write_text(json.dumps(doc))
    assert re.search(r"parts\.json, row 5, column frame: frame has no x_dir", _error(folder))
    (folder / "parts.json").write_text("{\"parts\": [")
    assert "parts.json: not valid JSON (line 1" in _error(folder)
    (folder / "parts.json").unlink()
    (folder / "parts.csv").unlink()
    assert "parts.json: missing (the parts list)" in _error(folder)

    folder = _copy(out, tmp_path / "d")
    lines = (folder / "welds.csv").read_text().splitlines()
    cells = lines[2].split(",")
    cells[6] = "thick"                                            # throat_mm of the second weld
    lines[2] = ",".join(cells)
    (folder / "welds.csv").write_text("\n".join(lines) + "\n")
    assert "welds.csv, row 2, column throat_mm: expected a number, got 'thick'" in _error(folder)
    (folder / "welds.csv").unlink()
    assert "welds.csv: missing" in _error(folder)                 # the manifest lists it

    folder = _copy(out, tmp_path / "e")
    sheet = json.loads((folder / "parts.json").read_text())["parts"][0]["sheet_file"]
    (folder / sheet).write_text("0\nSECTION\n0\nNONSENSE\n")
    assert f"{folder / sheet}: not a readable DXF" in _error(folder)
    (folder / sheet).unlink()
    assert f"{folder / sheet}: missing (the cutting sheet of" in _error(folder)
    (folder / "manifest.json").unlink()
    assert "manifest.json: missing" in _error(folder)
    assert sorted(p.name for p in (folder / "glass").iterdir()) == sorted(
        p.name for p in (out / "glass").iterdir() if p.as_posix() != (out / sheet).as_posix())   # nothing added


def test_the_readme_example_runs_on_a_written_build(vault, tmp_path, capsys):
    _, out = vault
    import os

    readme = (REPO / "README.md").read_text(encoding="utf-8")
    section = readme.split("## Reading a build", 1)[1]
    block = re.search(r"```python\n(.*?)\n```", section, re.S).group(1)
    assert len([ln for ln in block.splitlines() if ln.strip()]) <= 5
    shutil.copytree(out, tmp_path / "out-python", ignore=shutil.ignore_patterns("*.step"))
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        exec(compile(block, "README.md", "exec"), {})
    finally:
        os.chdir(cwd)
    first, second = capsys.readouterr().out.splitlines()
    b, _ = vault
    counts = f"{b.summary.nodes} {len(b.glazing.welds)} {b.summary.glass_sheets + b.summary.plate_sheets}"
    assert first.startswith("{'panel': 24, 'beam': ") and first.endswith(f"}} {counts}"), first
    part_id, corners, sheet, length = second.split()
    assert part_id.startswith("B-") and int(corners) >= 4 and sheet.startswith("beams/plates_")
    assert float(length) > 1000


def test_the_model_imports_nothing_of_the_project():
    """``fabrication.model`` is data only, at the bottom: no import of ``fabrication`` or ``ppfab``."""
    for path in (REPO / "fabrication" / "model").glob("*.py"):
        text = path.read_text(encoding="utf-8")
        assert not re.search(r"^\s*(from|import)\s+(fabrication|ppfab)\b", text, re.M), path.name
        assert not re.search(r"^\s*from\s+\.\.", text, re.M), path.name


@pytest.mark.slow
def test_a_patch_of_a_real_mesh_reads_back_as_the_build(tmp_path):
    """A 5 × 4 patch of a surface of revolution (conical PP, WWmore/DOI ``objs/obj_rot/rot4_def1_sparse_rot.obj``,
    the shared data) built with halflap joints and one-edge plates where polylines cannot be planar beams; its joints open to 16 mm,
    the gap the build names for the clamping screws at its kinks (at 10 mm they stand 2.6 mm in the glass)."""
    from ppfab.io import load_mesh

    mesh = load_mesh(shared_file("DOI__rot4_def1_sparse_rot.obj"))
    assert mesh.grid_ids is not None
    ids = mesh.grid_ids[10:16, 8:13]
    rows, cols = ids.shape
    write_patch_obj(mesh.vertices, ids, tmp_path / "patch.obj")
    design = (f'[design]\nname = "rot_patch"\n[geometry]\nmesh = "{(tmp_path / "patch.obj").as_posix()}"\n'
              'scale = 7000.0\n[support]\nmethod = "pp"\n[beams]\njoint = "halflap"\ndepth = 150.0\n'
              'thickness = 12.0\nfallback = "segmented"\n[panels]\ngap = 16.0\n[nesting]\ntime_budget = 0.5\n[beam_nesting]\n'
              'time_budget = 0.5\n' + LIGHT)
    b = build(parse_design(tomllib.loads(design), base_dir=tmp_path))
    out = b.write(tmp_path / "out")
    _round_trip(b, out)
    package = open_build(out)
    assert package.kinds["panel"] == 20 and package.kinds["beam"] == b.summary.beam_plates
    assert set(package.kinds) >= {"panel", "beam", "strip"}
    assert len(package.nodes) == 30 and package.mesh.grid_shape == (6, 5)


@pytest.mark.slow
def test_the_bundled_default_reads_back_as_the_build(tmp_path):
    """The default design (22 × 15 faces, every part kind the default makes: panes, plates, strips, splice
    cover plates and the glass retention) written and read back equals the build in memory, to the tolerances
    of the module docstring; its kinds count what ``parts.csv`` holds."""
    from fabrication.design import DEFAULT_DESIGN

    text = DEFAULT_DESIGN.read_text(encoding="utf-8")
    assert "[output]" not in text
    b = build(parse_design(tomllib.loads(text + LIGHT), base_dir=DEFAULT_DESIGN.parent))
    out = b.write(tmp_path / "out")
    _round_trip(b, out)
    package = open_build(out)
    with open(out / "parts.csv", newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    kinds: dict[str, int] = {}
    for r in rows:
        kinds[r["kind"]] = kinds.get(r["kind"], 0) + 1
    assert dict(package.kinds) == kinds
    assert {"panel", "beam", "strip", "splice"} <= set(kinds) and len(kinds) >= 6
