"""A mesh whose net is far from conjugate is refused before the optimiser, in seconds, with the advice to remesh;
nets near conjugate pass.  The defect is checked against an independent estimate: the twist of each quad (the
normal part of its mixed difference) over the normal curvature across its edges, computed here with trimesh's
face normals and numpy."""

from __future__ import annotations

import time
import tomllib

import numpy as np
import pytest

from fabrication import build, parse_design
from ppfab.errors import DesignError
from ppfab.io import load_mesh
from ppfab.metrics import conjugacy_defect

from conftest import REPO, shared_file

PILLOW = "DOS__pillow_1.obj"
CONICAL1 = REPO / "examples" / "meshes" / "DOS__conical1.obj"


def twist_ratio(mesh) -> float:
    """Σ |n·(c0 − c1 + c2 − c3)| over Σ mean-edge × mean turning angle of the normals across the interior edges:
    normals from trimesh (each quad as two triangles, averaged), turning angles from the normals of face pairs."""
    import trimesh

    f = np.asarray(mesh.faces)
    v = np.asarray(mesh.vertices)
    tri = trimesh.Trimesh(v, f[:, [0, 1, 2, 0, 2, 3]].reshape(-1, 3), process=False)
    n = tri.face_normals.reshape(-1, 2, 3).sum(axis=1)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    c = v[f]
    twist = np.abs(np.einsum("ij,ij->i", n, c[:, 0] - c[:, 1] + c[:, 2] - c[:, 3]))
    edge_faces: dict[tuple[int, int], list[int]] = {}
    for k, face in enumerate(f):
        for a, b in zip(face, np.roll(face, -1)):
            edge_faces.setdefault((min(a, b), max(a, b)), []).append(k)
    turn = np.zeros(len(f))
    count = np.zeros(len(f))
    for faces in edge_faces.values():
        if len(faces) == 2:
            ang = np.arccos(np.clip(n[faces[0]] @ n[faces[1]], -1.0, 1.0))
            for k in faces:
                turn[k] += ang
                count[k] += 1
    ell = np.linalg.norm(c - np.roll(c, -1, axis=1), axis=-1).mean(axis=1)
    return float(twist.sum() / (ell * turn / np.maximum(count, 1)).sum())


def test_the_defect_agrees_with_an_independent_estimate():
    for path in (shared_file(PILLOW), CONICAL1):
        mesh = load_mesh(path)
        assert conjugacy_defect(mesh) == pytest.approx(twist_ratio(mesh), rel=0.05, abs=1e-3)


def pillow_design(extra: str = "") -> str:
    return (f'[design]\nname = "pillow"\n[geometry]\nmesh = "{shared_file(PILLOW).as_posix()}"\nscale = 1500.0\n'
            f'[optimize]\nfamilies = "both"\n{extra}[support]\nmethod = "pp"\n[beams]\njoint = "halflap"\n')


def test_a_net_far_from_conjugate_is_refused_in_seconds_before_the_optimiser():
    design = parse_design(tomllib.loads(pillow_design()))
    start = time.process_time()
    with pytest.raises(DesignError) as err:
        build(design)
    spent = time.process_time() - start
    message = str(err.value)
    assert message.startswith("optimize.max_conjugacy_defect: the mesh's net is far from a conjugate net (defect 0.58")
    assert "Remesh" in message and "\n" not in message
    assert spent < 10.0, f"{spent:.1f} CPU s: the refusal must come before the optimiser (it ran 164 CPU s)"


def test_a_conjugate_net_passes_the_gate():
    """conical1 (defect ≈ 0) is not refused by the gate: the P example optimises and reaches its support stage
    (where the structure gate speaks; that the build goes on is the bundled example's own test)."""
    assert conjugacy_defect(load_mesh(CONICAL1)) < 0.01
    text = (REPO / "examples" / "p_optimised_conical1.toml").read_text()
    design = parse_design(tomllib.loads(text), base_dir=REPO / "examples")
    from fabrication.progress import Progress
    from fabrication.pipeline.stages import stage_geometry

    geometry = stage_geometry(design, Progress(quiet=True), False)
    assert geometry.optimize_result is not None and geometry.optimize_result.targets_met


def test_check_reports_the_defect_and_whether_a_build_would_optimise_it(capsys):
    import json

    from fabrication.cli import main

    for path, optimisable in ((shared_file(PILLOW), False), (CONICAL1, True)):
        assert main(["check", str(path), "--json"]) == 0
        doc = json.loads(capsys.readouterr().out)
        assert doc["conjugacy_defect"] == pytest.approx(twist_ratio(load_mesh(path)), rel=0.05, abs=1e-3)
        assert doc["optimisable"] is optimisable
        by_family = doc["polylines_tangent_by_family"]
        assert by_family["rows"] + by_family["cols"] == len(doc["polylines_tangent"])
    assert main(["check", str(shared_file(PILLOW))]) == 0
    assert "far from a conjugate net (> 0.4): ppfab build refuses to optimise it" in capsys.readouterr().out
