"""The ``ppfab`` command line.

``main(argv)`` is a function (tests call it in-process).  Subcommands live in
``ppfab/cli/cmd_*.py``; each module defines ``NAME``, ``HELP``,
``add_arguments(parser)`` and ``run(args) -> int`` and is discovered here, so
a new command is one new file.  Heavy imports (build123d, ezdxf, matplotlib)
happen inside ``run`` so ``ppfab --version`` is instant.

Errors derived from :class:`~ppfab.errors.PpfabError` print one line
``ppfab: error: …`` and exit with their code (2 for bad input); Ctrl-C exits
130.  No traceback reaches the user unless ``PPFAB_DEBUG=1``.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import pkgutil
import sys

from ppfab import __version__
from ppfab.errors import PpfabError


def _commands() -> list:
    mods = []
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
        if info.name.startswith("cmd_"):
            mods.append(importlib.import_module(f"{__name__}.{info.name}"))
    return sorted(mods, key=lambda m: getattr(m, "ORDER", 50))


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # one line, exit 2
        self.exit(2, f"ppfab: error: {message}\n")


def make_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="ppfab", description="Planar panels and planar beams: design P/PP meshes and "
                                               "produce fabrication data.")
    parser.add_argument("--version", action="version", version=f"ppfab {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for mod in _commands():
        p = sub.add_parser(mod.NAME, help=mod.HELP, description=mod.HELP)
        mod.add_arguments(p)
        p.set_defaults(_run=mod.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    parser = make_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "command", None):
        parser.print_help()
        return 2
    level = logging.WARNING
    if getattr(args, "quiet", False):
        level = logging.ERROR
    elif getattr(args, "verbose", False):
        level = logging.INFO
    logging.basicConfig(level=level, format="%(message)s", stream=sys.stderr)
    try:
        return int(args._run(args) or 0)
    except PpfabError as exc:
        if os.environ.get("PPFAB_DEBUG"):
            raise
        print(f"ppfab: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("ppfab: interrupted", file=sys.stderr)
        return 130


def entry() -> None:  # pragma: no cover - console script
    sys.exit(main())
