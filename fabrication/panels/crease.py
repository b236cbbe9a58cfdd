"""The crease gate: the largest dihedral angle between neighbouring panels (``[panels] max_crease_deg``).

At an interior edge with faces ``f, g`` and oriented unit normals ``n_f, n_g`` (the normalised cross product
of the face diagonals, :func:`ppfab.metrics.mesh_dihedral_angles`) the dihedral angle is
``θ_e = atan2(‖n_f × n_g‖, n_f · n_g)`` in degrees: 0° where the panels are coplanar, 90° a right-angled
ridge.  A joint between two panes, its gasket or silicone and the beam plate below take a limited fold; a
mesh with an edge beyond the limit (a fin or a cusp an optimisation made) stops the build before anything
is written, listing the edges by their nodes and panels with the measured angles.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ppfab.errors import FabricationError
from ppfab.finding import Finding
from ppfab.mesh import QuadGrid, QuadMesh, as_quadmesh
from ppfab.metrics import mesh_dihedral_angles

from .. import contract


class CreaseError(FabricationError):
    """Edges whose dihedral angle exceeds ``panels.max_crease_deg``.

    ``offenders``: one :class:`~ppfab.finding.Finding` per edge (``crease``, the label ``N0012-N0013 (P-U03-V04 /
    P-U03-V05)``, its dihedral angle and the limit, degrees), worst first; ``limit_deg``.
    """

    def __init__(self, offenders: list[Finding], limit_deg: float):
        self.offenders = offenders
        self.limit_deg = limit_deg
        shown = ", ".join(f"{o.element} {o.value:.1f}°" for o in offenders[:8])
        more = f" (and {len(offenders) - 8} more)" if len(offenders) > 8 else ""
        super().__init__(f"{len(offenders)} edge(s) fold the glass by more than panels.max_crease_deg = "
                         f"{limit_deg:g}° (dihedral angle between neighbouring panels): {shown}{more}; smooth the "
                         "mesh there (in [optimize] a higher weight_fair or a lower crease_limit), or raise panels.max_crease_deg if the joints take that fold")


def check_creases(mesh: QuadMesh | QuadGrid, limit_deg: float, part_ids: Sequence[str] | None = None) -> np.ndarray:
    """``(E,)`` dihedral angles (degrees, NaN on the boundary) at ``mesh.edges``; raises :class:`CreaseError`
    naming every edge above ``limit_deg``.

    ``part_ids[f]``: the panel id of face ``f`` of the mesh's face order (the output OBJ), used in the
    message; omitted, faces are named by index.
    """
    qm = as_quadmesh(mesh)
    angles = mesh_dihedral_angles(qm)
    with np.errstate(invalid="ignore"):
        bad = np.flatnonzero(np.isfinite(angles) & (angles > limit_deg))
    if not len(bad):
        return angles
    bad = bad[np.argsort(-angles[bad], kind="stable")]
    edges, edge_faces = qm.edges, qm.topology.edge_faces

    def name(f: int) -> str:
        return part_ids[f] if part_ids is not None else f"face {f}"

    labels = [f"{contract.node_id(int(edges[k, 0]))}-{contract.node_id(int(edges[k, 1]))} "
              f"({name(int(edge_faces[k, 0]))} / {name(int(edge_faces[k, 1]))})" for k in bad]
    offenders = [Finding("crease", "", label, float(angles[k]), limit_deg,
                         f"{label} folds the glass by {angles[k]:.1f}°") for label, k in zip(labels, bad)]
    raise CreaseError(offenders, limit_deg)


def part_ids_by_face(panels: Sequence) -> list[str]:
    """``[part id of face f]`` in the output OBJ's face order, from the panels' ``face`` and ``part_id``."""
    out = [""] * len(panels)
    for p in panels:
        out[p.face] = p.part_id
    return out
