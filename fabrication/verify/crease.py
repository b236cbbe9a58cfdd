"""Creases of mesh.obj within ``panels.max_crease_deg``, recomputed from the file.

Each face's normal here is the normal of its least-squares plane (the right singular vector of the centred
corners ``(4, 3)`` with the smallest singular value), turned to the side its corner order turns about (the
sign of the vector area ``½ Σ c_k × c_{k+1}``) — not the diagonal cross product the build measures with.  At
an edge shared by faces ``f, g`` the dihedral angle is ``arccos(n_f · n_g)`` (``n_g`` negated where the two
faces run the edge the same way, i.e. are oriented inconsistently).  Every angle must be within the
manifest's ``fabrication.max_crease_deg`` (the design's ``panels.max_crease_deg``; builds written before the
key existed are not checked against a limit), and the manifest's ``quality.crease_max`` must be the largest.
"""

from __future__ import annotations

import numpy as np

from . import Verification, check

MARGIN_DEG = 0.05
"""Allowance for the two normals' difference on panels that are planar only within their tolerance (1 mm
over a 1 m panel turns a normal by about 0.06° at most; the typical difference is far smaller)."""


def edge_dihedral_angles(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Interior edges ``(E, 2)`` (vertex pairs, ``a < b``) and their dihedral angles ``(E,)`` in degrees."""
    p = np.asarray(vertices, dtype=float)[faces]                                   # (F, 4, 3)
    centred = p - p.mean(axis=1, keepdims=True)
    normal = np.linalg.svd(centred)[2][:, -1, :]                                   # (F, 3) least-squares normal
    area = 0.5 * np.cross(p, np.roll(p, -1, axis=1)).sum(axis=1)                   # (F, 3) vector area
    normal *= np.where(np.einsum("ij,ij->i", normal, area) < 0, -1.0, 1.0)[:, None]
    a = faces.reshape(-1)
    b = np.roll(faces, -1, axis=1).reshape(-1)
    face = np.repeat(np.arange(len(faces)), faces.shape[1])
    key = np.minimum(a, b) * (int(faces.max()) + 1) + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    key_s, face_s, fwd_s = key[order], face[order], (a < b)[order]
    pair = np.flatnonzero(key_s[1:] == key_s[:-1])
    f, g = face_s[pair], face_s[pair + 1]
    sign = np.where(fwd_s[pair] == fwd_s[pair + 1], -1.0, 1.0)
    cos = np.clip(np.einsum("ij,ij->i", normal[f], normal[g]) * sign, -1.0, 1.0)
    edges = np.stack([np.minimum(a, b)[order][pair], np.maximum(a, b)[order][pair]], axis=1)
    return edges, np.degrees(np.arccos(cos))


@check("crease")
def check_crease(v: Verification) -> None:
    mesh = v.mesh
    if mesh is None:
        return
    faces = np.asarray(mesh.faces)
    if faces.ndim != 2 or faces.shape[1] != 4 or not len(faces):
        return
    m = v.manifest
    rel = m.get("mesh", {}).get("path", "mesh.obj")
    edges, angle = edge_dihedral_angles(np.asarray(mesh.vertices), faces)
    largest = float(angle.max()) if len(angle) else 0.0
    limit = m.get("fabrication", {}).get("max_crease_deg")
    if limit is not None:
        bad = np.flatnonzero(angle > float(limit) + MARGIN_DEG)
        for k in bad[np.argsort(-angle[bad])][:20]:
            i, j = (int(x) for x in edges[k])
            v.error(rel, f"edge N{i:04d}-N{j:04d}", f"dihedral angle {angle[k]:.2f}° between its panels "
                                                    f"(> panels.max_crease_deg {float(limit):g}°)")
        if len(bad) > 20:
            v.error(rel, "crease", f"… {len(bad)} edges beyond panels.max_crease_deg {float(limit):g}° in all")
    listed = m.get("quality", {}).get("crease_max")
    if listed is not None and abs(float(listed) - largest) > MARGIN_DEG:
        v.error("manifest.json", "quality.crease_max", f"{float(listed):.3f}° but the largest dihedral angle of "
                                                        f"{rel} is {largest:.3f}°")
    v.checked.append("crease")
