"""The progress display of ppfab's commands: stage by stage on stderr (silent when quiet), with a live status
during each stage — a progress bar (tqdm) with counts and the time left on a terminal, status lines elsewhere —
that never goes quiet for more than about ``interval`` seconds; it records the seconds of each stage.

A stage reports what it has done with :meth:`Progress.advance` (nesting: nominal budget spent and the best
count of sheets so far; files: writers done of all; optimisation: iteration and δ through
:meth:`Progress.iteration`).  Between two reports a ticker thread keeps the display alive (elapsed time on a
terminal; a status line every ``interval`` seconds in a log), so a long CAD-kernel call never looks like a hang.
Every report is also an :class:`Event` in :attr:`Progress.events` and is passed to the ``hooks`` (tests and
notebooks read them).

In a log (not a terminal) every line is whole: a stage's status lines carry its count and time left
(``verify: 31 of 48 checks, bite (12 s, ≈ 6 s left)``), a warning logged during a stage is printed on its own
line (:meth:`Progress.message`, :class:`ProgressLogHandler`), and a stage whose header was broken by either ends
with its header repeated in front of its summary, so the lines that begin with ``[ppfab]`` are one summary line
per stage.
"""

from __future__ import annotations

import contextlib
import logging
import sys
import threading
import time
from dataclasses import dataclass
from typing import Any, Callable, Iterator, TextIO

from . import interrupts


@dataclass(frozen=True)
class Event:
    """One progress report: ``t`` (``time.perf_counter()``), the ``stage``, its ``kind`` (``start``, ``advance``,
    ``update``, ``tick``, ``done``, ``fail``), the ``done`` / ``total`` counts (``None`` when not counted) and
    the status ``text``."""

    t: float
    stage: str
    kind: str
    done: float | None = None
    total: float | None = None
    text: str = ""


def _eta(elapsed: float, done: float | None, total: float | None) -> str:
    """``"≈ 12 s left"`` from the rate so far (empty until something is done)."""
    if not done or not total or done >= total:
        return ""
    left = elapsed * (total - done) / done
    return f", ≈ {left:.0f} s left" if left < 120 else f", ≈ {left / 60:.0f} min left"


BAR_COUNTED = "{desc} {percentage:3.0f}%|{bar:20}| [{elapsed}<{remaining}] {postfix}"
"""The tqdm bar of a stage that counts its work: percentage, bar, time spent and time left, status."""

BAR_UNCOUNTED = "{desc} [{elapsed}] {postfix}"
"""The tqdm line of a stage before it knows its total (time spent and status)."""


class Progress:
    """``start(stage)``, then any number of ``note(text)`` / ``advance(done, total)`` / ``update(text)``, then
    ``done(summary)`` or ``fail()``.

    ``times[stage]`` holds the seconds each stage took.  ``verbose`` prints every ``update`` on its own line.
    ``bar``: draw a tqdm bar (default: when the stream is a terminal).  ``tick``: seconds between two
    keep-alive refreshes of a stage that reports nothing.
    """

    def __init__(self, quiet: bool = False, stream: TextIO | None = None, verbose: bool = False,
                 interval: float = 2.0, bar: bool | None = None, tick: float = 0.5):
        self.quiet = quiet
        self.verbose = verbose
        self.stream: TextIO = stream or sys.stderr
        self.interval = interval
        self.tick = tick
        self.times: dict[str, float] = {}
        self.events: list[Event] = []
        self.hooks: list[Callable[[Event], None]] = []
        self._t0 = 0.0
        self._origin = 0.0         # when the current count began (the rate of the time-left estimate)
        self._stage = ""
        self._line = ""            # what the stage line shows so far
        self._notes: list[str] = []
        self._status = ""
        self._counts: tuple[float | None, float | None] = (None, None)
        self._last_shown = time.perf_counter()
        self._status_shown = False
        self._midline = False      # a log line was begun and not ended (the stage header, its notes)
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self._use_bar = self.tty if bar is None else bar
        self._bar: Any = None
        self._lock = threading.RLock()
        self._stop = threading.Event()
        self._ticker: threading.Thread | None = None
        self.folder: Any = None

    # -- events --------------------------------------------------------------------------------------------

    def _event(self, kind: str, done: float | None = None, total: float | None = None, text: str = "") -> None:
        e = Event(time.perf_counter(), self._stage, kind, done, total, text)
        self.events.append(e)
        for hook in self.hooks:
            hook(e)

    # -- stages --------------------------------------------------------------------------------------------

    def start(self, stage: str, detail: str = "") -> None:
        interrupts.check()                  # a signal whose interruption was swallowed stops the run here
        with self._lock:
            self._stage, self._t0 = stage, time.perf_counter()
            self._last_shown = self._t0
            self._notes, self._status, self._counts = [], "", (None, None)
            self._line = f"[ppfab] {stage:<10} {detail}" if detail else f"[ppfab] {stage:<10}"
            self._origin = self._t0
            self._event("start", text=detail)
            if self.quiet:
                return
            if self._use_bar:
                self._open_bar()
            else:
                self._end_line()
                print(self._line, file=self.stream, end="", flush=True)
                self._midline = True
            self._start_ticker()

    def note(self, text: str) -> None:
        """Add ``text`` to the stage line (its summary when the stage is done)."""
        with self._lock:
            self._notes.append(text)
            self._line += f" {text}"
            if self.quiet:
                return
            if self._bar is not None:
                self._bar.set_description_str(self._line, refresh=True)
            else:
                self._clear_status()
                if self.tty or self._midline:       # a log whose header line was ended shows it in the summary
                    print(f" {text}", file=self.stream, end="", flush=True)

    def advance(self, done: float, total: float | None = None, text: str = "") -> None:
        """The running stage has done ``done`` of ``total`` (``None``: not known), with a status ``text``."""
        interrupts.check()
        with self._lock:
            last_done, last_total = self._counts
            if total != last_total or (last_done is not None and done < last_done):
                self._origin = time.perf_counter()      # a new count (the plates after the glass): new rate
            self._counts = (done, total)
            if text:
                self._status = text
            self._event("advance", done, total, text)
            self._show(force=False)

    def update(self, text: str) -> None:
        """A transient status of the running stage (e.g. an iteration and its δ)."""
        with self._lock:
            self._status = text
            self._event("update", *self._counts, text=text)
            if self.quiet:
                return
            if self.verbose:
                self._end_line()
                print(text, file=self.stream, flush=True)
                return
            self._show(force=False)

    def iteration(self, record: Any) -> None:
        """Optimiser callback: show an :class:`~ppfab.optimize.solver.IterationRecord` (iteration, stage, δ)."""
        interrupts.check()
        if self.verbose:
            self.update(record.line())
            return
        text = (f"iteration {record.iteration}, stage {record.stage}, max δ_f {record.delta_f_max:.2e}, "
                f"max δ_P {record.delta_p_max:.2e}")
        with self._lock:
            self._counts = (float(record.iteration), None)
        self.update(text)

    def done(self, summary: str = "") -> None:
        with self._lock:
            self._stop_ticker()
            dt = time.perf_counter() - self._t0
            self.times[self._stage] = self.times.get(self._stage, 0.0) + dt
            self._event("done", *self._counts, text=summary)
            if not self.quiet:
                self._last_line((f" {summary}" if summary else "") + f" ({dt:.1f} s)")
            self._stage, self._line = "", ""

    def _last_line(self, tail: str) -> None:
        """Print the stage's last line: its header (unless a terminal's status line or a line already begun
        shows it) followed by ``tail``; the bar or status line is closed first.  Called under the lock."""
        if self._bar is not None:
            self._close_bar()
            print(f"{self._line}{tail}", file=self.stream, flush=True)
        else:
            self._clear_status()
            head = "" if self.tty or self._midline else self._line
            print(f"{head}{tail}", file=self.stream, flush=True)
            self._midline = False

    def fail(self) -> None:
        with self._lock:
            self._stop_ticker()
            if self._stage:
                self._event("fail", *self._counts)
            if not self.quiet and self._stage:
                self._last_line(" failed")
            self._stage, self._line = "", ""

    def clear(self) -> None:
        """Remove a status line shown outside any stage (a terminal keeps no half-written line)."""
        with self._lock:
            self._stop_ticker()
            if not self.quiet:
                self._close_bar()
                self._clear_status()
                if self.tty and not self._line:
                    print("\r\033[K", file=self.stream, end="", flush=True)

    def message(self, text: str) -> None:
        """Print ``text`` (a warning, a notice) on a line of its own, the running stage's display kept intact:
        on a terminal above the bar or status line, in a log after ending the line begun."""
        with self._lock:
            if self._bar is not None:
                self._bar.write(text, file=self.stream)
                return
            if self.tty and self._stage:
                print(f"\r\033[K{text}", file=self.stream, flush=True)
                print(self._line, file=self.stream, end="", flush=True)
                self._status_shown = False
                return
            self._end_line()
            print(text, file=self.stream, flush=True)

    @contextlib.contextmanager
    def logs_here(self, name: str = "ppfab") -> Iterator[None]:
        """Within the block, records of the logger ``name`` are printed through :meth:`message` (not by the
        root logger's handler, which would write them into the middle of a stage line).  A quiet progress draws
        no stage lines: the records then go where logging sends them, unchanged."""
        if self.quiet:
            yield
            return
        logger = logging.getLogger(name)
        handler = ProgressLogHandler(self)
        logger.addHandler(handler)
        propagate, logger.propagate = logger.propagate, False
        try:
            yield
        finally:
            logger.removeHandler(handler)
            logger.propagate = propagate

    def _end_line(self) -> None:
        """End a log line that was begun (the stage header), so that what follows starts a line of its own."""
        if self._midline and not self.tty:
            print(file=self.stream, flush=True)
        self._midline = False

    # -- display -------------------------------------------------------------------------------------------

    def watch(self, folder: Any) -> None:
        """Count the files in ``folder`` (a :class:`~pathlib.Path`; ``None``: stop) into the status of the
        stages that follow: the writers report files written, not only writer by writer."""
        self.folder = folder

    def _files(self) -> str:
        if self.folder is None:
            return ""
        try:
            n = sum(1 for p in self.folder.rglob("*") if p.is_file())
        except OSError:
            return ""
        return f", {n} files written"

    def _status_text(self, now: float) -> str:
        done, total = self._counts
        count = self._files()
        if done is not None and total:
            count = f" {100 * done / total:.0f} %" + count
        return f"{self._status}{count} ({now - self._t0:.0f} s{_eta(now - self._origin, done, total)})".lstrip()

    def _show(self, force: bool) -> None:
        if self.quiet or not self._stage:
            return
        now = time.perf_counter()
        if self._bar is not None:
            done, total = self._counts
            if total is not None and self._bar.total != total:
                self._bar.total = total
                self._bar.bar_format = BAR_COUNTED
            if done is not None:
                self._bar.n = done
            self._bar.set_postfix_str(self._status + self._files(), refresh=False)
            self._bar.refresh()
            self._last_shown = now
            return
        if not force and now - self._last_shown < (0.2 if self.tty else self.interval):
            return
        self._last_shown = now
        status = self._status_text(now)
        if self.tty:
            print(f"\r\033[K{self._line} … {status}", file=self.stream, end="", flush=True)
            self._status_shown = True
        else:
            self._end_line()
            print(f"  {self._stage}: {status}", file=self.stream, flush=True)

    def _open_bar(self) -> None:
        from tqdm import tqdm

        self._bar = tqdm(total=None, desc=self._line, file=self.stream, leave=False, dynamic_ncols=True,
                         mininterval=0.1, bar_format=BAR_UNCOUNTED)

    def _close_bar(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def _clear_status(self) -> None:
        if self._status_shown and self.tty:
            print(f"\r\033[K{self._line}", file=self.stream, end="", flush=True)
        self._status_shown = False

    # -- keep-alive ----------------------------------------------------------------------------------------

    def _start_ticker(self) -> None:
        if self.tick <= 0:
            return
        stop = threading.Event()          # one per ticker: a ticker still asleep never serves the next stage
        self._stop = stop
        self._ticker = threading.Thread(target=self._run_ticker, args=(stop,), name="ppfab-progress", daemon=True)
        self._ticker.start()

    def _stop_ticker(self) -> None:
        self._stop.set()
        self._ticker = None

    def _run_ticker(self, stop: threading.Event) -> None:
        while not stop.wait(self.tick):
            with self._lock:
                if stop.is_set() or not self._stage:
                    return
                now = time.perf_counter()
                if now - self._last_shown >= (self.tick if self._bar is not None else self.interval):
                    self._event("tick", *self._counts, text=self._status)
                    self._show(force=True)


class ProgressLogHandler(logging.Handler):
    """A logging handler that prints each record (its message alone) through :meth:`Progress.message`
    (installed by :meth:`Progress.logs_here`, never for a quiet progress)."""

    def __init__(self, progress: Progress) -> None:
        super().__init__()
        self.progress = progress
        self.setFormatter(logging.Formatter("%(message)s"))

    def emit(self, record: logging.LogRecord) -> None:
        try:
            self.progress.message(self.format(record))
        except Exception:                       # a handler never raises into the code that logs
            self.handleError(record)
