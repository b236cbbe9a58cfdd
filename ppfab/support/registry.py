"""The table of support methods (``[support] method = …``).

A method is a function ``build(mesh, params, family, beams) -> SupportStructure`` registered with
:func:`support_method` by its own module in this package (``pp``, ``p``, ``conical``, ``parallel``);
:func:`get_support_method` imports every module of the package once, so a new method is one new file.
:func:`ppfab.support.select.support_structure` chooses among them (``auto``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

from ppfab.registry import Registry

if TYPE_CHECKING:  # pragma: no cover
    from ppfab.mesh import QuadMesh

    from .params import BeamContext, SupportParams
    from .structure import SupportStructure

_INFRASTRUCTURE = ("registry", "select", "structure", "params", "lines", "axes", "planar", "quality", "report")


@dataclass(frozen=True)
class SupportMethod:
    """One entry of :data:`SUPPORT_METHODS`: ``build(mesh, params, family, beams)``; ``family`` is the planar
    family (0 rows, 1 cols) when the caller knows it, else ``None``; ``beams`` the beam depth and torsion
    tolerance (:class:`~ppfab.support.params.BeamContext`) when a build knows them, else ``None``."""

    name: str
    build: Callable[["QuadMesh", "SupportParams", "int | None", "BeamContext | None"], "SupportStructure"]
    summary: str


_TABLE: Registry[SupportMethod] = Registry("support method", "ppfab.support", skip=_INFRASTRUCTURE)
SUPPORT_METHODS: dict[str, SupportMethod] = _TABLE.entries


def support_method(name: str, summary: str) -> Callable:
    """Decorator registering ``build(mesh, params, family, beams) -> SupportStructure`` under ``name``."""
    def register(fn: Callable) -> Callable:
        _TABLE.add(name, SupportMethod(name, fn, summary))
        return fn
    return register


def load_methods() -> dict[str, SupportMethod]:
    """Import every method module of :mod:`ppfab.support` (once) and return the table."""
    return _TABLE.load()


def check_method(name: str, key: str = "support.method") -> None:
    """Raise :class:`~ppfab.errors.DesignError` unless ``name`` is ``auto`` or a registered method."""
    _TABLE.check(name, key, also=("auto",))


def get_support_method(name: str, key: str = "support.method") -> SupportMethod:
    """Look a method up by name; an unknown name lists the valid ones."""
    return _TABLE.get(name, key)
