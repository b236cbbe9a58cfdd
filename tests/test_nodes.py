"""nodes.csv / nodes.json: one row per vertex with axis, beams, angles and torsion."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from conftest import shared_file

from fabrication.beams import BeamParams, build_beams
from fabrication.beams.samples import sample_pp_grid
from fabrication.contract import NODES_COLUMNS as CSV_COLUMNS
from fabrication.nodes import write_nodes
from ppfab import planes as pl
from ppfab.io import load_mesh
from ppfab.transforms.similarity import transform
from ppfab.support.pp import support_pp
from ppfab.support.select import support_structure

REQUIRED = ["node_id", "vertex", "x", "y", "z", "axis_x", "axis_y", "axis_z", "beams", "i", "j"]


def _read(path):
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def test_nodes_of_a_pp_patch(tmp_path):
    g = sample_pp_grid(4, 6)
    s = support_pp(g)
    bs = build_beams(s, BeamParams(max_length=5000.0))
    csv_path, json_path = write_nodes(tmp_path, bs)
    rows = _read(csv_path)
    assert set(REQUIRED) <= set(rows[0]) and list(rows[0]) == CSV_COLUMNS
    n = len(s.vertices)
    assert [int(r["vertex"]) for r in rows] == list(range(n))
    x = np.array([[float(r[c]) for c in "xyz"] for r in rows])
    a = np.array([[float(r[f"axis_{c}"]) for c in "xyz"] for r in rows])
    assert np.abs(x - s.vertices).max() < 1e-4 and np.abs(a - s.axes).max() < 1e-9
    ij = np.array([[int(r["i"]), int(r["j"])] for r in rows])
    assert np.array_equal(g.vertex_index[ij[:, 0], ij[:, 1]], np.arange(n))
    U, W = pl.normalize(g.support_u), pl.normalize(g.support_w)
    for r, (i, j) in zip(rows, ij):
        k = int(r["vertex"])
        expect = sorted(p.part_id for p in bs.plates if k in p.nodes.tolist())
        assert sorted(r["beams"].split(";")) == expect
        assert all(b.startswith((f"B-U{i:02d}", f"B-W{j:02d}")) for b in expect)
        dih = np.degrees(pl.angle_between(U[i], W[j]))
        assert float(r["dihedral_deg"]) == pytest.approx(dih, abs=1e-4)
        assert float(r["torsion_deg"]) < 1e-9
        interior = 0 < i < g.shape[0] - 1 and 0 < j < g.shape[1] - 1
        assert r["joint"] == ("halflap" if interior else "butt")
        if interior:
            c = np.cos(np.radians(dih))
            w = bs.params.slot_thickness * (1 + c) / np.sin(np.radians(dih)) + bs.params.fit
            assert float(r["slot_width_mm"]) == pytest.approx(w, abs=1e-4)
        # angle between each beam plane and the panels along its edges at the node
        faces = [(fi, fj) for fi in (i - 1, i) for fj in (j - 1, j) if 0 <= fi < g.shape[0] - 1 and 0 <= fj < g.shape[1] - 1]
        for b, ang in zip(r["beams"].split(";"), r["beam_panel_deg"].split(";")):
            plane = U[i] if b.startswith("B-U") else W[j]
            angles = [np.degrees(pl.angle_between(plane, g.face_planes[f])) for f in faces]
            assert float(ang) == pytest.approx(min(angles), abs=1e-4)
    doc = json.loads(json_path.read_text())
    assert doc["units"] == "mm" and doc["count"] == n
    assert doc["nodes"][7]["axis"] == pytest.approx(s.axes[7].tolist(), abs=1e-15)
    assert doc["nodes"][7]["grid"] == ij[7].tolist()
    assert doc["support"]["kind"] == "pp"


def test_nodes_of_a_general_mesh_report_torsion(tmp_path):
    mesh = transform(load_mesh(shared_file("compas_libigl__tubemesh.off")), scale=1000.0)
    mesh = type(mesh)(mesh.vertices, mesh.faces)            # forget the grid: a general quad mesh
    s = support_structure(mesh)
    assert not s.meta["exact"]
    bs = build_beams(s, BeamParams(joint="none", max_length=0), strict=False)
    csv_path, json_path = write_nodes(tmp_path, bs)
    rows = _read(csv_path)
    assert len(rows) == len(mesh.vertices) and all(r["i"] == "" and r["j"] == "" for r in rows)
    tors = np.degrees(s.torsion)
    e = s.edges
    for r in rows:
        k = int(r["vertex"])
        expect = tors[(e[:, 0] == k) | (e[:, 1] == k)].max()
        assert float(r["torsion_deg"]) == pytest.approx(expect, abs=1e-8)
        assert int(r["valence"]) == int(((e[:, 0] == k) | (e[:, 1] == k)).sum())
        assert len(r["beams"].split(";")) == int(r["valence"])         # one edge plate per edge here
    assert max(float(r["torsion_deg"]) for r in rows) > 0.01           # not torsion-free: reported
    doc = json.loads(json_path.read_text())
    assert doc["nodes"][0]["grid"] is None and doc["support"]["kind"] == "parallel"
