"""Glass panels: one per mesh face, planarity-checked, inset for the joints, flattened, labelled, typed.

>>> from fabrication.panels import PanelParams, make_panels   # doctest: +SKIP
"""

from .congruence import congruence_distance, group_congruent
from .panel import Panel, make_panels, panel_types
from .params import PanelParams

__all__ = ["Panel", "PanelParams", "make_panels", "panel_types", "group_congruent",
           "congruence_distance"]
