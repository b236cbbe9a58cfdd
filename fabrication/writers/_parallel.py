"""Writing the output files on two cores: the writers of :data:`SECOND_PROCESS` in a forked process.

The writers are independent except through the ``files`` table: some read the file names that earlier
writers recorded (the report's list of files, the manifest's digests; the sheet files of ``parts.csv`` come
from the build's parts list, not from the DXF writer).
The writers named in :data:`SECOND_PROCESS` read nothing of it; they run in one forked child process while
this process runs all the others in their order.  The child is joined before the first writer of
:data:`READS_EVERY_FILE` (the report lists every file, the manifest digests every file), and the ``files``
table each writer sees, and the one returned, are assembled in writer order from what each writer added —
exactly the table of a serial run, so every file is byte-identical to a serial build.

Safety (:mod:`fabrication.pipeline.folder`): the child only writes into the temporary folder; it ignores
SIGINT (a Ctrl-C reaches the whole process group: this process decides) and dies on SIGTERM/SIGHUP; it ends
with ``os._exit`` (``multiprocessing``), never unwinding this process's ``with`` blocks, so the atomic folder,
its lock and its clean-up stay with this process.  When this process fails or is interrupted, the child is
terminated and joined before the exception leaves :func:`write_split`, i.e. before the temporary folder is
removed.  When the child fails, its writers run again here, so the error raised is the writer's own.

Used when fork is available and the process may run on at least two cores (:func:`parallel_enabled`);
``PPFAB_PARALLEL_WRITERS=0`` turns it off, ``=1`` on.
"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

from .base import Files, Writer

if TYPE_CHECKING:  # pragma: no cover
    from ..progress import Progress
    from ..records import BuildRecord

SECOND_PROCESS: tuple[str, ...] = ("dxf_types",)
"""Writers that read nothing of the ``files`` table and run in the second process: the per-type DXFs (one file
per panel type, the largest share of the DXF time), beside STEP, the sheets, tables, exchange files and report
(at 22x15 to 88x60 faces the two halves take about the same time)."""

READS_EVERY_FILE: tuple[str, ...] = ("report", "manifest")
"""Writers that read the whole ``files`` table: the second process is joined before the first of them."""


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):          # pragma: no cover - not Linux
        return os.cpu_count() or 1


def parallel_enabled() -> bool:
    """Whether :func:`~fabrication.writers.write_all` uses a second process: ``PPFAB_PARALLEL_WRITERS`` = 0 or 1
    when set, else on when fork is available and at least two cores are."""
    import multiprocessing

    if "fork" not in multiprocessing.get_all_start_methods():
        return False
    flag = os.environ.get("PPFAB_PARALLEL_WRITERS", "").strip()
    if flag in ("0", "1"):
        return flag == "1"
    return cores() >= 2


def _merged(added: dict[str, Files], order: list[str]) -> Files:
    """The ``files`` table after the writers ``order`` (their additions, in that order)."""
    files: Files = {}
    for name in order:
        files.update(added.get(name, {}))
    return files


def _run(w: Writer, build: "BuildRecord", out: Path, before: Files) -> tuple[Files, str]:
    """Run one writer on a copy of the table ``before``; what it added and its note."""
    files = dict(before)
    note = w.write(build, out, files)
    return {k: v for k, v in files.items() if k not in before or before[k] != v}, note


class Forked:
    """``job()`` run in a forked process (``multiprocessing``), its result sent back through a pipe.

    The child ignores SIGINT (a Ctrl-C reaches the whole process group: the parent decides), dies on
    SIGTERM/SIGHUP and with its parent (:func:`_die_with_parent`), and ends with ``os._exit`` (never
    unwinding the parent's ``with`` blocks).  :meth:`result` waits for it: ``("ok", value)``, or ``("failed", why)`` when ``job`` raised or the process died first;
    :meth:`close` terminates it if still running and joins it (call it in a ``finally``).  Used by the writers
    here and by ``ppfab verify`` (:func:`fabrication.verify.verify`)."""

    def __init__(self, job: Callable[[], Any], name: str):
        import multiprocessing

        ctx = multiprocessing.get_context("fork")
        self._recv, send = ctx.Pipe(duplex=False)
        self._proc = ctx.Process(target=_forked_main, args=(job, send, os.getpid()), name=name, daemon=True)
        self._proc.start()
        send.close()

    def result(self) -> tuple[str, Any]:
        try:
            out = self._recv.recv()
        except EOFError:                        # killed (e.g. out of memory) before it could report
            out = ("failed", f"the {self._proc.name} process ended with code {self._proc.exitcode}")
        self._proc.join()
        return out

    def close(self) -> None:
        if self._proc.is_alive():
            self._proc.terminate()
        self._proc.join()
        self._recv.close()


def _die_with_parent(parent: int) -> None:
    """Ask the kernel to SIGKILL this process when its parent dies (Linux ``prctl(PR_SET_PDEATHSIG)``).

    A parent killed with SIGKILL runs no clean-up; without this its forked child would go on writing into the
    temporary folder and, sharing the parent's lock file, keep the output folder locked.  Ends at once when
    the parent is already gone.  Elsewhere (no ``prctl``) nothing is done."""
    import ctypes

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)          # 1 = PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # pragma: no cover - not Linux
        return
    if os.getppid() != parent:                                  # the parent died before prctl
        os._exit(1)


def _forked_main(job: Callable[[], Any], conn: Any, parent: int) -> None:
    _die_with_parent(parent)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for s in (getattr(signal, "SIGTERM", None), getattr(signal, "SIGHUP", None)):
        if s is not None:
            signal.signal(s, signal.SIG_DFL)
    try:
        conn.send(("ok", job()))
    except BaseException as exc:                # reported; the parent runs the work again for its error
        conn.send(("failed", f"{type(exc).__name__}: {exc}"))
    finally:
        conn.close()


def _side_writers(build: "BuildRecord", out: Path, writers: list[Writer]) -> list[tuple[str, Files, str, float]]:
    """The second process's work: run ``writers`` (each on an empty table); their additions, notes and times."""
    results = []
    for w in writers:
        t0 = time.perf_counter()
        added, note = _run(w, build, out, {})
        results.append((w.name, added, note, time.perf_counter() - t0))
    return results


def write_split(build: "BuildRecord", out: Path, progress: "Progress", writers: list[Writer]) -> Files:
    """Run ``writers`` (enabled, in order) with those of :data:`SECOND_PROCESS` in a forked process; returns the
    ``files`` table, equal to that of a serial run."""
    side = [w for w in writers if w.name in SECOND_PROCESS]
    order = [w.name for w in writers]
    added: dict[str, Files] = {}
    joined = False
    main = [w.name for w in writers if w.name not in SECOND_PROCESS]
    proc = Forked(lambda: _side_writers(build, out, side), "ppfab-writer")
    progress.watch(out)                       # the status counts the files written so far (both processes)
    try:
        for k, w in enumerate(writers):
            if w.name in SECOND_PROCESS:
                continue
            if not joined and w.name in READS_EVERY_FILE:
                _join(build, out, progress, proc, side, added, order)
                joined = True
            progress.start(w.name)
            i = main.index(w.name)
            progress.advance(i, None, f"file set {i + 1} of {len(main)}")
            try:
                added[w.name], note = _run(w, build, out, _merged(added, order[:k]))
            except BaseException:
                progress.fail()
                raise
            progress.done(note)
        if not joined:
            _join(build, out, progress, proc, side, added, order)
    finally:
        progress.watch(None)
        proc.close()
    return _merged(added, order)


def _join(build: "BuildRecord", out: Path, progress: "Progress", proc: Forked, side: list[Writer],
          added: dict[str, Files], order: list[str]) -> None:
    """Wait for the second process; record its writers (progress and times), or run them here if it failed."""
    status, payload = proc.result()
    if status == "ok":
        for name, files, note, seconds in payload:
            progress.start(name, "(second process)")
            progress._t0 = time.perf_counter() - seconds     # show and record the child's wall time
            progress.done(note)
            added[name] = files
        return
    for w in side:                              # again here: the writer's own exception, or success
        progress.start(w.name)
        try:
            added[w.name], note = _run(w, build, out, _merged(added, order[:order.index(w.name)]))
        except BaseException:
            progress.fail()
            raise
        progress.done(note)
