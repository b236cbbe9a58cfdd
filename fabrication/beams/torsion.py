"""Torsion as a fabrication tolerance: the offset of a node axis at the beam's bottom edge.

For an edge ``v_i v_j`` (unit direction ``ê``) with unit node axes ``a_i, a_j``, the plate of the edge lies in
the plane through the edge and one axis; followed for the beam depth ``D``, the other axis leaves that plane
by ``D·|det(ê, a_i, a_j)| / |ê × a_other|`` (:func:`ppfab.support.structure.torsion_offset`, the larger of
the two).  A torsion-free support structure has 0 (Def. 2.3); a build whose support exceeds
``[beams] max_torsion_mm`` on any edge stops here, before any plate is drawn, listing the edges.
"""

from __future__ import annotations

import numpy as np

from ppfab.errors import FabricationError
from ppfab.finding import Finding
from ppfab.support.structure import SupportStructure

from .. import contract
from .params import BeamParams


class TorsionError(FabricationError):
    """Edges of the support structure whose torsion at the bottom edge exceeds ``beams.max_torsion_mm``.

    ``offenders``: one :class:`~ppfab.finding.Finding` per edge (``torsion``, the edge label ``N0012-N0013``,
    its offset and the limit, mm), worst first; ``limit_mm``.
    """

    def __init__(self, message: str, offenders: list[Finding], limit_mm: float):
        self.offenders = offenders
        self.limit_mm = limit_mm
        super().__init__(message)


def edge_label(i: int, j: int) -> str:
    """``N0012-N0013``: an edge by the node ids of its ends."""
    return f"{contract.node_id(int(i))}-{contract.node_id(int(j))}"


def check_torsion(support: SupportStructure, params: BeamParams) -> np.ndarray:
    """``(E,)`` torsion offsets (mm at beam depth); raises :class:`TorsionError` above ``max_torsion_mm``."""
    edges = support.edges
    if not len(edges):
        return np.zeros(0)
    off = support.torsion_offset(params.depth)
    bad = np.flatnonzero(~(off <= params.max_torsion_mm))
    if not len(bad):
        return off
    bad = bad[np.argsort(-off[bad])]
    offenders = [Finding("torsion", "", edge_label(*edges[k]), float(off[k]), params.max_torsion_mm,
                         f"edge {edge_label(*edges[k])} is twisted {off[k]:.3g} mm at beam depth")
                 for k in bad]
    shown = ", ".join(f"{o.element} {o.value:.3g} mm" for o in offenders[:8])
    more = f" (and {len(bad) - 8} more)" if len(bad) > 8 else ""
    raise TorsionError(f"{len(bad)} edge(s) of the '{support.kind}' support structure exceed beams.max_torsion_mm "
                       f"= {params.max_torsion_mm:g} mm at beam depth {params.depth:g} mm: {shown}{more}; "
                       f"{_advice(support, params, edges[bad])}", offenders, params.max_torsion_mm)


def _advice(support: SupportStructure, params: BeamParams, bad_edges: np.ndarray) -> str:
    """What the designer can do, from the cause of the worst edge."""
    mesh = support.mesh
    i, j = (int(x) for x in bad_edges[0])
    misfit = support.misfit
    if misfit is not None and max(misfit[i], misfit[j]) * params.depth > params.max_torsion_mm:
        v = i if misfit[i] >= misfit[j] else j
        ending = [k for k, p in enumerate(mesh.polylines)
                  if not p.closed and v in (int(p.vertices[0]), int(p.vertices[-1]))
                  and support.polyline_planar is not None and support.polyline_planar[k]]
        topo = mesh.topology
        where = "a singular vertex" if not topo.boundary_vertices[v] else "a corner of the boundary"
        rule = "singular" if not topo.boundary_vertices[v] else "boundary"
        return (f"at {contract.node_id(v)} ({where}) the planes of polylines {ending[:6]} do not share a line "
                f"(misfit {np.degrees(np.arcsin(min(1.0, float(misfit[v])))):.1f}°); leave some of them out of "
                f"the planar families with [support] exclude (their ids, or the rule '{rule}'), or raise "
                "beams.max_torsion_mm")
    if support.kind == "parallel" and not support.meta.get("exact", True):
        return ("the least-squares parallel mesh is a compromise because the faces are not planar enough for an "
                "exact one; make the faces planar first ([optimize], or `ppfab optimize --families none`), or "
                "use method 'pp' or 'p' on a PP or P mesh")
    if support.left_out:
        return ("the edges of the polylines left out of the planar families cannot all be torsion-free with "
                "the axes the other planes fix; change [support] exclude (`ppfab check --polylines` lists the "
                "polylines), or raise beams.max_torsion_mm")
    return "optimise the mesh for planar faces and planar polylines ([optimize]), or raise beams.max_torsion_mm"
