"""The geometry stage of a design with ``[surface]``: read the surface, build the net on it, optimise it for
planar panels (P: the section rows stay planar) staying close to the designer's surface, measure how far the
result lies from that surface, place it."""

from __future__ import annotations

import logging
from typing import Callable

import numpy as np

from ppfab.geometry import Geometry, check_size, vertex_count
from ppfab.mesh import QuadGrid, QuadMesh
from ppfab.topology import families_of

from ..design import Design
from ..progress import Progress

log = logging.getLogger("ppfab")


def surface_geometry(design: Design, progress: Progress, allow_large: bool,
                     before_optimize: Callable[[QuadGrid | QuadMesh, tuple[str, ...]], None]) -> Geometry:
    """Read ``[surface]``, remesh it, optimise with ``[optimize]`` (closeness to the surface as read), place."""
    from ppfab.surface import remesh
    from ppfab.transforms.similarity import transform

    from ..surfacefile import read_surface, with_layer_guides

    spec = design.surface
    assert spec is not None
    geo = design.geometry
    surface = read_surface(spec.file(design.base_dir), spec.units, spec.object)
    spec = with_layer_guides(spec, spec.file(design.base_dir), surface)
    if surface.note:
        log.warning(surface.note)
    progress.note(f"{spec.net} net, spacing {spec.spacing:g} mm…")
    r = remesh(surface.samples, spec)
    mesh: QuadGrid | QuadMesh = r.net.mesh
    check_size(vertex_count(mesh), geo.max_vertices, allow_large)
    families: tuple[str, ...] = tuple(geo.planar_families or families_of(r.net.planar_family))
    if design.optimize is None and r.net.planar_family == "none":
        from ppfab.errors import DesignError

        raise DesignError("optimize", f"the {spec.net} net has no planar polylines before optimising: add "
                                      "[optimize] with families = \"rows\" (or \"both\") so its beams can be "
                                      "planar")
    result = None
    if design.optimize is not None:
        from ppfab.optimize import optimize

        families = tuple(geo.planar_families or families_of(design.optimize.families))
        before_optimize(mesh, families)
        progress.note("optimising…")
        result = optimize(mesh, design.optimize, callback=progress.iteration,
                          reference=(surface.samples.points, surface.samples.triangles))
        if not result.targets_met:
            from ppfab.optimize.outcome import UNMET_NEXT

            log.warning("optimisation did not meet its targets: %s; %s", result.message, UNMET_NEXT)
        mesh = result.mesh
    v = np.asarray(mesh.vertices).reshape(-1, 3)
    deviation = float(surface.distance(v).max())
    progress.note(f"largest distance to the surface {deviation:.2f} mm")
    mesh = transform(mesh, geo.scale, geo.rotate_z_deg, geo.translate, geo.flip_orientation)
    return Geometry(mesh, families, f"surface:{spec.path}", result, deviation)
