"""DXF R12 copies of the cutting files, for cutting tables that read nothing newer.

ezdxf's R12 exporter (:mod:`ezdxf.addons.r12export`) writes any document as R12 without changing it: TEXT and
DIMENSION stay as they are, each ``LWPOLYLINE`` becomes a 2D ``POLYLINE`` with the same vertices and closed flag.
Its stock conversion drops the entity's XDATA; the exporter below carries the ``PPFAB`` XDATA (part id, nest tag,
kind, type id) over, so an R12 file is read back exactly like the R2010 one.  R12 has no ``$INSUNITS``: the
files are in millimetres by contract.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..contract import XDATA_APPID


def _export_lwpolyline(exporter, entity) -> None:
    from ezdxf.addons.r12export import lwpolyline_to_polyline

    polyline = lwpolyline_to_polyline(entity)
    if entity.has_xdata(XDATA_APPID):
        polyline.set_xdata(XDATA_APPID, list(entity.get_xdata(XDATA_APPID)))
    if len(polyline.vertices):
        polyline.export_dxf(exporter.tagwriter())


def save_r12(doc, path: str | os.PathLike) -> Path:
    """Write ``doc`` (any version) as DXF R12 to ``path``, keeping the XDATA of the CUT outlines."""
    import logging

    from ezdxf.addons.r12export import R12Exporter

    from datetime import datetime

    from ezdxf.tools import juliandate

    path = Path(path)
    fixed = juliandate(datetime(2000, 1, 1))    # as ezdxf's fixed metadata: the exporter does not set them
    for var in ("$TDCREATE", "$TDUCREATE", "$TDUPDATE", "$TDUUPDATE"):
        doc.header[var] = fixed
    log = logging.getLogger("ezdxf")
    level = log.level
    log.setLevel(logging.ERROR)       # "units are not exported for DXF R12" is expected, not a warning to show
    try:
        exporter = R12Exporter(doc)
        exporter.exporters["LWPOLYLINE"] = _export_lwpolyline
        text = exporter.to_string()
    finally:
        log.setLevel(level)
    with open(path, "w", encoding="cp1252", errors="dxfreplace") as fh:      # R12: ANSI_1252, \U+nnnn escapes
        fh.write(text)
    return path
