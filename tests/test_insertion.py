"""How a beam plate goes into its place (``fabrication.beams.insertion``): the directions its half-lap slots and
end cuts admit, and ``[beams] segment = ["blocked"]``, which cuts the column plates no direction puts in across
their node axes at the nodes a greedy scan finds, each part then welded to the row there.

The window is checked against a brute-force search over 7,200 directions that tests each constraint as a dot
product (a slot admits a direction whose sideways travel over its length stays within half the clearance, an end
cut one that does not pull the end away from its row faster than half the clearance over the depth allows); the
cut builds against that search on every column plate, and against ``ppfab verify``'s erection check, which
sweeps the written solids along the written directions with manifold3d (no code shared with the window).
Inputs: ``smallest_roof``, ``conical_spheres_pp`` and the DOS quad_dome (WWmore/DOS, objs/obj_pq/quad_dome.obj,
in ``tests/data/meshes``) optimised to PP."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
CLEARANCE = 1.7


@dataclass
class _Slot:
    direction: np.ndarray
    length: float


@dataclass
class _Plate:
    """What the window reads of a plate: slots, end trims with their outward normals, depth, mean axis."""

    slots: list = field(default_factory=list)
    outward: dict = field(default_factory=dict)          # vertex -> outward unit normal of that end
    depth: float = 200.0
    axis: np.ndarray = field(default_factory=lambda: np.array([0.0, -1.0]))

    @property
    def trims(self):
        return [(v, 5.0) for v in self.outward]

    def body_direction(self, v: int) -> np.ndarray:
        return -self.outward[v]

    def node_axis(self, v: int) -> np.ndarray:
        n = self.outward[v]
        a = np.array([-n[1], n[0]])
        return a if a @ self.axis >= 0 else -a

    @property
    def top(self) -> np.ndarray:
        return np.zeros((2, 2))

    @property
    def bottom(self) -> np.ndarray:
        return np.array([self.axis, self.axis]) * self.depth


def _unit(deg: float) -> np.ndarray:
    return np.array([np.cos(np.radians(deg)), np.sin(np.radians(deg))])


def _admitted_brute(plate: _Plate, clearance: float, n: int = 7200) -> np.ndarray:
    """The admitted directions among ``n`` on the circle: within asin(c/2L) of every slot (its sine; the mating
    plate is centred, with half the clearance each side), and not moving any end away from its butting plate faster
    than the half clearance it stands off over the depth allows."""
    t = np.arange(n) * (2.0 * np.pi / n)
    d = np.stack([np.cos(t), np.sin(t)], axis=1)
    ok = np.ones(len(t), dtype=bool)
    for s in plate.slots:
        u = np.asarray(s.direction) / np.linalg.norm(s.direction)
        ok &= (d @ u > 0) & (np.abs(d[:, 0] * u[1] - d[:, 1] * u[0]) * s.length <= 0.5 * clearance + 1e-9)
    for n in plate.outward.values():
        ok &= d @ n >= -0.5 * clearance / plate.depth - 1e-9
    return d[ok]


@pytest.mark.parametrize("spread", [-20.0, -3.0, 0.0, 3.0, 20.0])
def test_a_segment_between_two_plates_comes_in_from_the_side_its_ends_open_to(spread):
    """A one-edge segment whose end axes lean ``spread``/2 out (positive: the gap between the rows widens
    downwards): it goes in from below where they spread downwards, from above where they spread upwards — the
    middle of the brute-force admitted arc."""
    from fabrication.beams.insertion import _window, blocked_plate

    left = _unit(180.0 - 0.5 * spread)           # the left end's outward normal, square to its axis
    right = _unit(0.5 * spread)
    plate = _Plate(outward={0: left, 1: right})
    mid = _window(plate, CLEARANCE)
    assert mid is not None and blocked_plate(plate, CLEARANCE) is None
    d = _unit(np.degrees(mid))
    brute = _admitted_brute(plate, CLEARANCE)
    assert len(brute)
    assert d @ left >= -0.5 * CLEARANCE / plate.depth - 1e-9 and d @ right >= -0.5 * CLEARANCE / plate.depth - 1e-9
    near = brute[brute @ d > np.cos(np.radians(30.0))]     # the admitted arc it chose (parallel ends admit two)
    centre = near.mean(axis=0)
    assert np.degrees(np.arccos(np.clip(d @ (centre / np.linalg.norm(centre)), -1, 1))) < 0.1
    if spread > 1.0:
        assert d[1] > 0.9                         # from below: the ends open downwards
    elif spread < -1.0:
        assert d[1] < -0.9


def test_random_plates_agree_with_the_brute_force_search():
    """200 random plates (up to four slots within 12° of the mean axis, guiding 60–150 mm, and up to two end
    cuts): the window exists exactly when the brute force admits a direction, and its direction is admitted."""
    from fabrication.beams.insertion import _window

    rng = np.random.default_rng(3)
    found = blocked = 0
    for _ in range(200):
        base = rng.uniform(-180, 180)
        slots = [_Slot(_unit(base + rng.uniform(-12, 12)), rng.uniform(60, 150)) for _ in range(rng.integers(0, 5))]
        outward = {}
        for v, side in enumerate(rng.permutation([90.0, -90.0])[: rng.integers(0, 3)]):
            outward[v] = _unit(base + side + rng.uniform(-15, 15))
        plate = _Plate(slots, outward, axis=_unit(base))
        if not slots and not outward:
            continue
        brute = _admitted_brute(plate, CLEARANCE)
        mid = _window(plate, CLEARANCE)
        if mid is None:
            blocked += 1
            # no direction 0.1° (the sampling step, twice) inside every constraint
            assert len(brute) <= 2, (len(brute), slots, outward)
            continue
        found += 1
        d = _unit(np.degrees(mid))
        for s in slots:
            assert abs(d[0] * s.direction[1] - d[1] * s.direction[0]) * s.length <= 0.5 * CLEARANCE + 1e-6
        for n in outward.values():
            assert d @ n >= -0.5 * CLEARANCE / plate.depth - 1e-9
        assert len(brute) > 0
    assert found > 40 and blocked > 40


def _write(folder: Path, text: str) -> Path:
    from fabrication import build, load_design
    from fabrication.progress import Progress
    from fabrication.writers import write_all

    design = folder.parent / f"{folder.name}.toml"
    design.write_text(text)
    b = build(load_design(design))
    folder.mkdir()
    write_all(b, folder, Progress(quiet=True), parallel=False)
    return folder


@pytest.fixture(scope="module")
def roofs(tmp_path_factory) -> tuple[Path, Path]:
    """``smallest_roof`` (columns crossing rows at up to 20° kinks) as it is and with ``segment = ["blocked"]``."""
    root = tmp_path_factory.mktemp("insertion")
    text = (ROOT / "examples" / "smallest_roof.toml").read_text()
    plain = _write(root / "plain", text)
    segmented = _write(root / "segmented", text.replace("[nesting]", '[beams]\nsegment = ["blocked"]\n\n[nesting]'))
    return plain, segmented


def _rows(folder: Path, name: str) -> list[dict[str, str]]:
    from fabrication.verify import read_csv

    return read_csv(folder / name)


def test_blocked_columns_are_cut_and_the_sweep_lets_them_in(roofs):
    """As built, three interior columns of ``smallest_roof`` are blocked (their slots spread 20–76°, so no part
    of two edges admits a direction either); with the rule they, and only they, are cut at every node, nothing is
    blocked, and the erection check's sweep of every written solid along its written direction passes through
    nothing (and so proves the order)."""
    from fabrication.verify import Verification
    from fabrication.verify.erection import TOLERANCE, check_erection

    plain, segmented = roofs
    was = {r["part_id"].split("-S")[0] for r in _rows(plain, "erection.csv") if r["blocked_spread_deg"]}
    assert was == {"B-W01", "B-W02", "B-W03"}
    assert not any(r["blocked_spread_deg"] for r in _rows(segmented, "erection.csv"))
    beams = [r for r in _rows(segmented, "parts.csv") if r["kind"] == "beam"]
    pieces: dict[str, list[int]] = {}
    for r in beams:
        pieces.setdefault(r["beam"], []).append(len(json.loads(r["nodes"])))
    assert all(n == [2] * 4 for b, n in pieces.items() if b in was)
    assert all(max(n) > 2 for b, n in pieces.items() if b not in was)        # the others stay continuous
    v = Verification(segmented)
    check_erection(v)
    assert v.findings == []
    passes = v.read.erection_passes
    assert any(p.part.startswith("B-W02-S") and p.through.startswith("B-U") for p in passes)   # it met the rows
    assert [p for p in passes if p.excess > TOLERANCE] == []


def test_the_terminal_and_json_say_which_beams_were_segmented(tmp_path, capsys, caplog):
    from fabrication.cli import main

    text = (ROOT / "examples" / "smallest_roof.toml").read_text()
    design = tmp_path / "d.toml"
    design.write_text(text.replace("[nesting]", '[beams]\nsegment = ["blocked"]\n\n[nesting]'))
    capsys.readouterr()
    with caplog.at_level("WARNING", logger="ppfab"):     # an earlier --quiet run may have left the logger at ERROR
        assert main(["build", str(design), "-o", str(tmp_path / "out"), "--json"]) == 0
    out, _ = capsys.readouterr()
    got = json.loads(out)["structure"]["segmented_blocked"]
    assert [g["beam"] for g in got] == ["B-W01", "B-W02", "B-W03"]
    said = [r.getMessage() for r in caplog.records if r.name == "ppfab"]
    assert any('segment = ["blocked"]: 3 column beam(s)' in m for m in said), said


def test_a_polyline_is_read_in_runs_between_its_breaks():
    """Open: the runs share their break node and the polyline's ends never break it; closed: read from the first
    break round to it, one run per break."""
    from fabrication.beams.plates import _spans

    vs = np.array([10, 11, 12, 13, 14, 15])
    assert [(list(p), c) for p, c in _spans(vs, False, {12, 14, 10})] == [([0, 1, 2], False), ([2, 3, 4], False),
                                                                          ([4, 5], False)]
    assert [(list(p), c) for p, c in _spans(vs, False, set())] == [([0, 1, 2, 3, 4, 5], False)]
    assert [(list(p), c) for p, c in _spans(vs, True, set())] == [([0, 1, 2, 3, 4, 5], True)]
    got = [list(vs[p]) for p, _ in _spans(vs, True, {13, 10})]
    assert got == [[10, 11, 12, 13], [13, 14, 15, 10]]
    assert [list(vs[p]) for p, _ in _spans(vs, True, {12})] == [[12, 13, 14, 15, 10, 11, 12]]


def _beams_stage(design, blocked: bool):
    from dataclasses import replace

    from fabrication.progress import Progress
    from fabrication.pipeline.stages import stage_beams, stage_geometry, stage_panels, stage_quality, stage_support

    p = Progress(quiet=True)
    g = stage_geometry(design, p, False)
    support = stage_support(design, g, p)
    panels = stage_panels(design, g, p, stage_quality(g, p))
    out = []
    for rule in ([], ["blocked"]) if blocked else ([],):
        beams = replace(design.beams, segment=[*design.beams.segment, *rule])
        out.append(stage_beams(replace(design, sections={**design.sections, "beams": beams}), support, p, panels))
    return support, out


def _brute_admits(plate, clearance: float) -> bool:
    """A direction among 360,000 (0.001° apart: two slots' arcs of ±0.5° can leave a few hundredths of a degree)
    that every slot and end cut of the written plate record admits."""
    fake = _Plate([_Slot(np.asarray(sl.direction, dtype=float), float(sl.length)) for sl in plate.slots],
                  {int(v): -np.asarray(plate.body_direction(int(v)), dtype=float) for v, _ in plate.trims},
                  depth=float(plate.depth))
    return len(_admitted_brute(fake, clearance, 360_000)) > 0


def _dome_design(tmp_path_factory):
    from fabrication import parse_design
    from ppfab.io import load_mesh, write_obj
    from ppfab.optimize import optimize

    res = optimize(load_mesh(ROOT / "tests" / "data" / "meshes" / "DOS__quad_dome.obj"), {"families": "both"})
    assert res.targets_met
    path = tmp_path_factory.mktemp("dome") / "dome.obj"
    write_obj(res.mesh, path)
    import tomllib

    return parse_design(tomllib.loads(
        f'[design]\nname = "dome"\n[geometry]\nmesh = "{path.as_posix()}"\nscale = 1000.0\n[support]\n'
        'method = "pp"\n[beams]\njoint = "halflap"\ndepth = 200.0\nthickness = 15.0\nfallback = "segmented"\n'))


@pytest.mark.parametrize("which", ["conical_spheres_pp", "quad_dome"])
def test_blocked_columns_are_cut_only_where_no_direction_puts_them_in(which, tmp_path_factory):
    """Without the rule some column plates admit no direction (brute force); with it every column plate admits
    one, the cuts are at nodes of the beams that were blocked, and those beams keep continuous parts through
    some of their nodes (the one-edge rule cut them all: 285 → 0 interior nodes on ``conical_spheres_pp``)."""
    from fabrication import load_design

    design = (load_design(ROOT / "examples" / "conical_spheres_pp.toml") if which == "conical_spheres_pp"
              else _dome_design(tmp_path_factory))
    support, (plain, cut) = _beams_stage(design, blocked=True)
    c = design.beams.clearance_mm
    was = {p.polyline for p in plain.plates if p.family == 1 and not _brute_admits(p, c)}
    assert was, "the example no longer has blocked columns"
    assert all(_brute_admits(p, c) for p in cut.plates if p.family == 1)
    breaks = dict(cut.node_breaks)
    assert set(breaks) <= was                                   # only beams that were blocked are cut
    for l, nodes in breaks.items():
        interior = set(int(k) for k in support.polylines[l].vertices[1:-1])
        assert set(nodes) <= interior
        parts = sorted((p for p in cut.plates if p.polyline == l), key=lambda p: p.piece)
        for k in nodes:                                         # both parts end there, neither runs through
            at = [p for p in parts if k in p.nodes.tolist()]
            assert len(at) == 2 and not any(bool(p.through[p.nodes.tolist().index(k)]) for p in at)
    kept = sum(int(p.through.sum()) for p in cut.plates if p.polyline in breaks)
    assert kept > 0                                             # not every node cut, as one-edge segments are
    assert sum(len(v) for v in breaks.values()) < sum(len(support.polylines[l].vertices) - 2 for l in breaks)


@pytest.mark.slow
def test_a_column_cut_at_nodes_is_welded_there_not_spliced_and_goes_in(tmp_path_factory, capsys):
    """``conical_spheres_pp`` with the rule, written and verified: ``ppfab verify`` passes (splices, welds, STEP,
    erection); every part meeting another at a break node has its weld to the row running through it in
    welds.csv and no splice cover plate joins two parts that meet at a node; the erection sweep of the written
    solids passes through nothing deeper than its tolerance."""
    from fabrication.cli import main
    from fabrication.verify import Verification
    from fabrication.verify.erection import TOLERANCE, check_erection

    text = (ROOT / "examples" / "conical_spheres_pp.toml").read_text()
    assert '[beams]\njoint = "halflap"\n' in text
    text = text.replace('[beams]\njoint = "halflap"\n', '[beams]\njoint = "halflap"\nsegment = ["blocked"]\n', 1)
    folder = _write(tmp_path_factory.mktemp("cut") / "out", text)
    assert main(["verify", str(folder), "--quiet"]) == 0, capsys.readouterr()
    parts = _rows(folder, "parts.csv")
    beams = [r for r in parts if r["kind"] == "beam" and r["beam_id"].startswith("B-W")]
    nodes = {r["part_id"]: json.loads(r["nodes"]) for r in beams}
    by_beam: dict[str, list[dict[str, str]]] = {}
    for r in beams:
        by_beam.setdefault(r["beam_id"], []).append(r)
    welds = {(r["node"], r["part"]) for r in _rows(folder, "welds.csv") if r["joint"] == "T"}
    meets = 0
    for rows in by_beam.values():
        rows.sort(key=lambda r: int(r["piece"]))
        for a, b in zip(rows, rows[1:]):
            shared = set(nodes[a["part_id"]]) & set(nodes[b["part_id"]])
            if shared:
                (k,) = shared
                meets += 1
                assert (str(k), a["part_id"]) in welds and (str(k), b["part_id"]) in welds
    assert meets >= 40
    for r in parts:
        if r["kind"] == "splice":
            a, _, b = r["joins"].partition(";")
            assert not set(nodes.get(a, [])) & set(nodes.get(b, [])), r["part_id"]
    v = Verification(folder)
    check_erection(v)
    assert v.findings == []
    assert [x for x in v.read.erection_passes if x.excess > TOLERANCE] == []
    assert not any(r["blocked_spread_deg"] for r in _rows(folder, "erection.csv"))
