"""The table of support methods (``[support] method = …``).

A method is a function ``build(mesh, params, family) -> SupportStructure`` registered with
:func:`support_method` by its own module in this package (``pp``, ``p``, ``conical``, ``parallel``);
:func:`get_support_method` imports every module of the package once, so a new method is one new file.
:func:`ppfab.support.select.support_structure` chooses among them (``auto``).
"""

from __future__ import annotations

import importlib
import pkgutil
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

from ppfab.errors import DesignError
from ppfab.schema import suggest

if TYPE_CHECKING:  # pragma: no cover
    from ppfab.mesh import QuadMesh

    from .params import SupportParams
    from .structure import SupportStructure

_INFRASTRUCTURE = ("registry", "select", "structure", "params")


@dataclass(frozen=True)
class SupportMethod:
    """One entry of :data:`SUPPORT_METHODS`: ``build(mesh, params, family)``; ``family`` is the planar family
    (0 rows, 1 cols) when the caller knows it, else ``None``."""

    name: str
    build: Callable[["QuadMesh", "SupportParams", "int | None"], "SupportStructure"]
    summary: str


SUPPORT_METHODS: dict[str, SupportMethod] = {}


def support_method(name: str, summary: str) -> Callable:
    """Decorator registering ``build(mesh, params, family) -> SupportStructure`` under ``name``."""
    def register(fn: Callable) -> Callable:
        if name in SUPPORT_METHODS:
            raise RuntimeError(f"support method {name!r} registered twice")
        SUPPORT_METHODS[name] = SupportMethod(name, fn, summary)
        return fn
    return register


def load_methods() -> dict[str, SupportMethod]:
    """Import every method module of :mod:`ppfab.support` (once) and return the table."""
    package = importlib.import_module("ppfab.support")
    for info in pkgutil.iter_modules(package.__path__):
        if info.name not in _INFRASTRUCTURE and not info.name.startswith("_"):
            importlib.import_module(f"ppfab.support.{info.name}")
    return SUPPORT_METHODS


def method_names() -> tuple[str, ...]:
    """The registered method names, sorted."""
    return tuple(sorted(load_methods()))


def get_support_method(name: str, key: str = "support.method") -> SupportMethod:
    """Look a method up by name; an unknown name lists the valid ones."""
    table = load_methods()
    if name not in table:
        raise DesignError(key, f"unknown method {name!r}{suggest(name, list(table))}; "
                               f"valid: auto, {', '.join(sorted(table))}")
    return table[name]
