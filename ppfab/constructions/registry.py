"""The table of constructions a design file's ``method`` selects from.

A construction is a plain function from a frozen parameter dataclass to a
:class:`~ppfab.mesh.QuadGrid` (or :class:`~ppfab.mesh.QuadMesh`).  Modules in
:mod:`ppfab.constructions` register theirs with :func:`construction`;
the package imports every module, so a new construction is one new file.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable

from ..registry import Registry
from ..schema import parse_params

if TYPE_CHECKING:  # pragma: no cover
    from _typeshed import DataclassInstance


@dataclass(frozen=True)
class Construction:
    """One entry of :data:`CONSTRUCTIONS`."""

    name: str
    params: type[DataclassInstance]
    build: Callable[[Any], Any]
    summary: str
    planar_families: tuple[str, ...]
    section: str


_TABLE: Registry[Construction] = Registry("method", "ppfab.constructions", skip=("registry",))
CONSTRUCTIONS: dict[str, Construction] = _TABLE.entries


def construction(name: str, params: type[DataclassInstance], summary: str, planar_families: tuple[str, ...] = ("rows", "cols"),
                 section: str = "") -> Callable:
    """Decorator registering ``fn(params) -> QuadGrid`` under ``name``.

    ``planar_families`` says which polyline families the result keeps planar
    (``"rows"``: ``v[i, :] ⊂ U_i``, ``"cols"``: ``v[:, j] ⊂ W_j``); ``section``
    cites the paper.
    """
    def register(fn: Callable[[Any], Any]) -> Callable[[Any], Any]:
        _TABLE.add(name, Construction(name, params, fn, summary, tuple(planar_families), section))
        return fn
    return register


def load_all() -> dict[str, Construction]:
    """Import every construction module of :mod:`ppfab.constructions` (once) and return the registry."""
    return _TABLE.load()


def get_construction(name: str, key: str = "geometry.method") -> Construction:
    """Look a construction up by name; an unknown name lists the valid ones."""
    return _TABLE.get(name, key)


def build_construction(name: str, params: dict | None, key: str = "geometry") -> Any:
    """Parse ``params`` for construction ``name`` and run it."""
    c = get_construction(name, f"{key}.method")
    record = parse_params(c.params, params or {}, f"{key}.params")
    return c.build(record)
