"""Usable support structures: node axes near the surface normals (checked before any beam is drawn).

A node axis far from the surface normal makes the beams at that node slant: a plate whose plane holds an
axis at angle ``φ`` from the normal meets the glass at about ``90° − φ``, and at ``φ → 90°`` it lies in the
surface.  :func:`check_axis_angles` refuses a structure whose axes leave the normals by more than
``[support] max_axis_angle_deg`` and says why they do.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ppfab.errors import GeometryError

from .structure import SupportStructure


def check_axis_angles(support: SupportStructure, limit_deg: float) -> np.ndarray:
    """``(N,)`` axis–normal angles (degrees); :class:`GeometryError` listing the vertices above ``limit_deg``."""
    ang = support.normal_angle_deg
    bad = np.flatnonzero(~(ang <= limit_deg))
    if not len(bad):
        return ang
    bad = bad[np.argsort(-ang[bad])]
    shown = ", ".join(f"N{int(k):04d} {ang[k]:.0f}°" for k in bad[:8])
    more = f" (and {len(bad) - 8} more)" if len(bad) > 8 else ""
    raise GeometryError(f"the node axes of {len(bad)} vertex(es) of the '{support.kind}' support structure leave the "
                        f"surface normal by more than support.max_axis_angle_deg = {limit_deg:g}°: {shown}{more}; "
                        f"{_advice(support, bad)}", element=f"vertex {int(bad[0])}", value=float(ang[bad[0]]))


def _weight_axes_hint() -> str:
    try:
        from ppfab.optimize.params import OptimizeParams
    except ImportError:  # pragma: no cover - the optimiser is part of the package
        return ""
    names = {f.name for f in dataclasses.fields(OptimizeParams)}
    return " with [optimize] weight_axes (support planes at right angles to the panels)" if "weight_axes" in names \
        else ""


def _advice(support: SupportStructure, bad: np.ndarray) -> str:
    at = support.planes_at
    if at is not None and np.mean(at[bad] <= 1) >= 0.5:
        return ("there the axes were solved to make the polylines left out of the planar families torsion-free "
                f"({len(support.left_out)} left out; `ppfab check --polylines` lists them and why): keep more "
                "polylines as planar beams ([support] exclude), or raise support.max_axis_angle_deg if slanted "
                "beams are acceptable")
    return ("there the planes of the polylines through the vertex meet in a line far from the normal; optimise "
            f"the mesh again{_weight_axes_hint()}, leave those polylines out ([support] exclude), or raise "
            "support.max_axis_angle_deg if slanted beams are acceptable")
