"""``ppfab methods [NAME]`` — list the constructions a design file can name, with their parameters."""

from __future__ import annotations

import argparse

NAME = "methods"
HELP = "list the construction methods of [geometry] and their [geometry.params] keys"
ORDER = 40


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("name", nargs="?", help="show the parameters of one method")
    p.add_argument("--markdown", action="store_true", help="print Markdown tables (used for the README)")


def run(args: argparse.Namespace) -> int:
    from ppfab.constructions import get_construction, load_all
    from ppfab.schema import describe

    registry = load_all()
    names = [args.name] if args.name else sorted(registry)
    for name in names:
        c = get_construction(name, "method")
        fams = "+".join(c.planar_families) or "none"
        if args.markdown:
            print(f"#### `{name}` — {c.summary} ({c.section}; planar families: {fams})\n")
            print("| key | type | default | meaning |\n|---|---|---|---|")
            for key, tp, default, doc in describe(c.params):
                print(f"| `{key}` | {tp} | `{default}` | {doc} |")
            print()
        else:
            print(f"{name:<22} {c.summary} [{c.section}; planar: {fams}]")
            if args.name:
                for key, tp, default, doc in describe(c.params):
                    print(f"    {key:<18} {tp:<22} {default:<14} {doc}")
    return 0
