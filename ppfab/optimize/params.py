"""Parameters of the P / PP / planar-quad optimisation (§3.3): the ``[optimize]`` table of a design file.

All weights act on a copy of the mesh scaled so that its mean edge length is 1
and centred at its centroid, so their meaning does not depend on the mesh's units.

Examples
--------
>>> from ppfab.schema import parse_params
>>> p = parse_params(OptimizeParams, {"families": "both", "max_iterations": 50}, "optimize")
>>> p.families, p.max_iterations, p.weight_fair
('both', 50, 0.01)
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import DesignError
from ..schema import param

FAMILIES = ("rows", "cols", "both", "none")


@dataclass(frozen=True)
class OptimizeParams:
    """What to make planar, the weights of the energies of §3.3, and when to stop."""

    families: str = param("rows", doc="polyline families to make planar: rows (family 0, P), cols (family 1, P), "
                                      "both (PP attempt) or none (planar faces only)", choices=FAMILIES)
    polylines: list[int] = param([], doc="indices into mesh.polylines that must also become planar "
                                         "(polylines with fewer than 3 vertices are skipped)", min=0)
    planar_faces: bool = param(True, doc="make the quads planar (energy E_f); false leaves faces free")
    weight_planarity: float = param(1.0, doc="λ_P: weight of E_P (vertices of a polyline in its support plane)",
                                    min=0.0)
    weight_faces: float = param(1.0, doc="λ_f: weight of E_f (vertices of a face in its plane)", min=0.0)
    weight_unit: float = param(1.0, doc="λ_1: weight of E_1 (unit normals)", exclusive_min=0.0)
    weight_fair: float = param(0.01, doc="λ_fair: weight of E_fair (second differences along polylines)", min=0.0)
    weight_close: float = param(0.01, doc="λ_close: weight of the closeness term to the input", min=0.0)
    fair_families: str = param("both", doc="polyline families that carry the fairness energy", choices=FAMILIES)
    fairness: str = param("auto", doc="E_fair on absolute second differences (the paper: smooths the mesh), "
                                      "relative to the input's (keeps its shape, smooths only the change), or "
                                      "auto: absolute when the input's max δ_f exceeds 1e-3 (far from planar "
                                      "quads), relative otherwise (a nearly finished design stays in place)",
                          choices=("auto", "absolute", "relative"))
    closeness: str = param("surface", doc="closeness to the input surface (distance to its tangent planes at "
                                          "the closest points, foot points updated each stage: vertices may "
                                          "slide along the surface), to the input vertices, or none",
                           choices=("surface", "vertices", "none"))
    slide: float = param(0.3, doc="with closeness = surface: weight, relative to weight_close, of the pull "
                                  "back to the input vertices (0 lets vertices slide freely along the surface)",
                         min=0.0)
    keep_conical: bool = param(False, doc="make the mesh conical, or keep it conical (§2.3.3, §4): adds E_conical "
                                          "(angle balance at interior valence-4 vertices) with weight "
                                          "weight_conical, and max conical residual <= target_conical to the "
                                          "targets")
    weight_conical: float = param(1.0, doc="λ_c: weight of E_conical (used with keep_conical)", exclusive_min=0.0)
    target_conical: float = param(1e-6, doc="with keep_conical: stop only when the conical residual "
                                            "max abs(α1 − α2 + α3 − α4) (rad) is at most this", exclusive_min=0.0)
    keep_circular: bool = param(False, doc="make the mesh circular (§2.3.3, Remark 2.1: the corners of every panel "
                                           "on a circle, a discrete principal net with vertex offsets): adds "
                                           "E_circular (opposite corner angles adding up to π) with weight "
                                           "weight_circular, and max circular residual <= target_circular to "
                                           "the targets; [support] method = \"circular\" builds its exact support")
    weight_circular: float = param(1.0, doc="λ_○: weight of E_circular (used with keep_circular)", exclusive_min=0.0)
    target_circular: float = param(1e-6, doc="with keep_circular: stop only when the circular residual "
                                              "max abs(α1 − α2 + α3 − α4) over the panels' corner angles (rad) "
                                              "is at most this", exclusive_min=0.0)
    orthogonal_nodes: bool = param(False, doc="support planes at right angles in every node (§2.3.4): where a "
                                              "planar row and a planar column cross, their planes orthogonal; adds "
                                              "E_nodes with weight weight_nodes and max |cos| of the angle between "
                                              "them <= target_nodes to the targets; needs families = both, and "
                                              "solves the support normals exactly (plane_solver exact)")
    weight_nodes: float = param(1.0, doc="λ_⊥n: weight of E_nodes (used with orthogonal_nodes)", exclusive_min=0.0)
    target_nodes: float = param(1e-6, doc="with orthogonal_nodes: stop only when max |cos| of the angle between the "
                                          "row and column planes at a node is at most this", exclusive_min=0.0)
    weight_orthogonal: float = param(0.0, doc="λ_⊥: weight of E_orth on the cosines of the face corner angles "
                                              "(near-rectangular panels; 0 switches it off)", min=0.0)
    orthogonality: str = param("keep", doc="E_orth: keep (one-sided: no corner moves further from 90° than in "
                                           "the input; does not bias a solution that keeps them) or right "
                                           "(pull every corner towards 90°, fading with the regularisation)",
                               choices=("keep", "right"))
    weight_axes: float = param(0.0, doc="λ_axes: weight of E_axes, support planes at right angles to the panels "
                                        "along them (§2.3.2), which brings the node axes of a PP mesh to the "
                                        "surface normals; fades with the regularisation (0 switches it off)",
                               min=0.0)
    crease_limit: float = param(15.0, doc="degrees by which an edge's dihedral angle may exceed the input's "
                                          "largest dihedral angle; a step that makes an edge crease beyond "
                                          "(input max + crease_limit) is refused, and a result with such an "
                                          "edge never counts as targets met", exclusive_min=0.0, max=180.0)
    weight_shape: float = param(1.0, doc="weight of the one-sided barrier that keeps every face corner at "
                                         "least shape_ratio of its input area (0 switches it off)", min=0.0)
    shape_ratio: float = param(0.25, doc="fraction of its input area a face corner triangle may shrink to "
                                         "before the shape barrier acts", min=0.0, exclusive_max=1.0)
    fix_boundary: bool = param(False, doc="keep boundary vertices where they are")
    fixed_vertices: list[int] = param([], doc="indices of vertices that must not move", min=0)
    anchors: list[list[float]] = param([], doc="vertices held at new positions, each [vertex, x, y, z] (mesh "
                                                "units; the studio's live anchors): the optimisation starts with "
                                                "them moved there and keeps them fixed")
    plane_solver: str = param("auto", doc="support normals in the linear system (exact: best steps, but a "
                                          "normal couples all vertices of its polyline, so the factorisation "
                                          "grows with polyline length²), eliminated by variable projection "
                                          "(projected: as sparse as the mesh), or auto (exact while "
                                          "Σ (polyline length)² <= 1.5e5)", choices=("auto", "exact", "projected"))
    linear_solver: str = param("auto", doc="sparse Cholesky of the damped normal equations: MKL PARDISO (pip "
                                           "install ppfab[fast]; 1.5-1.8x faster per factorisation), SuperLU with "
                                           "ppfab's nested-dissection ordering, or auto (PARDISO when installed)",
                               choices=("auto", "pardiso", "superlu"))
    target_delta_f: float = param(1e-6, doc="stop when max δ_f (face planarity, §3.3) is at most this",
                                  exclusive_min=0.0)
    target_delta_p: float = param(1e-6, doc="stop when max δ_P of the selected polylines is at most this",
                                  exclusive_min=0.0)
    max_conjugacy_defect: float = param(0.4, doc="ppfab build refuses, before optimising, a net whose "
                                                 "conjugacy defect (ppfab.metrics.conjugacy_defect: twist over "
                                                 "normal curvature, about 0 for a conjugate net) exceeds this: "
                                                 "such nets reach planar quads only by leaving the surface or not "
                                                 "at all; raise it to try anyway", min=0.0)
    max_iterations: int = param(500, doc="maximum number of Levenberg–Marquardt iterations "
                                         "(linear solves, rejected steps included)", min=1, max=100000)
    reg_decay: float = param(0.1, doc="factor applied to the weights of the soft goals (fairness, closeness, "
                                      "right angles, axes) when progress stalls (1 keeps the paper's energy "
                                      "fixed)", exclusive_min=0.0, max=1.0)
    reg_min: float = param(1e-6, doc="smallest factor the regularisation weights are reduced to",
                           exclusive_min=0.0, max=1.0)
    stall: float = param(0.05, doc="a stage ends when an accepted step lowers the energy by less than "
                                   "this fraction", exclusive_min=0.0, exclusive_max=1.0)
    min_edge_ratio: float = param(0.2, doc="reject a step that shortens an edge below this fraction of its "
                                           "input length (collapse guard)", exclusive_min=0.0, exclusive_max=1.0)

    def __post_init__(self):
        for k, a in enumerate(self.anchors):
            if len(a) != 4 or float(a[0]) != int(a[0]) or a[0] < 0 or not all(abs(float(x)) < 1e300 for x in a):
                raise DesignError(f"anchors[{k}]", f"{a} is not [vertex, x, y, z]: give a vertex index and a "
                                                   "finite point in mesh units")
        if self.orthogonal_nodes and self.families != "both":
            raise DesignError("orthogonal_nodes", f"orthogonal nodes are right angles between a planar row's and a "
                                                  f"planar column's planes where they cross: set families = "
                                                  f"\"both\" (is {self.families!r})")
        if self.families == "none" and not self.polylines and not self.planar_faces:
            raise DesignError("families", "nothing to optimise: families = 'none', no polylines and "
                                          "planar_faces = false")
