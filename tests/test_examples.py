"""Every example design builds: its geometry (fast, all of them) and, marked slow, the whole fabrication
package of the bundled default verified end to end (small nesting budgets unless PPFAB_FULL=1)."""

import re

import pytest

from fabrication.cli import main
from fabrication.design import DEFAULT_DESIGN, load_design
from ppfab.geometry import build_geometry
from ppfab.metrics import quality

from conftest import FULL, REPO

EXAMPLES = sorted((REPO / "examples").glob("*.toml"))


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_geometry(path):
    design = load_design(path)
    g = build_geometry(design.geometry, design.optimize, design.base_dir)
    q = quality(g.mesh)
    assert q.delta_f_max <= 1e-6 and q.flipped_edges == 0
    if "rows" in g.planar_families:
        assert q.delta_p_rows_max <= 1e-6
    if "cols" in g.planar_families:
        assert q.delta_p_cols_max <= 1e-6
    # realistic architectural size: panels between 0.5 m and 3 m, structure above 10 m
    qm = g.mesh.to_quadmesh() if hasattr(g.mesh, "to_quadmesh") else g.mesh
    e = qm.edge_lengths()
    assert 500 < e.mean() < 3000
    assert float((qm.vertices.max(0) - qm.vertices.min(0)).max()) > 10_000


def test_default_is_an_example():
    assert (REPO / "examples" / "default_pp_gridshell.toml").read_text() == DEFAULT_DESIGN.read_text()


@pytest.mark.slow
@pytest.mark.parametrize("name", ["default_pp_gridshell", "conical_spheres"])
def test_example_builds_and_verifies(tmp_path, name):
    text = (REPO / "examples" / f"{name}.toml").read_text()
    if not FULL:
        text = re.sub(r"time_budget = [0-9.]+", "time_budget = 0.5", text)
        for section in ("[nesting]", "[beam_nesting]"):
            if section not in text:
                text += f"\n{section}\ntime_budget = 0.5\n"
    design = tmp_path / f"{name}.toml"
    design.write_text(text)
    out = tmp_path / "out"
    assert main(["build", str(design), "-o", str(out), "--quiet"]) == 0
    assert main(["verify", str(out), "--quiet"]) == 0
