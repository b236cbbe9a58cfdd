"""The ``ppfab`` command line.

``main(argv)`` is a function (tests call it in-process).  Subcommands live in
``ppfab/cli/cmd_*.py``; each module defines ``NAME``, ``HELP``,
``add_arguments(parser)`` and ``run(args) -> int`` and is discovered here, so
a new command is one new file.  Heavy imports (build123d, ezdxf, matplotlib)
happen inside ``run`` so ``ppfab --version`` is instant.

Errors derived from :class:`~ppfab.errors.PpfabError` print one line
``ppfab: error: …`` and exit with their code (2 for bad input); so does an operating-system error
(disk full, permission denied: exit 1).  Ctrl-C, SIGTERM and SIGHUP stop a run the same way (an
exception unwinds it, so output folders are cleaned up) and exit ``128 + signal`` (130, 143, 129) — at any
moment, also while the CAD kernel and file libraries are imported (:func:`interruptible_imports`), and also when
the signal lands where Python ignores what its handler raises (a weak-reference callback): the run stops at its
next step (:mod:`fabrication.interrupts`).
Path arguments that are empty or hold a control character are refused before a command runs, and control
characters in an error message (a quoted key, value or path) are escaped, so the error stays one line.
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
from typing import Iterator

from ppfab import __version__
from ppfab.errors import PpfabError

from ..interrupts import STOP_SIGNALS, SIGNALS, Interrupted, handled, on_signal, quiet_unraisable


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


@contextlib.contextmanager
def interruptible_imports() -> Iterator[None]:
    """Import heavy libraries (the CAD kernel, the file libraries) so that SIGINT, SIGTERM and SIGHUP still stop
    the run at once: the signal interrupts the import like any other step, and whatever the interrupted library
    raises instead (a C extension interrupted in its initialisation may turn it into an ImportError, a library
    may swallow it) becomes the interruption itself.  Nothing is held: Ctrl-C during a slow import stops the run
    as promptly as anywhere else."""
    before = SIGNALS["last"]
    SIGNALS["last"] = None
    try:
        yield
    except BaseException as exc:
        signum = SIGNALS["last"] or _interrupted(exc)
        if signum is not None and not isinstance(exc, Interrupted):
            raise Interrupted(signum) from None
        raise
    else:
        if SIGNALS["last"] is not None:             # a library caught the interruption and went on
            raise Interrupted(SIGNALS["last"])
    finally:
        SIGNALS["last"] = SIGNALS["last"] or before


deferred_signals = interruptible_imports
"""The former name (``cmd_build.preload`` imports it): signals are no longer held, see :func:`interruptible_imports`."""


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


PATH_ARGUMENTS = ("design", "out", "mesh")
"""Arguments of the commands that name a file or folder: checked by :func:`_check_paths` before a command runs."""


def _check_paths(args: argparse.Namespace) -> None:
    """Refuse a path argument that is empty or holds a NUL byte or another control character, in one line,
    before any file is looked at (Python would raise ``ValueError`` on a NUL byte)."""
    from ppfab.errors import DesignError
    from ppfab.io.pathtext import path_problem, printable

    for name in PATH_ARGUMENTS:
        value = getattr(args, name, None)
        problem = path_problem(value) if isinstance(value, str) else None
        if problem is not None:
            shown = f" '{printable(value)}'" if value else ""
            positional = name == "mesh" or (name == "design" and args.command != "optimize") or \
                (name == "out" and args.command == "verify")
            raise DesignError(name if positional else f"--{name}",
                              f"the path{shown} {problem}; give the path of a file or folder")


def _printable(text: str) -> str:
    """Control characters in a message (quoted keys, values, paths) escaped, so the error stays one line."""
    from ppfab.io.pathtext import printable

    return printable(text)


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
        previous = {s: signal.signal(s, on_signal) for s in STOP_SIGNALS}
        if signal.getsignal(signal.SIGINT) is signal.default_int_handler:      # not when started ignoring it
            previous[signal.SIGINT] = signal.signal(signal.SIGINT, on_signal)
    try:
        with warnings.catch_warnings(), quiet_unraisable():
            if not debug:                        # every library warning goes to the log, none to the terminal
                warnings.simplefilter("always")
                warnings.showwarning = _showwarning
                for name in LIBRARY_LOGGERS:
                    logging.getLogger(name).setLevel(logging.INFO if level == logging.INFO else logging.ERROR)
            _check_paths(args)
            return int(args._run(args) or 0)
    except PpfabError as exc:
        if debug:
            raise
        print(f"ppfab: error: {_printable(str(exc))}", file=sys.stderr)
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
        print(f"ppfab: error: {_printable(_os_error(exc))}", file=sys.stderr)
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
        handled()
        for s, handler in previous.items():
            signal.signal(s, handler)


def threading_main() -> bool:
    """Signal handlers can only be installed from the main thread."""
    import threading

    return threading.current_thread() is threading.main_thread()


def entry() -> None:  # pragma: no cover - console script
    sys.exit(main())
