"""The support structure hangs on the side of the mesh opposite the glass's outside, whichever side of the
mesh's face normals ``[panels] outside`` puts the glass on (a mesh whose faces point inwards — a real mesh's
orientation is whatever its author left — otherwise got its glazing strips inside its plates: 1,433 part pairs
overlapping by up to 12 mm on a patch of a real rotational mesh)."""

import tomllib

import numpy as np
import pytest

from conftest import small_vault
from fabrication.design import parse_design
from fabrication.progress import Progress
from fabrication.pipeline.stages import stage_geometry, stage_panels, stage_support


@pytest.mark.parametrize("outside", ["normal", "reverse"])
def test_node_axes_point_away_from_the_glass_outside(outside):
    text = small_vault("side").replace("[panels]", f'[panels]\noutside = "{outside}"')
    design = parse_design(tomllib.loads(text))
    p = Progress(quiet=True)
    geometry = stage_geometry(design, p, False)
    support = stage_support(design, geometry, p)
    panels = stage_panels(design, geometry, p)
    faces = np.asarray(support.mesh.faces)
    axes = np.asarray(support.axes)
    # the outside normal of each pane, from its 3D corners as make_panels placed them, against the mesh order
    # of the face's corners (independent of the panel frame): +1 where the pane's outside is the face normal side
    V = np.asarray(support.mesh.vertices)
    dots = []
    for panel in panels.panels:
        q = V[faces[panel.mesh_face]]
        n_face = np.cross(q[2] - q[0], q[3] - q[1])
        n_face /= np.linalg.norm(n_face)
        n_out = np.asarray(panel.frame.normal)
        side = np.sign(n_out @ n_face)
        assert side == (1.0 if outside == "normal" else -1.0)
        dots.extend(axes[faces[panel.mesh_face]] @ n_out)
    assert max(dots) < -0.5            # every node axis at a pane's corners points into the structure, below the glass
