"""Optional files that cannot be written: an error that names the part, what is wrong and the key that skips it.

The optional files (``model.ifc``, ``model.3dm``, ``model.glb``, ``report.html``) are written after the required
ones (mesh, STEP, DXF, tables).  When one of them fails, the build stops with one line that says which file, which
part and why, and which ``[output]`` key builds without that file — not with the bare message of the library.
:func:`outline_problem` says what is wrong with an outline a CAD kernel refused to extrude.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ppfab.errors import FabricationError, PpfabError

from ..contract import GLB_FILE, IFC_FILE, RHINO_FILE
from .base import Files, Writer

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord

OPTIONAL_FILES: dict[str, tuple[str, str]] = {
    "ifc": ("ifc", IFC_FILE),
    "rhino": ("rhino", RHINO_FILE),
    "glb": ("glb", GLB_FILE),
    "report": ("report", "report.html"),
}
"""Writer name → (its ``[output]`` key, the file it writes)."""

POINT_TOLERANCE_MM = 1e-6
"""Outline points closer than this count as one point (a zero-length edge)."""


class OptionalFileError(FabricationError):
    """An optional file could not be written; ``key`` is the ``[output]`` key that skips it."""

    def __init__(self, file: str, key: str, message: str):
        self.file = file
        self.key = key
        super().__init__(f"{file}: {message}; it is optional: set [output] {key} = false to build without it")


def guarded(w: Writer) -> Writer:
    """``w`` itself for a required file; for an optional one, the same writer whose failure (any exception but an
    interruption or an operating-system error, which keep their own messages) is an :class:`OptionalFileError`."""
    if w.name not in OPTIONAL_FILES:
        return w
    key, file = OPTIONAL_FILES[w.name]
    write = w.write

    def guarded_write(build: "BuildRecord", out: Path, files: Files) -> str:
        try:
            return write(build, out, files)
        except (OSError, OptionalFileError):
            raise
        except PpfabError as exc:
            raise OptionalFileError(file, key, str(exc)) from None
        except Exception as exc:
            raise OptionalFileError(file, key, f"could not be written ({type(exc).__name__}: {exc})") from None

    return dataclasses.replace(w, write=guarded_write)


def part_failure(part_id: str, outline: np.ndarray, height: float, what: str, exc: Exception) -> FabricationError:
    """The error for a part a writer could not turn into a solid: its id, what failed (``what``, e.g. "the glTF
    mesh of its prism"), the library's reason and what is wrong with its outline."""
    return FabricationError(f"{part_id}: {what} failed ({type(exc).__name__}: {exc}; "
                            f"{outline_problem(outline, height)})")


def outline_problem(outline: np.ndarray, height: float) -> str:
    """What makes a flat outline ``(k, 2)`` (mm) and an extrusion height unfit for a solid: too few points, a
    zero-length edge (two consecutive points within :data:`POINT_TOLERANCE_MM`), no enclosed area, a height that
    is not positive or a non-finite value; ``"no defect found in its outline"`` when none of these applies."""
    pts = np.asarray(outline, dtype=float).reshape(-1, 2)
    if not np.all(np.isfinite(pts)):
        return "its outline has a non-finite coordinate"
    if not (np.isfinite(height) and height > 0):
        return f"its height is {height:g} mm, not a positive length"
    if len(pts) < 3:
        return f"its outline has {len(pts)} point(s), fewer than 3"
    edges = np.linalg.norm(np.roll(pts, -1, axis=0) - pts, axis=1)
    short = np.flatnonzero(edges <= POINT_TOLERANCE_MM)
    if len(short):
        k = int(short[0])
        return (f"its outline has a zero-length edge: points {k} and {(k + 1) % len(pts)} of {len(pts)} coincide at "
                f"({pts[k, 0]:.3f}, {pts[k, 1]:.3f}) mm ({len(short)} such edge(s))")
    x, y = pts[:, 0], pts[:, 1]
    area = 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
    if area <= POINT_TOLERANCE_MM * float(edges.sum()):
        return f"its outline encloses no area ({len(pts)} points on one line)"
    return "no defect found in its outline"
