"""Constructions of P and PP meshes (paper §3–§4), one module each, registered by name.

Every module in this package is imported by :func:`load_all`; a module
registers its constructions with :func:`~ppfab.constructions.registry.construction`.
"""

from __future__ import annotations

import importlib
import pkgutil

from .registry import CONSTRUCTIONS, Construction, build_construction, construction, get_construction

__all__ = ["CONSTRUCTIONS", "Construction", "build_construction", "construction", "get_construction", "load_all"]


def load_all() -> dict[str, Construction]:
    """Import every construction module (once) and return the registry."""
    for info in pkgutil.iter_modules(__path__):
        if info.name != "registry" and not info.name.startswith("_"):
            importlib.import_module(f"{__name__}.{info.name}")
    return CONSTRUCTIONS
