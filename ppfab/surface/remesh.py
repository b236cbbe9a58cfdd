"""A surface → a quad net on it: :func:`remesh` (the ``sections`` net so far), with what it measured.

Examples
--------
>>> import numpy as np
>>> from ppfab.surface import SurfaceSamples, SurfaceSpec, remesh
>>> x, y = np.meshgrid(np.linspace(0, 12000, 41), np.linspace(0, 8000, 31), indexing="ij")
>>> z = 2000 - 2e-5 * (x - 6000) ** 2 - 3e-5 * (y - 4000) ** 2 + 1e-5 * (x - 6000) * (y - 4000)
>>> pts = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
>>> ids = np.arange(41 * 31).reshape(41, 31)
>>> tri = np.concatenate([np.stack([ids[:-1, :-1], ids[1:, :-1], ids[1:, 1:]], -1).reshape(-1, 3),
...                       np.stack([ids[:-1, :-1], ids[1:, 1:], ids[:-1, 1:]], -1).reshape(-1, 3)])
>>> r = remesh(SurfaceSamples(pts, tri), SurfaceSpec(path="dome.obj", spacing=2000.0))
>>> r.summary()["faces"], r.net.dropped_outside, r.planarity_mm < 1e-9
(18, 6, True)
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..errors import DesignError
from .heightfield import HeightField, fit_height_field
from .plan import PlanFrame, plan_frame
from .samples import SurfaceSamples
from .sections import SectionsNet, sections_net
from .spec import SurfaceSpec

CELL_PER_SPACING = 8
"""Plan cells of the height-field fit per panel ``spacing``."""


@dataclass(frozen=True)
class RemeshResult:
    """The net on the surface and the numbers a designer checks.

    net : the :class:`SectionsNet` (its ``mesh`` in mm)
    frame : the plan frame (sections are ``x = const`` in it)
    height_field : the fitted ``z = f(x, y)``
    fit_deviation_mm : largest distance (in z of the frame) of the samples from the fitted height field
    planarity_mm : largest distance of a section row's vertex from its plane, before any optimisation
    panel_size_min, panel_size_max : shortest and longest kept edge, as a fraction of ``spacing``
    seconds : CPU time of the fit and the net
    """

    net: SectionsNet
    frame: PlanFrame
    height_field: HeightField
    fit_deviation_mm: float
    planarity_mm: float
    panel_size_min: float
    panel_size_max: float
    seconds: float

    def summary(self) -> dict:
        """Plain data (``--json`` of ``ppfab remesh``)."""
        n = self.net
        v = np.asarray(n.mesh.vertices).reshape(-1, 3)
        return {"vertices": int(len(v)), "faces": int(n.grid_faces.sum()), "faces_total": n.faces_total,
                "dropped_outside": n.dropped_outside, "dropped_sliver": n.dropped_sliver,
                "dropped_island": n.dropped_island, "planar_family": n.planar_family,
                "section_normal": self.frame.axes[0].tolist(),
                "fit_deviation_mm": self.fit_deviation_mm, "planarity_mm": self.planarity_mm,
                "panel_size_min": self.panel_size_min, "panel_size_max": self.panel_size_max,
                "seconds": self.seconds}


def remesh(samples: SurfaceSamples, spec: SurfaceSpec) -> RemeshResult:
    """Build the net of ``spec.net`` on a sampled surface (mm).

    Raises
    ------
    GeometryError : the surface is not a height field over the plan of the sections, or the net degenerates
        (the message gives the place in mm)
    DesignError : a net kind that is not built
    """
    t0 = time.process_time()
    if spec.net != "sections":
        raise DesignError("surface.net", f"{spec.net!r} is not built yet; use 'sections'")
    frame = plan_frame(samples.points, spec.plane_normal)
    local = frame.to_local(samples.points)
    hf = fit_height_field(local, spec.spacing / CELL_PER_SPACING, spec.smoothing * spec.spacing)
    fit_dev = float(np.max(np.abs(hf.f(local[:, 0], local[:, 1]) - local[:, 2])))
    loops = [frame.to_local(b)[:, :2] for b in samples.boundary]
    net = sections_net(hf, frame, loops, spec.spacing, spec.min_face)
    # the conjugate curves fan out or converge away from the middle: scale the two steps so that each
    # family's shortest and longest edge straddle the spacing (geometric mean 1), if that narrows the range
    # without losing more than a fifth of the panels
    g = tuple(float(np.sqrt(e.min() * e.max())) / spec.spacing for e in (net.edge_lengths_rows,
                                                                       net.edge_lengths_cols))
    if max(abs(np.log(g[0])), abs(np.log(g[1]))) > 0.02:
        other = sections_net(hf, frame, loops, spec.spacing, spec.min_face, (1.0 / g[0], 1.0 / g[1]))
        if _worst(other, spec.spacing) < _worst(net, spec.spacing) and \
                other.grid_faces.sum() >= 0.8 * net.grid_faces.sum():
            net = other
    v = np.asarray(net.mesh.vertices).reshape(-1, 3)
    planes = net.planes[net.row_of_vertex]
    planarity = float(np.max(np.abs(np.einsum("ij,ij->i", v, planes[:, :3]) + planes[:, 3])))
    sizes = np.concatenate([net.edge_lengths_rows, net.edge_lengths_cols]) / spec.spacing
    return RemeshResult(net, frame, hf, fit_dev, planarity, float(sizes.min()), float(sizes.max()),
                        time.process_time() - t0)


def _worst(net: SectionsNet, spacing: float) -> float:
    """The largest ``|log(edge / spacing)|`` over the kept edges of both families."""
    e = np.concatenate([net.edge_lengths_rows, net.edge_lengths_cols]) / spacing
    return float(np.abs(np.log(e)).max())
