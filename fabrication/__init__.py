"""ppfab's fabrication layer: millimetres, materials, CAD kernels and file formats.

Takes meshes and support structures from the geometry core (:mod:`ppfab`) and
produces what a shop cuts from: beam plates (STEP), glass panels and beam
plates nested on stock sheets (DXF), node data, parts lists and a report.
Heavy libraries (build123d, ezdxf, matplotlib) are imported inside
the functions that need them.
"""
