"""``ppfab new [METHOD | MESH] -o design.toml`` — write a commented starter design, ready to build."""

from __future__ import annotations

import argparse
import sys

NAME = "new"
HELP = "write a commented starter design (every key and its default) for a construction method or a mesh file"
ORDER = 5


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("source", nargs="?", default=None, metavar="METHOD | MESH",
                   help="a construction method (`ppfab methods`; default: bisector) or a quad mesh file "
                        "(.obj/.off), which is measured first to propose [optimize], [support] and [beams]")
    p.add_argument("-o", "--out", required=True, help="the design file to write (TOML)")
    p.add_argument("--force", action="store_true",
                   help="replace an existing design file, if `ppfab new` wrote it and it was not edited since")


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from ppfab.errors import DesignError

    from ..pipeline.overwrite import check_output_file, write_output_text
    from ..starter import starter_text

    out = Path(args.out)
    inputs = [args.source] if args.source and Path(args.source).exists() else []
    target = check_output_file(out, inputs=inputs, force=args.force)    # never an input, never someone's file
    if out.suffix.lower() != ".toml":
        raise DesignError("-o", f"{out}: a design file ends in .toml")
    text = starter_text(args.source, out)
    write_output_text(target, text)                                      # atomic, stamped as ppfab's
    print(f"ppfab: wrote {out}; build it with: ppfab build {out} -o OUT", file=sys.stderr)
    return 0
