"""``ppfab studio [DESIGN.toml]`` — design P and PP gridshells interactively in the browser."""

from __future__ import annotations

import argparse

NAME = "studio"
HELP = "edit a design interactively in the browser (handles, sliders, live figures, save and build)"
ORDER = 60


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("design", nargs="?", default=None, help="design file (TOML); omitted: the bundled default")
    p.add_argument("--port", type=int, default=8080, help="port to serve on (default 8080)")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to bind (default 127.0.0.1: this machine only; 0.0.0.0 exposes the studio "
                        "to the network). Either way only the printed address, which carries a key for this "
                        "session, is answered")
    p.add_argument("--no-browser", action="store_true", help="do not open a browser")


def run(args: argparse.Namespace) -> int:
    from ppfab.errors import DesignError

    if not 0 < args.port < 65536:
        raise DesignError("--port", f"must be in 1..65535, got {args.port}")
    try:
        import viser  # noqa: F401
    except ImportError:
        raise DesignError("studio", "the studio needs viser: pip install 'ppfab[studio]'") from None
    from ..studio.app import serve
    from ..studio.model import StudioModel

    model = StudioModel.load(args.design)
    return serve(model, args.host, args.port, not args.no_browser, args.design or "")
