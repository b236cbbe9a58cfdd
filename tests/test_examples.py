"""Every example design builds: its geometry (fast, all of them) and, marked slow, the whole fabrication
package of the bundled default verified end to end (small nesting budgets unless PPFAB_FULL=1)."""

import re
from pathlib import Path

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


def small_form(text: str, folder: Path) -> str:
    """An example as CI builds it from another folder: the same design, the same stages and writers, with
    nesting budgets of 0.5 s of nominal work for the glass and the plates (PPFAB_FULL=1 keeps the example's
    own budgets); a mesh file given relative to the example's ``folder`` is given by its full path."""
    text = re.sub(r'^mesh = "([^"]+)"', lambda m: f'mesh = "{(folder / m.group(1)).resolve()}"', text, flags=re.M)
    if FULL:
        return text
    text = re.sub(r"time_budget = [0-9.]+", "time_budget = 0.5", text)
    for section in ("[nesting]", "[beam_nesting]"):
        if section not in text:
            text += f"\n{section}\ntime_budget = 0.5\n"
    return text


@pytest.mark.slow
@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_builds_and_verifies(tmp_path, path, monkeypatch):
    """Every example builds, and every check of ``ppfab verify`` passes on its files: the build runs them on its
    temporary folder before renaming it (recorded here, not run twice)."""
    from fabrication import verify as verify_package

    results = []
    run = verify_package.verify

    def recording(folder):
        results.append(run(folder))
        return results[-1]

    monkeypatch.setattr(verify_package, "verify", recording)
    design = tmp_path / path.name
    design.write_text(small_form(path.read_text(), path.parent))
    out = tmp_path / "out"
    assert main(["build", str(design), "-o", str(out), "--quiet"]) == 0
    assert len(results) == 1 and results[0].ok
    assert {"placement", "types", "step_geometry", "panels_step", "axes", "torsion"} <= set(results[0].checked)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([design.name, "out"])
