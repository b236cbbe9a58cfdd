"""Atomic output folders and a small progress display.

:class:`AtomicFolder` writes into a temporary folder beside the target and
renames it into place only when the whole run succeeded; on any failure
(exception, Ctrl-C) the temporary folder is removed and an existing target
is left untouched.
"""

from __future__ import annotations

import os
import shutil
import sys
import time
import uuid
from pathlib import Path

from ..errors import PpfabError


class OutputExistsError(PpfabError):
    exit_code = 2


class AtomicFolder:
    """``with AtomicFolder(out, force) as tmp:`` — write into ``tmp``; committed on success."""

    def __init__(self, target: str | os.PathLike, force: bool = False):
        self.target = Path(target).absolute()
        self.force = force
        if self.target.exists() and not force:
            raise OutputExistsError(f"output folder {target} exists (use --force to replace it)")
        if self.target.exists() and not self.target.is_dir():
            raise OutputExistsError(f"output path {target} exists and is not a folder")
        self.tmp = self.target.parent / f".{self.target.name}.tmp-{uuid.uuid4().hex[:8]}"

    def __enter__(self) -> Path:
        try:
            self.target.parent.mkdir(parents=True, exist_ok=True)
            self.tmp.mkdir()
        except OSError as exc:
            raise OutputExistsError(f"cannot create output folder beside {self.target} ({exc.strerror})") from None
        return self.tmp

    def __exit__(self, exc_type, exc, tb) -> bool:
        if exc_type is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)
            return False
        old = None
        try:
            if self.target.exists():
                old = self.target.parent / f".{self.target.name}.old-{uuid.uuid4().hex[:8]}"
                os.replace(self.target, old)
            os.replace(self.tmp, self.target)
        except BaseException:
            if old is not None and not self.target.exists():
                os.replace(old, self.target)
            shutil.rmtree(self.tmp, ignore_errors=True)
            raise
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return False


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Write a file through a temporary sibling and an atomic rename."""
    p = Path(path)
    tmp = p.parent / f".{p.name}.tmp-{uuid.uuid4().hex[:8]}"
    try:
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, p)
    finally:
        if tmp.exists():
            tmp.unlink()


class Progress:
    """Stage-by-stage progress on stderr (silent when ``quiet``); records stage times."""

    def __init__(self, quiet: bool = False, stream=None):
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
