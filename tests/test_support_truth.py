"""One source of truth for the support structure: mesh.json carries the node axes and support planes of the
structure that was fabricated (the one of nodes.csv and the beams), for every example and with
``[support] flip``."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from fabrication.cli import main
from fabrication.design import load_design
from fabrication.progress import Progress
from fabrication.pipeline.stages import stage_geometry, stage_support
from fabrication.writers.mesh import grid_with_support
from ppfab.io import grid_to_json
from ppfab.mesh import QuadGrid

from conftest import REPO, small_design

EXAMPLES = sorted((REPO / "examples").glob("*.toml"))


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_mesh_json_holds_the_fabricated_structure(path):
    design = load_design(path)
    p = Progress(quiet=True)
    geometry = stage_geometry(design, p, False)
    support = stage_support(design, geometry, p)
    mesh = geometry.mesh
    grid = mesh if isinstance(mesh, QuadGrid) else mesh.grid
    if grid is None:
        pytest.skip("not a regular patch: no mesh.json")
    doc = grid_to_json(grid_with_support(grid, support))
    ids = support.mesh.grid_ids
    axes = np.asarray(doc["axes"])
    assert np.abs(axes - support.axes[ids]).max() < 1e-12
    v = np.asarray(doc["vertices"]).reshape(axes.shape)
    for key, lines, line_axes in (("support_u", v, axes), ("support_w", v.transpose(1, 0, 2), axes.transpose(1, 0, 2))):
        if key not in doc:
            continue
        planes = np.asarray(doc[key])
        n = planes[:, :3] / np.linalg.norm(planes[:, :3], axis=1, keepdims=True)
        # every axis lies in the support plane of its polyline (independent: the plane normal is ⟂ the axis)
        assert np.abs(np.einsum("ki,kji->kj", n, line_axes)).max() < 1e-7, key
        size = float(np.ptp(v.reshape(-1, 3), axis=0).max())
        dist = np.einsum("ki,kji->kj", n, lines) + (planes[:, 3] / np.linalg.norm(planes[:, :3], axis=1))[:, None]
        assert np.abs(dist).max() < 1e-7 * size, key


def _axes(folder):
    with open(folder / "nodes.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    nodes = np.array([[float(r[c]) for c in ("axis_x", "axis_y", "axis_z")] for r in rows])
    grid = np.asarray(json.loads((folder / "mesh.json").read_text())["axes"]).reshape(-1, 3)
    return nodes, grid


@pytest.mark.slow
def test_flipped_support_is_the_same_in_mesh_json_and_nodes_csv(tmp_path):
    plain, flipped = tmp_path / "plain.toml", tmp_path / "flipped.toml"
    # the beams on the glass's outside carry no glazing strips of ppfab's (they would lie inside the plates)
    plain.write_text(small_design(extra="[glazing]\nsupport = \"none\"\n"))
    flipped.write_text(small_design(extra="[support]\nflip = true\n[glazing]\nsupport = \"none\"\n"))
    for d, out in ((plain, "a"), (flipped, "b")):
        assert main(["build", str(d), "-o", str(tmp_path / out), "--quiet"]) == 0
    a_nodes, a_grid = _axes(tmp_path / "a")
    b_nodes, b_grid = _axes(tmp_path / "b")
    assert np.abs(b_grid - b_nodes).max() < 1e-8 and np.abs(a_grid - a_nodes).max() < 1e-8
    assert np.abs(b_nodes + a_nodes).max() < 1e-8                   # flipped: the other side, same lines


def test_beams_on_the_outside_with_glazing_strips_are_refused_before_building(tmp_path, capsys):
    """``flip = true`` with ppfab's glazing strips would put the strips and retention parts inside the plates
    (12 mm deep: the erection check found them all): refused at the support stage, one line naming the key."""
    d = tmp_path / "flipped.toml"
    d.write_text(small_design(extra="[support]\nflip = true\n"))
    assert main(["build", str(d), "-o", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ppfab: ") and err.count("\n") == 1 and "support.flip" in err and "inside the plates" in err
    assert not (tmp_path / "out").exists()
