"""``ppfab verify OUT`` — re-read an output folder and check it against the output contract."""

from __future__ import annotations

import argparse
import sys

NAME = "verify"
HELP = "re-read a build (STEP, DXF, CSV, OBJ, manifest) and check counts, names, placements, congruence, sha256"
ORDER = 30


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("out", help="an output folder written by ppfab build")
    p.add_argument("--quiet", action="store_true", help="print only problems")
    p.add_argument("--json", action="store_true",
                   help="print the result on stdout as JSON: ok, the checks run and every finding with its check "
                        "(code), file, element, value, limit and message")
    p.add_argument("--kernel", action="store_true",
                   help="read every STEP solid with the CAD kernel and validate every instance of model.ifc "
                        "against its schema (default: a text-level STEP reader, with the kernel loading each "
                        "file's product tree and one solid of each kind; the IFC schema validated on the product "
                        "tree and one shape and property of each kind)")


def run(args: argparse.Namespace) -> int:
    from fabrication.verify import verify

    result = verify(args.out, kernel=args.kernel)
    if args.json:
        import json

        print(json.dumps({"ok": result.ok, "checked": result.checked,
                          "findings": [f.as_dict() for f in result.findings]}, indent=2))
    for f in result.findings[:50]:
        print(f"ppfab: verify: {f}", file=sys.stderr)
    if len(result.findings) > 50:
        print(f"ppfab: verify: … and {len(result.findings) - 50} more", file=sys.stderr)
    if not args.quiet and not args.json:
        status = "OK" if result.ok else f"FAILED ({len(result.findings)} problem(s))"
        print(f"ppfab verify {args.out}: {status}; checked {', '.join(result.checked)}")
    return 0 if result.ok else 1
