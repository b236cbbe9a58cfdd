"""Reader of the flat DXFs of a build (cutting sheets, per-type and splice DXFs) with ezdxf: the CUT outlines
by their XDATA ``part_id``, the holes, the stock outline and the material written on the file."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..contract import STOCK_HEADER_VARS, XDATA_APPID, xdata_fields
from .errors import bad, missing

Points = tuple[tuple[float, float], ...]


@dataclass
class DxfCuts:
    """What one flat DXF cuts: outline per part id (in drawing order), holes ``(x, y, diameter)`` per part id
    (holes without a ``part_id`` under ``""``), the kind written on each outline, the SHEET and TRIM outlines and
    the header's material and thickness."""

    path: Path
    outlines: dict[str, Points] = field(default_factory=dict)
    kinds: dict[str, str] = field(default_factory=dict)
    holes: dict[str, list[tuple[float, float, float]]] = field(default_factory=dict)
    sheet: Points | None = None
    trim: Points | None = None
    material: str = ""
    thickness: str = ""


def read_cuts(path: Path, what: str) -> DxfCuts:
    """Read ``path`` (``what``: why it is needed, for the error when it is missing)."""
    import ezdxf
    from ezdxf.lldxf.const import DXFError

    if not path.is_file():
        raise missing(path, what)
    try:
        doc = ezdxf.readfile(path)
    except (DXFError, OSError, UnicodeDecodeError) as exc:
        raise bad(path, f"not a readable DXF ({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''})") \
            from None
    out = DxfCuts(path)
    custom = dict(doc.header.custom_vars) if doc.dxfversion >= "AC1018" else {}
    out.material, out.thickness = (str(custom.get(k, "")) for k in STOCK_HEADER_VARS)
    e: Any
    for e in doc.modelspace():
        kind, layer = e.dxftype(), e.dxf.layer
        if kind == "LWPOLYLINE":
            pts: Points = tuple((float(p[0]), float(p[1])) for p in e.get_points("xy"))
        elif kind == "POLYLINE" and not (e.is_3d_polyline or e.is_poly_face_mesh or e.is_polygon_mesh):
            pts = tuple((float(p[0]), float(p[1])) for p in e.points())   # R12: a 2D POLYLINE
        elif kind == "CIRCLE" and layer == "CUT":
            c = e.dxf.center
            out.holes.setdefault(xdata_fields(e).get("part_id", ""), []).append(
                (float(c[0]), float(c[1]), 2.0 * float(e.dxf.radius)))
            continue
        else:
            continue
        if layer == "SHEET":
            out.sheet = pts
        elif layer == "TRIM":
            out.trim = pts
        elif layer == "CUT":
            x = xdata_fields(e)
            pid = x.get("part_id", "")
            if not pid:
                raise bad(path, f"a CUT outline (handle {e.dxf.handle}) has no {XDATA_APPID} part_id XDATA")
            if pid in out.outlines:
                raise bad(path, f"part {pid} is cut twice")
            out.outlines[pid] = pts
            out.kinds[pid] = x.get("kind", "")
            if not out.material:
                out.material, out.thickness = x.get("material", ""), x.get("thickness_mm", "")
    return out


def box(points: Points | None) -> tuple[float, float, float, float] | None:
    """``(x0, y0, x1, y1)`` of an outline, ``None`` without one."""
    if not points:
        return None
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    return min(xs), min(ys), max(xs), max(ys)
