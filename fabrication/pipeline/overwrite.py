"""The one rule for every file ppfab writes on a user's request (``optimize -o``, ``new -o``, the studio's Save).

1. **Never an input.**  The output is refused when it is one of the command's input files: the same resolved
   path, or the same file by device and inode (a hard link, another spelling, a symbolic link to it).
2. **Anything else only with --force, and only what ppfab wrote.**  A file that exists is replaced only with
   ``force``, and only when ppfab wrote it and nobody changed it since: its last line is ppfab's stamp
   (:data:`STAMP_PREFIX` and the sha256 of every byte above it, :func:`stamp`).  A stamp edited away or a
   file edited after ppfab wrote it is someone's work and is refused even with ``force``.
3. **Atomically.**  The new content goes into a fresh temporary file in the same folder (created with
   ``O_CREAT | O_EXCL | O_NOFOLLOW``), is flushed to disk, and takes the name in one rename — a crash leaves
   the old file or the new one, never half of either.  Right before the rename the target is checked again:
   a file that appeared meanwhile (when there was none) or that changed meanwhile (when one is replaced)
   is left as it is and the write refused (:func:`rename_noreplace` makes the first case exact).

Use it in two steps, the check before any long work and the write at the end::

    target = check_output_file(out, inputs=[mesh_path], force=args.force)
    ...                                           # hours of work
    write_output(target, lambda tmp: write_mesh(mesh, tmp))   # or write_output_text(target, text)

or in one call, e.g. for a Save button: ``save_text(path, text, inputs=[...], force=overwrite_ok)``.
Refusals raise :class:`OutputFileError` (exit status 2) with a one-line message.
"""

from __future__ import annotations

import ctypes
import errno
import hashlib
import os
import re
import stat
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable

from ppfab.errors import PpfabError

STAMP_PREFIX = "# ppfab wrote this file; sha256 of the lines above: "
"""The start of the last line of every file written through :func:`write_output` (a comment in OBJ, OFF and
TOML); the 64 hex digits of the sha256 of the bytes before that line follow."""

_STAMP_RE = re.compile(re.escape(STAMP_PREFIX).encode() + rb"([0-9a-f]{64})\n\Z")

COMMIT_HOOKS: list[Callable[[Path, Path], None]] = []
"""Called as ``hook(target, tmp)`` right before an output (a file here, a folder in
:class:`~fabrication.pipeline.folder.AtomicFolder`) is checked again and renamed into place, when the new
content is complete in ``tmp``.  Empty in normal use; tests put a function here that does what a user might
do at that moment (create the target, save a file into it), which makes that race deterministic."""


class OutputFileError(PpfabError):
    """An output file may not be written (it is an input, it exists, it is not ppfab's, it changed)."""

    exit_code = 2


@dataclass(frozen=True)
class FileTarget:
    """An output file that passed :func:`check_output_file`.

    ``identity`` is ``(st_dev, st_ino, st_size, st_mtime_ns)`` of the file found there (a ppfab file that
    ``force`` allows to replace), ``None`` when there was none; the write is refused if that changed.
    """

    path: Path
    identity: tuple[int, int, int, int] | None


def _identity(st: os.stat_result) -> tuple[int, int, int, int]:
    return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)


def is_same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether the paths ``a`` and ``b`` name one file: equal resolved paths, or the same device and inode."""
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def stamp(data: bytes) -> bytes:
    """``data`` (ended by a newline if it is not) followed by ppfab's stamp line.

    >>> stamp(b"v 0 0 0\\n").splitlines()[-1][:16]
    b'# ppfab wrote th'
    """
    if data and not data.endswith(b"\n"):
        data += b"\n"
    return data + f"{STAMP_PREFIX}{hashlib.sha256(data).hexdigest()}\n".encode()


def written_by_ppfab(path: str | os.PathLike) -> bool:
    """Whether the regular file ``path`` ends with ppfab's stamp and is unchanged since (see :func:`stamp`)."""
    try:
        with open(path, "rb", buffering=0) as fh:
            st = os.fstat(fh.fileno())
            if not stat.S_ISREG(st.st_mode):
                return False
            size = st.st_size
            line = len(STAMP_PREFIX) + 65
            if size < line:
                return False
            fh.seek(size - line)
            m = _STAMP_RE.fullmatch(fh.read(line))
            if m is None:
                return False
            fh.seek(0)
            h = hashlib.sha256()
            left = size - line
            while left > 0:
                chunk = fh.read(min(left, 1 << 20))
                if not chunk:
                    return False
                h.update(chunk)
                left -= len(chunk)
            return h.hexdigest() == m.group(1).decode()
    except OSError:
        return False


def check_output_file(path: str | os.PathLike, inputs: Iterable[str | os.PathLike] = (), force: bool = False,
                      force_flag: str = "--force") -> FileTarget:
    """Raise :class:`OutputFileError` when ``path`` may not be written (see the module docstring); else
    return the :class:`FileTarget` to give :func:`write_output`.  ``force_flag`` names the option in messages."""
    given = str(path)
    p = Path(path)
    for f in inputs:
        if is_same_file(p, f):
            raise OutputFileError(f"{given} is the input {f}; write the result to another file")
    if p.is_symlink():
        raise OutputFileError(f"{given} is a symbolic link (to {os.readlink(p)}); give the path of a file")
    try:
        st = os.lstat(p)
    except FileNotFoundError:
        return FileTarget(p, None)
    except OSError as exc:
        raise OutputFileError(f"{given}: cannot be written ({exc.strerror})") from None
    if stat.S_ISDIR(st.st_mode):
        raise OutputFileError(f"{given} is a folder; give the path of a file")
    if not stat.S_ISREG(st.st_mode):
        raise OutputFileError(f"{given} exists and is not a regular file; give another name")
    if not force:
        raise OutputFileError(f"{given} exists; give another name, or {force_flag} to replace a file ppfab wrote")
    if not written_by_ppfab(p):
        raise OutputFileError(f"{given} was not written by ppfab, or was changed since (no intact ppfab stamp "
                              f"on its last line); {force_flag} replaces only ppfab's own files: give another name")
    return FileTarget(p, _identity(st))


def write_output(target: FileTarget, write: Callable[[Path], object], stamped: bool = True) -> None:
    """Write ``target`` atomically: ``write(tmp)`` fills a fresh temporary file beside it (same suffix),
    ppfab's stamp is appended (``stamped``), and the file takes the target's name when the target is still
    what :func:`check_output_file` found (nothing, or the same unchanged ppfab file).  Otherwise
    :class:`OutputFileError` is raised and the target is left as it is; the temporary file never remains."""
    p = target.path
    tmp = p.with_name(f".{p.stem}.tmp-{uuid.uuid4().hex[:8]}{p.suffix}")
    try:
        os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o666))
    except OSError as exc:
        raise OutputFileError(f"{p}: cannot write in {p.parent} ({exc.strerror})") from None
    try:
        write(tmp)
        if stamped:
            data = stamp(tmp.read_bytes())
            with open(tmp, "wb") as fh:
                fh.write(data)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        for hook in list(COMMIT_HOOKS):
            hook(p, tmp)
        _commit(target, tmp)
    finally:
        if os.path.lexists(tmp):
            os.unlink(tmp)


def _commit(target: FileTarget, tmp: Path) -> None:
    p = target.path
    if target.identity is None:
        try:
            rename_noreplace(tmp, p)
        except FileExistsError:
            raise OutputFileError(f"{p} appeared while ppfab was writing it; it was left as it is and "
                                  "nothing was written: give another name") from None
        return
    try:
        st = os.lstat(p)
    except FileNotFoundError:
        st = None
    if st is None or _identity(st) != target.identity or not written_by_ppfab(p):
        raise OutputFileError(f"{p} was changed while ppfab was writing it; it was left as it is and nothing "
                              "was written: give another name")
    os.chmod(tmp, stat.S_IMODE(st.st_mode))
    os.replace(tmp, p)


def write_output_text(target: FileTarget, text: str, stamped: bool = True) -> None:
    """:func:`write_output` for a text (UTF-8)."""
    write_output(target, lambda tmp: tmp.write_bytes(text.encode("utf-8")), stamped=stamped)


def save_text(path: str | os.PathLike, text: str, inputs: Iterable[str | os.PathLike] = (),
              force: bool = False, force_flag: str = "--force") -> Path:
    """Check and write in one call (e.g. a Save button; ``force`` is the user's "replace" answer): the text
    goes to ``path`` under the rule of this module, stamped; returns the path.  Raises :class:`OutputFileError`."""
    target = check_output_file(path, inputs, force, force_flag)
    write_output_text(target, text)
    return target.path


_AT_FDCWD = -100
_RENAME_NOREPLACE = 1
_renameat2: Callable[..., int] | None | bool = False       # False: not looked up yet


def _libc_renameat2() -> Callable[..., int] | None:
    global _renameat2
    if _renameat2 is False:
        try:
            fn = ctypes.CDLL(None, use_errno=True).renameat2
            fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
            fn.restype = ctypes.c_int
            _renameat2 = fn
        except (AttributeError, OSError):
            _renameat2 = None
    return _renameat2 if callable(_renameat2) else None


def rename_noreplace(src: str | os.PathLike, dst: str | os.PathLike) -> None:
    """Rename ``src`` to ``dst`` in one step, raising :class:`FileExistsError` when anything (a file, a
    folder, even empty, a symbolic link) is at ``dst``: nothing there is ever replaced.

    Linux ``renameat2(RENAME_NOREPLACE)`` makes the check and the rename one atomic step; where it is
    missing the check comes right before ``rename`` (which still refuses a folder that is not empty).
    """
    fn = _libc_renameat2()
    if fn is not None:
        if fn(_AT_FDCWD, os.fsencode(src), _AT_FDCWD, os.fsencode(dst), _RENAME_NOREPLACE) == 0:
            return
        err = ctypes.get_errno()
        if err == errno.EEXIST:
            raise FileExistsError(err, os.strerror(err), str(dst))
        if err not in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP):
            raise OSError(err, os.strerror(err), str(src))
    if os.path.lexists(dst):
        raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), str(dst))
    try:
        os.rename(src, dst)
    except OSError as exc:
        if exc.errno in (errno.ENOTEMPTY, errno.EEXIST):
            raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), str(dst)) from None
        raise
