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

from .contract import NODES_CONTRACT_COLUMNS as NODES_COLUMNS
from .contract import PARTS_CONTRACT_COLUMNS as PARTS_COLUMNS


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
            bare = sorted(set(range(len(mesh.faces))) - set(faces))
            v.error(rel, "panels", f"{len(panels)} panel rows for {len(mesh.faces)} mesh faces"
                                   + (f"; faces without a panel: {bare[:10]}" if bare else ""))
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


def _inset_face_2d(corners: np.ndarray, delta: float) -> np.ndarray:
    """Independent reference for a panel: the face ``(4, 3)`` in its own plane, counter-clockwise,
    every edge line moved inward by ``delta``, consecutive lines intersected → ``(4, 2)``."""
    c = corners - corners.mean(axis=0)
    _, _, vt = np.linalg.svd(c)
    p = c @ vt[:2].T
    x, y = p[:, 0], p[:, 1]
    if np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)) < 0:
        p = p[::-1]
    e = np.roll(p, -1, axis=0) - p
    n = np.stack([-e[:, 1], e[:, 0]], axis=1) / np.linalg.norm(e, axis=1)[:, None]
    b = np.einsum("ki,ki->k", n, p) + delta
    out = []
    for k in range(len(p)):
        a = np.array([n[k - 1], n[k]])
        out.append(np.linalg.solve(a, [b[k - 1], b[k]]))
    return np.array(out)


def _shape_signature(poly: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Edge lengths and interior angles of a polygon, in order (orientation-independent angles)."""
    p = np.asarray(poly, dtype=float)
    e = np.roll(p, -1, axis=0) - p
    lengths = np.linalg.norm(e, axis=1)
    e_in = p - np.roll(p, 1, axis=0)
    cross = e_in[:, 0] * e[:, 1] - e_in[:, 1] * e[:, 0]
    ang = np.abs(np.arctan2(cross, np.einsum("ki,ki->k", e_in, e)))
    return lengths, ang


def congruence_error(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """Smallest (max edge-length difference, max angle difference) over cyclic shifts and reversal."""
    la, aa = _shape_signature(a)
    best = (np.inf, np.inf)
    for poly in (np.asarray(b, dtype=float), np.asarray(b, dtype=float)[::-1]):
        lb, ab = _shape_signature(poly)
        if len(lb) != len(la):
            continue
        for k in range(len(lb)):
            dl = float(np.abs(np.roll(lb, k) - la).max())
            da = float(np.abs(np.roll(ab, k) - aa).max())
            if dl + da < best[0] + best[1]:
                best = (dl, da)
    return best


def check_dxf(v: Verification) -> None:
    """Every cutting sheet: ezdxf audit, contract layers/entities, parts once, inside TRIM, spacing,
    agreement with parts.csv, and (glass) congruence with the 3D face inset by half the gap."""
    from shapely import Polygon, STRtree

    from .writers.dxf import check_sheet_dxf

    m = v.data.get("manifest", {})
    files = m.get("files", {})
    fab = m.get("fabrication", {})
    parts = {r["part_id"]: r for r in v.data.get("parts", [])}
    mesh = v.data.get("mesh")
    seen: dict[str, str] = {}
    for key, spacing_key in (("glass_sheets", "nesting"), ("beam_sheets", "beam_nesting")):
        spacing = float(fab.get(spacing_key, {}).get("spacing", fab.get("part_spacing", 0.0)))
        for sheet_no, rel in enumerate(files.get(key, []), start=1):
            try:
                content = check_sheet_dxf(v.folder / rel)
            except Exception as exc:  # noqa: BLE001 - reported as a finding
                v.error(rel, "", str(exc))
                continue
            polys = []
            trim = Polygon(content.trim_outline).buffer(1e-6)
            for part in content.parts:
                pid = part.part_id
                if pid in seen:
                    v.error(rel, pid, f"part is also cut on {seen[pid]}")
                seen[pid] = rel
                row = parts.get(pid)
                if row is None:
                    v.error(rel, pid, "part is not in parts.csv")
                elif str(row.get("sheet")) != str(sheet_no) or row.get("nest_tag") != part.nest_tag:
                    v.error(rel, pid, f"sheet/nest tag ({sheet_no}, {part.nest_tag}) differ from parts.csv "
                                      f"({row.get('sheet')}, {row.get('nest_tag')})")
                poly = Polygon(part.points)
                if not poly.is_valid:
                    v.error(rel, pid, "outline intersects itself")
                if not trim.contains(poly):
                    v.error(rel, pid, "outline leaves the usable (TRIM) area")
                polys.append((pid, poly))
                if key == "glass_sheets" and mesh is not None and row is not None and row.get("face", "") != "":
                    face = int(row["face"])
                    ref = _inset_face_2d(mesh.vertices[mesh.faces[face]], 0.5 * float(fab.get("panel_gap", 0.0)))
                    dl, da = congruence_error(ref, part.points)
                    if dl > 1e-6 or da > 1e-6:
                        v.error(rel, pid, f"outline is not the face {face} inset by half the gap "
                                          f"(edge lengths differ by {dl:.3g} mm, angles by {da:.3g} rad)")
            tree = STRtree([p for _, p in polys])
            for i, (pid, poly) in enumerate(polys):
                for j in tree.query(poly, predicate="dwithin", distance=max(spacing - 1e-6, 0.0)):
                    if j > i:
                        d = poly.distance(polys[j][1])
                        what = "overlaps" if d == 0 else f"is {d:.3g} mm from"
                        v.error(rel, pid, f"{what} {polys[j][0]} (spacing {spacing:g} mm)")
    for pid, row in parts.items():
        if pid not in seen and (files.get("glass_sheets") or files.get("beam_sheets")):
            v.error("parts.csv", pid, "part is on no cutting sheet")
    v.checked.append("dxf")


def check_step(v: Verification) -> None:
    """beams.step: one valid solid per beam part, named by its part id, a plate of the beam thickness."""
    files = v.data.get("manifest", {}).get("files", {})
    rel = files.get("beams_step")
    if rel is None:
        return
    from build123d import import_step

    from .writers.step import named_solids

    try:
        pairs = named_solids(import_step(str(v.folder / rel)))
    except Exception as exc:  # noqa: BLE001
        v.error(rel, "", f"cannot be read by the CAD kernel ({exc})")
        return
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
    v.checked.append("step")


CHECKS: list[Callable[[Verification], None]] = [check_manifest, check_mesh, check_parts, check_nodes, check_dxf,
                                                 check_step]


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
