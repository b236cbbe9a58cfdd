"""Repeated parts: which parts are one type, and the rigid motion that places a type's shape on each of its
occurrences — the element types of ``model.ifc`` and the instanced meshes of ``model.glb``.

A BIM tool counts, schedules and draws a type once (``IfcPlateType``, ``IfcMemberType``, …) and places its shape
(an ``IfcRepresentationMap``) on every occurrence by an ``IfcMappedItem``.  Which parts share a type
(:func:`type_key`):

* a glass pane: its panel type (``type_id``; every pane is typed).  The glass is cut to the outline of the
  type's first pane (:func:`fabrication.panels.panel.type_flat_parts`), so the type's shape *is* the pane as
  built: each occurrence maps it, placed by the motion that fits it best onto the pane's own outline — within
  the type tolerance (``[panels] type_tolerance``) of the face, by the definition of a type;
* a beam plate or splice cover plate: its ``type_id`` (congruent plates; cover plates of one size and skew);
* a glazing strip or retention box: its kind and its size to 0.001 mm (``strip 1234.5 x 60 x 8``);
* the screws of a plate: their diameter and length (the type of the fastener; each occurrence keeps its own
  row of screws).

In ``model.ifc`` a type is written when two or more parts share it (every panel type is).  Every occurrence other than a pane
maps its type's shape only where that shape lies within :data:`MAP_TOLERANCE_MM` of its own body after the
motion (plates that are mirror images in a symmetric roof); the others keep their own body and are still typed.

A motion (:class:`Motion`) acts in the occurrence's own frame (its ``Element.frame``): a rotation about the
frame's normal and a shift in its plane — or, where only the mirror image fits (a plate turned over), that
rotation after a reflection ``x ↦ −x``, turned over in 3D as ``z ↦ 2 z0 + h − z`` so that the solid keeps its
place ``z0 … z0 + h`` along the normal and the motion is proper (no mirroring operator for viewers to honour).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..panels.congruence import correspondences, kabsch_2d
from ._elements import Element

MAP_TOLERANCE_MM = 1e-5
"""Largest corner distance (mm) at which a part other than a pane is drawn as its type's shape moved onto it:
below the 1e-4 mm to which ``ppfab verify`` places every solid, so a mapped plate is the plate."""


@dataclass(frozen=True)
class Motion:
    """``x ↦ R x + t`` in an element's frame (mm): ``rotation (3, 3)`` proper, ``shift (3,)``; ``error`` the
    largest corner distance of the moved shape from the element's own outline (mm)."""

    rotation: np.ndarray
    shift: np.ndarray
    error: float

    def apply(self, points: np.ndarray) -> np.ndarray:
        """``(n, 3)`` points moved."""
        return np.asarray(points, dtype=float) @ self.rotation.T + self.shift


def type_key(el: Element) -> str | None:
    """The name of the IFC type ``el`` belongs to, ``None`` for a part typed by nothing.

    >>> import numpy as np
    >>> from ppfab.frame import Frame
    >>> box = np.array([[0.0, 0.0], [1234.5, 0.0], [1234.5, 60.0], [0.0, 60.0]])
    >>> f = Frame(np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    >>> type_key(Element("S-1", "strip", "rows", "", box, f, 0.0, 8.0))
    'strip 1234.5 x 60 x 8'
    """
    type_id = str(el.props.get("type_id", "") or "")
    if type_id:
        return type_id
    if el.kind == "screw":
        d = 2.0 * float(np.linalg.norm(np.asarray(el.outline, dtype=float), axis=1).max())
        return f"screw {_mm(d)} x {_mm(el.height)}"
    if el.kind in ("strip",) or el.kind in _BOX_KINDS:
        size = np.ptp(np.asarray(el.outline, dtype=float), axis=0)
        return f"{el.kind} {_mm(max(size))} x {_mm(min(size))} x {_mm(el.height)}"
    return None


_BOX_KINDS = ("setting_block", "stop", "pressure_gasket", "pressure_plate", "cover_cap")


def _mm(x: float) -> str:
    return f"{round(float(x), 3):g}"


def mappable(el: Element) -> bool:
    """Whether ``el``'s body can be its type's shape moved: one prism, or two faces (a bevelled plate) — not the
    row of screws of a plate (their count and places differ between plates)."""
    return el.copies is None


def fit_motion(shape: Element, el: Element) -> Motion | None:
    """The proper rigid motion in ``el``'s frame that puts ``shape``'s body (outline, holes, top face, extruded
    from its ``z0`` by its height) best onto ``el``'s: over every way the corners can correspond (where the
    outline starts; reversed under a reflection, which turns the solid over), the 2D Procrustes fit of the
    corners, judged by the largest corner distance.  ``None`` when the two bodies cannot be one shape (other
    corner counts, heights, holes, or an error that the holes or top face make larger than the outline's).
    """
    a = np.asarray(shape.outline, dtype=float)
    b = np.asarray(el.outline, dtype=float)
    if a.shape != b.shape or abs(shape.height - el.height) > 1e-9 or len(shape.holes) != len(el.holes) \
            or shape.two_faces != el.two_faces:
        return None
    k = len(a)
    # every way the corners can correspond: the shape's outline started at each corner, then (a plate turned
    # over: no turned-over bevelled plate, its faces would swap) reflected x ↦ −x and reversed
    rots, shifts, errors = kabsch_2d(b, correspondences(a, mirror=not shape.two_faces))
    c = int(np.flatnonzero(errors <= errors.min() + 1e-12)[0])
    err, rot2, shift2 = float(errors[c]), rots[c], shifts[c]
    flip, s = c >= k, c % k
    mirror = np.diag([-1.0, 1.0]) if flip else np.eye(2)
    lin = rot2 @ mirror                                   # the 2D map, det −1 when turned over
    rotation = np.zeros((3, 3))
    rotation[:2, :2] = lin
    rotation[2, 2] = -1.0 if flip else 1.0
    # z0 … z0 + h of the shape onto the element's: shifted, or turned over (z ↦ e0 + h + s0 − z)
    dz = el.z0 + shape.z0 + shape.height if flip else el.z0 - shape.z0
    shift = np.array([shift2[0], shift2[1], dz])
    motion = Motion(rotation, shift, err)
    if len(el.holes):                                     # every hole onto one of the same diameter
        h_src = np.asarray(shape.holes, dtype=float).reshape(-1, 3)
        h_dst = np.asarray(el.holes, dtype=float).reshape(-1, 3)
        moved = motion.apply(np.c_[h_src[:, :2], np.zeros(len(h_src))])[:, :2]
        d = np.linalg.norm(moved[:, None, :] - h_dst[None, :, :2], axis=2)
        d[np.abs(h_src[:, None, 2] - h_dst[None, :, 2]) > 1e-9] = np.inf
        err = max(err, float(d.min(axis=1).max()), float(d.min(axis=0).max()))
    if shape.two_faces:
        top = np.roll(shape.top_outline(), -s, axis=0)
        moved_top = top @ rot2.T + shift2
        err = max(err, float(np.linalg.norm(moved_top - el.top_outline(), axis=1).max()))
    return Motion(rotation, shift, err)


def frame_axes(el: Element) -> np.ndarray:
    """``(3, 3)`` the axes of ``el``'s frame as columns ``ex, ey, normal`` (frame → world)."""
    return np.column_stack([el.frame.ex, el.frame.ey, el.frame.normal])


@dataclass(frozen=True)
class Instance:
    """A part drawn as another's body moved: ``shape`` (the first part of its type) placed by ``motion`` in the
    part's own frame."""

    shape: Element
    motion: Motion

    def rotation(self, el: Element) -> np.ndarray:
        """``(3, 3)`` the world rotation that turns ``shape``'s body into ``el``'s: into ``shape``'s frame, the
        motion's rotation in ``el``'s frame, out of ``el``'s frame (proper: a plate turned over is a half turn)."""
        return frame_axes(el) @ self.motion.rotation @ frame_axes(self.shape).T

    def moved(self, el: Element) -> np.ndarray:
        """``(3,)`` where the origin of ``shape``'s frame goes (world mm): the motion's shift in ``el``'s frame."""
        return el.frame.origin + frame_axes(el) @ self.motion.shift

    def placement(self, el: Element) -> np.ndarray:
        """``(4, 4)`` the rigid motion of the world (mm) that puts ``shape``'s body where ``el``'s is:
        ``x ↦ Q (x − o) + m`` with ``Q`` :meth:`rotation`, ``o`` the origin of ``shape``'s frame, ``m``
        :meth:`moved`."""
        q = self.rotation(el)
        out = np.eye(4)
        out[:3, :3] = q
        out[:3, 3] = self.moved(el) - q @ self.shape.frame.origin
        return out


@dataclass(frozen=True)
class TypePlan:
    """Which parts share a type and which are drawn as their type's shape moved.

    ``keys``: ``part_id → (kind, key)`` of every part with a type key (:func:`type_key`); ``counts``: the parts
    per ``(kind, key)``; ``first``: ``(kind, key) → part_id`` of the part whose body is the type's shape (the
    first mappable part of the type, in the order given); ``moved``: ``part_id → Instance`` of every other part
    whose body is that shape moved within its tolerance (:func:`fit_motion`)."""

    keys: dict[str, tuple[str, str]]
    counts: dict[tuple[str, str], int]
    first: dict[tuple[str, str], str]
    moved: dict[str, Instance]

    def shared(self, kind_key: tuple[str, str]) -> bool:
        """Whether a type is written for ``kind_key``: two or more parts share it, or it is a panel type."""
        return self.counts.get(kind_key, 0) >= 2 or kind_key[0] == "panel"


def plan_types(els: list[Element], tolerance: float = MAP_TOLERANCE_MM,
               pane_tolerance: float | None = None) -> TypePlan:
    """The types of ``els`` and the parts drawn as their type's shape: a part other than a pane within ``tolerance``
    mm of the shape moved; a pane within ``pane_tolerance`` (the panel type tolerance: the glass is cut to the
    type's outline) when it is given, else within ``tolerance`` like any part."""
    keys: dict[str, tuple[str, str]] = {}
    counts: dict[tuple[str, str], int] = {}
    first: dict[tuple[str, str], str] = {}
    shapes: dict[tuple[str, str], Element] = {}
    moved: dict[str, Instance] = {}
    for el in els:
        key = type_key(el)
        if key is None:
            continue
        kk = (el.kind, key)
        keys[el.part_id] = kk
        counts[kk] = counts.get(kk, 0) + 1
        if not mappable(el):
            continue
        shape = shapes.setdefault(kk, el)
        if shape is el:
            first[kk] = el.part_id
            continue
        limit = pane_tolerance + 1e-6 if el.kind == "panel" and pane_tolerance is not None else tolerance
        motion = fit_motion(shape, el)
        if motion is not None and motion.error <= limit:
            moved[el.part_id] = Instance(shape, motion)
    return TypePlan(keys, counts, first, moved)


def instances(els: list[Element], tolerance: float = MAP_TOLERANCE_MM) -> dict[str, Instance]:
    """``part_id → Instance`` for every part whose body is the first of its type's (:func:`type_key`) moved within
    ``tolerance`` mm (:func:`fit_motion`); the first parts themselves and the parts that fit no shape are left
    out (they keep their own bodies)."""
    return plan_types(els, tolerance).moved
