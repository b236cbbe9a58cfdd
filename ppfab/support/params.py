"""The ``[support]`` table of a design file: how the node axes and support planes are found."""

from __future__ import annotations

from dataclasses import dataclass

from ppfab.errors import DesignError
from ppfab.schema import param


@dataclass(frozen=True)
class SupportParams:
    """How the support structure is found (the ``[support]`` table of a design file)."""

    method: str = param("auto", doc="'auto', 'pp' (the axis of a vertex is the line where its two polyline "
                                    "planes meet), 'p' (axes in the planes of one family), 'conical' (cone axes), "
                                    "'parallel' (least-squares parallel mesh), 'circular' (circular meshes: the unit vertex offset)")
    family: str = param("rows", doc="the planar family for method 'p': 'rows' or 'cols'",
                        choices=("rows", "cols"))
    planar_tolerance: float = param(1e-6, doc="δ_P (relative) below which a polyline counts as planar "
                                              "(method 'auto' and 'parallel'), and the relative distance from "
                                              "a line below which a polyline counts as straight (its plane is "
                                              "then the one through it that contains the surface normal)",
                                    min=0.0)
    max_normal_angle_deg: float = param(30.0, doc="a polyline whose plane is further than this from the surface "
                                                  "normal at one of its vertices is not a planar beam (rule "
                                                  "'tangent' of exclude); method 'parallel': if the exact "
                                                  "parallel mesh turns an axis further than this from the "
                                                  "normal, use the least-squares compromise (its torsion is "
                                                  "checked against beams.max_torsion_mm)",
                                        exclusive_min=0, max=90)
    exclude: list[int | str] = param(["auto"], doc="methods 'pp' and 'p': polylines left out of the planar "
                                                   "families (their edges become beams of one edge each, in "
                                                   "their own support planes): polyline ids (`ppfab check "
                                                   "--polylines` lists them) and rules 'auto' (the polylines "
                                                   "that cannot be planar beams, see docs), 'tangent', "
                                                   "'boundary', 'closed', 'singular', 'closed-singular', "
                                                   "'nonplanar'; [] keeps every polyline")
    max_axis_angle_deg: float = param(75.0, doc="largest angle between a node axis and the surface normal; a "
                                                "build whose axes leave the normals by more stops, naming the "
                                                "vertices (a beam along such an axis meets the glass at less "
                                                "than 90° minus this; the paper's PP constructions reach 60°)",
                                      exclusive_min=0, max=90)
    flip: bool = param(False, doc="turn all axes to the other side (beams on the outside; with [glazing] "
                                  "support = 'none': ppfab's strips would lie inside the plates)")

    def __post_init__(self) -> None:
        from .lines import RULES
        from .registry import check_method

        check_method(self.method, "method")
        for k, s in enumerate(self.exclude):
            if isinstance(s, str) and s != "auto" and s not in RULES:
                from ppfab.schema import suggest

                raise DesignError(f"exclude[{k}]", f"unknown rule {s!r}{suggest(s, ['auto', *RULES])}; rules: "
                                                   f"auto, {', '.join(RULES)}")
            if isinstance(s, int) and s < 0:
                raise DesignError(f"exclude[{k}]", f"polyline ids are 0 or more, got {s}")


@dataclass(frozen=True)
class BeamContext:
    """What the support methods need to know of the beams: their ``depth`` and the largest torsion
    ``max_torsion`` (offset of an axis at the bottom edge), both in mesh units (mm in a build)."""

    depth: float
    max_torsion: float
