"""``ppfab optimize IN.obj -o OUT.obj`` — make faces and polylines planar (P / PP, paper §3.3)."""

from __future__ import annotations

import argparse
import json
from dataclasses import asdict
import sys
from pathlib import Path

NAME = "optimize"
HELP = "optimise a quad mesh for planar faces and planar polylines (P: rows or cols, PP: both)"
ORDER = 30

EPILOG = """exit status: 0 targets met, 1 mesh written but targets not met, 2 bad input.
Any field of the [optimize] table can be given with --set KEY=VALUE (e.g. --set weight_fair=0.1)."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.epilog = EPILOG
    p.add_argument("mesh", help="input quad mesh (.obj or .off)")
    p.add_argument("-o", "--out", required=True, help="output mesh (.obj or .off), same vertex and face order")
    p.add_argument("--force", action="store_true",
                   help="replace an existing output file, if ppfab wrote it and it is unchanged (never an input)")
    p.add_argument("--families", choices=["rows", "cols", "both", "none"], default=None,
                   help="polyline families to make planar (default rows; none = planar faces only)")
    p.add_argument("--polylines", default=None,
                   help="comma-separated indices (in QuadMesh.polylines order: family 0, then 1) of further "
                        "polylines to make planar")
    p.add_argument("--fix-boundary", action="store_true", help="keep boundary vertices in place")
    p.add_argument("--keep-conical", action="store_true",
                   help="make or keep the mesh conical (max conical residual <= target_conical, 1e-6 rad)")
    p.add_argument("--keep-circular", action="store_true",
                   help="make the mesh circular: every panel's corners on a circle (max circular residual <= "
                        "target_circular, 1e-6 rad)")
    p.add_argument("--orthogonal-nodes", action="store_true",
                   help="support planes at right angles where a planar row and a planar column cross (§2.3.4; "
                        "needs --families both)")
    p.add_argument("--fixed", default=None, help="comma-separated indices of vertices that must not move")
    p.add_argument("--target-df", type=float, default=None, help="target max δ_f (default 1e-6)")
    p.add_argument("--target-dp", type=float, default=None, help="target max δ_P (default 1e-6)")
    p.add_argument("--max-iter", type=int, default=None, help="maximum Levenberg–Marquardt iterations (default 500)")
    p.add_argument("--design", default=None, help="take parameters from the [optimize] table of this TOML file")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="set any optimisation parameter (TOML value syntax), repeatable")
    p.add_argument("--verbose", action="store_true", help="print energies and metrics of every iteration")
    p.add_argument("--quiet", action="store_true",
                   help="no progress display and no detail lines; the result line is still printed")
    p.add_argument("--json", action="store_true", help="print a JSON summary (with the per-iteration history)")


def _int_list(text: str | None, key: str) -> list[int] | None:
    from ppfab.errors import DesignError

    if text is None:
        return None
    try:
        return [int(t) for t in text.replace(" ", "").split(",") if t]
    except ValueError:
        raise DesignError(key, f"expected comma-separated integers, got {text!r}") from None


def _parse_set(items: list[str]) -> dict:
    from ppfab.errors import DesignError

    import tomllib

    out = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise DesignError("--set", f"expected KEY=VALUE, got {item!r}")
        try:
            out[key.strip()] = tomllib.loads(f"v = {value.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            out[key.strip()] = value.strip()          # a bare word: a string
    return out


def _design_table(path: str) -> dict:
    from ppfab.errors import DesignError

    import tomllib

    try:
        doc = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise DesignError("--design", f"cannot read {path} ({exc.strerror})") from None
    except tomllib.TOMLDecodeError as exc:
        raise DesignError("--design", f"{path} is not valid TOML ({exc})") from None
    table = doc.get("optimize", {})
    if not isinstance(table, dict):
        raise DesignError("optimize", "expected a table")
    return table


def collect_params(args: argparse.Namespace) -> dict:
    """The ``[optimize]`` table from ``--design``, then ``--set``, then the dedicated options."""
    table = _design_table(args.design) if args.design else {}
    table.update(_parse_set(args.set))
    direct = {
        "families": args.families, "polylines": _int_list(args.polylines, "--polylines"),
        "fixed_vertices": _int_list(args.fixed, "--fixed"), "target_delta_f": args.target_df,
        "target_delta_p": args.target_dp, "max_iterations": args.max_iter,
    }
    table.update({k: v for k, v in direct.items() if v is not None})
    if args.fix_boundary:
        table["fix_boundary"] = True
    if args.keep_conical:
        table["keep_conical"] = True
    if args.keep_circular:
        table["keep_circular"] = True
    if args.orthogonal_nodes:
        table["orthogonal_nodes"] = True
    return table


def run(args: argparse.Namespace) -> int:
    from ppfab.errors import GeometryError, MeshFileError
    from ppfab.io import load_mesh, write_mesh
    from ppfab.optimize import optimize

    from ..pipeline.overwrite import check_output_file, write_output
    from ..progress import Progress

    out = Path(args.out)
    if out.is_dir():
        raise MeshFileError(str(out), "is a folder; give the path of the mesh file to write (.obj or .off)")
    if out.suffix.lower() not in (".obj", ".off"):
        raise MeshFileError(str(out), f"unknown mesh format '{out.suffix}' (use .obj or .off)")
    if not out.parent.exists():
        raise MeshFileError(str(out), f"folder {out.parent} does not exist")
    inputs = [args.mesh] + ([args.design] if args.design else [])
    target = check_output_file(out, inputs=inputs, force=args.force)      # refuse before the work
    params = collect_params(args)
    mesh = load_mesh(args.mesh)
    progress = Progress(quiet=args.quiet or args.json, verbose=args.verbose)
    try:
        result = optimize(mesh, params, callback=progress.iteration)
    except GeometryError as exc:
        raise MeshFileError(args.mesh, str(exc)) from None
    finally:
        progress.clear()
    write_output(target, lambda tmp: write_mesh(result.mesh, tmp))       # atomic, stamped as ppfab's
    if args.json:
        doc = result.summary()
        doc.update({"input": str(args.mesh), "output": str(out),
                    "history": [asdict(h) for h in result.history]})
        print(json.dumps(doc, indent=2))
    else:
        print(f"{args.mesh} -> {out}: {result.message}", file=sys.stderr)    # even with --quiet: met or not
    if not args.json and not args.quiet:
        q = result.quality
        print(f"  {result.iterations} iterations, {result.time:.2f} s; mean displacement "
              f"{result.displacement_mean:.3g} ({result.displacement_rel:.2e} of the bounding-box diagonal); "
              f"δ_P rows {q.delta_p_rows_max:.2e}, cols {q.delta_p_cols_max:.2e}", file=sys.stderr)
        print(f"  distance to the input surface max {result.surface_distance_max:.3g} / mean "
              f"{result.surface_distance_mean:.3g}; crease max {result.crease_max_input:.1f}° -> "
              f"{result.crease_max:.1f}°; conical residual max {result.conical_max_input:.2e} -> "
              f"{result.conical_max:.2e} rad; circular residual max {result.circular_max_input:.2e} -> "
              f"{result.circular_max:.2e} rad"
              + (f"; node angle off 90° max {result.node_angle_max_input:.3g} -> {result.node_angle_max:.3g}°"
                 if result.params.orthogonal_nodes else ""), file=sys.stderr)
    return 0 if result.targets_met else 1
