"""``joint = "none"``: plain intersecting plates, nothing cut (for checking a structure, not for cutting)."""

from __future__ import annotations

from . import JointType, joint_type

NONE = joint_type(JointType("none", "plain intersecting plates, nothing cut", cuts_ends=False, segments=False,
                            planar_requirement=None))
