"""``ppfab remesh SURFACE -o NET.obj`` — a designer's surface (Rhino .3dm NURBS, triangle mesh) → a quad net on it."""

from __future__ import annotations

import argparse
import json
import sys

NAME = "remesh"
HELP = "remesh a surface (.3dm NURBS or a triangle mesh .obj/.off/.stl/.ply) into a quad net (sections: planar " \
       "rows and their conjugate curves; principal: curvature lines; conjugate: the conjugate net nearest two guide " \
       "directions; pp: two families of planar sections), " \
       "written as a quad OBJ"
ORDER = 6


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("surface", help="the surface file (.3dm, .obj, .off, .stl, .ply)")
    p.add_argument("-o", "--out", required=True, help="the quad mesh to write (.obj)")
    p.add_argument("--spacing", type=float, default=1500.0, help="target panel size in mm (default 1500)")
    p.add_argument("--net", default="sections", help="the net kind: sections, principal, conjugate or pp (default sections)")
    p.add_argument("--plane-normal", type=float, nargs=3, metavar=("X", "Y", "Z"), default=None,
                   help="normal of the section planes (default: vertical planes across the longer plan direction)")
    p.add_argument("--pencil-axis", type=float, nargs=2, metavar=("X", "Y"), default=None,
                   help="sections net: section planes through the vertical line at plan point X Y (mm, outside the "
                        "outline) instead of parallel planes")
    p.add_argument("--second-normal", type=float, nargs=3, metavar=("X", "Y", "Z"), default=None,
                   help="pp net: normal of the column planes, horizontal (default: across --plane-normal in plan)")
    p.add_argument("--guides", type=float, nargs=6, metavar=("X1", "Y1", "Z1", "X2", "Y2", "Z2"), default=None,
                   help="conjugate net: the directions the rows and the columns should follow (default: the plan's "
                        "axes)")
    p.add_argument("--guide-layers", nargs="+", metavar="LAYER", default=None,
                   help="conjugate net, a .3dm: the layer of the rows' guide curves, and optionally the columns'")
    p.add_argument("--search-planes", action="store_true",
                   help="sections and conjugate nets: try section planes every 15° then 2.5° in plan and keep the "
                        "net whose edges stay nearest the spacing")
    p.add_argument("--units", default=None, help="units of a mesh file: mm, cm, m, in, ft (a .3dm states its own)")
    p.add_argument("--smoothing", type=float, default=1.0,
                   help="knot spacing of the curvature fit as a fraction of the spacing (default 1.0)")
    p.add_argument("--object", default=None, help="in a .3dm: the name of the surface object to use")
    p.add_argument("--json", action="store_true", help="print the measurements as JSON on stdout")
    p.add_argument("--force", action="store_true", help="replace an output file that ppfab wrote")


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    import numpy as np

    from ppfab.errors import DesignError
    from ppfab.io.meshfile import write_obj
    from ppfab.schema import parse_params
    from ppfab.surface import SurfaceSpec, remesh

    from ..pipeline.overwrite import check_output_file, write_output
    from ..surfacefile import read_surface, with_layer_guides

    out = Path(args.out)
    if out.suffix.lower() != ".obj":
        raise DesignError("-o", f"{out}: the quad mesh is written as OBJ (.obj)")
    target = check_output_file(out, inputs=[args.surface], force=args.force)
    spec = parse_params(SurfaceSpec, {k: v for k, v in {
        "path": args.surface, "net": args.net, "spacing": args.spacing, "plane_normal": args.plane_normal,
        "second_normal": args.second_normal, "pencil_axis": args.pencil_axis,
        "guides": [args.guides[:3], args.guides[3:]] if args.guides is not None else None,
        "guide_layers": args.guide_layers, "search_planes": args.search_planes or None, "units": args.units, "smoothing": args.smoothing, "object": args.object}.items() if v is not None},
        "surface")
    surface = read_surface(args.surface, spec.units, spec.object)
    spec = with_layer_guides(spec, args.surface, surface)
    if surface.note:
        print(f"ppfab: note: {surface.note}", file=sys.stderr)
    result = remesh(surface.samples, spec)
    v = np.asarray(result.net.mesh.vertices).reshape(-1, 3)
    deviation = float(surface.distance(v).max())
    planar = {"rows": "rows are the planar sections", "both": "rows and columns are planar sections",
              "none": ("rows and columns are curvature lines" if spec.net == "principal" else
                       "rows and columns are conjugate curves")}[result.net.planar_family]
    header = (f"ppfab remesh: {spec.net} net of {surface.samples.source}, spacing {spec.spacing:g} mm, "
              f"units mm; {planar}")
    write_output(target, lambda tmp: write_obj(result.net.mesh, tmp, header))
    summary = {**result.summary(), "deviation_mm": deviation, "surface": surface.samples.source,
               "units": surface.samples.units, "out": str(out)}
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        n = result.net
        print(f"ppfab: wrote {out}: {summary['faces']} quads, {summary['vertices']} vertices "
              f"({n.dropped_outside} boundary quads dropped, {n.dropped_sliver} slivers, {n.dropped_island} "
              f"cut off); {planar}" + (f", planar to {result.planarity_mm:.1e} mm" if n.planar_family != "none"
                                       else "") +
              f"; largest distance to the surface {deviation:.2f} mm; edges {result.panel_size_min:.2f}–"
              f"{result.panel_size_max:.2f} × spacing; twist median {summary['twist_median']:.3f}, max "
              f"{summary['twist_max']:.3f} (0: conjugate)" +
              (f"; directions within {result.guide_deviation_deg:.1f}° of the guides"
               if result.guide_deviation_deg is not None else "") +
              (f"; section planes through the vertical axis at {result.pencil_axis}"
               if result.pencil_axis is not None else "") +
              (f"; section planes: the best of {result.planes_tried} directions, normal "
               f"{np.round(result.frame.axes[0], 3).tolist()}" if result.planes_tried else ""), file=sys.stderr)
        for u in result.umbilics:
            print(f"ppfab: note: an umbilic near the outline at (x, y) = ({u[0]:.0f}, {u[1]:.0f}) mm: the "
                  "curvature lines turn around it", file=sys.stderr)
    return 0
