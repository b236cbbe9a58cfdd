"""From a designer's surface to a quad net on it (NURBS surface or triangle mesh, sampled in mm).

The fabrication layer reads the file (:mod:`fabrication.surfacefile`: rhino3dm, trimesh) into
:class:`SurfaceSamples`; :func:`remesh` fits the surface as a height field over its plan frame and builds
the net asked for in :class:`SurfaceSpec` — the ``sections`` net (:mod:`.sections`: planar sections by
parallel planes, rows of the grid, and their conjugate curves, seeded by :mod:`.balance`), the
``principal`` net (:mod:`.principal`: curvature lines, refused at umbilics), the ``conjugate`` net
(:mod:`.conjugate`: the conjugate pair nearest two guide directions) or the ``pp`` net (:mod:`.pp`:
two families of planar sections, refused when far from conjugate) — trimmed to the surface's outline with
its holes (:mod:`.trim`).  The net then goes the way of any quad mesh: P optimisation with closeness to
the original surface, support structure, fabrication.
"""

from __future__ import annotations

from .conjugate import conjugate_net
from .plan import PlanFrame, plan_frame
from .pp import pp_net
from .principal import principal_net, umbilics
from .remesh import RemeshResult, remesh
from .samples import SurfaceSamples
from .sections import SectionsNet, sections_net
from .spec import NETS, UNITS, SurfaceSpec

__all__ = ["SurfaceSamples", "SurfaceSpec", "RemeshResult", "remesh", "SectionsNet", "sections_net", "PlanFrame",
           "plan_frame", "NETS", "UNITS", "principal_net", "umbilics", "pp_net",
           "conjugate_net"]
