"""Atomic output folders: written through a temporary sibling and renamed into place (single files:
:mod:`fabrication.pipeline.overwrite`).

:class:`AtomicFolder` writes into a temporary folder beside the target and
renames it into place only when the whole run succeeded; on any failure
(exception, Ctrl-C, SIGTERM, SIGHUP) the temporary folder is removed and an existing target
is left untouched.  While it works it holds the target's :class:`~fabrication.pipeline.lock.OutputLock`,
and it first removes the leftovers of killed runs (:func:`~fabrication.pipeline.lock.remove_stale`).

What may be replaced (:func:`check_target`): with ``force``, only a folder that is a previous ppfab build
(:func:`previous_build_problem`) — never a symbolic link, the current folder or one holding it, or a
folder holding an input (the design file, the mesh file).  That is checked again right before each rename
of the commit (a folder that appeared, a previous build that changed while the build was written: refused,
the finished build kept in its temporary folder), and a previous build is removed file by file, only what
its manifest lists unchanged (:func:`remove_build`), never with ``rmtree``.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import shutil
import stat
import uuid
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Iterable, Literal

from ppfab.errors import PpfabError

from .lock import MARKER, OutputLock, remove_stale, write_marker
from . import overwrite
from .. import interrupts
from .overwrite import rename_noreplace

log = logging.getLogger("ppfab")


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


@dataclass(frozen=True)
class FolderState:
    """What is at a path, to tell later whether anything changed: the path's own ``(st_dev, st_ino,
    st_mode)``, and for a folder every entry below it as ``(relative path, mode, size, mtime_ns, inode)``
    (symbolic links not followed)."""

    root: tuple[int, int, int]
    entries: tuple[tuple[str, int, int, int, int], ...]

    def difference(self, now: "FolderState | None") -> str | None:
        """``None`` when ``now`` is this state, else what changed (one phrase, for a message)."""
        if now is None:
            return "was removed"
        if now.root != self.root:
            return "was replaced"
        before = {e[0]: e for e in self.entries}
        after = {e[0]: e for e in now.entries}
        for rel in sorted(after.keys() - before.keys()):
            return f"gained {rel}"
        for rel in sorted(before.keys() - after.keys()):
            return f"lost {rel}"
        for rel in sorted(before):
            if before[rel] != after[rel]:
                return f"had {rel} changed"
        return None


def folder_state(path: str | os.PathLike) -> FolderState | None:
    """The :class:`FolderState` of ``path``; ``None`` when nothing is there (not even a dangling link)."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return None
    root = (st.st_dev, st.st_ino, st.st_mode)
    if not stat.S_ISDIR(st.st_mode):
        return FolderState(root, ())
    entries = []
    for dirpath, dirnames, filenames in os.walk(os.fspath(path)):
        for name in dirnames + filenames:
            full = os.path.join(dirpath, name)
            try:
                e = os.lstat(full)
            except FileNotFoundError:
                continue
            entries.append((os.path.relpath(full, path), e.st_mode, e.st_size, e.st_mtime_ns, e.st_ino))
    return FolderState(root, tuple(sorted(entries)))


def remove_build(folder: str | os.PathLike) -> list[str]:
    """Remove the ppfab build ``folder`` file by file; returns the relative paths it had to leave (empty when
    the folder is gone).

    A file goes only when its manifest lists it and its sha256 is the listed one; folders go only when
    empty (``rmdir``); ``manifest.json`` and the folder itself go last, only when nothing else remained.  A
    file that appears or changes while this runs is therefore never removed, unlike with ``rmtree``.
    """
    root = Path(folder)
    try:
        doc = json.loads((root / "manifest.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        doc = None
    ok = isinstance(doc, dict) and str(doc.get("generator", "")).startswith("ppfab")
    listed: dict[str, str] = doc["sha256"] if ok and isinstance(doc.get("sha256"), dict) else {}
    left: list[str] = []
    for dirpath, dirnames, filenames in os.walk(root, topdown=False):
        for name in filenames + dirnames:
            p = Path(dirpath) / name
            rel = p.relative_to(root).as_posix()
            if p.is_symlink():
                left.append(rel)
            elif p.is_dir():
                with contextlib.suppress(OSError):
                    p.rmdir()
            elif rel == "manifest.json" and ok:
                continue
            elif rel in listed and p.is_file() and _sha256(p) == listed[rel]:
                p.unlink()
            else:
                left.append(rel)
    if left:
        return sorted(left)
    if ok:
        with contextlib.suppress(FileNotFoundError):
            (root / "manifest.json").unlink()
    try:
        root.rmdir()
    except OSError:
        return sorted(p.name for p in root.iterdir())
    return []


class OutputChangedError(OutputExistsError):
    """The output folder appeared or changed while the build was written; the finished build is kept."""

    def __init__(self, message: str, kept: Path):
        self.kept = kept
        super().__init__(message)


class AtomicFolder:
    """``with AtomicFolder(out, force) as tmp:`` — write into ``tmp``; committed on success.

    The commit, under the lock, checks the target again right before each rename: when there was no
    folder at the start and there is one now, or when (``force``) the previous build is no longer exactly
    what was checked (:class:`FolderState` and :func:`previous_build_problem`), nothing is renamed or removed
    and :class:`OutputChangedError` names the temporary folder that keeps the finished build.  The previous
    build, moved aside, is removed by :func:`remove_build` only.  :data:`~fabrication.pipeline.overwrite.COMMIT_HOOKS`
    run right before these checks.
    """

    def __init__(self, target: str | os.PathLike, force: bool = False, protect: Iterable[str | os.PathLike] = ()):
        self.target = Path(os.path.abspath(target))
        self.force = force
        self.protect = tuple(protect)
        check_target(target, force, self.protect)
        self.tmp = self.target.parent / f".{self.target.name}.tmp-{uuid.uuid4().hex[:8]}"
        self._lock = OutputLock(self.target)
        self._start: FolderState | None = None

    def __enter__(self) -> Path:
        self._lock.__enter__()
        try:
            check_target(self.target, self.force, self.protect)      # again, under the lock
            self._start = folder_state(self.target)
            remove_stale(self.target, previous_build_problem, remove_build)
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

    def _refuse(self, what: str, old: Path | None = None) -> OutputChangedError:
        """Keep the finished build where it is, release the lock, and say so."""
        self._lock.__exit__(None, None, None)
        where = f"; the previous build is in {old}" if old is not None else ""
        return OutputChangedError(f"output folder {self.target} {what} while the build was written, so nothing "
                                  f"was replaced or removed{where}; the finished build is in {self.tmp}",
                                  kept=self.tmp)

    def _problem(self, path: Path) -> str | None:
        """What changed at ``path`` (the target, or the previous build moved aside) since the start."""
        now = folder_state(path)
        if self._start is None:
            return None if now is None else "appeared"
        why = self._start.difference(now)
        if why is None:
            why = previous_build_problem(path)
            why = None if why is None else f"changed ({why})"
        return why

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> Literal[False]:
        if exc_type is not None:
            self._cleanup()
            return False
        try:
            interrupts.check()              # a signal whose interruption a library swallowed: commit nothing
            (self.tmp / MARKER).unlink()
            for hook in list(overwrite.COMMIT_HOOKS):
                hook(self.target, self.tmp)
        except BaseException:
            self._cleanup()
            raise
        why = self._problem(self.target)                            # right before the first rename
        if why is not None:
            raise self._refuse(why)
        old = None
        if self._start is not None:
            old = self.target.parent / f".{self.target.name}.old-{os.getpid()}-{uuid.uuid4().hex[:8]}"
            try:
                rename_noreplace(self.target, old)
            except FileNotFoundError:
                raise self._refuse("was removed") from None
            why = self._problem(old)                                # written to just before it moved?
            if why is not None:
                try:
                    rename_noreplace(old, self.target)
                except OSError:
                    raise self._refuse(why, old) from None
                raise self._refuse(why)
        try:
            rename_noreplace(self.tmp, self.target)
        except FileExistsError:
            restored = False
            if old is not None:
                with contextlib.suppress(OSError):
                    rename_noreplace(old, self.target)
                    restored = True
            raise self._refuse("appeared", None if restored else old) from None
        except BaseException:
            if old is not None:
                with contextlib.suppress(OSError):
                    rename_noreplace(old, self.target)
            self._cleanup()
            raise
        if old is not None:
            left = remove_build(old)
            if left:
                log.warning("kept %s, the previous build of %s: %s appeared in it while it was replaced",
                            old, self.target, ", ".join(left[:3]))
        self._lock.__exit__(None, None, None)
        return False
