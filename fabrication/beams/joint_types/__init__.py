"""The table of joint types (``[beams] joint = …``): how plates meet at a node.

A joint type (:class:`JointType`) says whether ending plates are set back to clear the others
(``cuts_ends``), whether the non-continuous family is cut into segments between the crossings
(``segments``), what a polyline that cannot be one planar plate means for it (``planar_requirement``), and
what happens where two plates run through one node (``through``: e.g. the half-lap slots).  Each type is one
module of this package registering itself with :func:`joint_type`; adding a joint is one new file.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

from ppfab.registry import Registry

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np

    from ppfab.finding import Finding
    from ppfab.support.structure import SupportStructure

    from ..params import BeamParams
    from ..plates import BeamPlate, Slot


@dataclass(frozen=True)
class ThroughNode:
    """What a joint type makes of a node where plates run through: its ``kind``, the slot ``width`` (mm, or
    ``nan``), the crossing ``line`` (point, unit direction) and the slots cut into each plate."""

    kind: str
    width: float
    line: "tuple[np.ndarray, np.ndarray] | None"
    slots: "dict[str, list[Slot]]"
    defects: "list[Finding]"


ThroughHook = Callable[["list[BeamPlate]", "list[int]", int, "np.ndarray", "SupportStructure", "BeamParams"],
                       "ThroughNode | None"]


@dataclass(frozen=True)
class JointType:
    """One entry of :data:`JOINT_TYPES` (see the module docstring)."""

    name: str
    summary: str
    cuts_ends: bool
    segments: bool
    planar_requirement: str | None
    through: ThroughHook | None = None


_TABLE: Registry[JointType] = Registry("joint", "fabrication.beams.joint_types")
JOINT_TYPES: dict[str, JointType] = _TABLE.entries


def joint_type(jt: JointType) -> JointType:
    """Register a joint type under its name."""
    return _TABLE.add(jt.name, jt)


def get_joint_type(name: str, key: str = "beams.joint") -> JointType:
    """Look a joint type up by name; an unknown name lists the valid ones."""
    return _TABLE.get(name, key)
