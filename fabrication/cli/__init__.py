"""The ``ppfab`` command line.

``main(argv)`` is a function (tests call it in-process).  Subcommands live in
``ppfab/cli/cmd_*.py``; each module defines ``NAME``, ``HELP``,
``add_arguments(parser)`` and ``run(args) -> int`` and is discovered here, so
a new command is one new file.  Heavy imports (build123d, ezdxf, matplotlib)
happen inside ``run`` so ``ppfab --version`` is instant.

Errors derived from :class:`~ppfab.errors.PpfabError` print one line
``ppfab: error: …`` and exit with their code (2 for bad input); so does an operating-system error
(disk full, permission denied: exit 1).  Ctrl-C, SIGTERM and SIGHUP stop a run the same way (an
exception unwinds it, so output folders are cleaned up) and exit ``128 + signal`` (130, 143, 129).
Library warnings (numpy's overflow and invalid-value RuntimeWarnings, matplotlib's, any other) and the
libraries' own logger warnings go to the log (``--verbose``), never raw to stderr.
No traceback reaches the user unless ``PPFAB_DEBUG=1``.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import logging
import os
import pkgutil
import signal
import sys
import warnings
from typing import Any, Iterator

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


class Interrupted(KeyboardInterrupt):
    """Raised in the main thread by SIGTERM or SIGHUP, so a run unwinds exactly as on Ctrl-C."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


STOP_SIGNALS = tuple(s for s in (getattr(signal, "SIGTERM", None), getattr(signal, "SIGHUP", None)) if s)


_SIGNALS: dict[str, Any] = {"defer": 0, "pending": None}


def _stop(signum: int) -> None:
    for s in STOP_SIGNALS + (signal.SIGINT,):       # a second signal must not interrupt the clean-up
        signal.signal(s, signal.SIG_IGN)
    raise Interrupted(signum)


def _on_signal(signum: int, frame: object) -> None:
    if _SIGNALS["defer"]:
        _SIGNALS["pending"] = signum
        return
    _stop(signum)


@contextlib.contextmanager
def deferred_signals() -> Iterator[None]:
    """Hold SIGINT, SIGTERM and SIGHUP until the block is done (e.g. while a C extension initialises, which
    would turn the interruption into an ImportError), then stop as if they had come after it."""
    _SIGNALS["defer"] += 1
    try:
        yield
    finally:
        _SIGNALS["defer"] -= 1
        pending, _SIGNALS["pending"] = _SIGNALS["pending"], None
        if pending is not None and not _SIGNALS["defer"]:
            _stop(pending)


def _interrupted(exc: BaseException) -> int | None:
    """The signal behind an exception that a library raised while it was interrupted, else ``None``."""
    seen = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        seen.add(id(e))
        if isinstance(e, KeyboardInterrupt):
            return int(getattr(e, "signum", signal.SIGINT))
        e = e.__cause__ or e.__context__
    return None


LIBRARY_LOGGERS = ("matplotlib", "ezdxf", "trimesh", "shapely", "build123d", "OCP", "ifcopenshell", "PIL")
"""Loggers of the libraries ppfab calls: their warnings are shown with ``--verbose`` only."""


def _showwarning(message, category, filename, lineno, file=None, line=None) -> None:
    logging.getLogger("ppfab").info("%s: %s", category.__name__, message)


def _os_error(exc: OSError) -> str:
    what = f"{exc.filename}: " if exc.filename else ""
    return f"{what}{exc.strerror or exc}" + (" (free some space or write elsewhere)"
                                             if getattr(exc, "errno", None) == 28 else "")


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
    debug = bool(os.environ.get("PPFAB_DEBUG"))
    previous = {}
    if threading_main():
        previous = {s: signal.signal(s, _on_signal) for s in STOP_SIGNALS}
        if signal.getsignal(signal.SIGINT) is signal.default_int_handler:      # not when started ignoring it
            previous[signal.SIGINT] = signal.signal(signal.SIGINT, _on_signal)
    try:
        with warnings.catch_warnings():
            if not debug:                        # every library warning goes to the log, none to the terminal
                warnings.simplefilter("always")
                warnings.showwarning = _showwarning
                for name in LIBRARY_LOGGERS:
                    logging.getLogger(name).setLevel(logging.INFO if level == logging.INFO else logging.ERROR)
            return int(args._run(args) or 0)
    except PpfabError as exc:
        if debug:
            raise
        print(f"ppfab: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except BrokenPipeError:                      # the reader of stdout went away (``ppfab … | head``)
        try:
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        except (OSError, ValueError, AttributeError):
            pass
        return 141
    except OSError as exc:
        if debug:
            raise
        print(f"ppfab: error: {_os_error(exc)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as exc:
        signum = getattr(exc, "signum", signal.SIGINT)
        print(f"ppfab: interrupted ({signal.Signals(signum).name})", file=sys.stderr)
        return 128 + int(signum)
    except Exception as exc:
        signum = _interrupted(exc)
        if signum is None or debug:
            raise
        print(f"ppfab: interrupted ({signal.Signals(signum).name})", file=sys.stderr)
        return 128 + signum
    finally:
        _SIGNALS["defer"], _SIGNALS["pending"] = 0, None
        for s, handler in previous.items():
            signal.signal(s, handler)


def threading_main() -> bool:
    """Signal handlers can only be installed from the main thread."""
    import threading

    return threading.current_thread() is threading.main_thread()


def entry() -> None:  # pragma: no cover - console script
    sys.exit(main())
