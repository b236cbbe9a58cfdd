"""Ctrl-C, SIGTERM and SIGHUP as one interruption that always stops a run.

The command line's handler (:func:`on_signal`) raises :class:`Interrupted` in the main thread, so a run unwinds
exactly as on Ctrl-C and its output folder is cleaned up.  Python runs a signal handler wherever the main
thread happens to be, and in a few places it *ignores* what the handler raises: a weak-reference callback (the
import system's module locks have one), a ``__del__``, a ``finally`` inside a library that swallows
``KeyboardInterrupt``.  Left there, the run would go on and could finish with exit 0 although it was told to
stop.  So the handler also records the signal as *pending* until the command line has handled the
interruption, and :func:`check` — called where a run passes anyway (each stage's start, each counted step, right
before an output folder is committed) — raises it again.  :func:`quiet_unraisable` keeps Python's "Exception
ignored in …" report of such a swallowed interruption off the terminal.
"""

from __future__ import annotations

import contextlib
import logging
import signal
import sys
import threading
from typing import Any, Iterator

log = logging.getLogger("ppfab")


class Interrupted(KeyboardInterrupt):
    """Raised in the main thread by SIGTERM or SIGHUP, so a run unwinds exactly as on Ctrl-C."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


STOP_SIGNALS = tuple(s for s in (getattr(signal, "SIGTERM", None), getattr(signal, "SIGHUP", None)) if s)
"""The signals that stop a run besides SIGINT."""

SIGNALS: dict[str, Any] = {"last": None, "pending": None}
"""``last``: the signal the handler saw most recently (:func:`fabrication.cli.interruptible_imports` reads and
resets it); ``pending``: a signal whose interruption the command line has not handled yet."""


def on_signal(signum: int, frame: object) -> None:
    """The handler of SIGINT, SIGTERM and SIGHUP: record the signal, ignore any further one (a second signal must
    not interrupt the clean-up), raise :class:`Interrupted`."""
    SIGNALS["last"] = SIGNALS["pending"] = signum
    for s in STOP_SIGNALS + (signal.SIGINT,):
        signal.signal(s, signal.SIG_IGN)
    raise Interrupted(signum)


def handled() -> None:
    """The command line has stopped the run for the pending signal (or the run is over): forget it."""
    SIGNALS["pending"] = None
    SIGNALS["last"] = None


def check() -> None:
    """Raise :class:`Interrupted` again when a signal arrived and its interruption was swallowed where Python
    ignores exceptions; nothing otherwise, and nothing outside the main thread (a signal is the main thread's)."""
    signum = SIGNALS["pending"]
    if signum is not None and threading.current_thread() is threading.main_thread():
        raise Interrupted(signum)


@contextlib.contextmanager
def quiet_unraisable() -> Iterator[None]:
    """While a run lasts, an interruption that Python could only report as "Exception ignored in …" goes to the
    log (``--verbose``) instead of the terminal; :func:`check` raises it again.  Anything else is reported as
    Python would."""
    previous = sys.unraisablehook

    def hook(unraisable: Any) -> None:
        if isinstance(unraisable.exc_value, KeyboardInterrupt) and SIGNALS["pending"] is not None:
            log.info("interruption swallowed in %r; stopping at the next step", unraisable.object)
            return
        previous(unraisable)

    sys.unraisablehook = hook
    try:
        yield
    finally:
        sys.unraisablehook = previous
