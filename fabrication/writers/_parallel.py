"""Writing the output files on two cores: the writers of :data:`SECOND_PROCESS` in a forked process.

The writers are independent: each reads the build and the ``files`` table every writer declared before any
wrote (:func:`~fabrication.writers.declared_files`).  Those named in :data:`SECOND_PROCESS` run in one forked
child process while this process runs all the others in their order; the child is joined before the
writers of :data:`READS_EVERY_FILE` (the manifest digests every file), so every file is byte-identical to a
serial build.

Safety (:mod:`fabrication.pipeline.folder`): the child only writes into the temporary folder; it ignores
SIGINT (a Ctrl-C reaches the whole process group: this process decides) and dies on SIGTERM/SIGHUP; it ends
with ``os._exit`` (``multiprocessing``), never unwinding this process's ``with`` blocks, so the atomic folder,
its lock and its clean-up stay with this process.  When this process fails or is interrupted, the child is
terminated and joined before the exception leaves :func:`write_split`, i.e. before the temporary folder is
removed.  When the child fails, its writers run again here, so the error raised is the writer's own.

Used when fork is available and the process may run on at least two cores (:func:`parallel_enabled`);
``PPFAB_PARALLEL_WRITERS=0`` turns it off, ``=1`` on.  Without the second process, the writers of
:data:`CONFINED` (whose libraries keep their memory) still run each in a forked process of its own, one at a
time (:func:`confined`), under the same rules.
"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

from .base import Files, Writer, run_writer

if TYPE_CHECKING:  # pragma: no cover
    from ..progress import Progress
    from ..records import BuildRecord

CONFINED: tuple[str, ...] = ("ifc", "rhino", "glb")
"""Writers that run in a forked process that ends when their file is written (:func:`confined`; forked from the
second process when there is one), so that what they allocated goes back to the system: openNURBS's heap stays
with the process (at 44 × 30 faces the 3dm writer left 210 MB resident under the self-check that followed), and
at 88 × 60 the glTF writer (trimesh's scene and the manifold meshes it is built from) left 355 MB.  The IFC
writer left 370 MB at 44 × 30 while it filled IfcOpenShell's file, which never frees its instances
(IfcOpenShell issue 7185); it now writes text (:mod:`fabrication.writers._ifc_text`) and stays confined for the
elements and the type plan it builds.  Where fork is not available they run here."""

SECOND_PROCESS: tuple[str, ...] = ("dxf_types", "ifc", "rhino", "glb")
"""Writers that run in the second process: the per-type DXFs (one file per panel type), the IFC, 3dm and glTF
files, beside STEP, the sheets, tables, drawings and report.  The glTF writer moved here when the IFC writer
stopped going through IfcOpenShell's object model (102 CPU s at 88 × 60 faces before); docs/performance.md gives
the two processes' shares."""

READS_EVERY_FILE: tuple[str, ...] = ("manifest",)
"""Writers that read the files of the second process's writers (the manifest digests every file): the second
process is joined before the first of them.  (The report and the drawing set's PDF read the drawings, written
in this process before them.)"""


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):          # pragma: no cover - not Linux
        return os.cpu_count() or 1


def fork_available() -> bool:
    """Whether this platform can fork a process (``multiprocessing``'s "fork" start method)."""
    import multiprocessing

    return "fork" in multiprocessing.get_all_start_methods()


def parallel_enabled() -> bool:
    """Whether :func:`~fabrication.writers.write_all` uses a second process: ``PPFAB_PARALLEL_WRITERS`` = 0 or 1
    when set, else on when fork is available and at least two cores are."""
    if not fork_available():
        return False
    flag = os.environ.get("PPFAB_PARALLEL_WRITERS", "").strip()
    if flag in ("0", "1"):
        return flag == "1"
    return cores() >= 2


class Forked:
    """``job()`` run in a forked process (``multiprocessing``), its result sent back through a pipe.

    The child ignores SIGINT (a Ctrl-C reaches the whole process group: the parent decides), dies on
    SIGTERM/SIGHUP and with its parent (:func:`_die_with_parent`), and ends with ``os._exit`` (never
    unwinding the parent's ``with`` blocks).  :meth:`result` waits for it: ``("ok", value)``, or ``("failed", why)`` when ``job`` raised or the process died first;
    :meth:`close` terminates it if still running and joins it (call it in a ``finally``).  Used by the writers
    here and by ``ppfab verify`` (:func:`fabrication.verify.verify`).

    ``may_fork``: the child may fork processes of its own (``multiprocessing`` forbids that to a daemon
    process).  It is then no daemon, which changes nothing here: :meth:`close` ends and joins it either way,
    and it dies with its parent."""

    def __init__(self, job: Callable[[], Any], name: str, may_fork: bool = False):
        import multiprocessing

        ctx = multiprocessing.get_context("fork")
        self._recv, send = ctx.Pipe(duplex=False)
        self._proc = ctx.Process(target=_forked_main, args=(job, send, os.getpid()), name=name,
                                 daemon=not may_fork)
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
            self._proc.join(CLOSE_WAIT_S)
            if self._proc.is_alive():           # SIGTERM ignored (a handler inherited before the child set its
                self._proc.kill()               # own): a test run hung on such a child in join()
        self._proc.join()
        self._recv.close()


CLOSE_WAIT_S = 10.0
"""Seconds :meth:`Forked.close` gives a terminated child before it kills it (SIGKILL)."""


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


def _side_writers(build: "BuildRecord", out: Path, writers: list[Writer], files: Files
                  ) -> list[tuple[str, str, float]]:
    """The second process's work: run ``writers``, those of :data:`CONFINED` each in a forked process of its own
    (:func:`confined`); their notes and times.  In the second process itself, the IFC writer's memory (which
    IfcOpenShell kept, when the IFC writer filled its file) lay under the 3dm writer's: at 44 × 30 faces it was the
    build's largest forked process, 920 MB (683 MB for the largest with the two forked apart)."""
    results = []
    for w in writers:
        t0 = time.perf_counter()
        note = (confined(w) if w.name in CONFINED else w).write(build, out, files)
        results.append((w.name, note, time.perf_counter() - t0))
    return results


def in_own_process(job: Callable[[], Any], name: str) -> Any:
    """``job()`` run in a forked process of its own that ends with it (:class:`Forked`), its result sent back, so
    what its libraries keep goes when that process ends.  Without fork, or when no process can be had, it runs
    here; when the process fails it runs again here, so an error raised is the job's own.  For the writers of
    :data:`CONFINED` (:func:`confined`) and verify's checks of :data:`fabrication.verify.CONFINED`."""
    if not fork_available():
        return job()
    try:
        proc = Forked(job, name)
    except OSError:                             # no process to be had
        return job()
    try:
        status, value = proc.result()
    finally:
        proc.close()
    return value if status == "ok" else job()


def confined(w: Writer) -> Writer:
    """``w`` writing in a forked process of its own, waited for (the writers of :data:`CONFINED`, forked from this
    process, or from the second when there is one): what its library keeps goes when that process ends.  Without
    fork, or when no process can be had, it writes here; when the process fails it writes again here, so the error
    raised is the writer's own.  The file written is the same either way (like :func:`~fabrication.writers._failures.guarded`, a writer with
    another ``write``: :func:`~fabrication.writers.base.run_writer` shows and times it as any other)."""
    import dataclasses

    write = w.write

    def confined_write(build: "BuildRecord", out: Path, files: Files) -> str:
        return in_own_process(lambda: write(build, out, files), f"ppfab-{w.name}")

    return dataclasses.replace(w, write=confined_write)


def write_split(build: "BuildRecord", out: Path, progress: "Progress", writers: list[Writer], files: Files) -> None:
    """Run ``writers`` (enabled, in order, the table ``files`` declared) with those of :data:`SECOND_PROCESS` in a
    forked process; the same files as a serial run."""
    side = [w for w in writers if w.name in SECOND_PROCESS]
    joined = False
    main = [w.name for w in writers if w.name not in SECOND_PROCESS]
    proc = Forked(lambda: _side_writers(build, out, side, files), "ppfab-writer", may_fork=True)
    progress.watch(out)                       # the status counts the files written so far (both processes)
    try:
        for w in writers:
            if w.name in SECOND_PROCESS:
                continue
            if not joined and w.name in READS_EVERY_FILE:
                _join(build, out, progress, proc, side, files)
                joined = True
            run_writer(confined(w) if w.name in CONFINED else w, build, out, files, progress,
                       (main.index(w.name), len(main)))
        if not joined:
            _join(build, out, progress, proc, side, files)
    finally:
        progress.watch(None)
        proc.close()


def _join(build: "BuildRecord", out: Path, progress: "Progress", proc: Forked, side: list[Writer],
          files: Files) -> None:
    """Wait for the second process; record its writers (progress and times), or run them here if it failed."""
    status, payload = proc.result()
    if status == "ok":
        for name, note, seconds in payload:
            progress.start(name, "(second process)")
            progress._t0 = time.perf_counter() - seconds     # show and record the child's wall time
            progress.done(note)
        return
    for w in side:                              # again here: the writer's own exception, or success
        run_writer(w, build, out, files, progress)
