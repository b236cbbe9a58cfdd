"""``ppfab build [DESIGN.toml] -o OUT`` — the whole fabrication package from a design file."""

from __future__ import annotations

import argparse
import json
import sys
from typing import TYPE_CHECKING

NAME = "build"
HELP = "build a design (default: the bundled PP gridshell) into a complete fabrication folder"
ORDER = 10


if TYPE_CHECKING:  # pragma: no cover
    from ..pipeline.records import Build


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("design", nargs="?", default=None,
                   help="design file (TOML); omitted: the bundled default example")
    p.add_argument("--example", metavar="NAME", help="build a bundled example (`ppfab examples` lists them)")
    p.add_argument("-o", "--out", required=True, help="output folder (written atomically)")
    p.add_argument("--force", action="store_true",
                   help="replace an existing output folder, if it is a previous ppfab build")
    p.add_argument("--quiet", action="store_true", help="no progress display")
    p.add_argument("--json", action="store_true", help="print a machine-readable summary on stdout")
    p.add_argument("--allow-large", action="store_true",
                   help="proceed with meshes above geometry.max_vertices")


def preload() -> None:
    """Import the CAD kernel and the file libraries now, with signals held: an interruption inside a C
    extension's initialisation would surface as an ImportError instead of a clean stop."""
    import importlib

    from . import deferred_signals

    with deferred_signals():
        for name in ("build123d", "ezdxf", "shapely", "matplotlib"):
            importlib.import_module(name)
        importlib.import_module("matplotlib").use("Agg")
        importlib.import_module("matplotlib.pyplot")


def run(args: argparse.Namespace) -> int:
    from ppfab.errors import DesignError

    from ..design import load_design
    from ..examples import example_path
    from ..pipeline.folder import check_target
    from ..pipeline.lock import OutputLock
    from ..pipeline.stages import build
    from ..progress import Progress

    if args.example and args.design:
        raise DesignError("--example", f"give a design file or --example, not both ({args.design!r} and "
                                       f"--example {args.example!r})")
    design = load_design(example_path(args.example) if args.example else args.design)
    progress = Progress(quiet=args.quiet or args.json)
    check_target(args.out, force=args.force, protect=design.input_files())    # refuse before the work
    with OutputLock(args.out), progress.logs_here():       # one run per output folder; warnings on lines of their own
        preload()
        result = build(design, progress=progress, allow_large=args.allow_large)
        out = result.write(args.out, force=args.force, progress=progress)
    manifest = json.loads((out / "manifest.json").read_text(encoding="utf-8"))
    if args.json:
        print(json.dumps({"out": str(args.out), "files": manifest["files"], "summary": manifest["summary"],
                          "quality": manifest["quality"], "structure": structure_counts(result),
                          "times_s": progress.times}, indent=2))
    elif not args.quiet:
        print(f"ppfab: wrote {args.out} ({len(manifest['sha256'])} files)", file=sys.stderr)
    return 0


def structure_counts(result: "Build") -> dict[str, object]:
    """What ``--json`` says of the structure: planar beams kept, polylines left out of the requested planar
    families (and why), the column beams ``[beams] segment = ["blocked"]`` cut at nodes (and at which), and the one-edge
    plates the build made."""
    from ..contract import beam_ids
    from ..pipeline.structure_gate import structure_change

    change = structure_change(result.support, beam_ids(result.support))
    plates = result.beams.plates
    planar = result.support.polyline_planar
    ids = beam_ids(result.support)
    blocked = result.beams.node_breaks
    return {"planar_polylines": int(planar.sum()) if planar is not None else 0,
            "left_out": [{"beam": b, "polyline": k, "reason": why} for b, k, why in change.left_out],
            "segmented_blocked": [{"beam": ids[l], "polyline": l, "nodes": list(k)} for l, k in blocked],
            "one_edge_plates": sum(1 for p in plates if p.meta.get("segment")),
            "plates": len(plates)}
