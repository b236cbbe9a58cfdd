"""The studio's handles drawn in the 3D view: a transform gizmo and a label per handle, a translucent square for a
plane handle, the spheres of ``conical_spheres``; moved in place when only their positions change."""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from .scene import plane_square


def draw_handles(scene: Any, model: Any, wanted: list, size: float, callback: Callable[[str], Any]) -> dict[str, Any]:
    """Draw the handles ``wanted`` (:meth:`fabrication.studio.model.StudioModel.handles`) at gizmo ``size`` (m) in
    ``scene`` (viser's scene API), each gizmo calling ``callback(key)``'s function when dragged; returns the drawn
    items by name (``<key>``, ``<key>-label``, ``<key>-plane``, ``sphere<k>``)."""
    from .handles import placement

    drawn: dict[str, Any] = {}
    for h in wanted:
        g = scene.add_transform_controls(f"/handles/{h.key}", scale=size, position=tuple(h.position),
                                         disable_rotations=not h.rotatable, disable_sliders=True)
        g.on_update(callback(h.key))
        drawn[h.key] = g
        drawn[f"{h.key}-label"] = scene.add_label(f"/handles/{h.key}-label", h.label, position=tuple(h.position))
        if h.normal is not None:                 # a plane handle: its plane, translucent, in its colour
            verts, faces = plane_square(np.asarray(h.position, float), h.normal, 0.6 * size)
            drawn[f"{h.key}-plane"] = scene.add_mesh_simple(
                f"/handles/{h.key}-plane", verts, faces, color=h.color, opacity=0.25, side="double")
    if model.method == "conical_spheres":
        s, R, t = placement(model.geometry)
        for k, sph in enumerate(model.params.get("spheres", [])):
            c = (s * R @ np.asarray(sph[:3], dtype=float) + t) / 1000.0
            drawn[f"sphere{k}"] = scene.add_icosphere(f"/handles/sphere{k}", radius=abs(float(sph[3])) * s / 1000.0,
                                                      color=(200, 60, 160), opacity=0.12, position=tuple(c),
                                                      subdivisions=2)
    return drawn


def move_handles(scene: Any, method: str | None, drawn: dict[str, Any], wanted: list, size: float,
                 drawn_size: float | None) -> bool:
    """Move the ``drawn`` handles to ``wanted`` when they are the same handles at the same size (a position
    message each, instead of removing and creating every gizmo); ``False`` when they must be drawn anew."""
    keys = [h.key for h in wanted]
    if method == "conical_spheres" or not keys or drawn_size != size or \
            set(drawn) != {k for h in wanted for k in (h.key, f"{h.key}-label")} | {
                f"{h.key}-plane" for h in wanted if h.normal is not None}:
        return False
    for h in wanted:
        gizmo = drawn[h.key]
        if np.array_equal(np.asarray(gizmo.position, dtype=float), np.asarray(h.position, dtype=float)):
            continue                             # not moved: no message
        gizmo.position = tuple(h.position)
        drawn[f"{h.key}-label"].position = tuple(h.position)
        if h.normal is not None:
            drawn[f"{h.key}-plane"].remove()
            verts, faces = plane_square(np.asarray(h.position, float), h.normal, 0.6 * size)
            drawn[f"{h.key}-plane"] = scene.add_mesh_simple(
                f"/handles/{h.key}-plane", verts, faces, color=h.color, opacity=0.25, side="double")
    return True
