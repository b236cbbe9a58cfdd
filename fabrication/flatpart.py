"""Flat parts and their placements on stock sheets — the common currency of panels, beams,
nesting and DXF writing.

A :class:`FlatPart` is a closed outline in the part's own flat frame (mm);
a :class:`Placement` puts it on a sheet: a sheet point is
``R(rotation_deg) · M · p + (x, y)`` where ``M`` mirrors ``x ↦ −x`` when
``mirrored`` and ``R`` rotates counter-clockwise about the part's own origin.
That is the mapping ``parts.csv`` documents (``x, y, rotation_deg``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ppfab.metrics import polygon_area


@dataclass(frozen=True, eq=False)
class FlatPart:
    """One part to cut from flat stock.

    Parameters
    ----------
    part_id : unique id, e.g. ``P-U07-V12`` (panel) or ``B-U03`` (beam)
    kind : ``"panel"`` or ``"beam"``
    outline : (k, 2) float, closed polygon (not repeating the first point), counter-clockwise, mm
    marks : polylines ``(p, 2)`` drawn on layer ``MARK`` (node axes, orientation marks)
    label : text written on layer ``LABEL`` (defaults to ``part_id``)
    type_id : congruence class (identical parts share it)
    rotations : allowed rotations in degrees, ``None`` = the nesting default
    free_rotation : any rotation is allowed (a material without grain or pattern, e.g. float glass);
        ``rotations`` is then ignored
    mirror_allowed : may be placed mirrored
    meta : free data carried into the parts list (material, thickness, …)
    """

    part_id: str
    kind: str
    outline: np.ndarray
    marks: tuple = ()
    label: str = ""
    type_id: str = ""
    rotations: tuple[float, ...] | None = None
    mirror_allowed: bool = False
    meta: dict = field(default_factory=dict)
    free_rotation: bool = False

    @property
    def area(self) -> float:
        return float(polygon_area(self.outline))


@dataclass(frozen=True)
class Placement:
    """Where a part lies on a sheet: ``sheet`` index (0-based), translation, rotation, mirror, nest tag."""

    part_id: str
    sheet: int
    x: float
    y: float
    rotation_deg: float
    mirrored: bool = False
    nest_tag: str = ""


def place_points(points: np.ndarray, placement: Placement) -> np.ndarray:
    """Map part-frame points ``(k, 2)`` to sheet coordinates (see module docstring)."""
    p = np.asarray(points, dtype=float).copy()
    if placement.mirrored:
        p[:, 0] = -p[:, 0]
    a = np.radians(placement.rotation_deg)
    c, s = np.cos(a), np.sin(a)
    rot = np.array([[c, -s], [s, c]])
    return p @ rot.T + np.array([placement.x, placement.y])
