"""The glass make-up: parsed as the trade writes it, its thickness, tolerance and weight computed here a second
way by hand, refusals that say what to write, and overhead glazing refused unless laminated."""

from __future__ import annotations

import numpy as np
import pytest

from fabrication.panels import PanelParams, make_panels
from fabrication.panels.makeup import OVERHEAD_FROM_VERTICAL_DEG, check_overhead, parse_makeup
from ppfab.errors import DesignError
from ppfab.mesh import QuadGrid
from ppfab.schema import parse_params


@pytest.mark.parametrize("text, plies, thickness, tolerance, kg_m2", [
    ("8 HS / 1.52 PVB / 8 HS", 3, 17.52, 0.3 + 0.3 + 0.1, 0.016 * 2500 + 0.00152 * 1070),
    ("6 FT-HST / 0.76 SGP / 6 HS", 3, 12.76, 0.2 + 0.2 + 0.1, 0.012 * 2500 + 0.00076 * 950),
    ("10 FT", 1, 10.0, 0.3, 0.010 * 2500),
    ("10 HS / 1.52 PVB / 10 HS / 1.52 PVB / 10 HS", 5, 33.04, 0.9 + 0.2, 0.030 * 2500 + 0.00304 * 1070),
    ("15 fl", 1, 15.0, 0.5, 0.015 * 2500),
])
def test_make_ups_parse_to_their_thickness_tolerance_and_weight(text, plies, thickness, tolerance, kg_m2):
    m = parse_makeup(text)
    assert len(m.plies) == plies
    assert m.thickness_mm == pytest.approx(thickness, abs=1e-12)
    assert m.thickness_tolerance_mm == pytest.approx(tolerance, abs=1e-12)
    assert m.mass_per_m2(2500.0) == pytest.approx(kg_m2, rel=1e-12)
    assert parse_makeup(m.text()) == m                       # the canonical text reads back to the same make-up


def test_toughened_plies_are_ordered_heat_soaked_and_laminates_say_so():
    assert parse_makeup("6 FT / 1.52 PVB / 6 HS").heat_soak
    assert not parse_makeup("8 HS / 1.52 PVB / 8 HS").heat_soak
    assert parse_makeup("8 HS / 1.52 PVB / 8 HS").laminated and not parse_makeup("10 FT").laminated
    assert "laminated" in parse_makeup("8 HS / 1.52 PVB / 8 HS").description()


@pytest.mark.parametrize("text, says", [
    ("toughened 10 mm", "ply 1 'toughened 10 mm' is not '<mm> <kind>'"),
    ("8 XX / 1.52 PVB / 8 HS", "ply 1: unknown kind 'XX'"),
    ("8 HS / 1.5 PVB / 8 HS", "multiples of 0.38 mm"),
    ("8 HS / 8 HS", "must alternate"),
    ("8 HS / 1.52 PVB", "ends with an interlayer"),
    ("0 HS", "outside 0-25 mm"),
])
def test_a_make_up_that_is_not_one_is_refused_naming_the_ply(text, says):
    with pytest.raises(DesignError) as err:
        parse_params(PanelParams, {"makeup": text}, "panels")
    assert says in str(err.value) and "\n" not in str(err.value)


def test_a_thickness_that_contradicts_the_make_up_is_refused():
    with pytest.raises(DesignError, match=r"thickness: 10 mm, but the make-up '8 HS / 1.52 PVB / 8 HS' is 17.52 mm"):
        parse_params(PanelParams, {"thickness": 10.0}, "panels")
    assert parse_params(PanelParams, {"thickness": 17.52}, "panels").thickness == 17.52


def inclination_from_vertical(normal: np.ndarray) -> float:
    """Degrees a plane with this normal lies off the vertical: 90° minus the normal's angle to the vertical."""
    n = normal / np.linalg.norm(normal)
    return 90.0 - float(np.degrees(np.arccos(abs(n[2]))))


@pytest.mark.parametrize("tilt_deg, laminated, refused", [(5.0, False, False), (12.0, False, True),
                                                          (60.0, True, False), (89.0, False, True)])
def test_overhead_glazing_must_be_laminated(tilt_deg, laminated, refused):
    """A plane grid tilted ``tilt_deg`` off the vertical: its panes' frames (made by make_panels) measured
    independently, and the rule applied to them."""
    t = np.radians(tilt_deg)
    i, j = np.meshgrid(np.arange(3.0), np.arange(2.0), indexing="ij")
    # plane spanned by x and (0, sin t, cos t): its normal is t off the horizontal, so the plane t off the vertical
    v = i[..., None] * np.array([1.0, 0.0, 0.0]) + j[..., None] * np.array([0.0, np.sin(t), np.cos(t)])
    makeup = "8 HS / 1.52 PVB / 8 HS" if laminated else "10 FT"
    panels = make_panels(QuadGrid(v), PanelParams(makeup=makeup), scale=1000.0)
    incl = max(inclination_from_vertical(p.frame.normal) for p in panels)
    assert incl == pytest.approx(tilt_deg, abs=1e-9)
    call = lambda: check_overhead(parse_makeup(makeup), incl, panels[0].part_id)  # noqa: E731
    if refused:
        assert tilt_deg > OVERHEAD_FROM_VERTICAL_DEG
        with pytest.raises(DesignError, match="must be laminated safety glass"):
            call()
    else:
        call()
