"""``ppfab verify OUT``: re-read a build's files and check them against each other and the output contract.

Each check appends :class:`Finding` records (file, element, message); the
command fails when any finding is an error.  The checks re-read files with
the real readers: JSON, CSV, the OBJ reader of :mod:`ppfab.io`, ezdxf (with its
auditor) for DXF and the CAD kernel for STEP.
"""

from __future__ import annotations

import csv
import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

PARTS_COLUMNS = ["part_id", "kind", "sheet", "x", "y", "rotation_deg", "nest_tag", "area_mm2"]
NODES_COLUMNS = ["node_id", "vertex", "x", "y", "z", "axis_x", "axis_y", "axis_z", "beams"]


@dataclass(frozen=True)
class Finding:
    file: str
    element: str
    message: str

    def __str__(self) -> str:
        return f"{self.file}: {self.element}: {self.message}" if self.element else f"{self.file}: {self.message}"


@dataclass
class Verification:
    folder: Path
    findings: list[Finding] = field(default_factory=list)
    checked: list[str] = field(default_factory=list)
    data: dict[str, Any] = field(default_factory=dict)

    def error(self, file: str, element: str, message: str) -> None:
        self.findings.append(Finding(file, element, message))

    @property
    def ok(self) -> bool:
        return not self.findings


def read_csv(path: Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def check_manifest(v: Verification) -> None:
    path = v.folder / "manifest.json"
    if not path.exists():
        v.error("manifest.json", "", "missing")
        return
    try:
        m = json.loads(path.read_text(encoding="utf-8"))
    except ValueError as exc:
        v.error("manifest.json", "", f"not valid JSON ({exc})")
        return
    v.data["manifest"] = m
    for key in ("generator", "units", "design", "mesh", "fabrication", "files", "quality", "sha256"):
        if key not in m:
            v.error("manifest.json", key, "missing key")
    if m.get("units") != "mm":
        v.error("manifest.json", "units", f"must be 'mm', got {m.get('units')!r}")
    for name, digest in sorted(m.get("sha256", {}).items()):
        f = v.folder / name
        if not f.exists():
            v.error(name, "", "listed in the manifest but missing")
        elif _sha(f) != digest:
            v.error(name, "", "sha256 differs from the manifest (file changed after the build)")
    listed = set()
    for value in m.get("files", {}).values():
        listed.update([value] if isinstance(value, str) else [x for x in value if isinstance(x, str)])
    for name in sorted(listed - set(m.get("sha256", {}))):
        v.error("manifest.json", name, "file listed without a sha256")
    v.checked.append("manifest")


def check_mesh(v: Verification) -> None:
    from ppfab.io import read_mesh

    m = v.data.get("manifest", {})
    rel = m.get("mesh", {}).get("path", "mesh.obj")
    try:
        mesh = read_mesh(v.folder / rel)
    except Exception as exc:  # noqa: BLE001 - reported as a finding
        v.error(rel, "", f"cannot be read: {exc}")
        return
    v.data["mesh"] = mesh
    me = m.get("mesh", {})
    if me.get("vertices") not in (None, len(mesh.vertices)):
        v.error(rel, "vertices", f"{len(mesh.vertices)} in the file, {me.get('vertices')} in the manifest")
    if me.get("faces") not in (None, len(mesh.faces)):
        v.error(rel, "faces", f"{len(mesh.faces)} in the file, {me.get('faces')} in the manifest")
    if "rows" in me:
        cols = me["cols"] if not me.get("closed") else me["cols"] + 1
        if (me["rows"] - 1) * (cols - 1) != len(mesh.faces):
            v.error(rel, "grid", f"rows {me['rows']} x cols {me['cols']} do not match {len(mesh.faces)} faces")
    v.checked.append("mesh")


def check_parts(v: Verification) -> None:
    files = v.data.get("manifest", {}).get("files", {})
    rel = files.get("parts_csv")
    if rel is None:
        return
    rows = read_csv(v.folder / rel)
    v.data["parts"] = rows
    if rows:
        missing = [c for c in PARTS_COLUMNS if c not in rows[0]]
        if missing:
            v.error(rel, "columns", f"missing contract columns {missing}")
            return
    ids, tags = set(), set()
    for r, row in enumerate(rows, start=2):
        if row["part_id"] in ids:
            v.error(rel, f"line {r}", f"part id {row['part_id']} appears twice")
        ids.add(row["part_id"])
        if row["nest_tag"] in tags:
            v.error(rel, f"line {r}", f"nest tag {row['nest_tag']} appears twice")
        tags.add(row["nest_tag"])
        if row["kind"] not in ("panel", "beam"):
            v.error(rel, row["part_id"], f"kind must be panel or beam, got {row['kind']!r}")
    mesh = v.data.get("mesh")
    panels = [row for row in rows if row["kind"] == "panel"]
    if mesh is not None and panels:
        faces = sorted(int(row["face"]) for row in panels)
        if faces != list(range(len(mesh.faces))):
            missing = sorted(set(range(len(mesh.faces))) - set(faces))
            v.error(rel, "panels", f"{len(panels)} panel rows for {len(mesh.faces)} mesh faces"
                                   + (f"; faces without a panel: {missing[:10]}" if missing else ""))
    v.checked.append("parts")


def check_nodes(v: Verification) -> None:
    files = v.data.get("manifest", {}).get("files", {})
    rel = files.get("nodes_csv")
    mesh = v.data.get("mesh")
    if rel is None or mesh is None:
        return
    rows = read_csv(v.folder / rel)
    if rows:
        missing = [c for c in NODES_COLUMNS if c not in rows[0]]
        if missing:
            v.error(rel, "columns", f"missing contract columns {missing}")
            return
    if len(rows) != len(mesh.vertices):
        v.error(rel, "rows", f"{len(rows)} nodes for {len(mesh.vertices)} mesh vertices")
    part_ids = {row["part_id"] for row in v.data.get("parts", [])}
    for row in rows:
        k = int(row["vertex"])
        if not 0 <= k < len(mesh.vertices):
            v.error(rel, row["node_id"], f"vertex {k} does not exist")
            continue
        p = np.array([float(row[c]) for c in ("x", "y", "z")])
        if np.abs(p - mesh.vertices[k]).max() > 1e-3:
            v.error(rel, row["node_id"], f"position differs from OBJ vertex {k} by "
                                          f"{np.abs(p - mesh.vertices[k]).max():.3g} mm")
        a = np.array([float(row[c]) for c in ("axis_x", "axis_y", "axis_z")])
        if abs(np.linalg.norm(a) - 1) > 1e-6:
            v.error(rel, row["node_id"], f"axis is not a unit vector (|a| = {np.linalg.norm(a):.6f})")
        for b in filter(None, row["beams"].split(";")):
            if part_ids and b not in part_ids:
                v.error(rel, row["node_id"], f"beam {b} is not in the parts list")
    v.checked.append("nodes")


CHECKS: list[Callable[[Verification], None]] = [check_manifest, check_mesh, check_parts, check_nodes]


def verify(folder: str | Path) -> Verification:
    """Run every check on an output folder."""
    v = Verification(Path(folder))
    if not v.folder.is_dir():
        v.error(str(folder), "", "is not a folder")
        return v
    for check in CHECKS:
        check(v)
        if not v.data.get("manifest"):
            break
    return v
