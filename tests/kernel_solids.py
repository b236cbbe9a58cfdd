"""Helpers of the tests that measure plates against glazing strips with the CAD kernel, apart from the code
under test: the stages of a design up to the glazing, a real mesh patch to build, a strip as a plain box and the
depth of the kernel's common part of two solids."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from conftest import shared_file


def stages(design_path: Path):
    """``(beams, glazing)``: the beams and glazing stages of the design at ``design_path`` (nothing written)."""
    from fabrication.design import load_design
    from fabrication.pipeline import stages as st
    from fabrication.progress import Progress

    d = load_design(design_path)
    p = Progress(quiet=True)
    g = st.stage_geometry(d, p, False)
    q = st.stage_quality(g, p)
    s = st.stage_support(d, g, p)
    panels = st.stage_panels(d, g, p, q)
    beams = st.stage_beams(d, s, p, panels)
    return beams, st.stage_glazing(d, s, panels, beams, p)


def rot4_patch_design(root: Path, reverse_columns: bool = False) -> Path:
    """A design of the 9 × 8-vertex patch of the real conical PP mesh DOI__rot4_def1_sparse_rot.obj (rows 20:29,
    columns 0:8, 3 m scale; its plates lean up to 29° off their strips), written into ``root``."""
    from ppfab.io import load_mesh, write_obj
    from ppfab.mesh import QuadGrid

    grid = load_mesh(shared_file("DOI__rot4_def1_sparse_rot.obj")).to_grid()
    cols = slice(7, None, -1) if reverse_columns else slice(0, 8)
    write_obj(QuadGrid(np.ascontiguousarray(grid.vertices[20:29, cols])), root / "patch.obj")
    (root / "d.toml").write_text(f'[design]\nname = "rot4 patch"\n[geometry]\nmesh = "{(root / "patch.obj").as_posix()}"\n'
                                 'scale = 3000.0\n[beams]\nfallback = "segmented"\n')
    return root / "d.toml"


def strip_solid(strip):
    """The strip as the kernel's box over its rectangle (frame and thickness only: none of the bevel code)."""
    from fabrication.writers.step import _placed_prism

    return _placed_prism(strip.outline(), strip.frame, 0.0, strip.thickness, strip.part_id)


def kernel_depth(a, b, u: np.ndarray) -> float:
    """Depth (mm, along ``u``) of the kernel's common part of two solids, 0 when it has no volume."""
    from build123d import Solid
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Common

    common = Solid(BRepAlgoAPI_Common(a.wrapped, b.wrapped).Shape())
    if common.volume < 1e-6:
        return 0.0
    z = np.array([tuple(p) for p in common.vertices()], dtype=float) @ u
    return float(z.max() - z.min())
