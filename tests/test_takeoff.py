"""The steel take-off and weld length of a build: the manifest's summary and the report add up every part kind of
parts.csv (beam plates, glazing strips, splice cover plates) and every row of welds.csv, recomputed here from the
rows; each mass also recomputed from its own dimensions and the material density."""

from __future__ import annotations

import csv
import json
import math

import pytest

from conftest import built_folder, small_vault

DESIGN = small_vault("takeoff", max_length=5000.0, joint="halflap")
built = built_folder("takeoff", DESIGN)


def rows(path):
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def test_the_steel_take_off_is_every_steel_part_of_parts_csv(built):
    parts = rows(built / "parts.csv")
    summary = json.loads((built / "manifest.json").read_text())["summary"]
    kinds = {r["kind"] for r in parts}
    assert {"beam", "strip", "splice"} <= kinds, kinds          # the vault is split, so it has cover plates
    by_kind = {k: sum(float(r["mass_kg"]) for r in parts if r["kind"] == k) for k in ("beam", "strip", "splice")}
    assert summary["beam_mass_kg"] == pytest.approx(by_kind["beam"], abs=5e-4 * len(parts))
    assert summary["steel_mass_kg"] == pytest.approx(sum(by_kind.values()), abs=5e-4 * len(parts))
    assert summary["steel_mass_kg"] > summary["beam_mass_kg"] + by_kind["strip"] * 0.99
    for r in parts:                           # each mass from its own area × thickness × 7850 kg/m³ (strips gross)
        if r["kind"] in ("beam", "strip"):
            assert float(r["mass_kg"]) == pytest.approx(float(r["area_mm2"]) * float(r["thickness_mm"]) * 7850e-9,
                                                        rel=1e-3, abs=1e-3)
        elif r["kind"] == "splice":           # net of its bolt holes
            holes = int(r["holes"]) * math.pi * 0.25 * float(r["hole_mm"]) ** 2
            assert float(r["mass_kg"]) == pytest.approx((float(r["area_mm2"]) - holes) * float(r["thickness_mm"])
                                                        * 7850e-9, rel=1e-3, abs=1e-3)


def test_the_weld_length_is_every_row_of_welds_csv(built):
    welds = rows(built / "welds.csv")
    summary = json.loads((built / "manifest.json").read_text())["summary"]
    assert {w["joint"] for w in welds} >= {"halflap", "T"}
    assert summary["weld_length_m"] == pytest.approx(sum(float(w["weld_length_mm"]) for w in welds) / 1e3,
                                                     abs=1e-6 * len(welds))
    report = (built / "report.html").read_text(encoding="utf-8")
    assert f"{summary['steel_mass_kg'] / 1000:.2f} t" in report and f"{summary['weld_length_m']:.1f} m" in report
