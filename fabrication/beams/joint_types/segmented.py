"""``joint = "segmented"`` (P meshes): one family runs through the nodes as continuous planar plates, the other
is cut into one-edge segments between the crossings, each in its own support plane, butting against the
continuous plates (their ends set back to clear them)."""

from __future__ import annotations

from . import JointType, joint_type

SEGMENTED = joint_type(JointType("segmented", "P: one family continuous, the other cut into segments between "
                                              "crossings", cuts_ends=True, segments=True,
                                 planar_requirement="the continuous family of segmented joints must be planar"))
