"""Marking on the cutting sheets: every label and engraved text upright (rotation in (−90°, 90°]); every beam
plate carries one face mark on MARK and the opposite one on MARK_BACK, and the mark on MARK names the side of
the plate's plane ``n`` (``parts.csv`` ``plane``) that the face looking up from the sheet faces, from the
placement (``rotation_deg``, ``mirrored``) and the flat frame (``frame``) of ``parts.csv``
(:mod:`fabrication.marking`)."""

from __future__ import annotations

import ast

import numpy as np

from ..marking import face_marks
from . import Verification, check


def up_normal(row: dict) -> np.ndarray | None:
    """The 3D normal of the face that looks up from the sheet: the image of the sheet's ``+z`` under the part's
    placement, ``A e_x × A e_y`` with ``A = [x_dir y_dir] · M · R(−θ)`` (``None`` without a frame)."""
    try:
        frame = ast.literal_eval(row.get("frame", "") or "None")
        a = np.radians(float(row["rotation_deg"]))
    except (ValueError, SyntaxError, KeyError):
        return None
    if not isinstance(frame, dict):
        return None
    rinv = np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]])
    m = np.diag([-1.0, 1.0]) if str(row.get("mirrored", "0")) == "1" else np.eye(2)
    lin = np.stack([frame["x_dir"], frame["y_dir"]], axis=1) @ (m @ rinv)
    return np.cross(lin[:, 0], lin[:, 1])


@check("marking", 51)
def check_marking(v: Verification) -> None:
    rows = {r["part_id"]: r for r in v.data.get("parts", [])}
    for rel, texts in v.data.get("dxf_texts", {}).items():
        faces: dict[tuple[str, str], list[str]] = {}
        for t in texts:
            if not -90.0 < t.rotation_deg <= 90.0:
                v.error(rel, t.xdata.get("part_id", t.text), f"text {t.text!r} on {t.layer} is turned "
                                                             f"{t.rotation_deg:.1f}° (upside down)")
            if t.xdata.get("mark") == "face":
                faces.setdefault((t.xdata.get("part_id", ""), t.layer), []).append(t.text)
        for pid, (_, pts) in v.data.get("cut", {}).items():
            row = rows.get(pid)
            if row is None or row.get("kind") != "beam" or v.data["cut"][pid][0] != rel:
                continue
            top, under = faces.get((pid, "MARK"), []), faces.get((pid, "MARK_BACK"), [])
            up = up_normal(row)
            if up is None:
                continue
            try:
                n = np.asarray(ast.literal_eval(row["plane"]), dtype=float)[:3]
            except (ValueError, SyntaxError, KeyError):
                continue
            family = {"rows": 0, "cols": 1}.get(row.get("family", ""), 2)
            want = face_marks(family, 1 if float(up @ n) > 0 else -1)
            if top != [want[0]] or under != [want[1]]:
                v.error(rel, pid, f"face marks {top} / {under} (MARK / MARK_BACK), expected {want[0]!r} / "
                                  f"{want[1]!r} for mirrored={row.get('mirrored')}")
