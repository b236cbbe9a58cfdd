"""The ``[surface]`` table of a design file: a surface to remesh into a quad net.

Examples
--------
>>> from ppfab.schema import parse_params
>>> s = parse_params(SurfaceSpec, {"path": "roof.3dm", "spacing": 1500.0}, "surface")
>>> s.net, s.spacing, s.plane_normal
('sections', 1500.0, None)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..errors import DesignError
from ..schema import param

NETS = ("sections", "principal", "conjugate", "pp")
"""The net kinds built."""

UNITS = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4, "ft": 304.8}
"""Length units a mesh file may be declared in, and their size in millimetres."""


@dataclass(frozen=True)
class SurfaceSpec:
    """Which surface, which net on it, and how large the panels are."""

    path: str = param("", doc="the surface file: a Rhino .3dm (the first NURBS surface or Brep face, trims "
                              "kept) or a triangle mesh (.obj, .off, .stl, .ply); relative to the design file")
    net: str = param("sections", doc="the net: sections (planar sections by parallel planes and their "
                                     "conjugate curves; the sections are the rows, planar before optimising), "
                                     "principal (curvature lines: conjugate and orthogonal; refused at an "
                                     "umbilic), conjugate (the conjugate net nearest two guide directions, "
                                     "guides; also through umbilics) or pp (two families of planar sections, "
                                     "both planar before optimising; refused when far from conjugate)",
                     choices=NETS)
    spacing: float = param(1500.0, doc="target panel size, mm (arc length along both families)",
                           exclusive_min=0.0)
    plane_normal: list[float] | None = param(None, doc="normal of the parallel section planes (default: "
                                                       "vertical planes across the longer plan direction)",
                                             length=3)
    pencil_axis: list[float] | None = param(None, doc="sections net: the section planes form a pencil through "
                                                      "the vertical line at this plan point [x, y] (mm, the "
                                                      "surface's coordinates, outside its outline) instead of "
                                                      "parallel planes: sections that fan out from the axis",
                                            length=2)
    search_planes: bool = param(False, doc="sections and conjugate nets: try vertical section planes (and guides "
                                           "turned with them) every 15° in plan, then every 2.5° near the best, "
                                           "and keep the net whose edges stay nearest the spacing (a few "
                                           "seconds); plane_normal and guides are then the start, not fixed")
    second_normal: list[float] | None = param(None, doc="pp net: normal of the column planes, horizontal "
                                                        "(default: across plane_normal in plan)", length=3)
    guides: list[list[float]] | None = param(None, doc="conjugate net: two directions [x, y, z] the rows and "
                                                        "the columns should follow, projected on the plan "
                                                        "(default: the plan's axes, x the longer plan "
                                                        "direction)", length=2)
    row_guides: list[list[list[float]]] | None = param(None, doc="conjugate net: guide curves the rows should "
                                                                 "follow, each a polyline of points [x, y, z] in "
                                                                 "mm (the surface's coordinates), projected on "
                                                                 "the plan; between curves their directions are "
                                                                 "blended by distance")
    column_guides: list[list[list[float]]] | None = param(None, doc="conjugate net: guide curves for the columns, "
                                                                    "as row_guides (default: the second of guides, "
                                                                    "else across the rows' guide in plan)")
    guide_layers: list[str] | None = param(None, doc="conjugate net, a .3dm surface: the layer whose curves are "
                                                    "the rows' guide curves, and optionally the columns' layer "
                                                    "([\"Rows\"] or [\"Rows\", \"Columns\"]; a layer's name or "
                                                    "full path); each curve is sampled in mm")
    max_warp: float = param(60.0, doc="pp net: largest warp of a quad before optimising, mm (the normal part "
                                      "of c0 - c1 + c2 - c3: about how far planar panels move off the surface); "
                                      "a net warped more is refused", exclusive_min=0.0)
    units: str | None = param(None, doc="units of a mesh file (mm, cm, m, in, ft); a .3dm states its own and "
                                        "this must then be absent or agree", choices=tuple(UNITS))
    smoothing: float = param(1.0, doc="knot spacing of the least-squares spline whose curvature sets the net's "
                                      "directions, as a fraction of spacing (heights are not smoothed); raise "
                                      "it for a coarse faceted mesh", exclusive_min=0.0)
    min_face: float = param(0.25, doc="boundary panels smaller than this fraction of spacing² are dropped "
                                      "as slivers", min=0.0, max=1.0)
    object: str | None = param(None, doc="in a .3dm with several surfaces: the name of the object to use")

    def __post_init__(self) -> None:
        if not self.path:
            raise DesignError("path", "give the surface file (.3dm, .obj, .off, .stl or .ply)")
        curves = "row_guides" if self.row_guides is not None else "column_guides" if self.column_guides is not None \
            else "guide_layers" if self.guide_layers is not None else None
        if self.guide_layers is not None and not 1 <= len(self.guide_layers) <= 2:
            raise DesignError("guide_layers", f"names the rows' layer and optionally the columns' (one or two "
                                              f"names), not {len(self.guide_layers)}")
        if self.guide_layers is not None and (self.row_guides is not None or self.column_guides is not None):
            raise DesignError("guide_layers", "and row_guides / column_guides are both given: the curves come from "
                                              "the .3dm's layers or from the design, not both")
        if curves is not None and self.net != "conjugate":
            raise DesignError(curves, f"only the conjugate net follows guide curves (net is {self.net!r}); set "
                                      "net = 'conjugate' or remove the curves")
        if self.pencil_axis is not None:
            other = "plane_normal" if self.plane_normal is not None else "search_planes" if self.search_planes \
                else None
            if self.net != "sections":
                raise DesignError("pencil_axis", f"only the sections net has a pencil of planes (net is "
                                                 f"{self.net!r}); set net = 'sections' or remove pencil_axis")
            if other is not None:
                raise DesignError("pencil_axis", f"and {other} both say where the section planes go: a pencil "
                                                 "contains its vertical axis; remove one of them")
        if curves is not None and self.search_planes:
            raise DesignError("search_planes", f"turns the guide directions, and {curves} are fixed curves: set "
                                               "search_planes = false or remove the curves")

    def file(self, base_dir: Path | None = None) -> Path:
        """The surface file, a relative path taken from ``base_dir`` (the design file's folder)."""
        p = Path(self.path)
        return p if p.is_absolute() or base_dir is None else base_dir / p
