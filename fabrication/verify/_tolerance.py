"""The panel-type tolerance a build used, read from its manifest's ``fabrication.panels``."""

from __future__ import annotations


def type_tolerance(fab: dict) -> float:
    """``panels.type_tolerance`` when the build set it, else ``panels.congruence_tolerance`` (mm; 0 if neither)."""
    panels = fab.get("panels", {}) or {}
    value = panels.get("type_tolerance")
    return float(value if value is not None else panels.get("congruence_tolerance", 0.0))
