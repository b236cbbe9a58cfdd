"""How a beam plate goes into its place: the directions its slots and end cuts admit, and the plates no single
direction puts in.

A plate moves in its own plane.  A half-lap slot along ``s`` guiding over a length ``L`` admits the directions
within ``asin(c/L)`` of ``s`` (``c`` the joint clearance: the mating plate moves ``L·|sin Δ|`` sideways in a
slot ``c`` wider than it); an end cut along a node axis, butting against the plate that runs through that
node, admits the half-plane of directions that bring the end towards that plate (widened by ``asin(c/D)``
over the depth ``D``).  A plate going onto plates already standing goes in along the middle of the arc all of
them admit nearest its mean axis (:func:`plate_direction`); where they admit none it is :class:`Blocked`.  One
going in first, into nothing, goes along the bisector of its guides (:func:`guide_bisector`).  Used by the
erection sequence (:mod:`fabrication.erection`) and by the beams stage's ``[beams] segment = ["blocked"]``
rule, which cuts such column plates into one-edge segments (each admits the side its two ends open to).
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
                f"plate {self.play_mm:.2f} mm sideways in its slot (clearance {self.clearance_mm:.2f} mm): no "
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


def _window(plate: "BeamPlate", clearance: float) -> float | None:
    """The angle (plate frame) of the direction a plate is moved along into its place: the middle of the arc of
    directions its slots and end cuts all admit nearest its mean axis (top → bottom); ``None`` where none is
    admitted by all, or nothing constrains it.

    A slot along ``s`` guiding over a length ``L`` admits the directions within ``asin(c/L)`` of ``s`` (the
    mating plate moves ``L·|sin Δ|`` sideways in a slot ``c`` wider than it).  An end cut along the node axis
    faces the plate it butts against on one side only: coming in along ``d`` its gap to that plate is
    ``c + h·(d·n)`` at ``h`` before its place (``n`` the end's outward normal in the plate's plane), so it admits
    the half-plane ``d·n ≥ 0``, widened by ``asin(c/D)`` over the depth ``D``.  A piece between two plates so
    comes in from the side its ends open to — from below where the axes spread downwards — where a guide on both
    sides of each axis would have to be parallel to both."""
    arcs: list[tuple[float, float]] = []             # (centre, half-width) on the circle of directions
    for sl in plate.slots:
        w = float(np.arcsin(min(1.0, clearance / max(float(sl.length), 1e-9))))
        arcs.append((float(np.arctan2(sl.direction[1], sl.direction[0])), w))
    for v, _ in plate.trims:
        out = -np.asarray(plate.body_direction(int(v)), dtype=float)
        arcs.append((float(np.arctan2(out[1], out[0])),
                     0.5 * np.pi + float(np.arcsin(min(1.0, clearance / max(float(plate.depth), 1e-9))))))
    arcs = [(c, w) for c, w in arcs if w < np.pi]
    if not arcs:
        return None

    def off(a: float, b: float) -> float:          # b − a, counter-clockwise, in [0, 2π)
        return float((b - a) % (2.0 * np.pi))

    def admitted(t: float) -> bool:
        return all(abs(off(c, t) if off(c, t) <= np.pi else off(c, t) - 2.0 * np.pi) <= w + 1e-12 for c, w in arcs)

    ends = [c + w for c, w in arcs]
    ref = _reference(plate)
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


def guide_bisector(plate: "BeamPlate") -> np.ndarray:
    """``(3,)`` unit bisector of the extreme directions of a plate's slots and end axes (:func:`_guides`), in its
    plane; without either, the mean of its node axes top → bottom.  The way a plate goes in when nothing stands
    yet (the rows, first) and the way a splice cover plate is lowered beside it."""
    ang, _ = _guides(plate)
    mid = 0.5 * (ang.max() + ang.min()) if len(ang) else _reference(plate)
    return _unit3(plate.frame.vec3d(np.array([np.cos(mid), np.sin(mid)])))


def plate_direction(plate: "BeamPlate", clearance: float) -> np.ndarray:
    """``(3,)`` unit direction a plate is put in along, in its plane, onto plates already standing: the middle of
    the directions its slots and end cuts admit (:func:`_window`); where they admit none, :func:`guide_bisector`."""
    mid = _window(plate, clearance)
    if mid is None:
        return guide_bisector(plate)
    return _unit3(plate.frame.vec3d(np.array([np.cos(mid), np.sin(mid)])))


def blocked_plate(plate: "BeamPlate", clearance: float) -> Blocked | None:
    """The :class:`Blocked` record of a plate that no direction moves into its place through its slots and past
    the plates its ends butt against (:func:`_window`), else ``None``; it gives the spread of its slots' and end
    axes' directions and the sideways travel ``L·|sin Δ|`` of a guide of length ``L`` at angle ``Δ`` from their
    bisector."""
    if _window(plate, clearance) is not None:
        return None
    ang, length = _guides(plate)
    if len(ang) < 2:
        return None
    mid = 0.5 * (ang.max() + ang.min())
    play = float((length * np.abs(np.sin(ang - mid))).max())
    return Blocked(plate.part_id, float(np.degrees(ang.max() - ang.min())), play, clearance)
