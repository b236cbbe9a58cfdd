"""beams.step: one valid solid per beam part, named by its part id, a plate of the beam thickness, under its beam
and family in the product tree, in its family's colour; panels.step: one solid per panel; both headers name ppfab."""

from __future__ import annotations

from typing import Any

import numpy as np

from . import Verification, check


@check("step", 60)
def check_step(v: Verification) -> None:
    """beams.step: one valid solid per beam part, named by its part id, a plate of the beam thickness."""
    files = v.data.get("manifest", {}).get("files", {})
    rel = files.get("beams_step")
    if rel is None:
        return
    from build123d import import_step

    from ..writers.step import named_solids

    try:
        shape = import_step(str(v.folder / rel))
        pairs = named_solids(shape)
    except Exception as exc:  # noqa: BLE001
        v.error(rel, "", f"cannot be read by the CAD kernel ({exc})")
        return
    v.data["beam_solids"] = {name: solid for name, solid in reversed(pairs)}
    beams = {r["part_id"]: r for r in v.data.get("parts", []) if r["kind"] == "beam"}
    t = float(v.data["manifest"].get("fabrication", {}).get("beam_thickness", 0.0))
    names = [n for n, _ in pairs]
    for name in sorted(set(beams) - set(names)):
        v.error(rel, name, "beam part has no solid")
    for name in sorted({n for n in names if names.count(n) > 1}):
        v.error(rel, name, "more than one solid carries this name")
    for name, solid in pairs:
        if name not in beams:
            v.error(rel, name or "(unnamed)", "solid is not a beam part in parts.csv")
            continue
        if not solid.is_valid:
            v.error(rel, name, "solid is not valid (BRepCheck)")
        pts = np.array([tuple(p) for p in solid.vertices()])
        c = pts - pts.mean(axis=0)
        normal = np.linalg.svd(c)[2][2]
        spread = float(np.ptp(c @ normal))
        if t and abs(spread - t) > 1e-6 * max(1.0, t):
            v.error(rel, name, f"solid is {spread:.6g} mm thick, expected {t:g} mm")
        area = float(beams[name].get("area_mm2") or 0.0)
        if t and area and abs(solid.volume - area * t) > 1e-4 * area * t:
            v.error(rel, name, f"volume {solid.volume:.6g} mm³ ≠ outline area × thickness {area * t:.6g} mm³")
    _check_tree(v, rel, beams, shape)
    v.checked.append("step")


def solid_paths(shape: Any, path: tuple[str, ...] = ()) -> list[tuple[tuple[str, ...], Any]]:
    """``(labels of the assemblies above, solid)`` of every solid below ``shape`` (root first)."""
    from build123d import Solid

    if isinstance(shape, Solid):
        return [(path, shape)]
    kids = list(getattr(shape, "children", ()) or ())
    if not kids:
        return [(path, s) for s in shape.solids()]
    out: list[tuple[tuple[str, ...], Any]] = []
    for kid in kids:
        out.extend(solid_paths(kid, path + (shape.label,)))
    return out


def check_header(v: Verification, rel: str) -> None:
    from ppfab import __version__

    from ..contract import FIXED_TIMESTAMP

    head = (v.folder / rel).read_bytes().partition(b"ENDSEC;")[0].decode("ascii", "replace")
    for needed in (f"'ppfab {__version__}'", f"'{FIXED_TIMESTAMP}'", "FILE_DESCRIPTION(('ppfab"):
        if needed not in head:
            v.error(rel, "header", f"does not name {needed} (ppfab, its version, the fixed time stamp)")


def _check_tree(v: Verification, rel: str, beams: dict, shape) -> None:
    """The product tree of beams.step: design → family → beam id → plate, each solid in its family's colour."""
    from ..contract import COLOURS

    check_header(v, rel)
    for path, solid in solid_paths(shape):
        row = beams.get(solid.label)
        if row is None:
            continue
        want = (row.get("family", ""), row.get("beam_id", ""))
        if tuple(path[-2:]) != want:
            v.error(rel, solid.label, f"sits under {'/'.join(path[1:]) or 'the root'}, expected {'/'.join(want)}")
        colour = getattr(solid, "color", None)
        rgb = COLOURS.get(want[0])
        if rgb is not None and (colour is None or max(abs(a - b) for a, b in zip(tuple(colour), rgb)) > 1e-3):
            v.error(rel, solid.label, f"colour {colour} is not the colour of family {want[0]}")
