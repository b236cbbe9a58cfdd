"""The record of one node (one mesh vertex) as ``nodes.json`` holds it: :class:`Node`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

from . import values as v
from .part import ColumnError, Point3


@dataclass(frozen=True)
class NodeBeam:
    """A beam plate meeting at a node: its part id, role (``through``/``end``), support plane ``[nx, ny, nz, d]``,
    the angles to the panels along it there, and its end set-back from the axis (``None`` when it runs through)."""

    part_id: str
    role: str
    plane: tuple[float, ...] | None
    panel_angles_deg: tuple[float, ...]
    panel_angle_min_deg: float | None
    trim_mm: float | None


@dataclass(frozen=True)
class NodePair:
    """Two plates meeting at a node and the angle between their planes."""

    a: str
    b: str
    dihedral_deg: float | None
    opening_deg: float | None
    same_beam: bool


_KNOWN = {"node_id", "vertex", "grid", "position", "axis", "beams", "joint", "valence", "boundary", "dihedral_deg",
          "pairs", "torsion_deg", "torsion_mm", "axis_normal_deg", "slot_width_mm"}


@dataclass(frozen=True)
class Node:
    """One node: id (``N0042``), OBJ vertex, grid index ``(i, j)`` on a regular patch, position (mm), unit node
    axis, the plates meeting there, the joint, and the angles and torsion there; other keys in ``extra``."""

    node_id: str
    vertex: int
    position: Point3
    axis: Point3
    grid: tuple[int, int] | None = None
    beams: tuple[NodeBeam, ...] = ()
    joint: str = ""
    valence: int | None = None
    boundary: bool = False
    dihedral_deg: float | None = None
    pairs: tuple[NodePair, ...] = ()
    torsion_deg: float | None = None
    torsion_mm: float | None = None
    axis_normal_deg: float | None = None
    slot_width_mm: float | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)

    @property
    def beam_ids(self) -> tuple[str, ...]:
        """The part ids of the plates meeting here."""
        return tuple(b.part_id for b in self.beams)

    @classmethod
    def from_record(cls, rec: Mapping[str, Any]) -> "Node":
        """From one entry of ``nodes.json`` (or the build's node table); raises :class:`ColumnError`."""
        def get(name: str, conv: Any) -> Any:
            try:
                return conv(rec.get(name))
            except (ValueError, TypeError, KeyError, AttributeError) as exc:
                raise ColumnError(name, str(exc) or "malformed") from None

        def vec3(c: Any) -> Point3:
            out = v.numbers(c, 3)
            if out is None:
                raise ValueError("missing")
            return out  # type: ignore[return-value]

        def grid(c: Any) -> tuple[int, int] | None:
            if v.empty(c):
                return None
            ij = v.whole_numbers(c)
            if len(ij) != 2:
                raise ValueError(f"expected [i, j], got {c!r}")
            return ij[0], ij[1]

        def beams(c: Any) -> tuple[NodeBeam, ...]:
            return tuple(NodeBeam(v.text(b["part_id"]), v.text(b.get("role")), v.numbers(b.get("plane"), 4),
                                  v.numbers(b.get("panel_angles_deg")) or (), v.opt_float(b.get("panel_angle_min_deg")),
                                  v.opt_float(b.get("trim_mm"))) for b in (c or ()))

        def pairs(c: Any) -> tuple[NodePair, ...]:
            return tuple(NodePair(v.text(p["a"]), v.text(p["b"]), v.opt_float(p.get("dihedral_deg")),
                                  v.opt_float(p.get("opening_deg")), v.flag(p.get("same_beam"))) for p in (c or ()))

        node_id = get("node_id", v.text)
        vertex = get("vertex", v.opt_int)
        if not node_id or vertex is None:
            raise ColumnError("node_id" if not node_id else "vertex", "missing")
        return cls(node_id=node_id, vertex=vertex, position=get("position", vec3), axis=get("axis", vec3),
                   grid=get("grid", grid), beams=get("beams", beams), joint=get("joint", v.text),
                   valence=get("valence", v.opt_int), boundary=get("boundary", v.flag),
                   dihedral_deg=get("dihedral_deg", v.opt_float), pairs=get("pairs", pairs),
                   torsion_deg=get("torsion_deg", v.opt_float), torsion_mm=get("torsion_mm", v.opt_float),
                   axis_normal_deg=get("axis_normal_deg", v.opt_float),
                   slot_width_mm=get("slot_width_mm", v.opt_float),
                   extra={k: val for k, val in rec.items() if k not in _KNOWN and not v.empty(val)})
