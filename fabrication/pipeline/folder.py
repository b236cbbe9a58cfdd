"""Atomic output: folders and single files written through a temporary sibling and renamed into place.

:func:`atomic_file` does the same for one file.  :class:`AtomicFolder` writes into a temporary folder beside the target and
renames it into place only when the whole run succeeded; on any failure
(exception, Ctrl-C) the temporary folder is removed and an existing target
is left untouched.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import uuid
from pathlib import Path
from types import TracebackType
from typing import Iterator, Literal

from ppfab.errors import PpfabError


class OutputExistsError(PpfabError):
    exit_code = 2


class AtomicFolder:
    """``with AtomicFolder(out, force) as tmp:`` — write into ``tmp``; committed on success."""

    def __init__(self, target: str | os.PathLike, force: bool = False):
        self.target = Path(target).absolute()
        self.force = force
        self.check_target(target, force)
        self.tmp = self.target.parent / f".{self.target.name}.tmp-{uuid.uuid4().hex[:8]}"

    @staticmethod
    def check_target(target: str | os.PathLike, force: bool = False) -> None:
        """Raise :class:`OutputExistsError` when ``target`` may not be (re)placed."""
        path = Path(target).absolute()
        if path.exists() and not force:
            raise OutputExistsError(f"output folder {target} exists (use --force to replace it)")
        if path.exists() and not path.is_dir():
            raise OutputExistsError(f"output path {target} exists and is not a folder")

    def __enter__(self) -> Path:
        try:
            self.target.parent.mkdir(parents=True, exist_ok=True)
            self.tmp.mkdir()
        except OSError as exc:
            raise OutputExistsError(f"cannot create output folder beside {self.target} ({exc.strerror})") from None
        return self.tmp

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> Literal[False]:
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


@contextlib.contextmanager
def atomic_file(path: str | os.PathLike) -> Iterator[Path]:
    """``with atomic_file(p) as tmp:`` — write the file ``tmp`` (a sibling of ``p`` with the same suffix);
    it replaces ``p`` in one rename when the block succeeds and is removed when it fails."""
    p = Path(path)
    tmp = p.parent / f".{p.stem}.tmp-{uuid.uuid4().hex[:8]}{p.suffix}"
    try:
        yield tmp
        os.replace(tmp, p)
    finally:
        if tmp.exists():
            tmp.unlink()
