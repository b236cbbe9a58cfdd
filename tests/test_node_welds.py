"""Every node joint is specified: each half-lap crossing is welded in its four corners over the depth, each node
where every plate ends joins its plates with a corner weld; counted here from the plates alone (which plate runs
through which node), angles from the plates' planes with numpy."""

from __future__ import annotations

from collections import defaultdict

import numpy as np
import pytest

from fabrication import load_design
from fabrication.glazing.welds import CORNER_PREPARATION, HALFLAP_RUNS, corner_welds, halflap_welds, preparation
from fabrication.progress import Progress
from fabrication.pipeline.stages import stage_beams, stage_geometry, stage_support

from conftest import REPO


def beams_of(path):
    design = load_design(path)
    p = Progress(quiet=True)
    support = stage_support(design, stage_geometry(design, p, False), p)
    return design, stage_beams(design, support, p)


def incidence(plates):
    """node → [(plate, runs through?)] from each plate's own nodes and ``through`` flags."""
    at: dict[int, list[tuple[object, bool]]] = defaultdict(list)
    for p in plates:
        for v, through in zip(p.nodes, p.through):
            at[int(v)].append((p, bool(through)))
    return at


def plane_angle_deg(a, b) -> float:
    """Angle between two planes ``(n, d)``, 0…90°, from their unit normals."""
    na, nb = np.asarray(a[:3], float), np.asarray(b[:3], float)
    c = abs(float(na @ nb)) / (np.linalg.norm(na) * np.linalg.norm(nb))
    return float(np.degrees(np.arccos(min(1.0, c))))


@pytest.fixture(scope="module")
def default_beams():
    return beams_of(REPO / "fabrication" / "data" / "default.toml")


def test_every_half_lap_crossing_of_the_default_is_welded_in_its_four_corners(default_beams):
    design, beams = default_beams
    at = incidence(beams.plates)
    crossings = {v: ps for v, ps in at.items()
                 if sum(1 for _, t in ps if t) == 2 and len({p.beam_id for p, t in ps if t}) == 2}
    welds = halflap_welds(beams.joints, design.beams.depth, design.beams.thickness)
    assert len(crossings) == 294                                      # the default's 22 x 15 interior nodes
    assert {w.vertex for w in welds} == set(crossings) and len(welds) == len(crossings)
    for w in welds:
        (a, _), (b, _) = [x for x in crossings[w.vertex] if x[1]]
        assert {w.part, w.to} == {a.part_id, b.part_id}
        assert w.length_mm == pytest.approx(HALFLAP_RUNS * design.beams.depth)
        dihedral = plane_angle_deg(a.plane, b.plane)
        assert w.dihedral_deg == pytest.approx(dihedral, abs=1e-6)
        assert (w.preparation, w.throat_mm) == preparation(dihedral, design.beams.thickness)
        assert w.joint == "halflap"


def test_every_node_where_all_plates_end_is_joined(default_beams):
    design, beams = default_beams
    at = incidence(beams.plates)
    corners = {v for v, ps in at.items() if len(ps) >= 2 and not any(t for _, t in ps)}
    welds = corner_welds(beams.joints, design.beams.depth, design.beams.thickness)
    assert len(corners) == 4 and {w.vertex for w in welds} == corners
    for w in welds:
        ids = {p.part_id for p, _ in at[w.vertex]}
        assert {w.part, w.to} <= ids and w.part != w.to
        assert w.preparation == CORNER_PREPARATION and w.length_mm == pytest.approx(2 * design.beams.depth)
        assert w.throat_mm == design.beams.thickness


def test_a_p_design_joins_its_corner_nodes_too():
    design, beams = beams_of(REPO / "examples" / "conical_spheres.toml")
    at = incidence(beams.plates)
    corners = {v for v, ps in at.items() if len(ps) >= 2 and not any(t for _, t in ps)}
    welds = corner_welds(beams.joints, design.beams.depth, design.beams.thickness)
    joined = defaultdict(set)
    for w in welds:
        joined[w.vertex] |= {w.part, w.to}
    assert set(joined) == corners
    for v in corners:                            # every ending plate of another beam is welded to some plate
        beams_there = {p.beam_id for p, _ in at[v]}
        if len(beams_there) >= 2:
            assert {p.part_id for p, _ in at[v]} == joined[v]
