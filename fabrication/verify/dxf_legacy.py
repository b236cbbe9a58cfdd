"""dxf_r12/ and dxf_r2000/: each file in its DXF version, passing the cutting-file contract, with the same parts,
nest tags, outlines and dimensions as the file of the same name in the main folders."""

from __future__ import annotations

import numpy as np

from ..contract import DXF_OLDEST, LEGACY_DXF, R12_OLDEST, TYPE_DIR
from . import Verification, check

VERSION_CODES = {"R12": "AC1009", "R2000": "AC1015"}


@check("dxf_legacy")
def check_dxf_legacy(v: Verification) -> None:
    files = v.manifest.get("files", {})
    from ..writers.dxf import read_sheet_dxf, check_sheet_dxf

    done = False
    for version, folder in LEGACY_DXF.items():
        for rel in files.get(folder, []):
            done = True
            main = rel[len(folder) + 1:]
            is_type = main.startswith(TYPE_DIR + "/")
            try:
                c = check_sheet_dxf(v.folder / rel, require_sheet=not is_type,
                                    oldest=R12_OLDEST if version == "R12" else DXF_OLDEST)
                ref = read_sheet_dxf(v.folder / main)
            except Exception as exc:  # noqa: BLE001 - reported as a finding
                v.error(rel, "", str(exc))
                continue
            if c.dxfversion != VERSION_CODES[version]:
                v.error(rel, "", f"DXF version {c.dxfversion}, expected {version} ({VERSION_CODES[version]})")
            mine = {p.part_id: p for p in c.parts}
            for p in ref.parts:
                q = mine.get(p.part_id)
                if q is None:
                    v.error(rel, p.part_id, f"part of {main} is missing")
                elif q.nest_tag != p.nest_tag or q.points.shape != p.points.shape or \
                        np.abs(q.points - p.points).max() > 1e-6:
                    v.error(rel, p.part_id, f"outline or nest tag differs from {main}")
            if len(c.parts) != len(ref.parts) or len(c.dimensions) != len(ref.dimensions) or \
                    (c.dimensions and np.abs(np.array(c.dimensions) - ref.dimensions).max() > 1e-6):
                v.error(rel, "", f"{len(c.parts)} parts and {len(c.dimensions)} dimensions, {main} has "
                                 f"{len(ref.parts)} and {len(ref.dimensions)}")
    if done:
        v.checked.append("dxf_legacy")
