"""What a designer can do when a mesh file cannot be fabricated as it is: advice appended to a refusal.

A mesh a designer brings is seldom a P or PP mesh yet.  When its panels are not planar within the tolerance,
:func:`planarity_advice` says which step is missing, from the design and the measured metrics:

* a mesh file without an ``[optimize]`` section: add one — with the families the beams need (both for
  half-lap joints, the continuous family for segmented ones); a family whose polylines are already planar
  (max δ_P ≤ 1e-6) is named, and only the other family needs optimising;
* an ``[optimize]`` section that did not meet its targets: its own message (how it stopped), and that the
  net may need other polylines (a net far from a conjugate net has no nearby planar-quad mesh).

:func:`refuse_far_from_conjugate` says so before the optimiser runs, in a fraction of a second, where
:func:`ppfab.metrics.conjugacy_defect` of the input exceeds ``[optimize] max_conjugacy_defect``.  Measured on
the real meshes of the test set (``docs/optimisation.md``): nets above 0.4 — pillow (geodesic, 0.58), wein99
(S-net, 0.42), conical1_diagKite (0.64) — missed their targets after 500 iterations (pillow: 17 minutes), and
the hypar grid (0.98) met them only by moving the surface 23 % of its size; below 0.2 every net met them.
"""

from __future__ import annotations

from ppfab.metrics import Quality
from ppfab.topology import FAMILY_NAMES

from ..design import Design

PLANAR = 1e-6
"""δ_P below which a family counts as already planar."""


def needed_families(design: Design) -> tuple[str, ...]:
    """The families the design's beams need planar: both for half-lap joints or PP support, the continuous
    family for segmented joints (rows when not given)."""
    if design.beams.joint == "segmented" or design.support.method == "p":
        fam = design.beams.continuous if design.beams.continuous != "auto" else design.support.family
        return (fam,)
    return FAMILY_NAMES


def planarity_advice(design: Design, quality: Quality, optimize_result: object = None) -> str:
    """One clause for a panel-planarity refusal of a mesh file (``""`` for a construction)."""
    if design.geometry.mesh is None:
        return ""
    need = needed_families(design)
    dp = {"rows": quality.delta_p_rows_max, "cols": quality.delta_p_cols_max}
    planar = [f for f in FAMILY_NAMES if dp[f] <= PLANAR]
    todo = [f for f in need if f not in planar]
    if design.optimize is None:
        if not todo:
            return (f"the mesh's faces are not planar (max δ_f {quality.delta_f_max:.1e}) although its "
                    f"{' and '.join(need)} are (max δ_P {max(dp[f] for f in need):.1e}): add an [optimize] section "
                    f"with families = \"{'both' if len(need) == 2 else need[0]}\" to make the faces planar and keep "
                    "them so")
        if planar and len(need) == 2:
            done = planar[0]
            return (f"the {done} are already planar (max δ_P {dp[done]:.1e}) but the {todo[0]} are not "
                    f"(max δ_P {dp[todo[0]]:.1e}) and the faces are not (max δ_f {quality.delta_f_max:.1e}): add "
                    f"an [optimize] section with families = \"{todo[0]}\" and polylines = the {done}' ids (`ppfab "
                    "check --polylines`) to optimise the other family only, or families = \"both\"")
        return (f"the mesh file is not a {'PP' if len(need) == 2 else 'P'} mesh yet (max δ_f "
                f"{quality.delta_f_max:.1e}, max δ_P rows {dp['rows']:.1e} / cols {dp['cols']:.1e}): add an "
                f"[optimize] section with families = \"{'both' if len(need) == 2 else need[0]}\" (or run "
                "`ppfab optimize` first)")
    met = getattr(optimize_result, "targets_met", None)
    if met is False:
        msg = str(getattr(optimize_result, "message", "")).rstrip(".")
        return (f"the [optimize] section did not meet its targets ({msg}); a net far from a conjugate net has no "
                "planar-quad mesh nearby: remesh along conjugate curves (e.g. the principal directions), or "
                "relax panels.planarity_tolerance")
    return ""


def refuse_far_from_conjugate(defect: float, limit: float) -> None:
    """Refuse, before the optimiser, a net whose conjugacy defect ``defect`` exceeds ``limit``
    (:class:`~ppfab.errors.DesignError` on ``optimize.max_conjugacy_defect``, one line)."""
    from ppfab.errors import DesignError

    if defect > limit:
        raise DesignError("optimize.max_conjugacy_defect", (
            f"the mesh's net is far from a conjugate net (defect {defect:.2f}; a conjugate net has about 0, the "
            f"limit is {limit:g}): planar quads with planar polylines exist near it only far from the surface, so "
            "optimising would run long and miss its targets or move the surface by tens of per cent. Remesh the "
            "surface along conjugate curves (ppfab remesh MESH -o NET.obj --search-planes: planar sections and "
            "their conjugate curves; --net principal | conjugate) and build that mesh, or raise "
            "[optimize] max_conjugacy_defect to try anyway"))
