"""The clamping screws of the pressure plates stand in the joint between two panes; where a kink closes the joint
towards the glass's top (a valley), a screw can stand in the glass.  ``screw_clearance`` says how far the glass
could move towards the screws in its plane before touching one (negative: how far it is in).

Checked against a closed form for a pane tilted by β beside a vertical screw (its top edge ``w − t·sin β`` from
the axis, so it may move ``(w − t·sin β − r)/cos β`` along its plane), against shapely (the pane's section moved
by that much touches the thickened axis), and on ``smallest_roof`` against the manifold3d overlaps of the written
screws and panes that ``ppfab verify``'s erection check measures."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from fabrication.glazing.screws import screw_clearance

REPO = Path(__file__).resolve().parents[1]


@dataclass
class _Frame:
    normal: np.ndarray


@dataclass
class _Pane:
    """A pane beside the joint ``y = 0`` of a valley: its bottom edge along ``x`` at ``y = w``, rising at β."""
    w: float
    beta: float
    thickness_mm: float = 17.52

    @property
    def frame(self) -> _Frame:
        return _Frame(np.array([0.0, -math.sin(self.beta), math.cos(self.beta)]))

    def outline_3d(self) -> np.ndarray:
        up = np.array([0.0, math.cos(self.beta), math.sin(self.beta)])
        a, b = np.array([0.0, self.w, 0.0]), np.array([1000.0, self.w, 0.0])  # counter-clockwise seen from N
        return np.array([a, b, b + 1500.0 * up, a + 1500.0 * up])


def _screw(height: float = 60.0) -> np.ndarray:
    return np.array([[[500.0, 0.0, -10.0], [500.0, 0.0, -10.0 + height]]])


@pytest.mark.parametrize("w, beta_deg", [(5.0, 0.0), (5.0, 10.0), (5.0, 15.0), (9.0, 20.0), (12.0, 5.0)])
def test_a_tilted_pane_beside_a_vertical_screw(w, beta_deg):
    pane = _Pane(w, math.radians(beta_deg))
    m = np.cross(np.array([1.0, 0.0, 0.0]), pane.frame.normal)
    assert m[1] < 0                                                  # the edge's outward normal: towards the joint
    c = screw_clearance(_screw(), 8.0, [(pane, 0, 0.0)])
    b, t = pane.beta, pane.thickness_mm
    assert c == pytest.approx((w - t * math.sin(b) - 4.0) / math.cos(b), abs=1e-9)


@pytest.mark.parametrize("w, beta_deg", [(5.0, 15.0), (9.0, 20.0), (12.0, 5.0)])
def test_moved_by_the_clearance_the_pane_touches_the_screw(w, beta_deg):
    """shapely, in the section across the edge: the pane's section moved by ``c`` along its plane is at the
    screw's radius from the axis; 0.01 mm further it is nearer."""
    from shapely.geometry import LineString, Polygon

    pane = _Pane(w, math.radians(beta_deg))
    c = screw_clearance(_screw(), 8.0, [(pane, 0, 0.0)])
    up = np.array([math.cos(pane.beta), math.sin(pane.beta)])       # (y, z) along the pane, away from the joint
    n = np.array([-math.sin(pane.beta), math.cos(pane.beta)])
    axis = LineString([(0.0, -10.0), (0.0, 50.0)])
    for shift, near in ((c, False), (c + 0.01, True)):
        a = np.array([w, 0.0]) - shift * up
        section = Polygon([a, a + 500.0 * up, a + 500.0 * up + pane.thickness_mm * n, a + pane.thickness_mm * n])
        if near:
            assert section.distance(axis) < 4.0 - 0.005
        else:
            assert section.distance(axis) == pytest.approx(4.0, abs=1e-9)


def test_a_screw_beside_another_pane_of_the_strip_is_not_measured_against_this_one():
    pane = _Pane(1.0, 0.3)
    off = np.array([[[2500.0, 0.0, -10.0], [2500.0, 0.0, 50.0]]])
    assert screw_clearance(off, 8.0, [(pane, 0, 0.0)]) == math.inf
    assert screw_clearance(_screw(), 8.0, [(pane, 0, 0.0)]) < 0


def test_screws_in_the_glass_stop_the_build_before_any_file_with_the_joint_that_clears_them(tmp_path, capsys):
    """smallest_roof with 10 mm joints: the build stops (exit 2) in one line naming ``panels.gap``, the plates
    whose screws stand in the glass and the joint that clears them, and writes no folder; that joint, built,
    leaves no screw in the glass."""
    import tomllib

    from fabrication import build
    from fabrication.cli import main
    from fabrication.design import parse_design

    example = REPO / "examples" / "smallest_roof.toml"
    doc = tomllib.loads(example.read_text(encoding="utf-8"))
    doc["panels"]["gap"] = 10.0
    design = tmp_path / "d.toml"
    design.write_text(example.read_text(encoding="utf-8").replace("gap = 18.0", "gap = 10.0"), encoding="utf-8")
    capsys.readouterr()
    assert main(["build", str(design), "-o", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    import re
    found = re.search(r"panels\.gap: (\d+) pressure plate\(s\) have clamping screws standing in the glass.*"
                      r"widen \[panels\] gap to at least (\d+) mm \(from 10\)", err)
    assert found, err
    assert not (tmp_path / "out").exists()
    doc["panels"]["gap"] = float(found.group(2))
    ret = build(parse_design(doc, source="<smallest_roof, the joint it names>", base_dir=example.parent)).retention
    assert ret is not None and min(s.clearance_mm for s in ret.screws) >= 0.0


def test_smallest_roof_screws_in_the_glass_are_those_verify_measures_and_names(monkeypatch):
    """The build's clearance of every screw set of ``smallest_roof`` with 10 mm joints (its example widens them
    to 18 mm for this) against the overlaps in place that the erection check measures with manifold3d on the
    written STEP solids and rebuilt screws: a set whose screws stand in the glass overlaps a pane by its depth
    (within 0.05 mm) and the check names the pane and the screw; a set with room overlaps none.  With the
    example's 18 mm joints no screw stands in the glass."""
    import tempfile
    import tomllib

    from fabrication import build, load_design
    from fabrication.design import parse_design
    from fabrication.progress import Progress
    from fabrication.verify import Verification
    from fabrication.verify.erection import check_erection
    from fabrication.writers import write_all

    example = REPO / "examples" / "smallest_roof.toml"
    assert all(s.clearance_mm >= 0.0 for s in build(load_design(example)).retention.screws)
    doc = tomllib.loads(example.read_text(encoding="utf-8"))
    doc["panels"]["gap"] = 10.0
    import fabrication.glazing.retention as retention
    import fabrication.glazing.screws as screws

    for module in (retention, screws):                  # built and written, for verify to judge
        monkeypatch.setattr(module, "SCREWS_IN_GLASS_MM", float("inf"))
    b = build(parse_design(doc, source="<smallest_roof, 10 mm joints>", base_dir=example.parent))
    ret = b.retention
    assert ret is not None and ret.screws
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        out.mkdir()
        write_all(b, out, Progress(quiet=True), parallel=False)
        v = Verification(out)
        check_erection(v)
    measured: dict[str, float] = {}
    for p in v.read.erection_passes:
        pair = sorted((p.part, p.through), key=lambda s: not s.startswith("SC-"))
        if pair[0].startswith("SC-") and pair[1].startswith("P-"):
            measured[pair[0]] = max(measured.get(pair[0], 0.0), p.static)
    tight = {s.part_id: -s.clearance_mm for s in ret.screws if s.clearance_mm < 0}
    assert tight and max(tight.values()) > 3.0                        # smallest_roof's valleys close its joints
    for sid, depth in tight.items():
        assert measured.get(sid, 0.0) == pytest.approx(depth, abs=0.05), sid
    for s in ret.screws:
        if s.clearance_mm >= 0.05:
            assert measured.get(s.part_id, 0.0) <= 0.25, s.part_id
    named = [e for e in v.findings if " inside it in its final place" in str(e)]
    pairs = {tuple(sorted((p.part, p.through))) for p in v.read.erection_passes
             if p.static > 0.25 and {p.part[:3], p.through[:3]} & {"SC-"} and {p.part[:2], p.through[:2]} & {"P-"}}
    assert named and all("SC-" in e.message for e in named)
    assert len(named) == min(20, len(pairs)) and len({(e.element, e.message) for e in named}) == len(named)
