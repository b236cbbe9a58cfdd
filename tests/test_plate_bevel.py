"""The fit of the glazing strips on their leaning beam plates: the overlap bevels.csv states is the one the solids
have, and the bevel is specified exactly where the lean exceeds glazing.bevel_min_deg.

The overlap is measured apart from fabrication.glazing.bevel: each plate's outline (its frame, thickness and
outline as the beams stage made them) clipped to the middle half of the span under a strip, extruded through the
plate's thickness, intersected in manifold3d with the strip's box; the depth of the intersection along the strip's
normal is how far the plate's top corner runs into the strip.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import REPO


@pytest.fixture(scope="module")
def staged():
    from fabrication.design import load_design
    from fabrication.pipeline import stages as st
    from fabrication.pipeline.progress import Progress

    d = load_design(REPO / "examples" / "smallest_roof.toml")
    p = Progress(quiet=True)
    g = st.stage_geometry(d, p, False)
    q = st.stage_quality(g, p)
    s = st.stage_support(d, g, p)
    panels = st.stage_panels(d, g, p, q)
    beams = st.stage_beams(d, s, p)
    return beams, st.stage_glazing(d, s, panels, beams, p)


def intersection_depth(plates, strip) -> float:
    """Depth (mm, along the strip's normal) of the plates' prisms (the pieces of the strip's beam) over the middle
    half of the strip's span inside the strip's box, by manifold3d: the deepest over the pieces."""
    return max((piece_depth(p, strip) for p in plates), default=0.0)


def piece_depth(plate, strip) -> float:
    import manifold3d as m3
    from shapely.geometry import Polygon, box

    u = strip.frame.normal
    xm = 0.5 * (strip.x0 + strip.x1)
    half = 0.25 * strip.length
    ends = strip.frame.to3d(np.array([[xm - half, 0.0], [xm + half, 0.0]]))
    ends2 = plate.frame.to2d(ends)
    lo, hi = ends2[:, 0].min(), ends2[:, 0].max()
    piece = Polygon(plate.outline).intersection(box(lo, -1e5, hi, 1e5))
    if piece.is_empty or piece.geom_type != "Polygon":
        return 0.0
    ring = np.asarray(piece.exterior.coords)[:-1]
    n = plate.frame.normal
    t = plate.thickness
    flat = plate.frame.to3d(ring)
    prism = m3.Manifold.hull_points(np.vstack([flat - 0.5 * t * n, flat + 0.5 * t * n]))
    rect = strip.frame.to3d(strip.outline())
    slab = m3.Manifold.hull_points(np.vstack([rect, rect + strip.thickness * u]))
    common = prism ^ slab
    if common.is_empty() or common.volume() < 1e-9:
        return 0.0
    z = np.asarray(common.to_mesh().vert_properties)[:, :3] @ u
    return float(z.max() - z.min())


def test_the_stated_overlap_is_the_one_of_the_solids(staged):
    from fabrication.glazing.bevel import plate_under, strip_bevels

    beams, glazing = staged
    bevels = {b.strip: b for b in strip_bevels(glazing.strips, beams.plates, glazing.params.bevel_min_deg)}
    assert len(bevels) == len(glazing.strips) == 40
    measured = []
    for s in glazing.strips:
        plate = plate_under(s, beams.plates)
        depth = intersection_depth([p for p in beams.plates if p.beam_id == s.beam_id], s)
        b = bevels[s.part_id]
        assert depth == pytest.approx(b.overlap_mm, abs=0.02), s.part_id
        assert b.delta_mm == pytest.approx(0.5 * plate.thickness * math.tan(math.radians(b.lean_deg)), rel=1e-9)
        measured.append(depth)
    assert max(measured) > 1.0                               # smallest_roof's plates lean up to 13.6°


def test_a_bevel_is_specified_exactly_above_the_threshold(staged):
    from fabrication.glazing.bevel import strip_bevels

    beams, glazing = staged
    bevels = strip_bevels(glazing.strips, beams.plates, 2.0)
    steep = [b for b in bevels if b.lean_deg > 2.0]
    assert 0 < len(steep) < len(bevels)
    for b in bevels:
        assert b.bevelled == (b.lean_deg > 2.0)
        assert b.text() == (f"top edge +{b.delta_mm:.2f} mm, bevel {b.lean_deg:.1f}° to the strip" if b.bevelled
                            else "square")
    assert not any(b.bevelled for b in strip_bevels(glazing.strips, beams.plates, 45.0))
