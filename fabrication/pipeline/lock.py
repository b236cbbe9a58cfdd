"""One writer per output folder, and the leftovers of runs that were killed.

:class:`OutputLock` holds an exclusive ``flock`` on ``.NAME.lock`` beside the output folder ``NAME`` for as
long as a run works on it; a second run to the same folder is refused at once with the first one's pid
(the kernel drops the lock when a process dies, even by SIGKILL, so a lock is never stale; a forked
helper process, which shares the lock, dies with its parent: :mod:`fabrication.writers._parallel`).  The lock
is re-entrant within one process: the command line takes it before the compute stages and
:meth:`~fabrication.pipeline.records.Build.write` takes it again around the writers.

The lock file is only ever created new (``O_CREAT | O_EXCL | O_NOFOLLOW`` under a fresh name, then
hard-linked into place, see :func:`_create_locked`): ppfab never opens what it finds at the lock path for
writing, never follows a symbolic link there and never truncates a file.  A symbolic link, a folder or a
file that is not a ppfab lock record at that path is refused in one line and left as it is; the lock file
of a killed run (a ppfab record nobody holds) is removed and a new one made.

A temporary folder carries :data:`MARKER`, a small JSON record ``{pid, host, start}`` of the run writing
it (``start`` is the process start time, so a recycled pid is not mistaken for the writer).
:func:`remove_stale` deletes, while the lock is held, the temporary folders of ``NAME`` whose marker
names a process of this host that no longer runs (or that hold nothing but an unfinished marker: the run
died between making the folder and writing it), and the ``.NAME.old-<pid>-…`` folders (a previous
build moved aside during a replacement) of dead pids that are still complete ppfab builds — put back as
``NAME`` when the run died before its own folder took that name.  Nothing without these signs is ever
deleted.
"""

from __future__ import annotations

import contextlib
import errno
import json
import logging
import os
import re
import shutil
import socket
import stat
import uuid
from pathlib import Path
from typing import Any

try:                                    # POSIX; elsewhere builds are not locked
    import fcntl
except ImportError:  # pragma: no cover
    fcntl = None  # type: ignore[assignment]

from ppfab.errors import PpfabError

from ..contract import PARTIAL_MARKER
from .overwrite import rename_noreplace

log = logging.getLogger("ppfab")

MARKER = PARTIAL_MARKER
"""File inside a temporary output folder naming the process that writes it (removed before the rename)."""


class OutputBusyError(PpfabError):
    """Another run is writing the same output folder."""

    exit_code = 2


def _start_time(pid: int) -> str:
    """The start time of process ``pid`` (clock ticks since boot, from ``/proc``), ``""`` when unknown."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return ""
    return stat.rsplit(")", 1)[-1].split()[19]


def process_record() -> dict[str, Any]:
    """``{pid, host, start}`` of this process (the content of :data:`MARKER`)."""
    return {"pid": os.getpid(), "host": socket.gethostname(), "start": _start_time(os.getpid())}


def process_alive(record: dict[str, Any]) -> bool:
    """Whether the process of a :func:`process_record` still runs (``True`` when that cannot be told:
    another host, a malformed record, a process of another user)."""
    try:
        pid = int(record["pid"])
        host = str(record["host"])
        start = str(record.get("start", ""))
    except (KeyError, TypeError, ValueError):
        return True
    if host != socket.gethostname() or pid <= 0:
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    now = _start_time(pid)
    return not (start and now and now != start)


def write_marker(folder: Path) -> None:
    (folder / MARKER).write_text(json.dumps(process_record()) + "\n", encoding="utf-8")


def _read_marker(folder: Path) -> dict[str, Any] | None:
    return _read_record(folder / MARKER)


def _read_record(path: Path) -> dict[str, Any] | None:
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return doc if isinstance(doc, dict) else None


def _unstarted(folder: Path) -> bool:
    """Whether ``folder`` holds nothing but, at most, an unfinished :data:`MARKER`: a run killed between
    making its temporary folder and writing the marker.  A live run writing it would hold the lock the
    caller of :func:`remove_stale` holds, and there is nothing in it to lose."""
    try:
        entries = list(folder.iterdir())
    except OSError:
        return False
    return all(e.name == MARKER and e.is_file() and not e.is_symlink() for e in entries)


def lock_path(target: Path) -> Path:
    return target.parent / f".{target.name}.lock"


_HELD: dict[Path, list[Any]] = {}          # lock file → [open file, depth] (re-entrant within a process)


class OutputLock:
    """``with OutputLock(out):`` — exclusive use of the output folder ``out`` (see the module docstring).

    The folder's parent is created when missing.  Raises :class:`OutputBusyError` naming the other run's
    pid when the folder is being written.
    """

    def __init__(self, target: str | os.PathLike):
        self.target = Path(os.path.abspath(target))
        self.path = lock_path(self.target)
        self._made: list[Path] = []                 # parent folders created here (removed again if left empty)

    def __enter__(self) -> "OutputLock":
        held = _HELD.get(self.path)
        if held is not None:
            held[1] += 1
            return self
        if fcntl is None:  # pragma: no cover
            _HELD[self.path] = [None, 1]
            return self
        try:
            missing = [p for p in [self.target.parent, *self.target.parent.parents] if not p.exists()]
            self.target.parent.mkdir(parents=True, exist_ok=True)
            self._made = missing
        except OSError as exc:
            raise OutputBusyError(f"cannot create the folder {self.target.parent} ({exc.strerror})") from None
        for _ in range(100):
            fd = _create_locked(self.path)
            if fd is None:
                _take_existing(self.path, self.target)
            else:
                _HELD[self.path] = [fd, 1]
                return self
        raise OutputBusyError(f"cannot take the lock file {self.path}: it keeps changing; "
                              "wait for the other ppfab runs to finish")

    def __exit__(self, *exc: object) -> None:
        held = _HELD[self.path]
        held[1] -= 1
        if held[1] > 0:
            return
        del _HELD[self.path]
        fd = held[0]
        if fd is None:  # pragma: no cover
            return
        try:                                    # while still locked, and only the file this run made
            if os.path.samestat(os.fstat(fd), os.lstat(self.path)):
                os.unlink(self.path)
        except OSError:
            pass
        os.close(fd)
        for p in self._made:                    # innermost first; only empty ones go
            try:
                p.rmdir()
            except OSError:
                break


_OPEN_NEW = os.O_RDWR | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | getattr(os, "O_CLOEXEC", 0)
_OPEN_OLD = os.O_RDWR | os.O_NOFOLLOW | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0)


def _create_locked(path: Path) -> int | None:
    """A new lock file at ``path``, already locked and holding this run's record; ``None`` when anything
    (a file, a symbolic link, a folder) is at ``path``.

    The file is made under a fresh name with ``O_CREAT | O_EXCL | O_NOFOLLOW``, locked and written there,
    then hard-linked to ``path`` (``link`` neither follows nor replaces what is at its destination), so the
    lock file never exists empty or unlocked and nothing at ``path`` is ever opened for writing.
    """
    spare = path.with_name(f"{path.name}-{uuid.uuid4().hex[:8]}")
    try:
        fd = os.open(spare, _OPEN_NEW, 0o644)
    except OSError as exc:
        raise OutputBusyError(f"cannot create the lock file {path} ({exc.strerror})") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)          # nobody else can know this file yet
        os.write(fd, (json.dumps(process_record()) + "\n").encode("utf-8"))
        os.link(spare, path)
    except FileExistsError:
        os.close(fd)
        return None
    except OSError as exc:
        os.close(fd)
        if exc.errno in (errno.EPERM, errno.ENOTSUP, errno.ENOSYS):    # no hard links on this file system
            return _create_in_place(path)
        raise OutputBusyError(f"cannot create the lock file {path} ({exc.strerror})") from None
    finally:
        with contextlib.suppress(OSError):
            os.unlink(spare)
    return fd


def _create_in_place(path: Path) -> int | None:
    """:func:`_create_locked` where the file system has no hard links: ``O_CREAT | O_EXCL | O_NOFOLLOW`` at
    ``path`` itself (a run that looks in the instant before the lock and record are in place refuses)."""
    try:
        fd = os.open(path, _OPEN_NEW, 0o644)
    except FileExistsError:
        return None
    except OSError as exc:
        raise OutputBusyError(f"cannot create the lock file {path} ({exc.strerror})") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(fd)                    # another run took it in that instant and will say what to do
        return None
    os.write(fd, (json.dumps(process_record()) + "\n").encode("utf-8"))
    return fd


def _is_record(text: str) -> bool:
    try:
        doc = json.loads(text)
    except ValueError:
        return False
    return isinstance(doc, dict) and {"pid", "host"} <= doc.keys()


def _take_existing(path: Path, target: Path) -> None:
    """Deal with what is at the lock path ``path``: raise :class:`OutputBusyError` when another run holds it
    or when it is not a ppfab lock file (a symbolic link, a folder, a file ppfab did not write: one-line
    refusal, nothing opened for writing, nothing truncated); remove it when it is the lock file of a run that
    was killed.  The caller then tries to create the lock file again."""
    try:
        fd = os.open(path, _OPEN_OLD)               # no O_CREAT, no O_TRUNC: reads what is there
    except FileNotFoundError:
        return                                      # removed by a run that just finished
    except OSError as exc:
        if os.path.islink(path):
            raise OutputBusyError(f"lock file {path} is a symbolic link (to {os.readlink(path)}), which ppfab "
                                  "did not make; remove it and run again") from None
        kind = "a folder" if path.is_dir() else exc.strerror
        raise OutputBusyError(f"lock file {path} cannot be used ({kind}); ppfab did not make it: "
                              "remove it and run again") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_uid != os.geteuid():
            what = "not a regular file" if not stat.S_ISREG(st.st_mode) else "owned by another user"
            raise OutputBusyError(f"lock file {path} is {what}, so ppfab did not make it; "
                                  "remove it and run again")
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            if exc.errno not in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                raise OutputBusyError(f"cannot lock {path} ({exc.strerror})") from None
            other = os.pread(fd, 4096, 0).decode("utf-8", "replace").strip()
            who = f" (pid {json.loads(other).get('pid')})" if _is_record(other) else ""
            raise OutputBusyError(f"output folder {target} is being written by another ppfab run{who}; "
                                  "wait for it to finish or choose another output folder") from None
        try:                                        # still the file at the path (not one just removed)?
            if not os.path.samestat(st, os.lstat(path)):
                return
        except FileNotFoundError:
            return
        text = os.pread(fd, 4096, 0).decode("utf-8", "replace").strip()
        if not _is_record(text):
            raise OutputBusyError(f"lock file {path} was not written by ppfab ({st.st_size} bytes of something "
                                  "else); remove it and run again")
        os.unlink(path)                             # left by a killed run: removed, never reused
        log.info("removed %s, left behind by a run that was killed", path)
    finally:
        os.close(fd)


def holds_lock(target: str | os.PathLike) -> bool:
    """Whether this process holds the :class:`OutputLock` of ``target``."""
    return lock_path(Path(os.path.abspath(target))) in _HELD


def remove_stale(target: Path, is_build: Any, remove_build: Any = None) -> list[Path]:
    """Delete the leftovers of killed runs writing ``target`` (the caller holds its lock); returns them.

    ``is_build(folder) -> str | None`` tells whether a folder is a complete ppfab build (``None``) or why not;
    ``remove_build(folder) -> list[str]`` removes such a build file by file and returns what it had to leave
    (:func:`~fabrication.pipeline.folder.remove_build`; without it the folder is removed whole).
    """
    removed: list[Path] = []
    name = re.escape(target.name)
    tmp_re = re.compile(rf"^\.{name}\.tmp-[0-9a-f]+$")
    old_re = re.compile(rf"^\.{name}\.old-([0-9]+)-[0-9a-f]+$")
    spare_re = re.compile(rf"^\.{name}\.lock-[0-9a-f]{{8}}$")
    try:
        entries = list(target.parent.iterdir())
    except OSError:
        return removed
    host = socket.gethostname()
    for p in sorted(entries):
        if spare_re.match(p.name) and p.is_file() and not p.is_symlink():
            rec = _read_record(p)           # a lock file of a run killed before it took its place
            if rec is not None and not process_alive(rec):
                p.unlink()
                removed.append(p)
            continue
        if p.is_symlink() or not p.is_dir():
            continue
        if tmp_re.match(p.name):
            rec = _read_marker(p)
            if rec is None and not _unstarted(p):
                continue
            if rec is not None and process_alive(rec):
                continue
        else:
            m = old_re.match(p.name)
            if m is None or process_alive({"pid": int(m.group(1)), "host": host}) or is_build(p) is not None:
                continue
            if not os.path.lexists(target):     # killed between moving the old build aside and the rename
                try:
                    rename_noreplace(p, target)
                except FileExistsError:
                    continue
                log.info("restored %s from %s, left behind by a run that was killed", target, p)
                continue
            if remove_build is not None:
                left = remove_build(p)
                if left:
                    log.warning("kept %s, left behind by a run that was killed: it holds %s, which ppfab "
                                "did not write", p, ", ".join(left[:3]))
                    continue
                log.info("removed %s, left behind by a run that was killed", p)
                removed.append(p)
                continue
        shutil.rmtree(p, ignore_errors=True)
        log.info("removed %s, left behind by a run that was killed", p)
        removed.append(p)
    return removed
