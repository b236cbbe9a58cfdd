"""The records of a finished build — data only, at the bottom of the fabrication layer (it imports nothing of
``fabrication`` or ``ppfab``).

:class:`Package` holds the :class:`Part` records of every kind (with a :class:`Placement` on its cutting sheet,
its :class:`Frame` and flat outline), the :class:`Node` and :class:`Weld` records, the :class:`Sheet` records
and the mesh.  :mod:`fabrication.readers` fills them from an output folder (``fabrication.open_build``) or
from a build in memory (``package_of``).
"""

from .mesh import MeshData
from .node import Node, NodeBeam, NodePair
from .package import Package, differences
from .parts_table import PartsTable
from .part import (KIND_DATA, BeamData, ColumnError, Frame, Hole, PanelData, Part, Placement, SpliceData,
                   StripData)
from .sheet import Sheet
from .weld import Weld

__all__ = ["KIND_DATA", "BeamData", "ColumnError", "Frame", "Hole", "MeshData", "Node", "NodeBeam", "NodePair",
           "Package", "PanelData", "PartsTable", "Part", "Placement", "Sheet", "SpliceData", "StripData", "Weld", "differences"]
