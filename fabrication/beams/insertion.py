"""How a beam plate goes into its place: the directions its slots and end cuts admit, and the plates no single
direction puts in.

A plate moves in its own plane.  A half-lap slot along ``s`` guiding over a length ``L`` admits the directions
within ``asin(c/2L)`` of ``s`` (``c`` the joint clearance: the mating plate, centred in a slot ``c`` wider than
it, moves ``L·|sin Δ|`` sideways and has ``c/2`` on either side); an end cut along a node axis, set back
``c/2`` from the plate that runs through that node, admits the half-plane of directions that bring the end
towards that plate (widened by ``asin(c/2D)`` over the depth ``D``).  Measured on the nominal plates, as the
written solids are; a plate at its upper thickness deviation leaves only half the fit on either side.  A plate
going onto plates already standing goes in along the middle of the arc all of them admit nearest its mean axis
(:func:`way_in`); where they admit none it is :class:`Blocked`.  One going in first, into nothing, goes
along the bisector of its guides (:func:`guide_bisector`).  Used by the
erection sequence (:mod:`fabrication.erection`) and by the beams stage's ``[beams] segment = ["blocked"]``
rule, which cuts such column plates at the nodes a greedy scan finds to give every part a way in (:func:`node_breaks`; a
one-edge part admits the side its two ends open to).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from .plates import BeamPlate


@dataclass(frozen=True)
class Blocked:
    """A plate that cannot slide along one direction through all its slots: the angle spread of its slot
    directions (degrees), the largest sideways travel of a mating plate in its slot (mm) and the clearance (mm)."""

    part_id: str
    spread_deg: float
    play_mm: float
    clearance_mm: float

    def __str__(self) -> str:
        return (f"{self.part_id}: the directions of its slots and end cuts spread {self.spread_deg:.2f}°, "
                f"sliding it in moves a mating "
                f"plate {self.play_mm:.2f} mm sideways in its slot (clearance {self.clearance_mm:.2f} mm, half "
                f"each side): no "
                f"single insertion direction")


def _unit3(v: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(v))
    if n < 1e-12:
        raise ValueError("zero insertion direction")
    return np.asarray(v, dtype=float) / n


def _angle(v: np.ndarray, ref: float) -> float:
    """The angle of the 2D vector ``v``, within ±π of ``ref``."""
    a = float(np.arctan2(v[1], v[0]))
    return ref + (a - ref + np.pi) % (2.0 * np.pi) - np.pi


def _reference(plate: "BeamPlate") -> float:
    """The angle (plate frame) of the mean of its node axes, top edge → bottom edge."""
    down = (np.asarray(plate.bottom, dtype=float) - np.asarray(plate.top, dtype=float)).mean(axis=0)
    return float(np.arctan2(down[1], down[0]))


def _guides(plate: "BeamPlate") -> tuple[np.ndarray, np.ndarray]:
    """The in-plane directions (angles, unwrapped near the plate's mean axis) of its slots and of the node axes
    where it ends, and the length over which each guides it (the slot length; the plate's depth)."""
    ref = _reference(plate)
    dirs = [np.asarray(s.direction, dtype=float) for s in plate.slots]
    lengths = [float(s.length) for s in plate.slots]
    for v, _ in plate.trims:
        dirs.append(plate.node_axis(int(v)))
        lengths.append(float(plate.depth))
    return np.array([_angle(d, ref) for d in dirs]), np.array(lengths)


Arc = tuple[float, float]
"""A set of directions on the circle: ``(centre, half-width)``, radians in the plate's frame."""


def _slot_arc(slot, clearance: float) -> Arc:
    """The directions a slot along ``s`` guiding over a length ``L`` admits: within ``asin(c/2L)`` of ``s`` (the
    mating plate, centred, has half the clearance on either side)."""
    w = float(np.arcsin(min(1.0, 0.5 * clearance / max(float(slot.length), 1e-9))))
    return float(np.arctan2(slot.direction[1], slot.direction[0])), w


def _end_arc(outward: np.ndarray, clearance: float, depth: float) -> Arc:
    """The directions an end cut with the in-plane outward normal ``outward`` admits: the half-plane
    ``d·n ≥ 0`` widened by ``asin(c/2D)`` over the depth ``D`` (the end stands ``c/2`` off the plate it butts
    against, :func:`fabrication.beams.joints.end_setback`)."""
    return (float(np.arctan2(outward[1], outward[0])),
            0.5 * np.pi + float(np.arcsin(min(1.0, 0.5 * clearance / max(float(depth), 1e-9)))))


def _arcs(plate: "BeamPlate", clearance: float) -> list[Arc]:
    """The arcs of every slot and end cut of a plate (:func:`_window`)."""
    arcs = [_slot_arc(sl, clearance) for sl in plate.slots]
    arcs += [_end_arc(-np.asarray(plate.body_direction(int(v)), dtype=float), clearance, plate.depth)
             for v, _ in plate.trims]
    return arcs


def _middle(arcs: list[Arc], ref: float) -> float | None:
    """The middle of the arc of directions every one of ``arcs`` admits nearest the angle ``ref``; ``None`` where
    they admit none in common, or nothing constrains."""
    arcs = [(c, w) for c, w in arcs if w < np.pi]
    if not arcs:
        return None

    def off(a: float, b: float) -> float:          # b − a, counter-clockwise, in [0, 2π)
        return float((b - a) % (2.0 * np.pi))

    def admitted(t: float) -> bool:
        return all(abs(off(c, t) if off(c, t) <= np.pi else off(c, t) - 2.0 * np.pi) <= w + 1e-12 for c, w in arcs)

    ends = [c + w for c, w in arcs]
    best: tuple[float, float] | None = None
    for start in (c - w for c, w in arcs):
        if not admitted(start):
            continue
        length = min(off(start, e) for e in ends if admitted(e))   # the admitted arc from ``start`` on
        mid = start + 0.5 * length
        away = abs(off(ref, mid) if off(ref, mid) <= np.pi else off(ref, mid) - 2.0 * np.pi)
        if best is None or away < best[0]:
            best = (away, mid)
    return None if best is None else best[1]


def _window(plate: "BeamPlate", clearance: float) -> float | None:
    """The angle (plate frame) of the direction a plate is moved along into its place: the middle of the arc of
    directions its slots and end cuts all admit nearest its mean axis (top → bottom); ``None`` where none is
    admitted by all, or nothing constrains it.

    A slot along ``s`` guiding over a length ``L`` admits the directions within ``asin(c/2L)`` of ``s`` (the
    mating plate, centred in a slot ``c`` wider than it, moves ``L·|sin Δ|`` sideways).  An end cut along the
    node axis faces the plate it butts against on one side only: coming in along ``d`` its gap to that plate is
    ``c/2 + h·(d·n)`` at ``h`` before its place (``n`` the end's outward normal in the plate's plane), so it
    admits the half-plane ``d·n ≥ 0``, widened by ``asin(c/2D)`` over the depth ``D``.  A piece between two
    plates so comes in from the side its ends open to — from below where the axes spread downwards — where a
    guide on both sides of each axis would have to be parallel to both."""
    return _middle(_arcs(plate, clearance), _reference(plate))


def _run_arcs(plate: "BeamPlate", clearance: float, a: int, b: int) -> list[Arc]:
    """The arcs of the part of ``plate`` from its node ``a`` to its node ``b`` (indices into ``plate.nodes``,
    ``a < b``) were it cut across the node axis at each of them that is not the plate's first or last node: the
    slots and end cuts of the nodes between, and at each new end the end cut butting against the plate that
    runs through that node (its outward normal away from the run's next node, square to the node's axis)."""
    last = len(plate.nodes) - 1
    nodes = [int(k) for k in plate.nodes]
    cut = {nodes[a]} if a > 0 else set()
    if b < last:
        cut.add(nodes[b])
    keep = set(nodes[a:b + 1]) - cut
    arcs = [_slot_arc(sl, clearance) for sl in plate.slots if int(sl.node) in keep]
    arcs += [_end_arc(-np.asarray(plate.body_direction(int(v)), dtype=float), clearance, plate.depth)
             for v, _ in plate.trims if int(v) in keep]
    for k, toward in ((a, a + 1), (b, b - 1)):
        if nodes[k] in cut:
            into = plate.body_direction(nodes[k], towards=nodes[toward])
            arcs.append(_end_arc(-np.asarray(into, dtype=float), clearance, plate.depth))
    return arcs


def node_breaks(plate: "BeamPlate", clearance: float) -> list[int]:
    """The nodes (vertex ids) at which to cut a plate no single direction puts in (:func:`blocked_plate`) so that
    every part admits one: scanning from its first node, each part runs to the furthest node whose run
    (:func:`_run_arcs`) still admits a direction, and is cut there; each part ends against the plate that runs
    through its end node, as a one-edge segment does.  Empty for a plate that is not blocked or has no node to
    cut at."""
    n = len(plate.nodes)
    if n < 3:
        return []
    ref = _reference(plate)

    def admits(a: int, b: int) -> bool:          # (0, n − 1): the plate's own arcs, admitted unless blocked
        arcs = _run_arcs(plate, clearance, a, b)
        return b == a + 1 or not arcs or _middle(arcs, ref) is not None

    out: list[int] = []
    a = 0
    while not admits(a, n - 1):
        b = a + 1
        while b + 1 < n - 1 and admits(a, b + 1):
            b += 1
        out.append(int(plate.nodes[b]))
        a = b
    return out


def guide_bisector(plate: "BeamPlate") -> np.ndarray:
    """``(3,)`` unit bisector of the extreme directions of a plate's slots and end axes (:func:`_guides`), in its
    plane; without either, the mean of its node axes top → bottom.  The way a plate goes in when nothing stands
    yet (the rows, first) and the way a splice cover plate is lowered beside it."""
    ang, _ = _guides(plate)
    mid = 0.5 * (ang.max() + ang.min()) if len(ang) else _reference(plate)
    return _unit3(plate.frame.vec3d(np.array([np.cos(mid), np.sin(mid)])))


def _blocked(plate: "BeamPlate", clearance: float) -> Blocked | None:
    """The :class:`Blocked` record of a plate whose slots and end cuts admit no common direction (:func:`_window`
    found none): the spread of their directions and the sideways travel ``L·|sin Δ|`` of a guide of length ``L``
    at angle ``Δ`` from their bisector; ``None`` with fewer than two guides."""
    ang, length = _guides(plate)
    if len(ang) < 2:
        return None
    mid = 0.5 * (ang.max() + ang.min())
    play = float((length * np.abs(np.sin(ang - mid))).max())
    return Blocked(plate.part_id, float(np.degrees(ang.max() - ang.min())), play, clearance)


def way_in(plate: "BeamPlate", clearance: float) -> tuple[np.ndarray, Blocked | None]:
    """``(3,)`` unit direction a plate is put in along, in its plane, onto plates already standing, and its
    :class:`Blocked` record (``None`` where it has a way in), from one :func:`_window`: the middle of the
    directions its slots and end cuts admit; where they admit none, :func:`guide_bisector`."""
    mid = _window(plate, clearance)
    if mid is None:
        return guide_bisector(plate), _blocked(plate, clearance)
    return _unit3(plate.frame.vec3d(np.array([np.cos(mid), np.sin(mid)]))), None


def blocked_plate(plate: "BeamPlate", clearance: float) -> Blocked | None:
    """The :class:`Blocked` record of a plate that no direction moves into its place through its slots and past
    the plates its ends butt against (:func:`_window`), else ``None``."""
    return None if _window(plate, clearance) is not None else _blocked(plate, clearance)
