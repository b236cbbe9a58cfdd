"""The erection sequence (erection.csv, drawings/erection.svg) and its proof by ``ppfab verify``'s erection check:
every part swept along its insertion direction from far away (manifold3d, from the STEP solids) passes through
no part of an earlier step; a reordered sequence is named with the part, the part it passes through and the
depth."""

from __future__ import annotations

import csv
import json
import re
import shutil
from pathlib import Path

import pytest

from conftest import small_vault

ROOT = Path(__file__).resolve().parents[1]


def _write(folder: Path, design_text: str | None = None, design_path: Path | None = None) -> Path:
    from fabrication import build, load_design
    from fabrication.progress import Progress
    from fabrication.writers import write_all

    if design_path is None:
        design_path = folder.parent / "d.toml"
        design_path.write_text(design_text or "")
    b = build(load_design(design_path))
    folder.mkdir()
    write_all(b, folder, Progress(quiet=True), parallel=False)
    return folder


@pytest.fixture(scope="module", params=["small_vault", "smallest_roof"])
def built(request, tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp(request.param)
    if request.param == "small_vault":
        return _write(root / "out", small_vault("erection vault"))
    return _write(root / "out", design_path=ROOT / "examples" / "smallest_roof.toml")


def _rows(folder: Path) -> list[dict[str, str]]:
    with open(folder / "erection.csv", newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def _check(folder: Path):
    from fabrication.verify import Verification
    from fabrication.verify.erection import check_erection

    v = Verification(folder)
    check_erection(v)
    return v


def _tampered(folder: Path, tmp_path: Path, rows: list[dict[str, str]]) -> Path:
    copy = tmp_path / "copy"
    shutil.copytree(folder, copy)
    with open(copy / "erection.csv", "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    return copy


def test_sequence_is_verified_by_an_independent_sweep(built):
    from fabrication.verify.erection import TOLERANCE

    v = _check(built)
    assert "erection" in v.checked
    assert v.findings == []
    passes = v.read.erection_passes
    blocked = {r["part_id"] for r in _rows(built) if r["blocked_spread_deg"]}
    # the sweeps met their neighbours: every pane its four gaskets at least, the strips the plates they sit on ...
    panes = {p.part for p in passes if p.part.startswith("P-")}
    assert panes and all(sum(1 for p in passes if p.part == pane and p.through.startswith("GK-")) >= 4
                         for pane in panes)
    # ... and the strips the plates they sit on (measured: the pairs are in the passes; since the plates are bevelled
    # and notched under the strips, none overlaps its plate in place by more than the tolerance)
    assert any(p.part.startswith("GS-") and p.through.startswith("B-") for p in passes)
    assert max(p.static for p in passes if p.part.startswith("GS-") and p.through.startswith("B-")) <= TOLERANCE
    # ... and no two parts stand in one another in their final places (the running strips' gaskets of a valley
    # node did, by 0.73 mm, before they met on the mitre plane)
    assert max(p.static for p in passes) <= TOLERANCE
    # ... and only a plate named as having no single direction passes deeper than it overlaps in place
    assert [p for p in passes if p.excess > TOLERANCE and p.part not in blocked] == []


def test_every_part_once_and_listed_in_the_manifest(built):
    m = json.loads((built / "manifest.json").read_text(encoding="utf-8"))
    assert m["files"]["erection_csv"] == "erection.csv"
    assert m["files"]["erection_drawing"] == "drawings/erection.svg"
    assert "erection.csv" in m["sha256"] and "drawings/erection.svg" in m["sha256"]
    rows = _rows(built)
    with open(built / "parts.csv", newline="", encoding="utf-8") as fh:
        parts = list(csv.DictReader(fh))
    ids = [r["part_id"] for r in rows if r["kind"] != "weld"]
    want = [p["part_id"] for p in parts] + ["GK" + p["part_id"][2:] for p in parts if p["kind"] == "strip"]
    assert sorted(ids) == sorted(want)
    steps = {r["kind"]: int(r["step"]) for r in rows}
    assert steps["row"] < steps["column"] < steps["strip"] < steps["gasket"] < steps["panel"]
    assert all(int(r["after"]) < int(r["step"]) for r in rows)
    svg = (built / "drawings" / "erection.svg").read_text(encoding="utf-8")
    drawn = [r["part_id"] for r in rows if r["kind"] in ("row", "column", "splice", "strip", "gasket", "panel")]
    assert svg.count("data-part=") == len(drawn)        # the plan draws the structure and glass, not the retention
    assert "step 1: row plates" in svg


def test_columns_before_rows_are_named_with_the_row_and_the_depth(built, tmp_path):
    rows = _rows(built)
    with open(built / "parts.csv", newline="", encoding="utf-8") as fh:
        slotted = {p["part_id"] for p in csv.DictReader(fh) if p["kind"] == "beam" and int(p["slots"] or 0) >= 1}
    column = next(r for r in rows if r["kind"] == "column" and r["part_id"] in slotted)
    for r in rows:
        r["step"] = "1" if r is column else str(int(r["step"]) + 1)
        r["after"] = "0" if r is column else str(int(r["after"]) + 1)
    v = _check(_tampered(built, tmp_path, rows))
    hits = [f for f in v.findings if f"passes through {column['part_id']} by" in f.message]
    assert hits, [str(f) for f in v.findings]
    assert all(f.element.startswith("B-U") for f in hits)          # a row, lowered onto the column set first
    depth = float(re.search(r"by ([0-9.]+) mm", hits[0].message).group(1))
    assert depth > 5.0                                              # through the plate, not a touch


def test_reversed_order_is_named(built, tmp_path):
    rows = _rows(built)
    last = max(int(r["step"]) for r in rows)
    for r in rows:
        r["step"] = str(last + 1 - int(r["step"]))
        r["after"] = "0"
    v = _check(_tampered(built, tmp_path, rows))
    # the strips, lowered onto panes already set, pass through the glass: the deepest named, the rest counted
    assert any(f.element.startswith("GS-") and "passes through P-" in f.message for f in v.findings)
    more = [f for f in v.findings if "more passes" in f.message]
    assert len(more) == 1 and int(more[0].message.split()[0]) > 20


def test_a_wrong_blocked_mark_and_a_missing_part_are_named(built, tmp_path):
    rows = _rows(built)
    row = next(r for r in rows if r["kind"] == "row")
    row["blocked_spread_deg"] = "12.00"
    dropped = next(r for r in rows if r["kind"] == "panel")
    v = _check(_tampered(built, tmp_path, [r for r in rows if r is not dropped]))
    assert any(f.element == row["part_id"] and "slides in clear" in f.message for f in v.findings)
    assert any(f.element == dropped["part_id"] and "appears 0 times" in f.message for f in v.findings)


def test_plates_with_no_single_direction_are_named_with_their_spread():
    """smallest_roof's middle column crosses three rows whose node axes fan out by tens of degrees: no single
    direction puts it through its slots, and the plan says so."""
    from fabrication import build, load_design
    from fabrication.erection import erection_plan

    b = build(load_design(ROOT / "examples" / "smallest_roof.toml"))
    plan = erection_plan(b.beams, b.glazing, b.panels.panels)
    blocked = {x.part_id: x for x in plan.blocked}
    assert "B-W02" in blocked and blocked["B-W02"].spread_deg > 30.0
    assert blocked["B-W02"].play_mm > blocked["B-W02"].clearance_mm
    assert "B-W02" in str(blocked["B-W02"]) and "spread" in str(blocked["B-W02"])
    assert all(x.part_id.startswith("B-W") for x in plan.blocked)   # rows go in first, into nothing


def test_strips_hung_inside_the_plates_are_named(tmp_path, monkeypatch):
    """The support turned to the glass's side (what a mesh with inward faces did before the support took the
    glass's outside): the glazing strips lie inside the plates. A leaning plate's corner rises into a strip by
    (t/2)·sin λ < t/2; these overlap by more, and the check names each strip with its plate and the depth."""
    import fabrication.panels.panel as panel

    real = panel.outside_sign
    monkeypatch.setattr(panel, "outside_sign", lambda mesh, mode="auto": -real(mesh, mode))
    folder = _write(tmp_path / "out", small_vault("strips inside"))
    v = _check(folder)
    inside = [f for f in v.findings if "deeper than half the plate's thickness" in f.message]
    assert inside, [str(f) for f in v.findings[:5]]
    depths = [float(re.search(r"by ([0-9.]+) mm", f.message).group(1)) for f in inside]
    assert min(depths) > 0.5 * 12.0             # the small vault's plates are 12 mm thick
    assert all(re.search(r"overlaps B-[UW]\d\d-S\d\d ", f.message) for f in inside)     # inside a beam plate
    more = [f for f in v.findings if "more parts inside a beam plate" in f.message]
    assert len(inside) == 20 and more and int(more[0].message.split()[0]) > 50      # strips, caps, screws ...


def test_a_part_fitted_by_hand_comes_from_the_installers_reach_not_from_beyond_the_roof():
    """Under a fold of the roof (a pane 1 m above a cover cap, as on the Enneper example), a cap swept down from
    beyond every earlier part goes through that pane; from ``HAND_APPROACH_MM`` above its place it does not, and
    a pane within that reach is still passed through."""
    import numpy as np

    from fabrication.verify._bodies import Body
    from fabrication.verify.erection import HAND_APPROACH_MM, sweep_passes

    def box(z0: float, size: float = 100.0, thick: float = 10.0) -> Body:
        c = np.array([[x, y, z] for x in (0.0, size) for y in (0.0, size) for z in (z0, z0 + thick)])
        return Body(c, True, c[0], np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), np.array([0, 0, 1.0]), thick,
                    None)

    from fabrication.verify.erection import BY_HAND

    assert "gasket" in BY_HAND and "cover_cap" in BY_HAND and "strip" not in BY_HAND   # laid on, not lowered
    down = np.array([0.0, 0.0, -1.0])
    for above, hand, passes in ((1000.0, True, False), (1000.0, False, True), (100.0, True, True)):
        bodies = {"P-fold": box(above), "CC-cap": box(0.0)}
        order = [("P-fold", 1, down), ("CC-cap", 2, down)]
        found = sweep_passes(order, bodies, {"CC-cap": HAND_APPROACH_MM} if hand else None)
        deep = [p for p in found if p.depth > 0.25]
        assert bool(deep) == passes, (above, hand)
        if passes:
            assert deep[0].depth == pytest.approx(10.0, abs=1e-6)      # through the pane's whole thickness


def test_parts_overlapping_in_their_final_places_are_named(tmp_path, monkeypatch):
    """A tampered build of ``smallest_roof`` (panes kinking by up to 20°): running strips ending without the mitre
    rule, set back by ``t_s·tan(κ/2)`` only as before it (a gasket of a valley node then stands in the next span's
    strip). The check names each
    overlap in place with the pair and its depth; the build as made has none (test above). A strip moved into its
    own plate is the bevels check's (tests/test_plate_bevel.py)."""
    import fabrication.glazing.strips as strips

    monkeypatch.setattr(strips, "mitre_setback", lambda *a: 0.0)
    v = _check(_write(tmp_path / "square", design_path=ROOT / "examples" / "smallest_roof.toml"))
    found = [f for f in v.findings if "in its final place by" in f.message and "deeper than half" not in f.message]
    assert found, [str(f) for f in v.findings[:5]]
    pairs = [re.search(r"^(G[SK]-\S+) overlaps (G[SK]-\S+) in its final place by ([0-9.]+) mm", f"{f.element} "
                       + f.message) for f in found]
    assert all(pairs), [str(f) for f in found]
    # the kink of smallest_roof's valleys is about 20°: the gasket's top, 3 mm above the strip's, reaches about
    # 3·tan(10°) past the mitre plane on each side; it stood 0.73 mm in the next strip
    assert 0.25 < max(float(m.group(3)) for m in pairs) < 2.5


def _random_prism(rng, convex: bool):
    """A random thin prism as a :class:`Body`: a quad (convex) or a notched hexagon in a random frame."""
    import numpy as np
    from shapely.geometry import Polygon

    from fabrication.verify._bodies import Body

    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    ex, ey, n = q[:, 0], q[:, 1], q[:, 2]
    w, h = rng.uniform(50, 400, size=2)
    ring = np.array([[0, 0], [w, 0], [w, h], [0, h]]) if convex else \
        np.array([[0, 0], [w, 0], [w, h], [0.6 * w, h], [0.6 * w, 0.4 * h], [0, 0.4 * h]])
    o = rng.uniform(-300, 300, size=3)
    t = float(rng.uniform(8, 30))
    base = o + ring[:, :1] * ex + ring[:, 1:] * ey
    pts = np.vstack([base, base + t * n])
    return Body(pts, convex, o, ex, ey, n, t, Polygon(ring))


def _apart(a, d, far, b, gap: float = 1e-6) -> bool:
    """One pair, axis by axis, written apart from ``Body.apart_from``: the sweep of ``a`` along ``[−far·d, 0]`` and
    ``b`` projected on each body's frame axes and on each normal crossed with ``d``; separated where on one axis
    the two intervals are more than ``gap`` apart."""
    for _, lo, hi, t_lo, t_hi in _axis_intervals(a, d, far, b):
        if lo > t_hi + gap or t_lo > hi + gap:
            return True
    return False


def _axis_intervals(a, d, far, b):
    """Per usable candidate axis (each body's frame axes, each normal crossed with ``d``): the unit axis, the
    interval of ``a`` swept along ``[−far·d, 0]`` and that of ``b`` on it."""
    import numpy as np

    for axis in [a.n, a.ex, a.ey, b.n, b.ex, b.ey, np.cross(a.n, d), np.cross(b.n, d)]:
        length = float(np.linalg.norm(axis))
        if length <= 1e-9:
            continue
        u = axis / length
        mine, theirs = a.corners @ u, b.corners @ u
        shift = -far * float(u @ d)
        yield u, mine.min() + min(shift, 0.0), mine.max() + max(shift, 0.0), theirs.min(), theirs.max()


@pytest.mark.parametrize("convex", [True, False])
def test_a_separating_plane_is_found_only_where_the_sweep_and_the_part_do_not_meet(convex):
    """Body.apart_from against manifold3d's own intersection of the swept body and the other: wherever apart says the
    two are separated, the intersection is empty; and it says so for most pairs that are (the sweep's shortcut)."""
    import numpy as np

    rng = np.random.default_rng(7 if convex else 8)
    said, disjoint, met = 0, 0, 0
    for _ in range(300):
        a, b = _random_prism(rng, convex), _random_prism(rng, True)
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        far = float(rng.uniform(0, 500))
        common = a.swept(d, far) ^ b.shape()
        empty = common.is_empty() or common.volume() <= 1e-9
        if a.apart_from(d, far, [b])[0]:
            said += 1
            assert empty
        disjoint += empty
        met += not empty
    assert met > 20 and said >= 0.5 * disjoint


def test_the_separating_planes_of_many_neighbours_at_once_are_those_of_each_pair():
    """Body.apart_from (one part's sweep against all its neighbours in a few array products) says what a plain
    axis-by-axis test of each pair says (``_apart``), over random prisms, convex and notched, moving in and out of their planes, and bodies whose
    normal lies along the way in (a cross product of zero length, an axis left out)."""
    import numpy as np

    rng = np.random.default_rng(11)
    compared, separated = 0, 0
    for trial in range(60):
        a = _random_prism(rng, bool(trial % 2))
        others = [_random_prism(rng, bool(rng.integers(2))) for _ in range(int(rng.integers(1, 12)))]
        d = a.n.copy() if trial % 7 == 0 else rng.normal(size=3)
        d /= np.linalg.norm(d)
        far = float(rng.uniform(0, 500))
        many = a.apart_from(d, far, others)
        one = [_apart(a, d, far, b) for b in others]
        assert many.tolist() == one
        compared += len(one)
        separated += sum(one)
    assert compared > 200 and 0.2 * compared < separated < compared


def test_a_move_of_the_least_overlap_along_its_axis_pulls_the_sweep_and_the_part_apart():
    """Body.overlaps (how far the other part must move along a candidate axis to clear the sweep, the least over
    the axes) against manifold3d: for random pairs that meet, the other part moved by that much (and 1 µm) along
    the axis that gives it, found axis by axis apart from the code under test, no longer meets the sweep; the
    least overlap is what the axis-by-axis computation gives."""
    import numpy as np

    rng = np.random.default_rng(5)
    moved = 0
    for trial in range(300):
        a, b = _random_prism(rng, bool(trial % 2)), _random_prism(rng, True)
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        far = float(rng.uniform(0, 300))
        least = float(a.overlaps(d, far, [b])[0])
        best = (np.inf, None, 0.0)
        for u, lo, hi, t_lo, t_hi in _axis_intervals(a, d, far, b):
            up, down = hi - t_lo, t_hi - lo                          # move the other up past hi, or down past lo
            if min(up, down) < best[0]:
                best = (min(up, down), u, up if up <= down else -down)
        assert least == pytest.approx(best[0], abs=1e-9)
        common = a.swept(d, far) ^ b.shape()
        if least < 0 or common.is_empty() or common.volume() <= 1e-6:
            continue
        step = best[2] + np.sign(best[2]) * 1e-3
        away = b.moved(np.block([[np.eye(3), (step * best[1])[:, None]], [np.zeros((1, 3)), np.ones((1, 1))]]),
                       b.points + step * best[1])
        after = a.swept(d, far) ^ away.shape()
        assert after.is_empty() or after.volume() <= 1e-6, (trial, least)
        moved += 1
    assert moved > 30


def test_manifold3d_starts_no_worker_threads_for_the_checks_and_gives_the_affinity_back():
    """The checks' manifold3d runs on one thread (its workers only doubled the CPU time of tiny booleans): in a
    fresh process, after ``_bodies.manifold3d()`` a thousand booleans start no thread, and the CPU affinity is what
    it was; without it the same booleans start oneTBB's workers wherever there is more than one core."""
    import os
    import subprocess
    import sys

    code = """
import os, sys
import numpy as np
if sys.argv[1] == "one":
    from fabrication.verify._bodies import manifold3d
    mask = os.sched_getaffinity(0)
    m3 = manifold3d()
    assert os.sched_getaffinity(0) == mask, "affinity not given back"
else:
    import manifold3d as m3
before = len(os.listdir("/proc/self/task"))
rng = np.random.default_rng(0)
for _ in range(1000):
    a = m3.Manifold.hull_points(rng.normal(size=(20, 3)))
    b = m3.Manifold.hull_points(rng.normal(size=(20, 3)) + 0.5)
    (a ^ b).volume()
print(len(os.listdir("/proc/self/task")) - before)
"""
    if not hasattr(os, "sched_getaffinity") or not os.path.isdir("/proc/self/task"):
        pytest.skip("needs Linux's CPU affinity and /proc")
    started = {how: int(subprocess.run([sys.executable, "-c", code, how], capture_output=True, text=True, check=True,
                                       cwd=ROOT).stdout.split()[-1]) for how in ("one", "default")}
    assert started["one"] == 0
    if len(os.sched_getaffinity(0)) > 1:
        assert started["default"] >= 1


def test_the_farthest_earlier_part_along_any_direction_is_among_those_on_the_hull():
    """_outermost keeps, per step, the earlier parts with a box corner on the hull of all earlier boxes: the
    farthest earlier box along 500 random directions is the same as over every earlier part (to the last bit),
    with far fewer parts kept; a flat set (every box in one plane) keeps all."""
    import numpy as np

    from fabrication.verify.erection import _outermost

    rng = np.random.default_rng(5)
    n = 400
    lo = rng.uniform(-5000, 5000, size=(n, 3))
    hi = lo + rng.uniform(1, 800, size=(n, 3))
    steps = rng.integers(1, 6, size=n)
    outer = _outermost(steps, lo, hi)
    centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    assert set(outer) == {int(s) for s in np.unique(steps) if (steps < s).any()}
    for step, kept in outer.items():
        earlier = np.flatnonzero(steps < step)
        assert set(kept) <= set(earlier) and len(kept) < 0.5 * len(earlier)
        for d in rng.normal(size=(100, 3)):
            d /= np.linalg.norm(d)
            every = (centre[earlier] @ -d + half[earlier] @ np.abs(d)).max()
            assert (centre[kept] @ -d + half[kept] @ np.abs(d)).max() == every
    flat_lo, flat_hi = lo.copy(), hi.copy()
    flat_lo[:, 2] = flat_hi[:, 2] = 0.0
    for step, kept in _outermost(steps, flat_lo, flat_hi).items():      # no hull of a flat set: every part kept
        assert kept.tolist() == np.flatnonzero(steps < step).tolist()
