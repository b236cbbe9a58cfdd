"""``ppfab examples`` — list the bundled example designs (``ppfab build --example NAME -o OUT`` builds one)."""

from __future__ import annotations

import argparse
import json

NAME = "examples"
HELP = "list the bundled example designs (build one with: ppfab build --example NAME -o OUT)"
ORDER = 45


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--path", metavar="NAME", help="print the path of one example's design file")
    p.add_argument("--json", action="store_true", help="print the list as JSON")


def run(args: argparse.Namespace) -> int:
    from ..examples import example_path, examples

    if args.path:
        print(example_path(args.path))
        return 0
    items = examples()
    if args.json:
        print(json.dumps([{"name": e.name, "method": e.method or None, "mesh": e.mesh or None, "title": e.title,
                           "description": e.description, "path": str(e.path)} for e in items], indent=2))
        return 0
    width = max(len(e.name) for e in items)
    for e in items:
        print(f"{e.name:<{width}}  {e.source:<34} {e.title}")
    print(f"\n{len(items)} examples; build one with: ppfab build --example NAME -o OUT")
    return 0
