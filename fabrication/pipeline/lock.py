"""One writer per output folder, and the leftovers of runs that were killed.

:class:`OutputLock` holds an exclusive ``flock`` on ``.NAME.lock`` beside the output folder ``NAME`` for as
long as a run works on it; a second run to the same folder is refused at once with the first one's pid
(the kernel drops the lock when a process dies, even by SIGKILL, so a lock is never stale; a forked
helper process, which shares the lock, dies with its parent: :mod:`fabrication.writers._parallel`).  The lock
is re-entrant within one process: the command line takes it before the compute stages and
:meth:`~fabrication.pipeline.records.Build.write` takes it again around the writers.

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

import errno
import json
import logging
import os
import re
import shutil
import socket
from pathlib import Path
from typing import Any

try:                                    # POSIX; elsewhere builds are not locked
    import fcntl
except ImportError:  # pragma: no cover
    fcntl = None  # type: ignore[assignment]

from ppfab.errors import PpfabError

log = logging.getLogger("ppfab")

MARKER = ".ppfab-partial"
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
    try:
        doc = json.loads((folder / MARKER).read_text(encoding="utf-8"))
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
        while True:
            try:
                fh = open(self.path, "a+", encoding="utf-8")
            except OSError as exc:
                raise OutputBusyError(f"cannot create the lock file {self.path} ({exc.strerror})") from None
            try:
                fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                fh.seek(0)
                other = fh.read().strip()
                fh.close()
                if exc.errno not in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                    raise OutputBusyError(f"cannot lock {self.path} ({exc.strerror})") from None
                who = f" (pid {json.loads(other).get('pid')})" if other.startswith("{") else ""
                raise OutputBusyError(f"output folder {self.target} is being written by another ppfab run{who}; "
                                      "wait for it to finish or choose another output folder") from None
            # the file may have been removed by a run that just finished: lock the file that is there now
            try:
                same = os.path.samestat(os.fstat(fh.fileno()), os.stat(self.path))
            except FileNotFoundError:
                same = False
            if same:
                break
            fh.close()
        fh.seek(0)
        fh.truncate()
        fh.write(json.dumps(process_record()) + "\n")
        fh.flush()
        _HELD[self.path] = [fh, 1]
        return self

    def __exit__(self, *exc: object) -> None:
        held = _HELD[self.path]
        held[1] -= 1
        if held[1] > 0:
            return
        del _HELD[self.path]
        fh = held[0]
        if fh is None:  # pragma: no cover
            return
        try:
            os.unlink(self.path)                # while still locked: nobody can hold a lock on it now
        except OSError:
            pass
        fh.close()
        for p in self._made:                    # innermost first; only empty ones go
            try:
                p.rmdir()
            except OSError:
                break


def holds_lock(target: str | os.PathLike) -> bool:
    """Whether this process holds the :class:`OutputLock` of ``target``."""
    return lock_path(Path(os.path.abspath(target))) in _HELD


def remove_stale(target: Path, is_build: Any) -> list[Path]:
    """Delete the leftovers of killed runs writing ``target`` (the caller holds its lock); returns them.

    ``is_build(folder) -> str | None`` tells whether a folder is a complete ppfab build (``None``) or why not.
    """
    removed: list[Path] = []
    name = re.escape(target.name)
    tmp_re = re.compile(rf"^\.{name}\.tmp-[0-9a-f]+$")
    old_re = re.compile(rf"^\.{name}\.old-([0-9]+)-[0-9a-f]+$")
    try:
        entries = list(target.parent.iterdir())
    except OSError:
        return removed
    host = socket.gethostname()
    for p in sorted(entries):
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
            if not target.exists():         # killed between moving the old build aside and the rename
                os.replace(p, target)
                log.info("restored %s from %s, left behind by a run that was killed", target, p)
                continue
        shutil.rmtree(p, ignore_errors=True)
        log.info("removed %s, left behind by a run that was killed", p)
        removed.append(p)
    return removed
