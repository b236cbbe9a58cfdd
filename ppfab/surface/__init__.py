"""From a designer's surface to a quad net on it (NURBS surface or triangle mesh, sampled in mm).

The fabrication layer reads the file (:mod:`fabrication.surfacefile`: rhino3dm, trimesh) into
:class:`SurfaceSamples`; :func:`remesh` fits the surface as a height field over its plan frame and builds
the net asked for in :class:`SurfaceSpec` — so far the ``sections`` net (:mod:`.sections`: planar sections
by parallel planes, rows of the grid, and their conjugate curves), trimmed to the surface's outline with
its holes (:mod:`.trim`).  The net then goes the way of any quad mesh: P optimisation with closeness to
the original surface, support structure, fabrication.
"""

from __future__ import annotations

from .plan import PlanFrame, plan_frame
from .remesh import RemeshResult, remesh
from .samples import SurfaceSamples
from .sections import SectionsNet, sections_net
from .spec import NETS, UNITS, SurfaceSpec

__all__ = ["SurfaceSamples", "SurfaceSpec", "RemeshResult", "remesh", "SectionsNet", "sections_net", "PlanFrame",
           "plan_frame", "NETS", "UNITS"]
