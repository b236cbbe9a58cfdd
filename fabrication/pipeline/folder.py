"""Atomic output: folders and single files written through a temporary sibling and renamed into place.

:func:`atomic_file` does the same for one file.  :class:`AtomicFolder` writes into a temporary folder beside the target and
renames it into place only when the whole run succeeded; on any failure
(exception, Ctrl-C, SIGTERM, SIGHUP) the temporary folder is removed and an existing target
is left untouched.  While it works it holds the target's :class:`~fabrication.pipeline.lock.OutputLock`,
and it first removes the leftovers of killed runs (:func:`~fabrication.pipeline.lock.remove_stale`).

What may be replaced (:func:`check_target`): with ``force``, only a folder that is a previous ppfab build
(:func:`previous_build_problem`) — never a symbolic link, the current folder or one holding it, or a
folder holding an input (the design file, the mesh file).
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import uuid
from pathlib import Path
from types import TracebackType
from typing import Iterable, Iterator, Literal

from ppfab.errors import PpfabError

from .lock import MARKER, OutputLock, remove_stale, write_marker


class OutputExistsError(PpfabError):
    exit_code = 2


def _sha256(path: Path) -> str:
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def previous_build_problem(folder: str | os.PathLike) -> str | None:
    """``None`` when ``folder`` holds a ppfab build and nothing else, else why not (one phrase).

    A build is a ``manifest.json`` whose ``generator`` is ppfab and whose ``sha256`` table lists every other
    file, each unchanged; an empty folder counts as one.  A symbolic link anywhere, a file the manifest does
    not list, or a listed file that was edited makes it someone's work, not a build.
    """
    root = Path(folder)
    if next(root.iterdir(), None) is None:
        return None
    manifest = root / "manifest.json"
    if manifest.is_symlink() or not manifest.is_file():
        return "it has no manifest.json of a ppfab build"
    try:
        doc = json.loads(manifest.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return "its manifest.json cannot be read"
    if not isinstance(doc, dict) or not str(doc.get("generator", "")).startswith("ppfab"):
        return "its manifest.json was not written by ppfab"
    listed: dict[str, str] = doc["sha256"] if isinstance(doc.get("sha256"), dict) else {}
    for p in sorted(root.rglob("*")):
        rel = p.relative_to(root).as_posix()
        if p.is_symlink():
            return f"it holds a symbolic link {rel}"
        if p.is_dir() or rel == "manifest.json":
            continue
        if rel not in listed:
            return f"it holds {rel}, which ppfab did not write"
        if not p.is_file() or _sha256(p) != listed[rel]:
            return f"{rel} was changed after the build"
    return None


def check_target(target: str | os.PathLike, force: bool = False, protect: Iterable[str | os.PathLike] = ()) -> None:
    """Raise :class:`OutputExistsError` when ``target`` may not be written (or, with ``force``, replaced).

    ``protect`` lists input files (design, mesh) the output folder must not hold.
    """
    given = str(target)
    path = Path(target)
    if path.is_symlink():
        where = os.readlink(path)
        state = "" if path.exists() else ", which does not exist"
        raise OutputExistsError(f"output path {given} is a symbolic link (to {where}{state}); give a folder path")
    full = Path(os.path.realpath(path))
    cwd = Path(os.path.realpath(os.getcwd()))
    if full == cwd or full in cwd.parents:
        raise OutputExistsError(f"output folder {given} is the current folder or holds it; "
                                "choose a new folder for the build")
    for f in protect:
        src = Path(os.path.realpath(f))
        if full == src or full in src.parents:
            raise OutputExistsError(f"output folder {given} holds the input {f}; choose another output folder")
    if not path.exists():
        return
    if not path.is_dir():
        raise OutputExistsError(f"output path {given} exists and is not a folder")
    if not force:
        raise OutputExistsError(f"output folder {given} exists (use --force to replace it)")
    why = previous_build_problem(path)
    if why is not None:
        raise OutputExistsError(f"output folder {given} is not a previous ppfab build ({why}); "
                                "--force replaces only a ppfab build: choose another output folder")


class AtomicFolder:
    """``with AtomicFolder(out, force) as tmp:`` — write into ``tmp``; committed on success."""

    def __init__(self, target: str | os.PathLike, force: bool = False, protect: Iterable[str | os.PathLike] = ()):
        self.target = Path(os.path.abspath(target))
        self.force = force
        self.protect = tuple(protect)
        check_target(target, force, self.protect)
        self.tmp = self.target.parent / f".{self.target.name}.tmp-{uuid.uuid4().hex[:8]}"
        self._lock = OutputLock(self.target)

    def __enter__(self) -> Path:
        self._lock.__enter__()
        try:
            check_target(self.target, self.force, self.protect)      # again, under the lock
            remove_stale(self.target, previous_build_problem)
            self.tmp.mkdir()
            write_marker(self.tmp)
        except OSError as exc:
            self._cleanup()
            raise OutputExistsError(f"cannot create output folder beside {self.target} ({exc.strerror})") from None
        except BaseException:
            self._cleanup()
            raise
        return self.tmp

    def _cleanup(self) -> None:
        shutil.rmtree(self.tmp, ignore_errors=True)
        self._lock.__exit__(None, None, None)

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> Literal[False]:
        if exc_type is not None:
            self._cleanup()
            return False
        old = None
        try:
            (self.tmp / MARKER).unlink()
            if self.target.exists():
                old = self.target.parent / f".{self.target.name}.old-{os.getpid()}-{uuid.uuid4().hex[:8]}"
                os.replace(self.target, old)
            os.replace(self.tmp, self.target)
        except BaseException:
            if old is not None and not self.target.exists():
                os.replace(old, self.target)
            self._cleanup()
            raise
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        self._lock.__exit__(None, None, None)
        return False


@contextlib.contextmanager
def atomic_file(path: str | os.PathLike) -> Iterator[Path]:
    """``with atomic_file(p) as tmp:`` — write the file ``tmp`` (a sibling of ``p`` with the same suffix);
    it replaces ``p`` in one rename when the block succeeds and is removed when it fails.  ``p`` must not
    be a folder or a symbolic link."""
    p = Path(path)
    if p.is_symlink() or (p.exists() and not p.is_file()):
        kind = "a symbolic link" if p.is_symlink() else "a folder" if p.is_dir() else "not a regular file"
        raise OutputExistsError(f"output {path} is {kind}; give the path of a file")
    tmp = p.parent / f".{p.stem}.tmp-{uuid.uuid4().hex[:8]}{p.suffix}"
    try:
        yield tmp
        os.replace(tmp, p)
    finally:
        if tmp.exists():
            tmp.unlink()
