"""ppfab — planar panels and planar supporting beams (Jiang, Wang, Tellier, Wallner, Pottmann 2022).

The geometry core: weighted planes (:mod:`ppfab.planes`), meshes
(:mod:`ppfab.mesh`), metrics (:mod:`ppfab.metrics`), the weighted face image
(:mod:`ppfab.faceimage`), constructions (:mod:`ppfab.constructions`),
optimisation (:mod:`ppfab.optimize`), support structures (:mod:`ppfab.support`)
and mesh files (:mod:`ppfab.io`).  It never imports the fabrication layer,
build123d, ezdxf, matplotlib or a nesting library.
"""

__version__ = "0.1.0"

from typing import TYPE_CHECKING, Any  # noqa: E402

from .errors import PpfabError  # noqa: E402

if TYPE_CHECKING:  # pragma: no cover
    from .mesh import QuadGrid, QuadMesh

__all__ = ["QuadGrid", "QuadMesh", "PpfabError", "__version__"]


def __getattr__(name: str) -> Any:
    """``QuadGrid`` and ``QuadMesh`` are imported on first use: ``ppfab --help`` need not load scipy."""
    if name in ("QuadGrid", "QuadMesh"):
        from . import mesh

        return getattr(mesh, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
