"""The results folder of a sweep, written under ppfab's overwrite rule (:mod:`fabrication.pipeline.overwrite`).

Layout of ``RESULTS/``::

    ppfab-sweep.toml     the ledger: sha256 of every table and page ppfab wrote here (stamped)
    results.parquet      one row per variant (the table of record)
    results.csv          the same rows as CSV
    index.html           the table and the plots
    designs/<key>.toml   every variant's design file (stamped), ready for ``ppfab build``
    builds/<key>/        stage ``files``: the variant's build folder
    best-<figure>.toml   ``--best FIGURE``

A folder that exists is used only when it is empty or holds an intact ledger (ppfab's stamp on its last
line).  The Parquet, CSV and HTML files cannot carry the stamp line, so the ledger records their digests:
such a file is replaced only when its bytes are those the ledger records (a file someone changed, or put
there, is refused), and never when it is one of the sweep's inputs.  Every file is written atomically
(a temporary file in the same folder, flushed, renamed); a commit of several files first records both the
old and the new digests, then renames the files, then records the new ones alone, so a stop at any moment
leaves files the ledger accepts.  Signals are held during a commit (:func:`held_signals`): Ctrl-C between
the Parquet and the CSV file cannot leave them disagreeing.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import signal
import threading
import tomllib
import uuid
from pathlib import Path
from typing import Any, Iterable, Iterator

from ..pipeline.overwrite import (STAMP_PREFIX, OutputFileError, check_output_file, is_same_file,
                                  write_output_text, written_by_ppfab)

LEDGER = "ppfab-sweep.toml"
TABLES = ("results.parquet", "results.csv")


def sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


@contextlib.contextmanager
def held_signals() -> Iterator[None]:
    """Hold SIGINT, SIGTERM and SIGHUP for the duration (main thread only); a signal that came meanwhile is
    delivered to the handler that was in place, right after."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    names = [s for s in (signal.SIGINT, getattr(signal, "SIGTERM", None), getattr(signal, "SIGHUP", None)) if s]
    caught: list[int] = []
    previous = {s: signal.signal(s, lambda signum, frame: caught.append(signum)) for s in names}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)
        if caught:
            handler = previous[signal.Signals(caught[0])]
            if callable(handler):
                handler(caught[0], None)
            elif handler == signal.SIG_DFL:
                os.kill(os.getpid(), caught[0])


def _atomic_bytes(path: Path, data: bytes) -> None:
    """``data`` into ``path`` through a fresh temporary file in the same folder, flushed, then renamed."""
    tmp = path.with_name(f".{path.name}.tmp-{uuid.uuid4().hex[:8]}")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o666)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    finally:
        if os.path.lexists(tmp):
            os.unlink(tmp)


class ResultsFolder:
    """``RESULTS/`` of one sweep: opened (and checked) by :meth:`open`, written by :meth:`commit`,
    :meth:`write_design` and :meth:`save_text`."""

    def __init__(self, root: Path, inputs: tuple[Path, ...], ledger: dict[str, list[str]]):
        self.root = root
        self.inputs = inputs
        self.ledger = ledger

    # -- opening -------------------------------------------------------------------------------------------
    @classmethod
    def open(cls, out: str | os.PathLike, inputs: Iterable[str | os.PathLike] = ()) -> "ResultsFolder":
        """Check ``out`` (see the module docstring) and create it when missing; raises
        :class:`~fabrication.pipeline.overwrite.OutputFileError` with a one-line message."""
        root = Path(out)
        ins = tuple(Path(p) for p in inputs)
        for f in ins:
            if is_same_file(root, f):
                raise OutputFileError(f"{out} is the input {f}; give a folder for the results")
        if root.is_symlink():
            raise OutputFileError(f"{out} is a symbolic link; give the path of a folder")
        if not root.exists():
            if not root.parent.is_dir():
                raise OutputFileError(f"{out}: the folder {root.parent} does not exist; create it or write elsewhere")
            root.mkdir()
            folder = cls(root, ins, {})
            folder._write_ledger()
            return folder
        if not root.is_dir():
            raise OutputFileError(f"{out} exists and is not a folder; give a folder for the results")
        ledger = root / LEDGER
        if not ledger.exists():
            if any(root.iterdir()):
                raise OutputFileError(f"{out} holds files but no {LEDGER}: it is not a ppfab sweep folder, and "
                                      "ppfab writes into no one else's folder; give another folder")
            folder = cls(root, ins, {})
            folder._write_ledger()
            return folder
        if not written_by_ppfab(ledger):
            raise OutputFileError(f"{ledger} was not written by ppfab or was changed since (no intact stamp); "
                                  "this folder is left as it is: give another folder")
        doc = tomllib.loads(ledger.read_text(encoding="utf-8"))
        files = {str(k): [str(h) for h in v] for k, v in doc.get("files", {}).items()}
        folder = cls(root, ins, files)
        for name in list(files):
            folder._check_ours(name)
        return folder

    def _check_ours(self, name: str) -> None:
        """Refuse when ``name`` exists and is not what the ledger says ppfab wrote (or is an input)."""
        p = self.root / name
        for f in self.inputs:
            if is_same_file(p, f):
                raise OutputFileError(f"{p} is the input {f}; move it out of the results folder")
        if not os.path.lexists(p):
            return
        if p.is_symlink() or not p.is_file():
            raise OutputFileError(f"{p} is not a regular file ppfab wrote; it is left as it is: give another folder")
        if sha256(p.read_bytes()) not in self.ledger.get(name, []):
            raise OutputFileError(f"{p} was not written by ppfab or was changed since (its digest is not in "
                                  f"{LEDGER}); it is left as it is: move it away or give another folder")

    def _write_ledger(self) -> None:
        lines = ["# The files of this sweep folder that ppfab wrote, by their sha256: ppfab replaces a file here",
                 "# only when its bytes are these.", "", "[files]"]
        lines += [f'"{name}" = [{", ".join(repr(h) for h in sorted(set(hs)))}]'.replace("'", '"')
                  for name, hs in sorted(self.ledger.items())]
        target = check_output_file(self.root / LEDGER, self.inputs, force=True)
        write_output_text(target, "\n".join(lines) + "\n")

    # -- writing -------------------------------------------------------------------------------------------
    def commit(self, files: dict[str, bytes]) -> None:
        """Write ``files`` (name → bytes, names of :data:`TABLES` or ``index.html``) as one step, signals
        held (see the module docstring)."""
        with held_signals():
            for name in files:
                self._check_ours(name)
            new = {name: sha256(data) for name, data in files.items()}
            for name, h in new.items():
                old = self.root / name
                keep = [sha256(old.read_bytes())] if old.is_file() else []
                self.ledger[name] = keep + [h]
            self._write_ledger()
            for name, data in files.items():
                _atomic_bytes(self.root / name, data)
            for name, h in new.items():
                self.ledger[name] = [h]
            self._write_ledger()

    def read_table(self) -> list[dict[str, Any]]:
        """The rows of ``results.parquet`` (none when there is no table yet)."""
        p = self.root / "results.parquet"
        if not p.is_file():
            return []
        import pyarrow.parquet as pq

        return list(pq.read_table(p).to_pylist())

    def write_design(self, key: str, text: str) -> Path:
        """``designs/<key>.toml`` (stamped); an identical file ppfab wrote is kept as it is."""
        folder = self.root / "designs"
        folder.mkdir(exist_ok=True)
        p = folder / f"{key}.toml"
        if written_by_ppfab(p) and strip_stamp(p.read_text(encoding="utf-8")) == text:
            return p
        target = check_output_file(p, self.inputs, force=True)
        write_output_text(target, text)
        return p

    def save_text(self, name: str, text: str) -> Path:
        """A stamped text file in the folder (``best-<figure>.toml``), replacing only ppfab's own."""
        target = check_output_file(self.root / name, self.inputs, force=True)
        write_output_text(target, text)
        return target.path


def strip_stamp(text: str) -> str:
    """``text`` without ppfab's stamp line at its end."""
    lines = text.splitlines(keepends=True)
    if lines and lines[-1].startswith(STAMP_PREFIX):
        lines = lines[:-1]
    return "".join(lines)
