"""The command line: ppfab check, the geometry part of ppfab build, design-file errors, atomic output."""

import json

import pytest

from fabrication.cli import main
from ppfab.io import load_mesh

from conftest import shared_file, small_design


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_check_on_shared_meshes_reports_metrics(capsys):
    code, out, _ = run(capsys, "check", shared_file("DOS__enneper2.obj"), "--json")
    assert code == 0
    q = json.loads(out)
    assert q["grid_shape"] == [31, 31]
    assert q["delta_f_max"] == pytest.approx(3.8e-4, rel=0.05)
    code, out, _ = run(capsys, "check", shared_file("DOS__enneper2.obj"), "--tol", "1e-5")
    assert code == 1 and "delta_f" in out
    code, _, _ = run(capsys, "check", shared_file("DOI__rot4_def1_sparse_rot.obj"), "--tol", "2e-6")
    assert code == 0


def test_check_bad_file_is_one_line_exit_2(capsys, tmp_path):
    p = tmp_path / "tri.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    code, out, err = run(capsys, "check", p)
    assert code == 2
    assert err.startswith("ppfab: error:") and err.count("\n") == 1 and "Traceback" not in err


GEOMETRY = small_design(7, 5, u_range=(-6.0, 6.0), v_range=(-4.0, 4.0), fast=False)


def test_check_on_built_obj_reports_pp(capsys, tmp_path):
    from fabrication.design import parse_design
    from ppfab.geometry import build_geometry
    from ppfab.io import write_obj
    import tomllib

    design = parse_design(tomllib.loads(GEOMETRY), sections=("design", "geometry"))
    mesh = build_geometry(design.geometry, design.optimize, design.base_dir).mesh
    write_obj(mesh, tmp_path / "m.obj")
    code, out, _ = run(capsys, "check", tmp_path / "m.obj", "--json", "--tol", "1e-9")
    assert code == 0
    q = json.loads(out)
    assert q["delta_p_rows_max"] <= 1e-9 and q["delta_p_cols_max"] <= 1e-9 and q["delta_f_max"] <= 1e-9
    assert load_mesh(tmp_path / "m.obj").grid.shape == (8, 6)
