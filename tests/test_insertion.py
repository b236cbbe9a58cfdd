"""How a beam plate goes into its place (``fabrication.beams.insertion``): the directions its half-lap slots and
end cuts admit, and ``[beams] segment = ["blocked"]``, which cuts the column plates no direction puts in into
one-edge segments.

The window is checked against a brute-force search over 7,200 directions that tests each constraint as a dot
product; the segmented build against ``ppfab verify``'s erection check, which sweeps the written solids along
the written directions with manifold3d (no code shared with the window)."""

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


def _admitted_brute(plate: _Plate, clearance: float) -> np.ndarray:
    """The admitted directions among 7,200 on the circle: within asin(c/L) of every slot (its sine), and not moving
    any end away from its butting plate faster than the clearance over the depth allows."""
    t = np.radians(np.arange(7200) * 0.05)
    d = np.stack([np.cos(t), np.sin(t)], axis=1)
    ok = np.ones(len(t), dtype=bool)
    for s in plate.slots:
        u = np.asarray(s.direction) / np.linalg.norm(s.direction)
        ok &= (d @ u > 0) & (np.abs(d[:, 0] * u[1] - d[:, 1] * u[0]) * s.length <= clearance + 1e-9)
    for n in plate.outward.values():
        ok &= d @ n >= -clearance / plate.depth - 1e-9
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
    assert d @ left >= -CLEARANCE / plate.depth - 1e-9 and d @ right >= -CLEARANCE / plate.depth - 1e-9
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
            assert abs(d[0] * s.direction[1] - d[1] * s.direction[0]) * s.length <= CLEARANCE + 1e-6
        for n in outward.values():
            assert d @ n >= -CLEARANCE / plate.depth - 1e-9
        assert len(brute) > 0
    assert found > 40 and blocked > 40


def _write(folder: Path, text: str) -> Path:
    from fabrication import build, load_design
    from fabrication.pipeline.progress import Progress
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


def test_blocked_columns_become_segments_that_the_sweep_lets_in(roofs):
    """As built, three interior columns of ``smallest_roof`` are blocked (their slots spread 20–76°); with the
    rule they, and only they, are one-edge segments, nothing is blocked, and the erection check's sweep of every
    written solid along its written direction passes through nothing (and so proves the order)."""
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
    v.data["manifest"] = json.loads((segmented / "manifest.json").read_text(encoding="utf-8"))
    v.data["parts"] = _rows(segmented, "parts.csv")
    check_erection(v)
    assert v.findings == []
    passes = v.data["erection_passes"]
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
