"""The progress display of ppfab's commands: stage by stage on stderr (silent when quiet), with a status line
refreshed during long stages (optimiser iterations, sheets filled); it records the seconds of each stage.

On a terminal the status line is rewritten in place; elsewhere (a log file, CI) a status is printed at most
every ``interval`` seconds, so a long stage never goes quiet and never floods the log.
"""

from __future__ import annotations

import sys
import time
from typing import Any, TextIO


class Progress:
    """``start(stage)``, then any number of ``note(text)`` / ``update(text)``, then ``done(summary)`` or ``fail()``.

    ``times[stage]`` holds the seconds each stage took.  ``verbose`` prints every ``update`` on its own line.
    """

    def __init__(self, quiet: bool = False, stream: TextIO | None = None, verbose: bool = False,
                 interval: float = 2.0):
        self.quiet = quiet
        self.verbose = verbose
        self.stream: TextIO = stream or sys.stderr
        self.interval = interval
        self.times: dict[str, float] = {}
        self._t0 = 0.0
        self._stage = ""
        self._line = ""            # what the stage line shows so far
        self._last_update = time.perf_counter()
        self._status_shown = False
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())

    def start(self, stage: str, detail: str = "") -> None:
        self._stage, self._t0 = stage, time.perf_counter()
        self._last_update = self._t0
        self._line = f"[ppfab] {stage:<10} {detail}"
        if not self.quiet:
            print(self._line, file=self.stream, end="", flush=True)

    def note(self, text: str) -> None:
        """Append ``text`` to the stage line."""
        self._line += f" {text}"
        if not self.quiet:
            self._clear_status()
            print(f" {text}", file=self.stream, end="", flush=True)

    def update(self, text: str) -> None:
        """A transient status of the running stage (e.g. an iteration and its δ)."""
        if self.quiet:
            return
        now = time.perf_counter()
        if self.verbose:
            print(f"\n{text}" if self._line else text, file=self.stream, end="" if self._line else "\n", flush=True)
            return
        if now - self._last_update < (0.2 if self.tty else self.interval):
            return
        self._last_update = now
        status = f"{text} ({now - self._t0:.0f} s)"
        if self.tty:
            print(f"\r\033[K{self._line} … {status}", file=self.stream, end="", flush=True)
        elif self._line:
            print(f"\n  {status}", file=self.stream, end="", flush=True)
        else:
            print(f"[ppfab] {status}", file=self.stream, flush=True)
        self._status_shown = True

    def iteration(self, record: Any) -> None:
        """Optimiser callback: show an :class:`~ppfab.optimize.solver.IterationRecord`."""
        if self.verbose:
            self.update(record.line())
        else:
            self.update(f"iteration {record.iteration}, stage {record.stage}, max δ_f {record.delta_f_max:.2e}, "
                        f"max δ_P {record.delta_p_max:.2e}")

    def done(self, summary: str = "") -> None:
        dt = time.perf_counter() - self._t0
        self.times[self._stage] = self.times.get(self._stage, 0.0) + dt
        if not self.quiet:
            self._clear_status()
            print(f" {summary} ({dt:.1f} s)", file=self.stream, flush=True)

    def fail(self) -> None:
        if not self.quiet and self._stage:
            self._clear_status()
            print(" failed", file=self.stream, flush=True)

    def clear(self) -> None:
        """Remove a status line shown outside any stage (a terminal keeps no half-written line)."""
        if not self.quiet:
            self._clear_status()
            if self.tty and not self._line:
                print("\r\033[K", file=self.stream, end="", flush=True)

    def _clear_status(self) -> None:
        if self._status_shown and self.tty:
            print(f"\r\033[K{self._line}", file=self.stream, end="", flush=True)
        self._status_shown = False
