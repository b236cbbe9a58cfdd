"""One reader of the STEP files for the verify checks: every solid with its name, the assemblies above it and its
colour, read by the CAD kernel's STEP translator (XCAF, names on).

``build123d.import_step`` reads the same document but then builds a Python tree of the whole assembly
(attaching each child walks its siblings) and looks for a colour on every face of a solid that has none on its
label; at 21,416 solids (the glazing of an 88 × 60 roof) that bookkeeping, not the kernel, dominated.  Here
the labels are walked once, each located shape is composed with the locations of the assemblies above it,
and a colour is looked up on the component and the product label only, which is where ppfab's writers put
it.  The solids are build123d :class:`~build123d.Solid` objects, so the checks measure them as before.

Not a check (the leading underscore keeps it out of the registry).
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from . import Verification


@dataclass(frozen=True)
class StepSolid:
    """A solid of a STEP file: its product name, the names of the assemblies above it (root first), the solid
    (placed in the file's model space) and its colour ``(r, g, b, a)`` or ``None``."""

    name: str
    path: tuple[str, ...]
    solid: Any
    colour: tuple[float, float, float, float] | None


class StepReadError(ValueError):
    """The CAD kernel could not read a STEP file."""


def read_step_solids(path: str | os.PathLike, colours: bool = False) -> list[StepSolid]:
    """Every solid of the STEP file ``path`` in file order (depth first); ``colours`` also reads the colours.

    Raises the audit event ``fabrication.verify.read`` with the path first (the kernel opens the file outside
    Python, where the ``open`` event does not see it), so a hook can tell which files a check read."""
    sys.audit("fabrication.verify.read", os.fspath(path))
    from build123d import Solid
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.OCP.collections import Sequence_TDF_Label
    from OCP.Quantity import Quantity_ColorRGBA, Quantity_TOC_sRGB
    from OCP.STEPCAFControl import STEPCAFControl_Reader
    from OCP.TCollection import TCollection_AsciiString, TCollection_ExtendedString
    from OCP.TDataStd import TDataStd_Name
    from OCP.TDF import TDF_Label
    from OCP.TDocStd import TDocStd_Document
    from OCP.TopAbs import TopAbs_FACE, TopAbs_SOLID
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS
    from OCP.XCAFDoc import XCAFDoc_ColorCurv, XCAFDoc_ColorGen, XCAFDoc_ColorSurf, XCAFDoc_ColorTool
    from OCP.XCAFDoc import XCAFDoc_DocumentTool

    doc = TDocStd_Document(TCollection_ExtendedString("XCAF"))
    shapes = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    reader = STEPCAFControl_Reader()
    reader.SetNameMode(True)
    reader.SetColorMode(colours)
    reader.SetLayerMode(False)
    if reader.ReadFile(os.fsdecode(path)) != IFSelect_RetDone or not reader.Transfer(doc):
        raise StepReadError(f"{os.fsdecode(path)}: the STEP translator could not read the file")

    def name_of(label: Any) -> str:
        attr = TDataStd_Name()
        if label.FindAttribute(TDataStd_Name.GetID_s(), attr):
            return TCollection_AsciiString(attr.Get()).ToCString()
        return ""

    colour_tool = XCAFDoc_DocumentTool.ColorTool_s(doc.Main())
    kinds = (XCAFDoc_ColorCurv, XCAFDoc_ColorGen, XCAFDoc_ColorSurf)

    def rgba(col: Any) -> tuple[float, float, float, float]:
        r, g, b = col.GetRGB().Values(Quantity_TOC_sRGB)      # the file's values (the kernel keeps linear RGB)
        return (r, g, b, col.Alpha())

    def colour_of(sub: Any, ref: Any, shape: Any) -> tuple[float, float, float, float] | None:
        """The colour of the component, else of the product, else of the shape, else of its first face (ppfab
        colours every face of a solid alike)."""
        col = Quantity_ColorRGBA()
        for label in (sub, ref):
            if any(XCAFDoc_ColorTool.GetColor_s(label, kind, col) for kind in kinds):
                return rgba(col)
        faces = TopExp_Explorer(shape, TopAbs_FACE)
        for item in (shape, faces.Current() if faces.More() else None):
            if item is not None and any(colour_tool.GetColor(item, kind, col) for kind in kinds):
                return rgba(col)
        return None

    out: list[StepSolid] = []

    def walk(parent: Any, loc: Any, above: tuple[str, ...]) -> None:
        labels = Sequence_TDF_Label()
        if parent is None:
            shapes.GetFreeShapes(labels)
        else:
            shapes.GetComponents_s(parent, labels)
        for i in range(1, labels.Length() + 1):
            sub = labels.Value(i)
            ref = sub
            if shapes.IsReference_s(sub):
                ref = TDF_Label()
                shapes.GetReferredShape_s(sub, ref)
            here = loc.Multiplied(shapes.GetLocation_s(sub)) if parent is not None else loc
            name = name_of(ref)
            if shapes.IsAssembly_s(ref):
                walk(ref, here, above + (name,))
                continue
            own = shapes.GetShape_s(ref)
            colour = colour_of(sub, ref, own) if colours else None
            found = TopExp_Explorer(own.Moved(here), TopAbs_SOLID)
            while found.More():
                out.append(StepSolid(name, above, Solid(TopoDS.Solid(found.Current())), colour))
                found.Next()

    walk(None, TopLoc_Location(), ())
    return out


def read_or_report(v: "Verification", rel: str, colours: bool = False) -> list[StepSolid] | None:
    """The solids of the build's file ``rel`` (:func:`read_step_solids`), or ``None`` after a finding on ``v``
    when the kernel cannot read it.

    What was read is kept in ``data["step_read"]`` (per process: the forked checks keep their own), so two checks
    of one process read a file once (glazing.step: the bite and the glazing_step checks); a file that cannot be
    read is reported by the first check only."""
    memo = v.data.setdefault("step_read", {})
    key = (rel, colours)
    if key not in memo:
        try:
            memo[key] = read_step_solids(v.folder / rel, colours)
        except Exception as exc:  # noqa: BLE001 - reported as a finding
            v.error(rel, "", f"cannot be read by the CAD kernel ({exc})")
            memo[key] = None
    got: list[StepSolid] | None = memo[key]
    return got
