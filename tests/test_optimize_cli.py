"""``ppfab optimize``: real files in and out, exit codes, atomic output, JSON, parameters."""

from __future__ import annotations

import json

import numpy as np
import pytest

from fabrication.cli import main
from ppfab.io import read_mesh
from ppfab.metrics import quality

from conftest import SHARED_DATA, shared_file  # noqa: E402

TUBE = SHARED_DATA / "compas_libigl__tubemesh.off"


@pytest.fixture(autouse=True)
def _needs_tube() -> None:
    """Every case here optimises the tube mesh of the shared data (skipped with a message when absent)."""
    shared_file(TUBE.name)


def test_optimize_writes_pp_mesh_in_input_order(tmp_path, capsys):
    out = tmp_path / "tube_pp.obj"
    rc = main(["optimize", str(TUBE), "-o", str(out), "--families", "both", "--json"])
    assert rc == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["targets_met"] and doc["iterations"] == len(doc["history"])
    assert doc["params"]["families"] == "both"
    src, res = read_mesh(TUBE), read_mesh(out)                       # through the real reader
    assert np.array_equal(src.faces, res.faces) and res.vertices.shape == src.vertices.shape
    q = quality(res.to_grid())
    assert max(q.delta_f_max, q.delta_p_rows_max, q.delta_p_cols_max) <= 1e-6
    disp = np.linalg.norm(res.vertices - src.vertices, axis=1).mean()
    assert doc["displacement_mean"] == pytest.approx(disp, rel=1e-6)
    assert [p.name for p in tmp_path.iterdir()] == ["tube_pp.obj"]     # no temporary file left behind


def test_verbose_prints_every_iteration(tmp_path, capsys):
    out = tmp_path / "o.off"
    assert main(["optimize", str(TUBE), "-o", str(out), "--verbose", "--set", "weight_fair=0.02"]) == 0
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.startswith("it ")]
    assert len(lines) >= 3 and "dF=" in lines[0] and "dP=" in lines[0]
    assert "targets met" in err
    assert read_mesh(out).faces.shape == (171, 4)


def test_unmet_targets_exit_1_but_write(tmp_path, capsys):
    out = tmp_path / "o.obj"
    assert main(["optimize", str(TUBE), "-o", str(out), "--max-iter", "1", "--quiet"]) == 1
    assert out.exists()


def test_design_table_and_options(tmp_path, capsys):
    design = tmp_path / "d.toml"
    design.write_text('[optimize]\nfamilies = "none"\nmax_iterations = 150\n', encoding="utf-8")
    out = tmp_path / "o.obj"
    assert main(["optimize", str(TUBE), "-o", str(out), "--design", str(design), "--fix-boundary", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["params"]["families"] == "none" and doc["params"]["fix_boundary"]
    src, res = read_mesh(TUBE), read_mesh(out)
    bnd = src.topology.boundary_vertices
    assert np.array_equal(res.vertices[bnd], src.vertices[bnd])


@pytest.mark.parametrize("argv, needle", [
    (["missing.obj", "-o", "{tmp}/o.obj"], "cannot read"),
    ([str(TUBE), "-o", "{tmp}/o.stl"], "unknown mesh format"),
    ([str(TUBE), "-o", "{tmp}/nope/o.obj"], "does not exist"),
    ([str(TUBE), "-o", "{tmp}/o.obj", "--set", "weight_fiar=1"], "did you mean 'weight_fair'"),
    ([str(TUBE), "-o", "{tmp}/o.obj", "--polylines", "1,x"], "comma-separated integers"),
    ([str(TUBE), "-o", "{tmp}/o.obj", "--polylines", "999"], "optimize.polylines[0]"),
    ([str(TUBE), "-o", "{tmp}/o.obj", "--target-df", "-1"], "optimize.target_delta_f"),
], ids=["missing", "format", "folder", "unknown-key", "bad-list", "bad-polyline", "bad-target"])
def test_bad_input_is_one_line_exit_2(tmp_path, capsys, argv, needle):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert main(["optimize", *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("ppfab: error:") and needle in err[0]
    assert not (tmp_path / "o.obj").exists()


def test_existing_output_survives_a_failed_run(tmp_path, capsys):
    out = tmp_path / "o.obj"
    out.write_text("keep me\n", encoding="utf-8")
    assert main(["optimize", str(TUBE), "-o", str(out), "--polylines", "999"]) == 2
    assert out.read_text(encoding="utf-8") == "keep me\n"
