"""The progress display of a build (stage by stage on stderr, silent when quiet); it records stage times."""

from __future__ import annotations

import sys
import time
from typing import TextIO


class Progress:
    """Stage-by-stage progress on stderr (silent when ``quiet``); records stage times."""

    def __init__(self, quiet: bool = False, stream: TextIO | None = None):
        self.quiet = quiet
        self.stream = stream or sys.stderr
        self.times: dict[str, float] = {}
        self._t0 = 0.0
        self._stage = ""

    def start(self, stage: str, detail: str = "") -> None:
        self._stage, self._t0 = stage, time.perf_counter()
        if not self.quiet:
            print(f"[ppfab] {stage:<10} {detail}", file=self.stream, end="", flush=True)

    def note(self, text: str) -> None:
        if not self.quiet:
            print(f" {text}", file=self.stream, end="", flush=True)

    def done(self, summary: str = "") -> None:
        dt = time.perf_counter() - self._t0
        self.times[self._stage] = self.times.get(self._stage, 0.0) + dt
        if not self.quiet:
            print(f" {summary} ({dt:.1f} s)", file=self.stream, flush=True)

    def fail(self) -> None:
        if not self.quiet and self._stage:
            print(" failed", file=self.stream, flush=True)
