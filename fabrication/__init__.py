"""ppfab's fabrication layer: millimetres, materials, CAD kernels and file formats — and, on top of it, the
build pipeline and the ``ppfab`` command.

The Python API of the whole pipeline (what the command line, the examples, the tests and a notebook call)::

    from fabrication import load_design, build
    b = build(load_design("roof.toml"))     # a typed Build: geometry, quality, support, panels, beams, …
    b.write("out")                          # the output folder, written atomically
    assert b.verify().ok                    # the same checks as `ppfab verify out`
    b.summary                               # totals (panels, sheets, lengths, weights, torsion)
    package = open_build("out")             # the typed parts, nodes, welds, sheets and mesh of a written folder

Heavy libraries (build123d, ezdxf, matplotlib) are imported inside the functions that need them, and the
API names below are loaded on first use, so ``import fabrication`` (and ``ppfab --version``) stays light.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from .design import Design, load_design, parse_design
    from .pipeline.stages import build
    from .progress import Progress
    from .pipeline.records import Build
    from .verify import verify
    from .model import Package
    from .readers import open_build, package_of

_API = {"Design": "design", "load_design": "design", "parse_design": "design",
        "build": "pipeline.stages", "Build": "pipeline.records", "Progress": "progress", "verify": "verify",
        "open_build": "readers", "package_of": "readers", "Package": "model"}

__all__ = ["Build", "Design", "Package", "Progress", "build", "load_design", "open_build", "package_of", "parse_design",
           "verify"]


def __getattr__(name: str) -> Any:
    if name in _API:
        return getattr(importlib.import_module(f"{__name__}.{_API[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
