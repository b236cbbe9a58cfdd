"""Constructions of P and PP meshes (paper §3–§4), one module each, registered by name.

Every module in this package is imported by :func:`load_all`; a module
registers its constructions with :func:`~ppfab.constructions.registry.construction`.
"""

from __future__ import annotations

from .registry import CONSTRUCTIONS, Construction, build_construction, construction, get_construction, load_all

__all__ = ["CONSTRUCTIONS", "Construction", "build_construction", "construction", "get_construction", "load_all"]
