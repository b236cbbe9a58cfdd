"""Setting blocks where a kink closes the joint: the block's room under the glass across it, the refusal that
names the panes and the joint that gives them room, and blocks of two panes in one joint (a valley) kept apart.

The real case: DOS quad_dome (WWmore/DOS, objs/obj_equilibrium/quad_dome.obj @ f15cff51, bundled with the examples),
made conical PP, whose panes kink by up to 36°.  Before, four of its setting blocks stood 0.40 mm in the glass
across their joint and the build failed its own clash check after writing every file."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fabrication.glazing.retention import JOINT_SPARE, _below_face, _clear_of


def _inside(points: np.ndarray, face) -> np.ndarray:
    """Whether points ``(k, 3)`` lie in the glass across: behind its edge face and within its slab."""
    origin, m, up, thick = face
    rel = points - origin
    h = rel @ up
    return (rel @ m <= 0.0) & (h >= 0.0) & (h <= thick)


@pytest.mark.parametrize("seed", range(12))
def test_the_room_under_the_glass_across_is_the_first_height_of_contact(seed):
    """``_below_face`` against a dense sampling of the rising block: below the height it returns no sample is in
    the glass across, a little above it one is (or it returns inf and none ever is)."""
    rng = np.random.default_rng(seed)
    n = np.array([0.0, 0.0, 1.0])
    tilt = np.radians(rng.uniform(-40, 40))
    up = np.array([0.0, np.sin(tilt), np.cos(tilt)])            # the pane across, kinked about x
    m = np.array([0.0, -np.cos(tilt), np.sin(tilt)])            # its edge face's outward normal (towards -y)
    face = (np.array([0.0, rng.uniform(5, 9), rng.uniform(-3, 3)]), m, up, 17.5)
    w = rng.uniform(2, 6)
    rect = np.array([[-50, 0, 0], [50, 0, 0], [50, w, 0], [-50, w, 0]], dtype=float)
    h = _below_face(rect, n, face)
    u, v, s = np.meshgrid(np.linspace(0, 1, 21), np.linspace(0, 1, 21), np.linspace(0, 1, 41), indexing="ij")

    def block(height: float) -> np.ndarray:
        return np.stack([-50 + 100 * u.ravel(), w * v.ravel(), height * s.ravel()], axis=1)

    for cap in (1.0, 5.0, 18.0):                      # a block never taller than cap: the plane's bound may answer
        capped = _below_face(rect, n, face, cap)
        assert capped == h if h < cap else capped >= cap
    if math.isinf(h):
        assert not _inside(block(60.0), face).any()
        return
    assert h >= 0.0
    assert not _inside(block(max(h - 1e-3, 0.0)), face).any()
    assert _inside(block(h + 0.05), face).any()


def _clear(t: float, lb: float, shift: float, avoid) -> bool:
    """The block centred ``t`` (``lb`` long, strip x = t + shift, reversed when shift < 0) is clear of ``avoid``."""
    x = sorted((shift + t - 0.5 * lb, shift + t + 0.5 * lb)) if shift >= 0 else \
        sorted((-shift - t - 0.5 * lb, -shift - t + 0.5 * lb))
    return all(x[1] + JOINT_SPARE <= u or v + JOINT_SPARE <= x[0] for u, v in avoid)


@pytest.mark.parametrize("shift", [0.0, 250.0, -1200.0])
def test_a_valley_block_moves_to_the_nearest_clear_station_or_is_refused(shift):
    """A 100 mm block at the quarter point of a 1,000 mm edge, the strip running along the edge or against it:
    moved towards the middle when that is clear, towards the end when only that is, ``None`` when neither is;
    every returned station checked clear of the taken intervals and on its stretch."""
    lb, length = 100.0, 1000.0

    def along(t: float) -> float:
        return shift + t if shift >= 0 else -shift - t

    def strip(a: float, b: float) -> tuple[float, float]:            # edge stretch [a, b] in strip x
        u, v = sorted((along(a), along(b)))
        return u, v

    free = _clear_of(250.0, 1.0, lb, length, along, [])
    assert free == 250.0
    middle = _clear_of(250.0, 1.0, lb, length, along, [strip(150.0, 320.0)])
    assert middle is not None and 250.0 < middle <= 500.0 and _clear(middle, lb, shift, [strip(150.0, 320.0)])
    end = _clear_of(250.0, 1.0, lb, length, along, [strip(180.0, 600.0)])
    assert end is not None and 50.0 <= end < 250.0 and _clear(end, lb, shift, [strip(180.0, 600.0)])
    assert _clear_of(250.0, 1.0, lb, length, along, [strip(100.0, 700.0)]) is None
    assert _clear_of(750.0, -1.0, lb, length, along, [strip(400.0, 700.0), strip(720.0, 1000.0)]) is None


def _design(tmp_path, gap: float):
    from fabrication.examples import example_path

    src = example_path("fig16_quad_dome_multipatch")
    text = src.read_text(encoding="utf-8").replace("gap = 15.0", f"gap = {gap}")
    text = text.replace('mesh = "meshes/', f'mesh = "{(src.parent / "meshes").as_posix()}/')
    design = tmp_path / "dome.toml"
    design.write_text(text, encoding="utf-8")
    return design


def test_blocks_without_room_are_refused_with_the_joint_that_fits(tmp_path, capsys):
    """At a 10 mm joint four panes' setting blocks would stand in the glass across (0.40 mm, what the clash check
    found after writing every file): the build stops before writing, in one line naming them and the joint that
    gives them room (15 mm, which builds: the next test)."""
    from fabrication.cli import main

    out = tmp_path / "out"
    assert main(["build", str(_design(tmp_path, 10.0)), "-o", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in err[0]
    assert "panels.gap: 4 pane(s) have no room for their setting blocks" in err[0]
    assert "widen [panels] gap to at least 15 mm (from 10)" in err[0]
    assert not out.exists()


def test_valley_blocks_that_find_no_clear_station_are_refused(tmp_path, capsys):
    """300 mm blocks: in one of the dome's valley joints the two panes' blocks cannot stand apart; the build stops
    before writing, in one line naming the pane, the strip and the key."""
    from fabrication.cli import main

    design = _design(tmp_path, 15.0)
    text = design.read_text(encoding="utf-8").replace("[glazing]\n", "[glazing]\nsetting_block_length = 300.0\n")
    design.write_text(text, encoding="utf-8")
    out = tmp_path / "out"
    assert main(["build", str(design), "-o", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in err[0]
    assert "glazing.setting_block_length: 1 pane(s) find no station for a setting block clear" in err[0]
    assert "P-0040 on GS-R0002-02" in err[0] and "now 300 mm" in err[0]
    assert not out.exists()


@pytest.mark.slow
def test_the_multipatch_dome_builds_and_its_blocks_clear_the_glass_and_each_other(tmp_path):
    """At the 15 mm joint the build verifies: no block or stop in the glass across (clash), none in another
    (the erection overlap check: in the dome's valleys both panes put their blocks in one joint, now apart
    along it); and its PP support is torsion-free."""
    import csv

    from fabrication import verify as verify_package
    from fabrication.cli import main

    out = tmp_path / "out"
    assert main(["build", str(_design(tmp_path, 15.0)), "-o", str(out), "--quiet"]) == 0
    result = verify_package.verify(out)
    assert result.ok and {"clash", "torsion"} <= set(result.checked)
    rows = list(csv.DictReader((out / "retention.csv").open(encoding="utf-8")))
    assert sum(r["kind"] == "setting_block" for r in rows) == 2 * 48
