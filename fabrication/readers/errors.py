"""The one error of the readers: :class:`BuildReadError`, a line naming the file, row and column."""

from __future__ import annotations

from pathlib import Path

from ppfab.errors import FabricationError


class BuildReadError(FabricationError, ValueError):
    """A file of a build folder is missing or malformed: the message names the file and, for a table, the row
    (1-based, the header not counted) and column."""


def missing(path: Path, what: str) -> BuildReadError:
    """``path`` is not there (``what``: why it is needed)."""
    return BuildReadError(f"{path}: missing ({what}); give the folder of a complete ppfab build")


def bad(path: Path, reason: str, row: int | None = None, column: str | None = None) -> BuildReadError:
    """``path``, ``row``, ``column`` cannot be read: ``reason``."""
    where = "".join([f", row {row}" if row is not None else "", f", column {column}" if column else ""])
    return BuildReadError(f"{path}{where}: {reason}")
