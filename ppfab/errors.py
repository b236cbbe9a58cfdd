"""The exception tree of ppfab.

Every error a user can cause derives from :class:`PpfabError`; the command
line prints ``ppfab: error: <message>`` and exits non-zero, never a
traceback.  Errors carry the data they talk about (key path, element,
measured value, limit) so callers can react without parsing the message.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    from .finding import Finding

from typing import Any, Sequence


class PpfabError(Exception):
    """Base class of every error ppfab raises on purpose."""

    exit_code = 1


class DesignError(PpfabError, ValueError):
    """A design file (or its Python equivalent) is malformed or out of range.

    ``key`` is the dotted key path at fault, e.g. ``fabrication.beam_depth``.
    """

    exit_code = 2

    def __init__(self, key: str, message: str):
        self.key = key
        super().__init__(f"{key}: {message}" if key else message)


class MeshFileError(PpfabError, ValueError):
    """A mesh file cannot be read as the quad mesh it must be."""

    exit_code = 2

    def __init__(self, path: str, message: str):
        self.path = str(path)
        super().__init__(f"{path}: {message}")


class GeometryError(PpfabError, ValueError):
    """A construction or a mesh is geometrically invalid (degenerate, folded, NaN).

    ``element`` names the offending element (e.g. ``face (3, 7)``, ``knot 2``)
    and ``value`` the measured quantity, when there is one.
    """

    def __init__(self, message: str, element: str | None = None, value: float | None = None):
        self.element = element
        self.value = value
        super().__init__(message)


class FoldError(GeometryError):
    """The mesh passes through a cuspidal edge: a face is flipped.

    ``mask``: boolean ``(m, n')`` of the folded faces, in the face layout of the mesh that was refused (set by
    :func:`ppfab.folds.check_folds`; ``None`` when the raiser had none).
    """

    mask: Any = None


class FabricationError(PpfabError):
    """Fabrication data cannot be produced without being wrong (stop before writing).

    ``defects``: the defect records behind the error when a check found several (empty otherwise).
    """

    defects: Sequence[Any] = ()


class NonPlanarPanelError(FabricationError):
    """Panels deviate from their plane by more than the tolerance (in mm)."""

    def __init__(self, offenders: "list[Finding]", tolerance_mm: float, advice: str = ""):
        """``offenders``: one :class:`~ppfab.finding.Finding` per panel (``planarity``, the panel id, its
        deviation and the tolerance, mm)."""
        self.offenders = offenders
        self.tolerance_mm = tolerance_mm
        worst = sorted(offenders, key=lambda o: -(o.value or 0.0))
        shown = ", ".join(f"{o.element} {o.value:.3g} mm" for o in worst[:8])
        more = f" (and {len(worst) - 8} more)" if len(worst) > 8 else ""
        super().__init__(
            f"{len(offenders)} panel(s) deviate from their plane by more than "
            f"{tolerance_mm:g} mm: {shown}{more}" + (f"; {advice}" if advice else "")
        )


class NestingError(FabricationError):
    """A part cannot be placed on any stock sheet."""


class VerificationError(PpfabError):
    """An output folder does not satisfy the output contract."""
