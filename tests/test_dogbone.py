"""Dog-bone reliefs at the closed ends of half-lap slots (``[beams] tool_radius``): every inner slot corner is
reached by a tool disc of that radius lying in the cut-away material (a morphological opening, shapely), and
the STEP solid is the outline extruded once (volume = outline area × thickness)."""

from __future__ import annotations

import numpy as np
import pytest
from shapely.geometry import Point, Polygon, box

from fabrication.beams import BeamParams, build_beams
from fabrication.beams.samples import sample_pp_grid
from ppfab.support.pp import support_pp


@pytest.fixture(scope="module")
def support():
    return support_pp(sample_pp_grid(4, 5))


def _corner_reach(plate, r: float) -> np.ndarray:
    """Distance of every inner slot corner from the opening of the plate's surroundings by a disc of radius
    ``r``: 0 where a disc of radius ``r`` outside the material covers the corner."""
    part = Polygon(plate.outline)
    air = box(*part.buffer(10 * r + 50).bounds).difference(part)
    opened = air.buffer(-r, quad_segs=64).buffer(r, quad_segs=64)
    return np.array([opened.distance(Point(q)) for s in plate.slots for q in s.inner_corners()])


@pytest.mark.parametrize("r", [2.0, 5.0])
def test_every_inner_slot_corner_admits_the_tool(support, r):
    sharp = build_beams(support, BeamParams(depth=150.0, thickness=12.0, max_length=0))
    relief = build_beams(support, BeamParams(depth=150.0, thickness=12.0, max_length=0, tool_radius=r))
    n = 0
    for a, b in zip(sharp.plates, relief.plates):
        if not b.slots:
            continue
        n += len(b.slots)
        assert _corner_reach(b, r).max() < 0.02 * r, b.part_id
        # without the relief the tool cannot reach the corner (the check can fail)
        assert _corner_reach(a, r).min() > 0.2 * r, a.part_id
        # the relief only removes material, and little of it: at most two discs per slot
        pa, pb = Polygon(a.outline), Polygon(b.outline)
        assert pb.difference(pa).area < 1e-6
        assert 0 < pa.area - pb.area <= len(b.slots) * 2 * np.pi * r * r * 1.02
    assert n > 0


def test_the_solid_is_the_relieved_outline_extruded_once(support):
    from fabrication.writers.step import plate_solid

    bs = build_beams(support, BeamParams(depth=150.0, thickness=12.0, max_length=0, tool_radius=4.0))
    for p in [q for q in bs.plates if q.slots][:4]:
        solid = plate_solid(p)
        assert solid.volume == pytest.approx(Polygon(p.outline).area * p.thickness, rel=1e-7)
        assert len(solid.faces()) == len(p.outline) + 2          # one side face per outline edge, no booleans


def test_a_tool_wider_than_the_slot_is_refused(support):
    from ppfab.errors import FabricationError

    with pytest.raises(FabricationError, match="narrower than the tool"):
        build_beams(support, BeamParams(depth=150.0, thickness=12.0, max_length=0, tool_radius=20.0))
