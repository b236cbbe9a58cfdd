"""Mesh files: OBJ and OFF (quads kept, never triangulated) and JSON with support planes.

:func:`read_mesh` returns a :class:`~ppfab.mesh.QuadMesh`; call
``.try_grid()`` / ``.to_grid()`` on it to recover the regular patch from
connectivity whatever the vertex order.  :func:`load_mesh` does both.
The names are loaded on first use, so :mod:`ppfab.io.pathtext` (path checks of the command line) needs no numpy.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from .jsonio import grid_from_json, grid_to_json
    from .meshfile import load_mesh, read_mesh, write_mesh, write_obj, write_off

_NAMES = {"read_mesh": "meshfile", "load_mesh": "meshfile", "write_mesh": "meshfile", "write_obj": "meshfile",
          "write_off": "meshfile", "grid_to_json": "jsonio", "grid_from_json": "jsonio"}

__all__ = ["read_mesh", "load_mesh", "write_mesh", "write_obj", "write_off", "grid_to_json", "grid_from_json"]


def __getattr__(name: str) -> Any:
    if name in _NAMES:
        return getattr(importlib.import_module(f"{__name__}.{_NAMES[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
