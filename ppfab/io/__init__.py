"""Mesh files: OBJ and OFF (quads kept, never triangulated) and JSON with support planes.

:func:`read_mesh` returns a :class:`~ppfab.mesh.QuadMesh`; call
``.try_grid()`` / ``.to_grid()`` on it to recover the regular patch from
connectivity whatever the vertex order.  :func:`load_mesh` does both.
"""

from .meshfile import load_mesh, read_mesh, write_mesh, write_obj, write_off
from .jsonio import grid_from_json, grid_to_json

__all__ = ["read_mesh", "load_mesh", "write_mesh", "write_obj", "write_off", "grid_to_json", "grid_from_json"]
