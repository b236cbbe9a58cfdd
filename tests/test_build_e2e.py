"""End to end: a design built into a folder that satisfies the output contract; ppfab verify passes on it and
fails, naming the file and element, on deliberately damaged copies."""

import csv
import json
import shutil

import numpy as np

from fabrication.cli import main
from ppfab.io import load_mesh

from conftest import built_folder, small_vault

SMALL = small_vault("e2e", max_length=5000.0, joint="halflap")
built = built_folder("e2e", SMALL)


def rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_contract(built):
    import hashlib

    m = json.loads((built / "manifest.json").read_text())
    assert m["units"] == "mm" and m["generator"].startswith("ppfab")
    assert m["mesh"]["rows"] == 7 and m["mesh"]["cols"] == 5
    assert set(m["mesh"]["planar_families"]) == {"rows", "cols"}
    for key in ("beam_depth", "beam_thickness", "panel_gap", "sheet", "sheet_margin", "part_spacing",
                "planarity_tolerance"):
        assert key in m["fabrication"], key
    for key in ("beams_step", "glass_sheets", "beam_sheets", "parts_csv", "nodes_csv", "report_html"):
        assert key in m["files"], key
    for name, digest in m["sha256"].items():
        assert hashlib.sha256((built / name).read_bytes()).hexdigest() == digest, name
    mesh = load_mesh(built / "mesh.obj")
    # OBJ row-major: v[i, j] is vertex i*(n+1)+j
    assert np.array_equal(mesh.grid.vertex_ids, np.arange(35).reshape(7, 5))
    parts = rows(built / "parts.csv")
    panels = [r for r in parts if r["kind"] == "panel"]
    beams = [r for r in parts if r["kind"] == "beam"]
    assert sorted(int(r["face"]) for r in panels) == list(range(24))
    assert all(r["face_i"] != "" and r["face_j"] != "" for r in panels)
    assert len({r["nest_tag"] for r in parts}) == len(parts)
    nodes = rows(built / "nodes.csv")
    assert len(nodes) == 35
    ids = {r["part_id"] for r in beams}
    assert all(set(filter(None, n["beams"].split(";"))) <= ids for n in nodes)
    html = (built / "report.html").read_text()
    assert "<script" not in html and "http://" not in html.replace("http://www.w3.org/2000/svg", "")
    assert "data:image/png;base64," in html and "Cutting sheets" in html


def test_verify_passes(built, capsys):
    assert main(["verify", str(built)]) == 0
    assert "OK" in capsys.readouterr().out


def damaged(built, tmp_path):
    copy = tmp_path / "copy"
    shutil.copytree(built, copy)
    return copy


def test_verify_names_a_dxf_part_moved_onto_another(built, tmp_path, capsys):
    import ezdxf

    out = damaged(built, tmp_path)
    sheet = out / json.loads((out / "manifest.json").read_text())["files"]["glass_sheets"][0]
    doc = ezdxf.readfile(sheet)
    cuts = [e for e in doc.modelspace() if e.dxftype() == "LWPOLYLINE" and e.dxf.layer == "CUT"]
    assert len(cuts) >= 2
    target = [tuple(p) for p in cuts[1].get_points("xyseb")]
    cuts[0].set_points(target, format="xyseb")
    doc.saveas(sheet)
    assert main(["verify", str(out)]) == 1
    err = capsys.readouterr().err
    assert sheet.name in err and "overlaps" in err


def test_verify_names_a_removed_step_solid(built, tmp_path, capsys):
    from build123d import Compound, export_step, import_step

    from fabrication.writers.step import named_solids

    out = damaged(built, tmp_path)
    pairs = named_solids(import_step(str(out / "beams.step")))
    dropped = pairs[0][0]
    keep = []
    for name, solid in pairs[1:]:
        solid.label = name
        keep.append(solid)
    export_step(Compound(children=keep), str(out / "beams.step"))
    assert main(["verify", str(out)]) == 1
    err = capsys.readouterr().err
    assert "beams.step" in err and dropped in err and "no solid" in err


def test_verify_names_a_deleted_csv_row(built, tmp_path, capsys):
    out = damaged(built, tmp_path)
    lines = (out / "parts.csv").read_text().splitlines(keepends=True)
    removed = lines[3].split(",")[0]
    (out / "parts.csv").write_text("".join(lines[:3] + lines[4:]))
    assert main(["verify", str(out)]) == 1
    err = capsys.readouterr().err
    assert "parts.csv" in err and removed in err
