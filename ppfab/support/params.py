"""The ``[support]`` table of a design file: how the node axes and support planes are found."""

from __future__ import annotations

from dataclasses import dataclass

from ppfab.schema import param


@dataclass(frozen=True)
class SupportParams:
    """How the support structure is found (the ``[support]`` table of a design file)."""

    method: str = param("auto", doc="'auto', 'pp' (U_i ∩ W_j), 'p' (axes in the planes of one family), "
                                    "'conical' (cone axes), 'parallel' (least-squares parallel mesh)")
    family: str = param("rows", doc="the planar family for method 'p': 'rows' or 'cols'",
                        choices=("rows", "cols"))
    planar_tolerance: float = param(1e-6, doc="δ_P (relative) below which a polyline counts as planar "
                                              "(method 'auto' and 'parallel')", min=0.0)
    max_normal_angle_deg: float = param(30.0, doc="methods 'p'/'parallel': if the exact parallel mesh turns an "
                                                  "axis further than this from the normal, use the least-squares "
                                                  "compromise (small torsion, reported)", exclusive_min=0, max=90)
    flip: bool = param(False, doc="turn all axes to the other side (beams on the outside)")

    def __post_init__(self) -> None:
        from .registry import check_method

        check_method(self.method, "method")
