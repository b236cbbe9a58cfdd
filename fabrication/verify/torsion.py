"""Torsion of the support structure within tolerance, recomputed from mesh.obj and the axes of nodes.csv.

For an edge ``v_i v_j`` with unit direction ``ê`` and unit node axes ``a_i, a_j``, the end axes and the edge
are coplanar iff ``det[ê, a_i, a_j] = 0`` (Def. 2.3).  Followed for the beam depth ``h``, the axis at one end
leaves the plane of the edge and the other axis by ``h·|det[ê, a_i, a_j]| / |ê × a_other|``; the larger of
the two is the edge's torsion in mm.  It must stay within ``beams.max_torsion_mm`` (``beams.plane_tolerance``
when the design has no such key), and each node's ``torsion_mm`` in ``nodes.csv`` must be the largest over
its edges.
"""

from __future__ import annotations

import numpy as np

from . import Verification, check
from ._shapes import number, torsion_tolerance


@check("torsion")
def check_torsion(v: Verification) -> None:
    rows = v.nodes
    mesh = v.mesh
    if rows is None or mesh is None or len(rows) != len(mesh.vertices):
        return
    m = v.manifest
    rel = m.get("files", {}).get("nodes_csv", "nodes.csv")
    depth = float(m.get("fabrication", {}).get("beam_depth", 0.0))
    tol, key = torsion_tolerance(m)
    a = np.zeros((len(rows), 3))
    listed = np.zeros(len(rows))
    for r in rows:
        k = int(r["vertex"])
        if not 0 <= k < len(rows):
            return                                    # the nodes check reports it
        a[k] = [number(r[c]) for c in ("axis_x", "axis_y", "axis_z")]
        listed[k] = number(r.get("torsion_mm"), 0.0)
    f = mesh.faces
    e = np.unique(np.sort(np.stack([f.ravel(), np.roll(f, -1, axis=1).ravel()], axis=1), axis=1), axis=0)
    d = mesh.vertices[e[:, 1]] - mesh.vertices[e[:, 0]]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    ai, aj = a[e[:, 0]], a[e[:, 1]]
    det = np.abs(np.einsum("ij,ij->i", d, np.cross(ai, aj)))
    base = np.minimum(np.linalg.norm(np.cross(d, ai), axis=1), np.linalg.norm(np.cross(d, aj), axis=1))
    offset = depth * det / np.maximum(base, 1e-300)
    bad = np.flatnonzero(~(offset <= tol + 1e-9))
    for k in bad[np.argsort(-offset[bad])][:20]:
        i, j = (int(x) for x in e[k])
        v.error(rel, f"edge N{i:04d}-N{j:04d}", f"torsion {offset[k]:.3g} mm at beam depth {depth:g} mm "
                                                f"(> {key} {tol:g} mm)")
    if len(bad) > 20:
        v.error(rel, "torsion", f"… {len(bad)} edges beyond {key} {tol:g} mm in all")
    node = np.zeros(len(rows))
    for col in (0, 1):
        np.maximum.at(node, e[:, col], offset)
    off = np.abs(node - listed)
    for k in np.flatnonzero(off > 1e-5 + 1e-6 * node)[:20]:
        v.error(rel, f"N{int(k):04d}", f"torsion_mm {listed[k]:.6g} differs from the torsion of its edges "
                                       f"{node[k]:.6g} mm")
    v.checked.append("torsion")
