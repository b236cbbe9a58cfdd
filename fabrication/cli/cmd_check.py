"""``ppfab check MESH`` — print the quality metrics of a mesh file and test them against a tolerance.

A mesh file larger than a build accepts (``geometry.max_vertices``, by its size and by its vertex count, both
known before it is parsed) is refused unless ``--allow-large`` is given; above
:data:`ppfab.io.meshfile.MAX_MESH_BYTES` it is refused in any case."""

from __future__ import annotations

import argparse
import json

NAME = "check"
HELP = "print quality metrics (δ_f, δ_P of rows and columns, deviation, conical residual, folds) of a mesh"
ORDER = 20


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("mesh", help="quad mesh file (.obj or .off)")
    p.add_argument("--tol", type=float, default=None,
                   help="fail (exit 1) when max δ_f or max δ_P of a planar family exceeds this")
    p.add_argument("--families", choices=["rows", "cols", "both", "none"], default="both",
                   help="which polyline families --tol applies to (default both)")
    p.add_argument("--polylines", action="store_true",
                   help="list every polyline (id, family, size, δ_P, tilt) and whether it can be a planar beam, "
                        "with the reason when not (the ids [support] exclude and [beams] segment take)")
    p.add_argument("--json", action="store_true", help="print the metrics as JSON")
    p.add_argument("--allow-large", action="store_true",
                   help="read meshes above the default geometry.max_vertices (250000 vertices)")


def run(args: argparse.Namespace) -> int:
    from ppfab.geometry import GeometrySpec, check_file_size, check_size
    from ppfab.io import load_mesh
    from ppfab.metrics import quality
    from ppfab.support.report import polyline_report, tangent_polylines

    limit = GeometrySpec(mesh=args.mesh).max_vertices      # what a build accepts without --allow-large
    check_file_size(args.mesh, limit, args.allow_large)
    mesh = load_mesh(args.mesh, None if args.allow_large else lambda n: check_size(n, limit, False))
    q = quality(mesh)
    tangent = tangent_polylines(mesh)
    records = polyline_report(mesh) if args.polylines else None
    from ppfab.metrics import conjugacy_defect
    from ppfab.optimize.params import OptimizeParams

    defect = conjugacy_defect(mesh)
    limit_defect = OptimizeParams().max_conjugacy_defect
    fams = [p.family for p in (mesh.to_quadmesh() if hasattr(mesh, "to_quadmesh") else mesh).polylines]
    across = {"rows": sum(1 for k in tangent if fams[k] == 0), "cols": sum(1 for k in tangent if fams[k] == 1)}
    if args.json:
        doc = q.as_dict()
        doc["polylines_tangent"] = tangent
        doc["polylines_tangent_by_family"] = across
        doc["conjugacy_defect"] = defect
        doc["optimisable"] = bool(defect <= limit_defect)
        if records is not None:
            doc["polylines"] = [r.as_dict() for r in records]
            doc["polylines_left_out"] = [r.id for r in records if not r.planar_beam and r.vertices >= 3]
        print(json.dumps(doc, indent=2))
    else:
        print(f"{args.mesh}")
        print(q.table())
        print(f"polylines that cannot be planar beams (plane > 30° from the normal): {len(tangent)}"
              + (f" — ids {_ids(tangent)}" if tangent else "")
              + ("" if records is not None else " (--polylines: every polyline, the full rule and the reasons)"))
        print(f"  of them rows {across['rows']}, cols {across['cols']}")
        print(f"conjugacy defect {defect:.2f} (twist over normal curvature; a conjugate net has about 0): "
              + (f"close enough to conjugate (≤ {limit_defect:g}) for planar quads near the surface"
                 if defect <= limit_defect else
                 f"far from a conjugate net (> {limit_defect:g}): ppfab build refuses to optimise it; remesh along "
                 "conjugate curves (e.g. principal curvature lines) or raise [optimize] max_conjugacy_defect"))
        if records is not None:
            _print_polylines(records)
    if args.tol is None:
        return 0
    worst = {"delta_f": q.delta_f_max}
    if args.families in ("rows", "both"):
        worst["delta_P rows"] = q.delta_p_rows_max
    if args.families in ("cols", "both"):
        worst["delta_P cols"] = q.delta_p_cols_max
    failed = {k: v for k, v in worst.items() if v > args.tol}
    if failed:
        msg = ", ".join(f"{k} {v:.3e}" for k, v in failed.items())
        print(f"ppfab: check failed: {msg} > tol {args.tol:g}")
        return 1
    return 0


def _ids(ids: list[int], limit: int = 30) -> str:
    return ", ".join(map(str, ids[:limit])) + (f" … ({len(ids) - limit} more)" if len(ids) > limit else "")


def _print_polylines(records: list) -> None:
    """The table of ``--polylines``: one line per polyline."""
    left = [r.id for r in records if not r.planar_beam and r.vertices >= 3]
    print(f"polylines left out of the planar families by [support] exclude = ['auto']: {len(left)}"
          + (f" — ids {_ids(left)}" if left else ""))
    print(f"{'id':>5} {'family':6} {'verts':>5} {'closed':6} {'δ_P':>9} {'tilt°':>6}  planar beam")
    for r in records:
        dp = "" if r.delta_p is None else f"{r.delta_p:.2e}"
        tilt = "" if r.tilt_deg is None else f"{r.tilt_deg:.1f}"
        fam = ("rows", "cols")[r.family] + ("*" if r.straight else "")
        state = "yes" if r.planar_beam else f"no: {r.reason}"
        print(f"{r.id:>5} {fam:6} {r.vertices:>5} {'yes' if r.closed else 'no':6} {dp:>9} {tilt:>6}  {state}")
