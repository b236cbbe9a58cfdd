"""The structure a design asks for is the structure it gets: polylines of a requested planar family that cannot
be planar beams stop the build (before the optimiser where the input already shows it), unless the design accepts
one-edge plates with ``[beams] fallback = "segmented"``; then the terminal and ``--json`` say so with counts."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from fabrication import build, parse_design
from fabrication.cli.cmd_build import structure_counts
from ppfab.errors import DesignError
from ppfab.io import load_mesh, write_obj
from ppfab.mesh import QuadGrid

from conftest import REPO

CONICAL1 = REPO / "examples" / "meshes" / "DOS__conical1.obj"
FAST = "\n[nesting]\ntime_budget = 0.5\n[beam_nesting]\ntime_budget = 0.5\n"


def p_conical1(fallback: str | None) -> str:
    """The bundled P example on conical1 (rows planar, segmented joints), with or without the fallback key."""
    text = (REPO / "examples" / "p_optimised_conical1.toml").read_text()
    text = text.replace('"meshes/', f'"{(REPO / "examples" / "meshes").as_posix()}/')
    text = re.sub(r'(?m)^fallback = "segmented"\n', "", text)
    if fallback is not None:
        text = text.replace("[beams]\n", f'[beams]\nfallback = "{fallback}"\n', 1)
    return text


def angle_to_normal_deg(points: np.ndarray, normals: np.ndarray) -> float:
    """Largest angle (degrees) between the surface normal at a vertex and the least-squares plane of the points,
    by an SVD of the centred points (the plane normal is the last right singular vector)."""
    _, _, vt = np.linalg.svd(points - points.mean(axis=0))
    n = vt[-1]
    return float(np.degrees(np.arcsin(np.clip(np.abs(normals @ n), 0.0, 1.0))).max())


def test_a_p_design_whose_rows_stand_across_the_surface_is_refused_before_optimising():
    design = parse_design(tomllib.loads(p_conical1(None)), base_dir=REPO / "examples")
    with pytest.raises(DesignError) as err:
        build(design)
    message = str(err.value)
    assert message.startswith("beams.fallback: ") and "before optimising" in message and "\n" not in message
    assert 'fallback = "segmented"' in message
    named = [(int(k), int(a), int(v)) for k, a, v in
             re.findall(r"polyline (\d+) \(rows\): plane (\d+)° from the normal at vertex (\d+)", message)]
    assert len(named) == 6 and int(re.match(r"beams\.fallback: (\d+) polyline", message).group(1)) >= len(named)
    # independently: trimesh's vertex normals of the triangulated input and an SVD plane per named polyline
    import trimesh

    mesh = load_mesh(CONICAL1)
    tri = trimesh.Trimesh(mesh.vertices, np.asarray(mesh.faces)[:, [0, 1, 2, 0, 2, 3]].reshape(-1, 3),
                          process=False)
    for k, shown, _ in named:
        line = mesh.polylines[k]
        assert line.family == 0
        idx = np.asarray(line.vertices)
        angle = angle_to_normal_deg(mesh.vertices[idx], tri.vertex_normals[idx])
        assert angle > 40.0 and abs(angle - shown) < 5.0, (k, angle, shown)


def stages_to_beams(design):
    """The build's stages up to the beams (what :func:`structure_counts` reads), without nesting and files."""
    from types import SimpleNamespace

    from fabrication.progress import Progress
    from fabrication.pipeline.stages import stage_beams, stage_geometry, stage_support

    p = Progress(quiet=True)
    support = stage_support(design, stage_geometry(design, p, False), p)
    return SimpleNamespace(support=support, beams=stage_beams(design, support, p))


def test_the_same_design_with_the_fallback_builds_and_says_how_many_plates_have_one_edge(caplog):
    design = parse_design(tomllib.loads(p_conical1("segmented")), base_dir=REPO / "examples")
    with caplog.at_level("WARNING", logger="ppfab"):
        result = stages_to_beams(design)
    counts = structure_counts(result)
    assert counts["left_out"], "conical1 made P keeps every row"
    left = {r["polyline"] for r in counts["left_out"]}
    one_edge = [p for p in result.beams.plates if p.polyline in left]
    assert one_edge and all(len(p.nodes) == 2 for p in one_edge)
    assert counts["one_edge_plates"] >= len(one_edge)
    warned = [r.getMessage() for r in caplog.records if "fallback" in r.getMessage()]
    assert len(warned) == 1 and f"{len(left)} polyline(s)" in warned[0]


def flat_mesh(path: Path) -> Path:
    """A 6 × 5 quad grid in the plane z = 0 whose polylines curve in that plane (each lies in the mesh plane,
    90° from its normal): no planar beam can stand on it."""
    i, j = np.meshgrid(np.arange(7.0), np.arange(6.0), indexing="ij")
    v = np.stack([i + 0.04 * j ** 2, j + 0.04 * i ** 2, 0.0 * i], axis=-1)
    write_obj(QuadGrid(v).to_quadmesh(), path)
    return path


def flat_design(mesh: Path, extra: str = "") -> str:
    return (f'[design]\nname = "flat"\n[geometry]\nmesh = "{mesh.as_posix()}"\nscale = 1500.0\n'
            f'[support]\nmethod = "pp"\n[beams]\njoint = "halflap"\n{extra}' + FAST)


def test_a_flat_mesh_is_not_called_a_pp_gridshell(tmp_path):
    mesh = flat_mesh(tmp_path / "flat.obj")
    with pytest.raises(DesignError) as err:
        build(parse_design(tomllib.loads(flat_design(mesh))))
    message = str(err.value)
    assert message.startswith("beams.fallback: ") and "one-edge plates" in message
    n_lines = len(load_mesh(mesh).polylines)
    assert int(re.match(r"beams\.fallback: (\d+) polyline", message).group(1)) == n_lines
    # 6 rows of 7 vertices... every edge of the mesh becomes its own plate
    edges = int(re.search(r"would become (\d+) one-edge plates", message).group(1))
    assert edges == 7 * 5 + 6 * 6


def test_the_flat_mesh_with_the_fallback_is_all_one_edge_plates(tmp_path):
    mesh = flat_mesh(tmp_path / "flat.obj")
    result = stages_to_beams(parse_design(tomllib.loads(flat_design(mesh, 'fallback = "segmented"\n'))))
    counts = structure_counts(result)
    assert counts["planar_polylines"] == 0
    assert counts["one_edge_plates"] == counts["plates"] == 7 * 5 + 6 * 6


def test_an_explicit_exclude_is_what_was_asked_for(tmp_path):
    """Polylines the designer excluded by id are not a change of structure: no refusal, and the build's
    structure counts list none of them as left out."""
    mesh = flat_mesh(tmp_path / "flat.obj")
    ids = list(range(len(load_mesh(mesh).polylines)))
    design = parse_design(tomllib.loads(flat_design(mesh).replace('method = "pp"\n',
                                                                  f'method = "pp"\nexclude = {ids}\n')))
    result = stages_to_beams(design)
    assert {k for k, _ in result.support.left_out} == set(ids)
    counts = structure_counts(result)
    assert counts["left_out"] == [] and counts["one_edge_plates"] == 7 * 5 + 6 * 6
