"""Where the studio may save: the rules that keep Save from destroying a file.

* the design the studio read and the mesh file it names are never overwritten (not even when asked);
* a file that exists and that this studio did not write (or that changed since it wrote it) is overwritten only
  when the caller says ``replace=True`` — the page asks with a checkbox that appears for such a target;
* a file this studio wrote earlier, unchanged since, may be saved over again;
* a new file is created exclusively (a file that appears meanwhile is not clobbered); a replacement is written
  to a temporary file beside it and moved over it, so the target is never left half-written.

A file counts as this studio's while its bytes hash to what the studio wrote there (SHA-256).
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

from ppfab.errors import DesignError

TargetKind = Literal["new", "session", "foreign", "input"]


@dataclass(frozen=True)
class Target:
    """A save target: ``path`` as given (expanded), ``kind`` what is there now."""

    path: Path
    kind: TargetKind


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve() or os.path.samefile(a, b)
    except OSError:
        return False


def _digest(path: Path) -> str | None:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None


@dataclass
class SaveRules:
    """The inputs (the design file, its mesh) and the files this studio has written (path → SHA-256)."""

    inputs: tuple[Path, ...] = ()
    written: dict[Path, str] = field(default_factory=dict)

    def target(self, path: str | Path) -> Target:
        """Check ``path`` (a ``.toml`` file in an existing folder) and say what is there.

        Raises :class:`~ppfab.errors.DesignError` for a name that cannot be a design file."""
        p = Path(str(path).strip()).expanduser()
        if not str(path).strip():
            raise DesignError("save", "give a file name ending in .toml")
        if p.suffix.lower() != ".toml":
            raise DesignError("save", f"{p}: give a file name ending in .toml")
        if not p.parent.is_dir():
            raise DesignError("save", f"{p.parent}: no such folder")
        if any(_same_file(p, i) for i in self.inputs):
            return Target(p, "input")
        if not os.path.lexists(p):
            return Target(p, "new")
        if not p.is_file():
            raise DesignError("save", f"{p}: exists and is not a file")
        digest = self.written.get(p.resolve())
        return Target(p, "session" if digest is not None and digest == _digest(p) else "foreign")

    def write(self, path: str | Path, text: str, replace: bool = False) -> Path:
        """Write ``text`` to ``path`` under the rules of the module docstring; returns the path written."""
        t = self.target(path)
        if t.kind == "input":
            raise DesignError("save", f"{t.path} is the design or mesh this studio read; it is never overwritten: "
                                      "give another file name")
        if t.kind == "foreign" and not replace:
            raise DesignError("save", f"{t.path} exists and was not written by this studio: tick 'replace the "
                                      "existing file' to overwrite it, or give another file name")
        data = text.encode("utf-8")
        if t.kind == "new":
            try:
                with open(t.path, "xb") as f:
                    f.write(data)
            except FileExistsError:
                raise DesignError("save", f"{t.path} appeared while saving; save again to see what it is") from None
        else:
            real = t.path.resolve()
            fd, tmp = tempfile.mkstemp(dir=real.parent, prefix=f".{real.name}.", suffix=".part")
            try:
                with os.fdopen(fd, "wb") as f:
                    f.write(data)
                os.chmod(tmp, real.stat().st_mode & 0o777)      # the replaced file keeps its permissions
                os.replace(tmp, real)
            except BaseException:
                Path(tmp).unlink(missing_ok=True)
                raise
        self.written[t.path.resolve()] = hashlib.sha256(data).hexdigest()
        return t.path
