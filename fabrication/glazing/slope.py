"""Panes that lie too flat to drain: the minimum slope warning (``[glazing] min_slope_deg``).

Water stands on flush-jointed glass that slopes less than about 2–5°: the panes sag between their supports, the
joint seals stand proud, and dirt collects along the lower edge.  A pane's slope is the angle between its plane
and the horizontal (``z`` is up): ``arccos |n_z|`` for its unit normal ``n``.  Panes below ``min_slope_deg``
(default 2°, our choice at the low end of that range, not a figure of a standard) are named in a warning and in
the report, with the drainage note :data:`DRAINAGE_NOTE`; the build goes on.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

log = logging.getLogger("ppfab")

DRAINAGE_NOTE = ("water stands on flush-jointed glass sloping less than about 2-5°: give these panes a drainage "
                 "concept (a fall of at least the minimum slope, drained pressure plates or raised caps across "
                 "the flow, a stepped lower edge) or change the shape")


@dataclass(frozen=True)
class FlatPane:
    """A pane flatter than the minimum slope: its part id and its slope (degrees from the horizontal)."""

    part_id: str
    slope_deg: float


def pane_slope_deg(normal: np.ndarray) -> float:
    """The slope (degrees) of a plane with ``normal``: 0 for a horizontal pane, 90 for a vertical one.

    >>> round(pane_slope_deg(np.array([0.0, np.sin(np.radians(3)), np.cos(np.radians(3))])), 9)
    3.0
    """
    n = np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n)
    return float(np.degrees(np.arccos(min(1.0, abs(float(n[2]))))))


def flat_panes(panels, min_slope_deg: float) -> list[FlatPane]:
    """The panes sloping less than ``min_slope_deg``, flattest first (their frame normals)."""
    out = [FlatPane(p.part_id, pane_slope_deg(p.frame.normal)) for p in panels]
    return sorted((f for f in out if f.slope_deg < min_slope_deg), key=lambda f: (f.slope_deg, f.part_id))


def warn_flat_panes(panels, min_slope_deg: float) -> list[FlatPane]:
    """:func:`flat_panes`, logged as one warning naming them (at most 12) with the drainage note."""
    flat = flat_panes(panels, min_slope_deg)
    if flat:
        names = ", ".join(f"{f.part_id} ({f.slope_deg:.2f}°)" for f in flat[:12])
        more = f" and {len(flat) - 12} more" if len(flat) > 12 else ""
        log.warning("%d pane(s) slope less than glazing.min_slope_deg = %g°: %s%s; %s", len(flat), min_slope_deg,
                    names, more, DRAINAGE_NOTE)
    return flat
