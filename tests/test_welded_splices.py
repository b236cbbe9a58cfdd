"""Welded splices: beams whose edges are too short for a bolted cover plate clear of the joints are cut for a
full-penetration butt weld instead (``[splices] kind``), and every cut is spliced one way or the other.

Clearances are measured here from the cut lines and node axes themselves (3D distances between the points of
the cut line and of the node axis at the top and the bottom edge), not from the window the splitter computed.
"""

from __future__ import annotations

import csv
import tomllib

import numpy as np
import pytest

from conftest import built_folder, small_vault
from fabrication import parse_design
from fabrication.beams.splitting import plan_cuts
from fabrication.cli import main
from fabrication.pipeline import stages
from fabrication.progress import Progress
from ppfab.errors import FabricationError

WELDED = small_vault("welded", max_length=2500.0, joint="halflap") + """
[splices]
kind = "welded"
"""
built = built_folder("welded", WELDED)


def _design(text: str, **splices):
    doc = tomllib.loads(text)
    doc.setdefault("splices", {}).update(splices)
    return parse_design(doc, "test.toml")


def _beams(design):
    p = Progress(quiet=True)
    geometry = stages.stage_geometry(design, p, False)
    support = stages.stage_support(design, geometry, p)
    return support, stages.stage_beams(design, support, p)


def _cut_clearances(support, beams, depth):
    """Per cut of a split beam: its kind and the smallest 3D distance from its top point to a node's top point
    and from its bottom point to that node's bottom point (``top + depth · axis``), over the beam's nodes."""
    out = []
    for a in beams.plates:
        if a.n_pieces < 2 or a.meta.get("segment") or a.piece == a.n_pieces - 1:
            continue
        top = a.frame.to3d(a.top[-1])
        bottom = a.frame.to3d(a.bottom[-1])
        line = support.polylines[a.polyline].vertices
        tops = support.vertices[line]
        bottoms = tops + depth * support.axes[line]
        out.append((a.meta["splice"], float(np.linalg.norm(tops - top, axis=1).min()),
                    float(np.linalg.norm(bottoms - bottom, axis=1).min())))
    return out


def test_a_leaning_cut_keeps_its_clearance_at_the_bottom_edge_too():
    """A straight beam whose node axes lean alternately ±30° along it: the cut line leans with the
    interpolated axis, so a cut clear of a node at the top edge can come closer to that node's axis at the
    bottom.  Every cut keeps the clearance at both edges, measured from the two lines."""
    k = 9
    x = np.linspace(0.0, 8 * 400.0, k)
    pts = np.c_[x, 0 * x, 0 * x]
    lean = np.radians(np.where(np.arange(k) % 2 == 0, 30.0, -30.0))
    axes = np.c_[np.sin(lean), 0 * x, -np.cos(lean)]
    plane = np.array([0.0, 1.0, 0.0, 0.0])
    clear, depth = 120.0, 200.0
    plan = plan_cuts(pts, axes, plane, False, depth, 1000.0, np.full(k, clear))
    assert not plan.problem and len(plan.cuts) >= 3
    for c in plan.cuts:
        i, j = c.edge, c.edge + 1
        top = (1 - c.t) * pts[i] + c.t * pts[j]
        a = (1 - c.t) * axes[i] + c.t * axes[j]
        bottom = top + depth * a / np.linalg.norm(a)
        for n in (i, j):
            assert abs(top[0] - pts[n, 0]) >= clear - 1e-6
            assert abs(bottom[0] - (pts[n, 0] + depth * axes[n, 0])) >= clear - 1e-6


@pytest.mark.slow
def test_the_default_at_88_by_60_faces_is_cut_for_welded_splices():
    """The bundled default at four times its resolution (edges 281–495 mm): a bolted splice needs about
    550 mm of edge, so ``kind = "auto"`` cuts its beams for welded splices, to max_length (5900 mm) unchanged;
    every welded cut keeps ``weld_clear`` from the nodes at the top and the bottom edge, every piece fits the
    stock, and every cut has one splice weld."""
    from test_real_builds import default_at

    d = default_at(88, 60)
    assert d.splices.kind == "auto" and d.beams.max_length == 5900.0
    support, beams = _beams(d)
    kinds = {p.meta.get("splice") for p in beams.plates if p.n_pieces > 1}
    assert kinds == {"welded"}
    cuts = _cut_clearances(support, beams, d.beams.depth)
    assert len(cuts) > 100
    assert min(min(t, b) for _, t, b in cuts) >= d.splices.weld_clear - 1e-6
    assert max(np.ptp(p.raw_outline[:, 0]) for p in beams.plates) <= 5900.0 + 1e-6
    from fabrication.glazing import welded_splices

    welds = welded_splices(beams.plates)
    assert len(welds) == len(cuts) and {w.joint for w in welds} == {"splice"}
    assert all("full penetration" in w.preparation and w.throat_mm == d.beams.thickness for w in welds)
    assert min(w.length_mm for w in welds) >= d.beams.depth - 1e-6    # the cut line runs down a leaning axis


@pytest.mark.slow
def test_bolted_splices_only_refuse_short_edges_and_say_what_to_change():
    from test_real_builds import DEFAULT_DESIGN

    doc = tomllib.loads(DEFAULT_DESIGN.read_text())
    doc["geometry"]["params"].update(faces_u=88, faces_v=60)
    doc.setdefault("splices", {})["kind"] = "bolted"
    d = parse_design(doc, str(DEFAULT_DESIGN), base_dir=DEFAULT_DESIGN.parent)
    with pytest.raises(FabricationError) as exc:
        _beams(d)
    msg = str(exc.value)
    need = 0.5 * (d.splices.length + d.beams.depth)
    assert "cannot be cut into pieces of at most 5900 mm" in msg and f"bolted splices {need:.0f} mm" in msg
    assert 'set splices.kind = "welded" or "auto"' in msg


def test_auto_keeps_bolted_splices_where_the_edges_hold_them():
    """The small vault with edges of about 1.5 m: auto cuts for bolted splices (cover plates clear of the
    joints by half their length plus half the depth, at both edges)."""
    d = _design(small_vault("auto", max_length=2500.0, joint="halflap"))
    support, beams = _beams(d)
    cuts = _cut_clearances(support, beams, d.beams.depth)
    assert cuts and {k for k, _, _ in cuts} == {"bolted"}
    need = 0.5 * (d.splices.length + d.beams.depth)
    assert min(min(t, b) for _, t, b in cuts) >= need - 1e-6


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_a_welded_build_lists_one_splice_weld_per_cut(built):
    parts = _rows(built / "parts.csv")
    welds = [r for r in _rows(built / "welds.csv") if r["joint"] == "splice"]
    assert not any(r["kind"] == "splice" for r in parts) and not (built / "splices.step").exists()
    pieces: dict[str, list[dict]] = {}
    for r in parts:
        if r["kind"] == "beam" and r["pieces"] not in ("", "1"):
            pieces.setdefault(r["beam_id"], []).append(r)
    cuts = sum(len(v) - 1 for v in pieces.values())
    assert cuts > 0 and len(welds) == cuts
    assert all(r["node"] == "" and float(r["dihedral_deg"]) == 0.0 for r in welds)
    joined = {frozenset((r["part"], r["to"])) for r in welds}
    for v in pieces.values():
        v.sort(key=lambda r: int(r["piece"]))
        for a, b in zip(v[:-1], v[1:]):
            assert frozenset((a["part_id"], b["part_id"])) in joined
            assert b["part_id"] in a["joins"].split(";")


def _write(path, rows):
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def test_verify_names_a_cut_whose_splice_weld_is_missing(built, tmp_path, capsys):
    import hashlib
    import json
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(built, copy)
    rows = _rows(copy / "welds.csv")
    gone = next(r for r in rows if r["joint"] == "splice")
    _write(copy / "welds.csv", [r for r in rows if r is not gone])
    m = json.loads((copy / "manifest.json").read_text())
    m["sha256"]["welds.csv"] = hashlib.sha256((copy / "welds.csv").read_bytes()).hexdigest()
    (copy / "manifest.json").write_text(json.dumps(m, indent=2))
    capsys.readouterr()
    assert main(["verify", str(copy), "--quiet"]) == 1
    err = capsys.readouterr().err
    pair = {gone["part"], gone["to"]}
    line = next(x for x in err.splitlines() if "has 0 splice cover plate(s)" in x)
    assert all(p in line for p in pair) and "(or a splice weld in welds.csv)" in line
