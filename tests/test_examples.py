"""Every example design builds: its geometry (fast, all of them) and, marked slow, its fabrication package.

The slow case in its small form (CI): every example runs every build stage, so every gate a build applies
(planarity, torsion, axis angle, crease, sizes, nesting) passes, and the panels are re-measured here; the
examples of ``WRITTEN_IN_CI`` also write their files and pass every check of ``ppfab verify`` (CI builds and
verifies the default and ``conical_spheres`` besides, through the command line).  With PPFAB_FULL=1 every
example writes and verifies, with its own nesting budgets."""

import re
from pathlib import Path

import numpy as np
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
    if design.surface is not None:                      # a surface: read, remeshed, optimised by the stage
        from fabrication.progress import Progress
        from fabrication.pipeline.stages import stage_geometry

        g = stage_geometry(design, Progress(quiet=True), True)
    else:
        g = build_geometry(design.geometry, design.optimize, design.base_dir)
    q = quality(g.mesh)
    assert q.delta_f_max <= 1e-6 and q.flipped_edges == 0
    # the design's own δ_P target where it sets one above 1e-6 (Fig. 16's multi-patch dome: 3e-6, the paper's level)
    tol_p = max(1e-6, design.optimize.target_delta_p) if design.optimize is not None else 1e-6
    if "rows" in g.planar_families:
        assert q.delta_p_rows_max <= tol_p
    if "cols" in g.planar_families:
        assert q.delta_p_cols_max <= tol_p
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
    own budgets); a mesh or surface file given relative to the example's ``folder`` is given by its full path."""
    text = re.sub(r'^(mesh|path) = "([^"]+)"', lambda m: f'{m.group(1)} = "{(folder / m.group(2)).resolve()}"',
                  text, flags=re.M)                                 # [geometry] mesh, [surface] path
    if FULL:
        return text
    text = re.sub(r"time_budget = [0-9.]+", "time_budget = 0.5", text)
    for section in ("[nesting]", "[beam_nesting]"):
        if section not in text:
            text += f"\n{section}\ntime_budget = 0.5\n"
    return text


WRITTEN_IN_CI = {"smallest_roof", "fig23_enneper_pp_to_conical", "surface_dome"}
"""Examples whose files CI writes and verifies: the smallest, a mesh file transformed to a conical PP mesh
(§4.2; folds, one-edge plates, welded splices: about 460 s) and the NURBS dome remeshed into sections (20 s;
a corner strip a quarter of its span, which the bevel check once looked for along its own length only). The closed ring of panels
(``conical_pp_rotational``, about 240 s) and ``p_optimised_conical1`` (a mesh file optimised to P with 1,147
segmented joints, about 260 s) are written in the full form only (``PPFAB_FULL=1``), to keep CI under 45 min;
CI builds them in memory and checks their stages."""


def check_stages(build) -> None:
    """What the typed build of an example must satisfy, measured here: one panel per face, each face's corners
    within ``panels.planarity_tolerance`` of their least-squares plane (the smallest singular value of the
    centred ``(4, 3)`` corners, its right singular vector the normal), and at least as many sheets as the
    area bound of the glass and of the plates."""
    d = build.design
    corners = np.stack([p.corners_3d for p in build.panels.panels])            # (F, 4, 3)
    centred = corners - corners.mean(axis=1, keepdims=True)
    _, _, vt = np.linalg.svd(centred)
    off = np.abs(np.einsum("fkj,fj->fk", centred, vt[:, 2])).max()
    assert off <= d.panels.planarity_tolerance, off
    assert build.summary.panels == len(build.panels.panels) > 0
    s = build.summary
    assert s.glass_sheets >= s.glass_lower_bound >= 1 and s.plate_sheets >= s.plate_lower_bound >= 1


@pytest.mark.slow
@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_builds_and_verifies(tmp_path, path, monkeypatch):
    """Every example builds; where it writes its files (see the module docstring), every check of ``ppfab
    verify`` passes on them: the build runs them on its temporary folder before renaming it (recorded here,
    not run twice)."""
    from fabrication import verify as verify_package
    from fabrication.pipeline.stages import build

    design = tmp_path / path.name
    design.write_text(small_form(path.read_text(), path.parent))
    if not FULL and path.stem not in WRITTEN_IN_CI:
        check_stages(build(load_design(design)))
        return

    results = []
    run = verify_package.verify

    def recording(folder, **options):                        # the build's self-check passes its progress
        results.append(run(folder, **options))
        return results[-1]

    monkeypatch.setattr(verify_package, "verify", recording)
    out = tmp_path / "out"
    assert main(["build", str(design), "-o", str(out), "--quiet"]) == 0
    assert len(results) == 1 and results[0].ok
    assert {"placement", "types", "step_geometry", "panels_step", "axes", "torsion"} <= set(results[0].checked)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([design.name, "out"])
