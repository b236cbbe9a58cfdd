"""``model.glb``: the whole structure as one binary glTF 2.0 file for viewing (any glTF viewer, most browsers'
3D viewers, Blender, Windows 3D Viewer).

One node per part, named by its part id, holding the closed triangle mesh of its prism
(:meth:`fabrication.writers._elements.Element.prism_mesh`) with a material per layer: transparent glass and one
colour per beam family (:data:`fabrication.contract.COLOURS`).  A part whose prism is that of the first part of its
type moved (:func:`fabrication.writers._instances.instances`: congruent within 1e-5 mm — the half-turn pairs of a
symmetric roof, strips of one length, retention parts of one size) is a node that places that part's mesh by
its transform (glTF mesh instancing): the mesh is stored once.  glTF's conventions hold: metres, +Y up, so a
point ``(x, y, z)`` mm of the other files is ``(x, z, −y) / 1000`` here (a rotation, so the solids keep their
orientation).  trimesh writes the file; it holds no time stamp.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..contract import COLOURS, GLB_FILE
from . import Files, writer
from ._elements import Element, elements
from ._instances import Instance, frame_axes, instances

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord

MM_TO_GLTF = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]) * 1e-3
"""``(3, 3)``: ppfab's mm, z up → glTF's metres, y up (row vectors: ``p_gltf = p_mm @ MM_TO_GLTF.T``)."""


def glb_bytes(build: "BuildRecord", files: Files) -> bytes:
    """The GLB of a build's panels and beam plates."""
    import trimesh
    from trimesh.visual.material import PBRMaterial

    materials = {}
    for layer, (r, g, b, a) in COLOURS.items():
        materials[layer] = PBRMaterial(name=layer, baseColorFactor=[r, g, b, a], metallicFactor=0.0 if
                                       layer == "glass" else 0.6, roughnessFactor=0.1 if layer == "glass" else 0.5,
                                       alphaMode="BLEND" if a < 1.0 else "OPAQUE", doubleSided=False)
    scene = trimesh.Scene()
    els = elements(build)
    moved = instances(els)
    centres: dict[str, np.ndarray] = {}
    for el in els:
        inst = moved.get(el.part_id)
        if inst is not None:                 # the mesh of its type's first part, placed by the node's transform
            shape = inst.shape
            scene.graph.update(frame_to=el.part_id, frame_from=scene.graph.base_frame, geometry=shape.part_id,
                               matrix=_instance_transform(inst, el, centres[shape.part_id]))
            continue
        try:
            v, f = el.prism_mesh()
        except Exception as exc:            # a degenerate outline: name the part and what is wrong with it
            from ._failures import part_failure

            raise part_failure(el.part_id, el.outline, el.height, "the glTF mesh of its prism", exc) from None
        # glTF stores float32: vertices relative to the part's centre, placed by its node's translation, keep
        # a 12 mm plate 30 m from the origin exact to well below a micrometre (absolute coordinates would not)
        c = centres[el.part_id] = v.mean(axis=0)
        mesh = trimesh.Trimesh((v - c) @ MM_TO_GLTF.T, f, process=False)
        mesh.visual = trimesh.visual.TextureVisuals(material=materials[el.layer])
        place = np.eye(4)
        place[:3, 3] = MM_TO_GLTF @ c
        scene.add_geometry(mesh, node_name=el.part_id, geom_name=el.part_id, transform=place)
    return bytes(scene.export(file_type="glb"))


def _instance_transform(inst: Instance, el: Element, centre: np.ndarray) -> np.ndarray:
    """``(4, 4)`` the glTF node transform that puts the stored mesh of ``inst.shape`` (glTF coordinates about its
    centre ``centre``, mm) where ``el`` is: back to mm, the world motion of :meth:`Instance.placement` (the
    centre moved to ``Q (c − o) + A t + p``: ``Q`` :meth:`Instance.rotation`, ``o`` the shape's frame origin,
    ``A``, ``p`` the axes and origin of ``el``'s frame, ``t`` the motion's shift), into glTF's metres, y up.  Its
    linear part is a rotation (the two unit conversions cancel)."""
    q = inst.rotation(el)
    to_mm = np.linalg.inv(MM_TO_GLTF)
    out = np.eye(4)
    out[:3, :3] = MM_TO_GLTF @ q @ to_mm
    out[:3, 3] = MM_TO_GLTF @ (q @ (centre - inst.shape.frame.origin) + frame_axes(el) @ inst.motion.shift
                               + el.frame.origin)
    return out


@writer("glb", order=70, declare=lambda build: {"glb": GLB_FILE}, enabled=lambda design: design.output.glb)
def write_glb(build: "BuildRecord", out: Path, files: Files) -> str:
    data = glb_bytes(build, files)
    (out / GLB_FILE).write_bytes(data)
    return f"{GLB_FILE}: {len(data) / 1e6:.1f} MB"
