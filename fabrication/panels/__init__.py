"""Glass panels: one per mesh face, planarity-checked, inset for the joints, flattened, labelled, typed.

>>> import numpy as np
>>> from ppfab.mesh import QuadGrid
>>> from fabrication.panels import PanelParams, make_panels
>>> x, y = np.meshgrid(np.arange(3) * 1500.0, np.arange(2) * 1200.0, indexing="ij")
>>> panels = make_panels(QuadGrid(np.stack([x, y, 0 * x], axis=-1)), PanelParams(gap=10.0))  # 2 x 1 faces, mm
>>> len(panels), round(panels[0].area_mm2)          # each pane inset by gap/2: 1490 mm x 1190 mm
(2, 1773100)
"""

from .congruence import congruence_distance, group_congruent
from .panel import Panel, make_panels, panel_types, type_flat_parts
from .params import PanelParams

__all__ = ["Panel", "PanelParams", "make_panels", "panel_types", "type_flat_parts", "group_congruent",
           "congruence_distance"]
