"""The record of one part: :class:`Part`, with its placement, frame and a small typed record per kind.

Made from the columns of one ``parts.json`` row (:meth:`Part.from_columns`) plus the geometry that the table
does not hold: the flat outline and holes (from the cutting sheets, the splice DXFs, or a strip's length and
width).  The readers and :func:`fabrication.readers.package_of` both go through :meth:`Part.from_columns`, so
a part read from a folder and the same part of the build in memory are made by one function.

Columns the record does not know (a kind added later, a new column) are kept in :attr:`Part.extra` with the
value the table holds; empty cells are left out of it.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any, Callable, Mapping

from . import values as v

NOT_ON_A_SHEET = 0
"""``parts.csv`` ``sheet`` of a part not nested on a cutting sheet (strips are cut from bars, cover plates from
their type's DXF, retention parts bought): the sheets are numbered from 1, so the column stays an integer column
for a typed reader (pandas reads it as ``int64``; empty cells made it ``float64``).  An empty cell (folders
written before this) reads the same."""

Point2 = tuple[float, float]
Point3 = tuple[float, float, float]


def column(name: str | tuple[str, ...], conv: Callable[[Any], Any], default: Any = None) -> Any:
    """A field filled from the column ``name`` (or the first present of several names: a column renamed
    between versions) through ``conv``."""
    names = (name,) if isinstance(name, str) else name
    return field(default=default, metadata={"columns": names, "conv": conv})


class ColumnError(ValueError):
    """A cell that cannot be read: ``column`` names it, the message says why."""

    def __init__(self, column: str, reason: str):
        super().__init__(reason)
        self.column = column
        self.reason = reason


def fill(cls: type, cols: Mapping[str, Any]) -> tuple[Any, set[str]]:
    """An instance of the record class ``cls`` from ``cols``, and the column names it used."""
    kwargs, used = {}, set()
    for f in fields(cls):
        names = f.metadata.get("columns")
        if not names:
            continue
        name = next((n for n in names if n in cols), None)
        if name is None:
            continue
        used.add(name)
        try:
            kwargs[f.name] = f.metadata["conv"](cols[name])
        except ValueError as exc:
            raise ColumnError(name, str(exc)) from None
    return cls(**kwargs), used


@dataclass(frozen=True)
class Frame:
    """A part's plane frame in the model (mm): origin and the unit axes; the flat outline's ``x, y`` are along
    ``x_dir``, ``y_dir`` from ``origin``."""

    origin: Point3
    x_dir: Point3
    y_dir: Point3
    normal: Point3

    @classmethod
    def from_value(cls, value: Any) -> "Frame | None":
        """From the ``frame`` cell (a table of four 3-vectors), ``None`` when empty."""
        if v.empty(value):
            return None
        doc = v.structured(value) if isinstance(value, str) else value
        if not isinstance(doc, dict):
            raise ValueError(f"expected a table origin, x_dir, y_dir, normal, got {value!r}")
        try:
            vec = {k: v.numbers(doc[k], 3) for k in ("origin", "x_dir", "y_dir", "normal")}
        except KeyError as exc:
            raise ValueError(f"frame has no {exc.args[0]}") from None
        return cls(**vec)  # type: ignore[arg-type]

    def to_model(self, x: float, y: float) -> Point3:
        """The model point of the flat point ``(x, y)``."""
        return tuple(o + x * a + y * b for o, a, b in zip(self.origin, self.x_dir, self.y_dir))  # type: ignore


@dataclass(frozen=True)
class Placement:
    """Where a part lies on its cutting sheet: the 1-based ``sheet``, its file, and the mapping
    ``R(rotation_deg) · M · p + (x, y)`` (``M`` mirrors ``x`` when ``mirrored``) of :mod:`fabrication.flatpart`."""

    sheet: int
    sheet_file: str
    x: float
    y: float
    rotation_deg: float
    mirrored: bool


@dataclass(frozen=True)
class Hole:
    """A round hole in the flat part: centre ``(x, y)`` in the part's frame and diameter, mm."""

    x: float
    y: float
    diameter: float


@dataclass(frozen=True)
class PanelData:
    """The columns of a glass pane."""

    face: int | None = column("face", v.opt_int)
    face_i: int | None = column("face_i", v.opt_int)
    face_j: int | None = column("face_j", v.opt_int)
    width_mm: float | None = column("width_mm", v.opt_float)
    height_mm: float | None = column("height_mm", v.opt_float)
    perimeter_mm: float | None = column("perimeter_mm", v.opt_float)
    weight_kg: float | None = column("weight_kg", v.opt_float)
    planarity_dev_mm: float | None = column("planarity_dev_mm", v.opt_float)
    min_angle_deg: float | None = column("min_angle_deg", v.opt_float)
    flags: tuple[str, ...] = column(("panel_flags", "flags"), v.words, ())
    outside: str = column("outside", v.text, "")
    rotation: str = column("rotation", v.text, "")
    bite_min_mm: float | None = column("bite_min_mm", v.opt_float)
    setting_blocks: str = column("setting_blocks", v.text, "")


@dataclass(frozen=True)
class BeamData:
    """The columns of a beam plate (a whole beam, a piece of a split one or a segment)."""

    beam_id: str = column("beam_id", v.text, "")
    family: str = column("family", v.text, "")
    piece: int | None = column("piece", v.opt_int)
    pieces: int | None = column("pieces", v.opt_int)
    length_mm: float | None = column("length_mm", v.opt_float)
    depth_mm: float | None = column("depth_mm", v.opt_float)
    mass_kg: float | None = column("mass_kg", v.opt_float)
    nodes: tuple[int, ...] = column("nodes", v.whole_numbers, ())
    slots: int | None = column("slots", v.opt_int)
    holes: int | None = column("holes", v.opt_int)
    hole_mm: float | None = column("hole_mm", v.opt_float)
    joins: tuple[str, ...] = column("joins", v.words, ())
    splices: tuple[str, ...] = column("splices", v.words, ())


@dataclass(frozen=True)
class StripData:
    """The columns of a glazing strip (flat bar on a beam's top edge, cut from stock bars)."""

    beam: str = column("beam", v.text, "")
    family: str = column("family", v.text, "")
    length_mm: float | None = column("length_mm", v.opt_float)
    width_mm: float | None = column("width_mm", v.opt_float)
    edge_nodes: tuple[int, ...] = column("edge_nodes", v.whole_numbers, ())
    bar: int | None = column("bar", v.opt_int)
    bar_start_mm: float | None = column("bar_start_mm", v.opt_float)
    mass_kg: float | None = column("mass_kg", v.opt_float)
    gasket: str = column("gasket", v.text, "")
    weld: str = column("weld", v.text, "")


@dataclass(frozen=True)
class SpliceData:
    """The columns of a splice cover plate."""

    beam: str = column("beam", v.text, "")
    family: str = column("family", v.text, "")
    joins: tuple[str, ...] = column("joins", v.words, ())
    width_mm: float | None = column("width_mm", v.opt_float)
    height_mm: float | None = column("height_mm", v.opt_float)
    holes: int | None = column("holes", v.opt_int)
    hole_mm: float | None = column("hole_mm", v.opt_float)
    bolts: str = column("bolts", v.text, "")
    mass_kg: float | None = column("mass_kg", v.opt_float)


@dataclass(frozen=True)
class RetentionData:
    """The columns of a retention part (setting block, stop, pressure gasket, pressure plate, cover cap, or the
    screws of one plate): the pane or strip it belongs to, the strip and beam under it, its box (length along the
    frame's ``x_dir``, width along ``y_dir``, height along ``normal``), how many (screws: the plate's), the mass of
    the row, and a screw row's stations along the strip (mm from the frame's origin) and diameter."""

    owner: str = column("owner", v.text, "")
    strip: str = column("strip", v.text, "")
    beam: str = column("beam", v.text, "")
    length_mm: float | None = column("length_mm", v.opt_float)
    width_mm: float | None = column("width_mm", v.opt_float)
    height_mm: float | None = column("height_mm", v.opt_float)
    quantity: int | None = column("quantity", v.opt_int)
    mass_kg: float | None = column("mass_kg", v.opt_float)
    diameter_mm: float | None = column("diameter_mm", v.opt_float)
    screw_stations_mm: tuple[float, ...] = column("screw_stations_mm", v.float_list, ())


RETENTION_KIND_NAMES = ("setting_block", "stop", "pressure_gasket", "pressure_plate", "cover_cap", "screw")
"""The retention kinds (the contract's ``RETENTION_KINDS``; the model imports nothing of the project)."""

KIND_DATA: dict[str, type] = {"panel": PanelData, "beam": BeamData, "strip": StripData, "splice": SpliceData,
                              **{k: RetentionData for k in RETENTION_KIND_NAMES}}
"""The typed record of each known kind; a part of another kind keeps all its own columns in ``extra``."""

Details = PanelData | BeamData | StripData | SpliceData | RetentionData

_COMMON = {"part_id", "kind", "type_id", "material", "thickness_mm", "area_mm2", "nest_tag", "sheet", "sheet_file",
           "x", "y", "rotation_deg", "mirrored", "frame", "plane"}


@dataclass(frozen=True)
class Part:
    """One part of a build, of any kind (``panel``, ``beam``, ``strip``, ``splice``, or one added later).

    ``outline`` is the flat cutting outline ``(k, 2)`` in the part's own frame (mm, counter-clockwise, not
    repeating the first point), ``None`` when no file of the build draws it; ``holes`` the round holes cut in it.
    ``frame`` and ``plane`` (``n·x + d = 0``) place a part that has them in the model; ``placement`` puts a part
    nested on a cutting sheet there.  ``details`` holds the columns of its kind, ``extra`` every other non-empty
    column.
    """

    part_id: str
    kind: str
    type_id: str = ""
    material: str = ""
    thickness_mm: float | None = None
    area_mm2: float | None = None
    nest_tag: str = ""
    placement: Placement | None = None
    outline: tuple[Point2, ...] | None = None
    holes: tuple[Hole, ...] = ()
    frame: Frame | None = None
    plane: tuple[float, float, float, float] | None = None
    details: Details | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def from_columns(cls, cols: Mapping[str, Any], outline: Any = None, holes: Any = ()) -> "Part":
        """The part of one parts-table row ``cols`` (JSON values, or CSV cells already typed by
        :func:`~fabrication.model.values.csv_typed`), with its flat ``outline`` ``(k, 2)`` and ``holes``
        ``(h, 3)`` (``x, y, diameter``) when known.  Raises :class:`ColumnError` naming a bad cell."""
        def get(name: str, conv: Callable[[Any], Any]) -> Any:
            try:
                return conv(cols.get(name))
            except ValueError as exc:
                raise ColumnError(name, str(exc)) from None

        part_id, kind = get("part_id", v.text), get("kind", v.text)
        if not part_id:
            raise ColumnError("part_id", "empty part id")
        placement = None
        if not v.empty(cols.get("sheet")) and get("sheet", v.opt_int) != NOT_ON_A_SHEET:
            xy = [get(k, v.opt_float) for k in ("x", "y", "rotation_deg")]
            if any(c is None for c in xy):
                missing = next(k for k, c in zip(("x", "y", "rotation_deg"), xy) if c is None)
                raise ColumnError(missing, "a part on a sheet needs x, y and rotation_deg")
            placement = Placement(get("sheet", v.opt_int), get("sheet_file", v.text), xy[0], xy[1], xy[2],
                                  get("mirrored", v.flag))
        data_cls = KIND_DATA.get(kind)
        details, used = fill(data_cls, cols) if data_cls else (None, set())
        extra = {k: val for k, val in cols.items() if k not in _COMMON and k not in used and not v.empty(val)}
        frame = get("frame", Frame.from_value)
        plane = get("plane", lambda c: v.numbers(c, 4))
        return cls(part_id=part_id, kind=kind, type_id=get("type_id", v.text), material=get("material", v.text),
                   thickness_mm=get("thickness_mm", v.opt_float), area_mm2=get("area_mm2", v.opt_float),
                   nest_tag=get("nest_tag", v.text), placement=placement,
                   outline=None if outline is None else tuple((float(x), float(y)) for x, y in outline),
                   holes=tuple(Hole(float(h[0]), float(h[1]), float(h[2])) for h in holes),
                   frame=frame, plane=plane, details=details, extra=extra)

    def outline_array(self) -> Any:
        """The outline as a numpy array ``(k, 2)`` (``(0, 2)`` when unknown)."""
        import numpy as np

        return np.array(self.outline if self.outline is not None else np.zeros((0, 2)), dtype=float).reshape(-1, 2)
