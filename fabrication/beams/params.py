"""Parameters of the beam plates (the ``[beams]`` table of a design file)."""

from __future__ import annotations

from dataclasses import dataclass

from ppfab.errors import DesignError
from ppfab.schema import param

from .tolerance import en10029_upper_deviation


@dataclass(frozen=True)
class BeamParams:
    """Planar beam plates along the support planes, and their joints at the nodes.

    Examples
    --------
    >>> from ppfab.schema import parse_params
    >>> parse_params(BeamParams, {"depth": 250, "joint": "segmented"}, "beams").depth
    250.0
    """

    depth: float = param(200.0, doc="beam depth, mm, measured along the node axes from the mesh (top edge) "
                                    "to the bottom edge", exclusive_min=0)
    thickness: float = param(12.0, doc="plate thickness, mm (centred on the support plane)", exclusive_min=0)
    material: str = param("S355 steel plate", doc="material name for the parts list")
    density: float = param(7850.0, doc="material density, kg/m³ (steel 7850, glulam 470)", exclusive_min=0)
    joint: str = param("halflap", doc="'halflap' (PP: slots from above in rows, from below in columns), "
                                      "'segmented' (P: one family continuous, the other cut into segments "
                                      "between crossings), 'none' (plain intersecting plates, to study a "
                                      "structure: a build refuses it where plates of two beams meet); see "
                                      "fabrication.beams.joint_types")
    clearance: float | str = param("auto", doc="extra slot width, mm, or 'auto': slots are cut for the thickest "
                                               "plate EN 10029 class A allows (nominal + upper deviation, e.g. "
                                               "15 → 16.3 mm) plus slot_fit; ends that butt against another plate "
                                               "stop half of the fit short of that plate's thickest face", min=0)
    slot_fit: float = param(0.5, doc="fit allowance, mm, added to the EN 10029 plate thickness when clearance = "
                                     "'auto' (unused with a numeric clearance)", min=0)
    slot_play: float = param(2.0, doc="vertical play of a half-lap, mm: each slot is cut this much deeper than "
                                      "half the depth, so the crossing plates seat without bottoming out and "
                                      "their top edges can be set flush", min=0)
    continuous: str = param("auto", doc="segmented joints: the family that runs through the nodes, 'rows', "
                                        "'cols' or 'auto' (a planar family, rows when both are)",
                            choices=("auto", "rows", "cols"))
    min_angle_deg: float = param(20.0, doc="plates meeting at a node at a smaller angle are reported as "
                                           "degenerate", min=0, exclusive_max=90)
    min_segment: float = param(10.0, doc="shortest acceptable edge or trimmed segment, mm", min=0)
    max_length: float = param(6000.0, doc="longest flat piece, mm (its extent along its chord); longer beams "
                                          "(and every closed one) are cut between nodes, clear of the joints, "
                                          "into pieces one plate thickness shorter (room for the raised edge of "
                                          "a bevel under the glazing strips); 0 = never split", min=0)
    max_torsion_mm: float = param(0.5, doc="largest torsion of the support structure, as the offset at the "
                                           "beam's bottom edge: how far, mm, the node axis at one end of an edge, "
                                           "followed for the depth, leaves the plane of the edge and the other "
                                           "axis; a build above it stops, listing the edges", min=0)
    segment: list[int | str] = param([], doc="polylines cut into beams of one edge each at every node, in "
                                             "their planes: polyline ids (`ppfab check --polylines`) and rules "
                                             "'boundary', 'closed', 'singular', 'closed-singular' (see [support] "
                                             "exclude), 'nonplanar' (further than plane_tolerance from its "
                                             "plane) and 'blocked' (the column plates that no single direction "
                                             "puts into their half-lap slots: cut across the node axis only at "
                                             "the nodes that give every part a way in, each part welded to the "
                                             "row there)")
    tool_radius: float = param(0.0, doc="radius of the cutting tool, mm: each inner corner at a slot's closed "
                                        "end gets a dog-bone relief, a circle of this radius through the corner, "
                                        "so that the mating plate seats fully; 0 = sharp corners (laser). Kerf "
                                        "notes per process: DXF header and report", min=0)
    plane_tolerance: float = param(0.5, doc="largest distance, mm, of a mesh vertex from the plane of the "
                                            "beam that carries it; a polyline further off cannot be one "
                                            "planar plate", exclusive_min=0)
    halflap_welds: bool = param(True, doc="weld every half-lap crossing along its crossing line, in its four "
                                         "corners over the depth (welds.csv joint 'halflap'); false: the "
                                         "crossings are not welded (the engineer's hinge or bolted cleat)")
    fallback: str = param("refuse", doc="a polyline of a requested planar family that cannot be a planar beam "
                                         "(its plane too far from the surface normal, or its axes conflict): "
                                         "'refuse' stops the build naming the polylines and why; 'segmented' "
                                         "accepts one-edge plates for them, said on the terminal and in --json",
                           choices=("refuse", "segmented"))

    def __post_init__(self) -> None:
        from .joint_types import get_joint_type

        if isinstance(self.clearance, str):
            if self.clearance != "auto":
                raise DesignError("clearance", f"expected a number of mm or 'auto', got {self.clearance!r}")
            en10029_upper_deviation(self.thickness, "thickness")
        if self.slot_play >= 0.5 * self.depth:
            raise DesignError("slot_play", f"{self.slot_play:g} mm is not below half the depth "
                                           f"({0.5 * self.depth:g} mm): the crossing plates would come apart")

        get_joint_type(self.joint, "joint")
        from ppfab.support.lines import RULES

        rules = [*(r for r in RULES if r != "tangent"), "blocked"]        # blocked: plates.BLOCKED_RULE
        for k, s in enumerate(self.segment):
            if isinstance(s, str) and s not in rules:
                from ppfab.schema import suggest

                raise DesignError(f"segment[{k}]", f"unknown rule {s!r}{suggest(s, rules)}; rules: "
                                                   f"{', '.join(rules)}")
            if isinstance(s, int) and s < 0:
                raise DesignError(f"segment[{k}]", f"polyline ids are 0 or more, got {s}")
        if self.max_length and self.max_length < 2 * self.min_segment:
            raise DesignError("max_length", f"must be 0 or at least twice min_segment ({2 * self.min_segment:g} mm), "
                                            f"got {self.max_length:g}")

    @property
    def thickness_deviation(self) -> float:
        """Upper deviation of the plate thickness the slots are cut for, mm: EN 10029 class A with
        ``clearance = "auto"``, 0 with a numeric clearance (the old rule ``t + clearance``)."""
        return en10029_upper_deviation(self.thickness) if self.clearance == "auto" else 0.0

    @property
    def slot_thickness(self) -> float:
        """The plate thickness a slot or end set-back is cut for, mm (nominal + :attr:`thickness_deviation`)."""
        return self.thickness + self.thickness_deviation

    @property
    def fit(self) -> float:
        """Fit allowance beyond :attr:`slot_thickness`, mm: ``slot_fit`` (auto) or the numeric clearance."""
        return self.slot_fit if self.clearance == "auto" else float(self.clearance)

    @property
    def clearance_mm(self) -> float:
        """Extra width of a square (90°) slot over the nominal thickness, mm (deviation + fit)."""
        return self.thickness_deviation + self.fit

    @property
    def slot_length(self) -> float:
        """Depth of every half-lap slot from its plate edge, mm: half the beam depth plus ``slot_play``."""
        return 0.5 * self.depth + self.slot_play

    @property
    def continuous_family(self) -> int | None:
        """0 (rows), 1 (cols) or ``None`` (auto)."""
        return {"rows": 0, "cols": 1}.get(self.continuous)

    def manifest(self) -> dict:
        """The entries this record contributes to ``manifest.json['fabrication']``."""
        return {"beam_depth": self.depth, "beam_thickness": self.thickness, "beam_material": self.material,
                "beam_density": self.density, "beam_joint": self.joint, "beam_clearance": self.clearance,
                "beam_thickness_deviation": self.thickness_deviation, "beam_slot_fit_mm": self.fit,
                "beam_slot_depth": self.slot_length,
                "beam_min_angle_deg": self.min_angle_deg, "beam_min_segment": self.min_segment,
                "beam_max_length": self.max_length, "beam_plane_tolerance": self.plane_tolerance,
                "beam_tool_radius": self.tool_radius,
                "beam_continuous": self.continuous}
