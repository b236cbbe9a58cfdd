"""The requested structure is honoured: polylines of a planar family the support left out stop the build.

A design asks for planar beams: both families with half-lap joints (PP), one continuous family with segmented
joints or a P support.  :func:`ppfab.support.planar.planar_support` leaves a polyline out of the planar beams
when it cannot be one (its plane is further than ``[support] max_normal_angle_deg`` from the surface normal, its
node axes conflict at a vertex, or they cross within the beam depth); the edges of such a polyline become beams of
one edge each.  That is a different structure from the one asked for (on a Great Court-like patch built with
half-lap joints, every row became one-edge plates), so it is refused here — naming the polylines, the reason and
the angle — unless the design accepts it with ``[beams] fallback = "segmented"``.

Polylines the designer excluded explicitly (``[support] exclude`` ids or rules other than ``"auto"``) are what was
asked for and never stop the build.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ppfab.errors import DesignError
from ppfab.mesh import QuadGrid, QuadMesh
from ppfab.support.structure import SupportStructure

EXPLICIT_REASON = "left out by support.exclude"
"""The reason :mod:`ppfab.support.planar` gives for a polyline the designer excluded by id or rule."""

SHOWN = 6
"""How many polylines a refusal names before it says how many more there are."""


@dataclass(frozen=True)
class StructureChange:
    """The polylines of the requested planar families that are not planar beams, and why.

    ``left_out``: ``(beam id, polyline index, reason)`` of every polyline the support left out on its own (not the
    ones ``[support] exclude`` names); ``edges``: how many one-edge plates they become.
    """

    left_out: tuple[tuple[str, int, str], ...]
    edges: int

    @property
    def changed(self) -> bool:
        return bool(self.left_out)

    def message(self) -> str:
        """One line: how many, which (the first :data:`SHOWN`), why, and the keys that change it."""
        shown = "; ".join(f"{bid} (polyline {k}): {why}" for bid, k, why in self.left_out[:SHOWN])
        more = f"; and {len(self.left_out) - SHOWN} more" if len(self.left_out) > SHOWN else ""
        return (f"{len(self.left_out)} polyline(s) of the requested planar families cannot be planar beams and "
                f"would become {self.edges} one-edge plates: {shown}{more}. Set [beams] fallback = \"segmented\" "
                "to accept one-edge plates for them, list them in [support] exclude, or remesh or optimise the "
                "mesh so that these polylines lie in planes near the surface normal (`ppfab check --polylines` "
                "lists every polyline with its angle)")


def structure_change(support: SupportStructure, beam_ids: list[str]) -> StructureChange:
    """What the support left out on its own, with the beam id of each polyline (``beam_ids[k]``, one per
    polyline of ``support.polylines``)."""
    rows = tuple((beam_ids[k], int(k), why) for k, why in support.left_out if why != EXPLICIT_REASON)
    edges = sum(max(len(support.polylines[k].vertices) - 1, 0) + (1 if support.polylines[k].closed else 0)
                for _, k, _ in rows)
    return StructureChange(rows, int(edges))


def honour_structure(change: StructureChange, fallback: str) -> None:
    """Refuse a structure change unless ``fallback == "segmented"`` (:class:`~ppfab.errors.DesignError` on
    ``beams.fallback``, exit code 2)."""
    if change.changed and fallback != "segmented":
        raise DesignError("beams.fallback", change.message())


EARLY_MARGIN_DEG = 10.0
"""Before optimising, a polyline is refused only when its plane is this much further from the surface normal
than ``[support] max_normal_angle_deg``: the optimiser moves the surface by a few per cent of its size and turns
the planes by a few degrees (conical1 made P: 43° before and after), never by tens of degrees."""


def refuse_before_optimising(mesh: QuadGrid | QuadMesh, families: tuple[str, ...], max_normal_angle_deg: float,
                             exclude: list[int | str], fallback: str) -> None:
    """Refuse a mesh design, before the optimiser runs, whose requested planar families hold polylines that
    cannot become planar beams: their least-squares plane (:func:`ppfab.support.lines.polyline_planes`) lies
    more than ``max_normal_angle_deg + EARLY_MARGIN_DEG`` from the surface normal at one of their vertices (a
    curve in a flat stretch of the surface, or across it).  Nothing is refused with ``fallback = "segmented"``
    or when ``[support] exclude`` names polylines itself (what is left out was then asked for)."""
    if fallback == "segmented" or any(s != "auto" for s in exclude) or not families:
        return
    from ppfab.support.lines import polyline_planes
    from ppfab.support.structure import as_quadmesh, vertex_normals
    from ppfab.topology import FAMILY_NAMES

    qm = as_quadmesh(mesh)
    planes = polyline_planes(qm, vertex_normals(qm))
    wanted = {FAMILY_NAMES.index(f) for f in families if f in FAMILY_NAMES}
    limit = max_normal_angle_deg + EARLY_MARGIN_DEG
    bad = [(k, float(planes.tilt_deg[k]), int(planes.tilt_vertex[k])) for k, p in enumerate(qm.polylines)
           if p.family in wanted and len(p) >= 3 and np.isfinite(planes.tilt_deg[k]) and planes.tilt_deg[k] > limit]
    if not bad:
        return
    bad.sort(key=lambda b: -b[1])
    shown = "; ".join(f"polyline {k} ({FAMILY_NAMES[qm.polylines[k].family]}): plane {t:.0f}° from the normal at "
                      f"vertex {v}" for k, t, v in bad[:SHOWN])
    more = f"; and {len(bad) - SHOWN} more" if len(bad) > SHOWN else ""
    raise DesignError("beams.fallback", f"{len(bad)} polyline(s) of the planar families asked for "
                      f"({', '.join(families)}) lie in planes more than {limit:g}° from the surface normal before "
                      f"optimising (support.max_normal_angle_deg = {max_normal_angle_deg:g}°), so they cannot become "
                      f"planar beams: {shown}{more}. Remesh along curves whose planes stand near the normal, choose "
                      "the other family, or set [beams] fallback = \"segmented\" to accept one-edge plates for them")
