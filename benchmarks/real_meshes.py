"""The table of docs/real-meshes.md: what ppfab makes of real quad meshes, tried as a new user would.

For every mesh in ``../shared/data`` and ``tests/data/meshes`` (third-party files, provenance in their
README.md) it records

* V / F and the kind of mesh (regular grid, boundary loops, interior vertices of valence != 4), counted
  here from the face records (polygons, never triangulated);
* the metrics before, from the public command ``ppfab check MESH --json`` (max δ_f, max δ_P of rows and
  columns, paper §3.3);
* P and PP optimisation, ``ppfab optimize MESH -o OUT.obj --families rows|both --json``: max δ_f and max
  δ_P after, the time, the largest vertex move relative to the bounding-box diagonal and the largest
  dihedral angle between neighbouring faces before -> after (the crease, computed here);
* the build of each optimised mesh: a design file (mesh scaled to a roof of about 10–40 m; P: ``[support]
  method = "p"`` with segmented beams, the rows continuous; PP: ``method = "pp"`` with half-lap joints),
  ``ppfab build`` and ``ppfab verify``: "built and verified" or the one-line refusal.

Only the ``ppfab`` command is used (the entry point this checkout's pyproject.toml declares, run with this
checkout first on PYTHONPATH), so the script does not depend on the package's internal layout.  Every command has a timeout.

Crease: for an interior edge shared by faces f, g with unit normals n_f, n_g (the normalised cross
product of the face diagonals, flipped where the two faces are oriented inconsistently), the dihedral
angle is ``arccos(n_f · n_g)`` in degrees (0 = flat); the table gives its maximum over all edges.

Run (from the checkout root; a full run took about 80 minutes on a shared 2-core machine):

    python benchmarks/real_meshes.py [--quick] [--only NAME] [--timeout 600] [--out docs/real-meshes.md]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import tomllib

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"
LOCAL = ROOT / "tests" / "data" / "meshes"
OUT_MD = ROOT / "docs" / "real-meshes.md"
ROOF_SPAN_MM = 30_000.0  # largest plan extent of the roof the mesh is scaled to
MIN_SPAN_MM = 10_000.0
MAX_EDGE_MM = 2_800.0  # keep panels smaller than a glass sheet (6000 x 3210) where the span allows


# ---------------------------------------------------------------------------------------------- mesh reading


def read_mesh(path: Path) -> tuple[np.ndarray, list[list[int]]]:
    """Vertices (N, 3) and polygon faces (0-based as written: OBJ indices minus one, OFF indices as they
    are) of an OBJ or OFF file.  OFF is read token by token, so face records split over lines are read
    too; nothing is checked or repaired here."""
    text = path.read_text(errors="replace")
    if path.suffix.lower() == ".obj":
        verts: list[list[float]] = []
        faces: list[list[int]] = []
        for line in text.splitlines():
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                verts.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                idx = [int(t.split("/")[0]) for t in parts[1:]]
                faces.append([i - 1 if i > 0 else len(verts) + i for i in idx])
        return np.asarray(verts, dtype=float).reshape(-1, 3), faces
    tokens = " ".join(line.split("#")[0] for line in text.splitlines()).split()
    head = tokens[0].upper()
    pos = 1
    if head != "OFF" and head.endswith("OFF"):
        raise ValueError(f"{path.name}: {tokens[0]} files are not read here")
    nv, nf = int(tokens[pos]), int(tokens[pos + 1])
    pos += 3
    verts_arr = np.asarray(tokens[pos:pos + 3 * nv], dtype=float).reshape(nv, 3)
    pos += 3 * nv
    faces = []
    for _ in range(nf):
        n = int(tokens[pos])
        faces.append([int(t) for t in tokens[pos + 1:pos + 1 + n]])
        pos += 1 + n
    return verts_arr, faces


@dataclass
class Combinatorics:
    faces_ok: bool
    one_based: bool
    boundary_loops: int = 0
    interior_valence: dict[int, int] = field(default_factory=dict)
    quads_only: bool = True

    def kind(self, grid: str | None) -> str:
        if not self.faces_ok:
            return "indices look 1-based" if self.one_based else "face indices out of range"
        parts = []
        if grid:
            parts.append(grid)
        else:
            parts.append("closed surface" if self.boundary_loops == 0 else
                         "disk" if self.boundary_loops == 1 else f"{self.boundary_loops} boundary loops")
        sing = ", ".join(f"{c}× val {v}" for v, c in sorted(self.interior_valence.items()) if v != 4)
        if sing:
            parts.append("singular: " + sing)
        return "; ".join(parts)


def combinatorics(verts: np.ndarray, faces: list[list[int]]) -> Combinatorics:
    """Boundary loops (connected components of the edges with one face) and interior valences."""
    flat = [i for f in faces for i in f]
    n = len(verts)
    ok = bool(flat) and min(flat) >= 0 and max(flat) < n
    one_based = bool(flat) and min(flat) >= 1 and max(flat) == n
    if not ok:
        return Combinatorics(False, one_based)
    edges: Counter = Counter()
    for f in faces:
        for a, b in zip(f, f[1:] + f[:1]):
            edges[(min(a, b), max(a, b))] += 1
    parent = list(range(n))

    def find(x: int) -> int:
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    boundary: set[int] = set()
    for (a, b), c in edges.items():
        if c == 1:
            boundary.update((a, b))
            parent[find(a)] = find(b)
    loops = len({find(v) for v in boundary})
    valence: Counter = Counter()
    for a, b in edges:
        valence[a] += 1
        valence[b] += 1
    used = set(flat)
    interior = Counter(valence[v] for v in used if v not in boundary)
    return Combinatorics(True, False, loops, dict(interior), all(len(f) == 4 for f in faces))


def max_crease_deg(verts: np.ndarray, faces: list[list[int]]) -> float:
    """Largest dihedral angle (degrees, 0 = flat) between two faces sharing an edge.

    Face normal of a quad (a, b, c, d): ``(c - a) × (d - b)`` normalised (the diagonals' cross product);
    the normal of g is flipped when the shared edge runs the same way in f and g (inconsistent
    orientation).  Vectorised over the (E, 2) pairs of faces."""
    quads = np.asarray([f for f in faces if len(f) == 4], dtype=int)
    if len(quads) != len(faces) or len(quads) == 0:
        return float("nan")
    p = verts[quads]  # (F, 4, 3)
    nrm = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
    a = quads.reshape(-1)
    b = np.roll(quads, -1, axis=1).reshape(-1)
    face = np.repeat(np.arange(len(quads)), 4)
    key = np.minimum(a, b) * len(verts) + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    key_s, face_s, fwd_s = key[order], face[order], (a < b)[order]
    pair = np.flatnonzero(key_s[1:] == key_s[:-1])  # interior edges: consecutive equal keys
    if len(pair) == 0:
        return 0.0
    f, g = face_s[pair], face_s[pair + 1]
    sign = np.where(fwd_s[pair] == fwd_s[pair + 1], -1.0, 1.0)
    cos = np.clip(np.einsum("ij,ij->i", nrm[f], nrm[g]) * sign, -1.0, 1.0)
    return float(np.degrees(np.arccos(cos)).max())


# ---------------------------------------------------------------------------------------------- commands


def ppfab_command(exe: str | None = None) -> list[str]:
    """The ``ppfab`` command of this checkout: the console-script entry point declared in its
    pyproject.toml, run with this interpreter (so an installed ``ppfab`` of another checkout is not used);
    ``exe`` overrides it with a given executable."""
    if exe:
        return [exe]
    with open(ROOT / "pyproject.toml", "rb") as fh:
        target = tomllib.load(fh)["project"]["scripts"]["ppfab"]
    module, func = target.split(":")
    return [sys.executable, "-c",
            f"import sys; from {module} import {func}; sys.argv[0] = 'ppfab'; sys.exit({func}())"]


def run(cmd: list[str], timeout: float) -> tuple[int | None, str, str, float]:
    """(exit code or None on timeout, stdout, stderr, seconds)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    env.setdefault("OMP_NUM_THREADS", "1")
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env, check=False)
    except subprocess.TimeoutExpired as exc:
        out = exc.stdout.decode(errors="replace") if isinstance(exc.stdout, bytes) else (exc.stdout or "")
        err = exc.stderr.decode(errors="replace") if isinstance(exc.stderr, bytes) else (exc.stderr or "")
        return None, out, err, time.perf_counter() - t0
    return proc.returncode, proc.stdout, proc.stderr, time.perf_counter() - t0


def error_line(stderr: str, stdout: str = "") -> str:
    """The ``ppfab: error: …`` line, else the last non-empty line of stderr (a traceback's last line)."""
    lines = [ln.strip() for ln in (stderr + "\n" + stdout).splitlines() if ln.strip()]
    errs = [ln for ln in lines if ln.startswith("ppfab: error:")]
    if errs:
        return errs[-1]
    return ("no error line; last line: " + lines[-1]) if lines else "no output"


def parse_json(stdout: str) -> dict | None:
    try:
        return json.loads(stdout)
    except (json.JSONDecodeError, ValueError):
        start = stdout.find("{")
        if start < 0:
            return None
        try:
            return json.loads(stdout[start:])
        except (json.JSONDecodeError, ValueError):
            return None


# ---------------------------------------------------------------------------------------------- one mesh


def roof_scale(verts: np.ndarray, faces: list[list[int]]) -> float:
    """Mesh units -> mm: the largest bounding-box extent becomes ROOF_SPAN_MM, reduced (down to
    MIN_SPAN_MM) where the longest edge would exceed MAX_EDGE_MM."""
    ext = float((verts.max(0) - verts.min(0)).max())
    quads = np.asarray([f for f in faces if len(f) == 4], dtype=int)
    edge = float(np.linalg.norm(verts[quads] - verts[np.roll(quads, -1, axis=1)], axis=2).max())
    s = ROOF_SPAN_MM / ext
    if edge * s > MAX_EDGE_MM:
        s = max(MIN_SPAN_MM / ext, MAX_EDGE_MM / edge)
    return s


DESIGN = """[design]
name = "{name} ({label})"
description = "Real quad mesh {name}, optimised with ppfab optimize --families {families}."

[geometry]
mesh = "{mesh}"
scale = {scale:.6g}

[support]
method = "{support}"
{support_extra}
[beams]
joint = "{joint}"
{beams_extra}depth = 200.0
thickness = 15.0

[output]
panels_step = false
ifc = false
rhino = false
glb = false
report = false

[nesting]
time_budget = 0.5

[beam_nesting]
time_budget = 0.5
"""


def build_and_verify(name: str, label: str, families: str, mesh: Path, work: Path, timeout: float,
                     cmd: list[str]) -> dict:
    verts, faces = read_mesh(mesh)
    scale = roof_scale(verts, faces)
    if label == "P":
        support, support_extra, joint, beams_extra = "p", 'family = "rows"\n', "segmented", 'continuous = "rows"\n'
    else:
        support, support_extra, joint, beams_extra = "pp", "", "halflap", ""
    work.mkdir(parents=True, exist_ok=True)
    design = work / f"design_{label}.toml"
    design.write_text(DESIGN.format(name=name, label=label, families=families, mesh=mesh.as_posix(), scale=scale,
                                    support=support, support_extra=support_extra, joint=joint,
                                    beams_extra=beams_extra))
    out = work / f"build_{label}"
    span = float((verts.max(0) - verts.min(0)).max()) * scale / 1000.0
    rec: dict = {"scale": scale, "span_m": span}
    rc, so, se, dt = run(cmd + ["build", str(design), "-o", str(out), "--force", "--quiet", "--json"], timeout)
    rec["build_s"] = dt
    if rc is None:
        rec["result"] = f"build timed out after {timeout:.0f} s"
        return rec
    if rc != 0:
        rec["result"] = error_line(se, so)
        return rec
    summary = parse_json(so) or {}
    rec["summary"] = summary.get("summary")
    rc, so, se, dt = run(cmd + ["verify", str(out), "--quiet"], timeout)
    rec["verify_s"] = dt
    if rc is None:
        rec["result"] = f"built; verify timed out after {timeout:.0f} s"
    elif rc != 0:
        problems = [ln.strip() for ln in (se + "\n" + so).splitlines() if ln.startswith("ppfab: verify:")]
        more = [ln for ln in problems if ln.startswith("ppfab: verify: … and ")]
        count = len(problems) - len(more) + sum(int(ln.split()[4]) for ln in more if ln.split()[4].isdigit())
        first = next((ln for ln in problems if ln not in more), None)
        rec["result"] = (f"built; verify failed ({count} problems), first: {first}" if first
                         else "built; verify failed: " + error_line(se, so))
    else:
        rec["result"] = "built and verified"
    rec.update(node_torsion(out / "nodes.csv"))
    return rec


def node_torsion(nodes_csv: Path) -> dict:
    """Largest torsion at a node (degrees and mm at the beam's bottom edge) and the number of nodes above
    1°, from the build's nodes.csv (columns ``torsion_deg``, ``torsion_mm``; missing columns give {})."""
    import csv

    if not nodes_csv.exists():
        return {}
    with open(nodes_csv, newline="") as fh:
        rows = list(csv.DictReader(fh))
    out: dict = {"nodes": len(rows)}
    for key in ("torsion_deg", "torsion_mm"):
        vals = [float(r[key]) for r in rows if r.get(key) not in (None, "")]
        if vals:
            out[key + "_max"] = max(vals)
            if key == "torsion_deg":
                out["nodes_over_1deg"] = sum(v > 1.0 for v in vals)
    nodes_json = nodes_csv.with_suffix(".json")
    if nodes_json.exists():
        doc = json.loads(nodes_json.read_text())
        angles = [n["axis_normal_deg"] for n in doc.get("nodes", []) if n.get("axis_normal_deg") is not None]
        if angles:
            out["axis_normal_max"] = max(angles)
        support = doc.get("support", {})
        if "left_out" in support:
            out["left_out"] = support["left_out"]
    return out


def survey(path: Path, work: Path, args: argparse.Namespace, cmd: list[str]) -> dict:
    name = path.stem
    rec: dict = {"name": path.name, "source": "tests/data/meshes" if path.parent.name == "meshes" else "shared"}
    verts, faces = read_mesh(path)
    comb = combinatorics(verts, faces)
    rec["V"], rec["F"] = len(verts), len(faces)
    rec["crease_before"] = max_crease_deg(verts, faces) if comb.faces_ok else float("nan")
    rc, so, se, dt = run(cmd + ["check", str(path), "--json"], args.timeout)
    check = parse_json(so) if rc is not None else None
    grid = None
    if check is not None:
        rec["check"] = check
        if check.get("grid_shape"):
            r, c = check["grid_shape"]
            grid = f"grid {r}×{c}" + (" (closed)" if check.get("closed") else "")
    else:
        rec["check_error"] = "check timed out" if rc is None else error_line(se, so)
    rec["kind"] = comb.kind(grid)
    diag = float(np.linalg.norm(verts.max(0) - verts.min(0)))
    for label, families in (("P", "rows"), ("PP", "both")):
        opt: dict = {}
        rec[label] = opt
        if check is None:
            opt["result"] = "not run (ppfab check refused the mesh)"
            continue
        out = work / f"{name}_{label}.obj"
        saved = work / f"{name}_{label}.run.json"
        if args.reuse and saved.exists() and out.exists():   # an earlier run's optimisation, as it was timed
            rc, so, se, dt = json.loads(saved.read_text())
        else:
            argv = cmd + ["optimize", str(path), "-o", str(out), "--families", families, "--quiet", "--json"]
            if args.quick or args.max_iter:
                argv += ["--max-iter", str(args.max_iter or 40)]
            rc, so, se, dt = run(argv, args.timeout)
            saved.write_text(json.dumps([rc, so, se[-4000:], dt]))
        opt["time_s"] = dt
        if rc is None:
            opt["result"] = f"optimize timed out after {args.timeout:.0f} s"
            continue
        res = parse_json(so)
        if rc not in (0, 1) or res is None or not out.exists():
            opt["result"] = error_line(se, so)
            continue
        opt.update({k: res.get(k) for k in ("targets_met", "iterations", "message", "delta_f_max", "delta_p_max",
                                             "time_s", "displacement_max", "skipped_polylines")})
        opt["time_s"] = res.get("time_s", dt)
        v2, f2 = read_mesh(out)
        opt["move_rel"] = float(np.linalg.norm(v2 - verts, axis=1).max() / diag) if v2.shape == verts.shape else None
        opt["crease_after"] = max_crease_deg(v2, f2)
        if args.no_build:
            continue
        opt["build"] = build_and_verify(name, label, families, out.resolve(), work / f"{name}_{label}", args.timeout,
                                        cmd)
    return rec


# ---------------------------------------------------------------------------------------------- table


def fmt(x: float | None, spec: str = ".1e") -> str:
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "–"
    return format(x, spec)


ABS_PATH = re.compile(r"(?<![\w.])/(?:[\w.+-]+/)+([\w.+-]+)")


def cell(text: str, limit: int = 0) -> str:
    """Table-safe text; with ``limit``, a long message is cut after the last ``; `` before that many
    characters (the records written by ``--json`` keep it whole)."""
    text = ABS_PATH.sub(r"\1", text)  # file names only: no paths of the machine that ran the survey
    if limit and len(text) > limit:
        cut = text.rfind("; ", 0, limit)
        text = text[:cut if cut > 0 else limit] + " …"
    return text.replace("|", "\\|").replace("\n", " ")


def opt_cell(opt: dict) -> str:
    if "delta_f_max" not in opt:
        return cell(opt.get("result", "–"))
    met = "met" if opt.get("targets_met") else "not met (" + str(opt.get("message") or "").split(":")[0] + ")"
    return (f"{fmt(opt['delta_f_max'])} / {fmt(opt['delta_p_max'])}, {opt['time_s']:.1f} s, "
            f"move {fmt(opt.get('move_rel'), '.1e')}, {met}")


def crease_cell(rec: dict, label: str) -> str:
    opt = rec[label]
    before, after = rec.get("crease_before"), opt.get("crease_after")
    if after is None:
        return "–"
    return f"{fmt(before, '.0f')}° → {fmt(after, '.0f')}°"


def build_cell(opt: dict) -> str:
    b = opt.get("build")
    if b is None:
        return "–"
    extra = f"{b['span_m']:.0f} m span"
    if "torsion_deg_max" in b:
        extra += (f", torsion max {b['torsion_deg_max']:.2g}° / {b.get('torsion_mm_max', float('nan')):.2g} mm, "
                  f"{b['nodes_over_1deg']} of {b['nodes']} nodes > 1°")
    if "axis_normal_max" in b:
        extra += f", axes ≤ {b['axis_normal_max']:.0f}° from the normals"
    if b.get("left_out"):
        extra += f", {b['left_out']} polylines left out of the planar families"
    return cell(b["result"], 320) + f" ({extra})"


def table(records: list[dict], quick: bool, max_iter: int | None = None, missing: list[str] | None = None,
          note: str | None = None) -> str:
    ok = sum(1 for r in records for lab in ("P", "PP")
             if (r[lab].get("build") or {}).get("result") == "built and verified")
    meshes = sorted({r["name"] for r in records for lab in ("P", "PP")
                     if (r[lab].get("build") or {}).get("result") == "built and verified"}, key=str.lower)
    by_kind = {lab: sum(1 for r in records if (r[lab].get("build") or {}).get("result") == "built and verified")
               for lab in ("P", "PP")}
    lines = [
        "# Real quad meshes: optimisation and build results",
        "",
        "Generated by `python benchmarks/real_meshes.py" + (" --quick" if quick else "")
        + (f" --max-iter {max_iter}" if max_iter else "") + "`"
        + (" (runs recorded with `--json`, the table assembled from them with `--table-from`)"
           if missing is not None else "")
        + (" (regenerate with "
           "`python benchmarks/real_meshes.py`; one mesh: `--only NAME`). Meshes: the shared real-mesh set "
           "(`../shared/data`, its README lists provenance) and `tests/data/meshes` (README there: repository, "
           "path, commit, licence). Every step runs the `ppfab` command (check, optimize, build, verify)."),
        "",
        ("Columns: V / F; kind (counted from the face records: grid shape as `ppfab check` finds it, boundary "
        "loops, interior vertices of valence ≠ 4); max δ_f and max δ_P rows / cols before (`ppfab check`); "
        "P (`--families rows`) and PP (`--families both`) optimisation: max δ_f / max δ_P after, wall time, "
        "largest vertex move relative to the bounding-box diagonal, whether the targets (1e-6) were met; the "
        "largest dihedral angle between neighbouring faces before → after; the build of the optimised mesh "
        "scaled to a roof of the given span (P: `[support] method = \"p\"`, segmented beams, rows "
        "continuous; PP: `method = \"pp\"`, half-lap joints), then `ppfab verify`; for a written build the "
        "largest torsion at a node (degrees, and mm at the beam's bottom edge, from its nodes.csv) and the "
        "nodes above 1°; the largest angle between a node axis and the surface normal, and how many polylines "
        "the support left out of the planar families (their edges are beams of one edge each). A build stops "
        "when the torsion exceeds `beams.max_torsion_mm` (0.5 mm), an axis leaves the normal by more than "
        "`support.max_axis_angle_deg` (75°) or neighbouring panels meet at a dihedral angle above "
        "`panels.max_crease_deg` (45°). Nesting budgets are 0.5 s of nominal work for the glass and the plates "
        "(the layouts are not the point here; every placement is still verified), and the optional viewing "
        "files are off (`panels.step`, `model.ifc`, `model.3dm`, `model.glb`, `report.html`): each build writes "
        "and verifies `beams.step`, the glass and plate DXFs, the parts, nodes and order tables, `mesh.obj` and "
        "`mesh.json`."),
        "",
        ("Times are wall-clock seconds of `ppfab optimize` on a 2-core machine shared with other work "
        "(OMP_NUM_THREADS=1; the load was high during this run); treat them as rough."
         + (f" Optimisations were capped at {max_iter} iterations to keep the run short; a record that says "
            "'iteration limit 500' comes from an earlier run of the same optimiser code with its default "
            "(reused with `--reuse`)." if max_iter else "")),
        "",
        *([note, ""] if note else []),
        f"Built and verified: {ok} of {2 * len(records)} builds ({by_kind['P']} P, {by_kind['PP']} PP) on "
        f"{len(meshes)} meshes: " + ", ".join(f"`{m}`" for m in meshes) + ".",
        "",
        ("| mesh | V / F | kind | δ_f / δ_P rows / cols before | P: δ_f / δ_P, time, move | crease P | P build | "
        "PP: δ_f / δ_P, time, move | crease PP | PP build |"),
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in sorted(records, key=lambda r: r["name"].lower()):
        c = r.get("check")
        before = (f"{fmt(c['delta_f_max'])} / {fmt(c['delta_p_rows_max'])} / {fmt(c['delta_p_cols_max'])}" if c
                  else cell(r.get("check_error", "–")))
        lines.append(f"| `{r['name']}` | {r['V']} / {r['F']} | {cell(r['kind'])} | {before} | {opt_cell(r['P'])} | "
                     f"{crease_cell(r, 'P')} | {build_cell(r['P'])} | {opt_cell(r['PP'])} | {crease_cell(r, 'PP')} | "
                     f"{build_cell(r['PP'])} |")
    lines.append("")
    if missing:
        lines += [f"Not in this run ({len(missing)} meshes; the run was stopped before it reached them): "
                  + ", ".join(f"`{m}`" for m in missing) + ".", ""]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", action="append", help="mesh file name or stem (repeatable; substring match)")
    ap.add_argument("--quick", action="store_true", help="at most 40 optimisation iterations")
    ap.add_argument("--max-iter", type=int, help="at most this many optimisation iterations (default: the "
                                                 "optimiser's, 500)")
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds for each command (default 600)")
    ap.add_argument("--out", type=Path, help="Markdown table to write (default docs/real-meshes.md; with --only: "
                                            "printed)")
    ap.add_argument("--json", type=Path, help="also write the raw records as JSON")
    ap.add_argument("--ppfab", help="run this ppfab executable instead of this checkout's entry point")
    ap.add_argument("--table-from", type=Path, metavar="JSON", action="append",
                    help="only write the table from the records of earlier --json runs (repeatable; a mesh in "
                         "several files: the last one counts)")
    ap.add_argument("--workdir", type=Path, help="keep optimised meshes, designs and builds here")
    ap.add_argument("--reuse", action="store_true", help="with --workdir: take the optimisations (mesh, record and "
                                                        "time) of an earlier run there instead of running them again")
    ap.add_argument("--no-build", action="store_true", help="only check and optimise (a later --reuse run builds)")
    ap.add_argument("--note", help="with --table-from: a paragraph placed under the header (e.g. which commit "
                                   "each run was recorded at)")
    ap.add_argument("--data", type=Path, action="append", help="folder of meshes (repeatable; default the shared "
                                                               "real-mesh set and tests/data/meshes)")
    args = ap.parse_args(argv)
    if args.reuse and args.workdir is None:
        ap.error("--reuse needs --workdir")
    folders = args.data or [SHARED, LOCAL]
    paths = sorted(p for d in folders for p in d.glob("*") if p.suffix.lower() in (".obj", ".off"))
    if args.table_from:
        merged: dict[str, dict] = {}
        for src in args.table_from:
            merged.update({r["name"]: r for r in json.loads(src.read_text())})
        missing = sorted({p.name for p in paths} - set(merged), key=str.lower)
        (args.out or OUT_MD).write_text(table(list(merged.values()), args.quick, args.max_iter, missing, args.note))
        return 0
    if args.only:
        paths = [p for p in paths if any(o in p.name for o in args.only)]
    if not paths:
        print("real_meshes.py: no mesh matches", file=sys.stderr)
        return 2
    cmd = ppfab_command(args.ppfab)
    work = args.workdir or Path(tempfile.mkdtemp(prefix="ppfab-real-meshes-"))
    records = []
    out_md = None if (args.out is None and args.only) else (args.out or OUT_MD)
    for p in sorted(paths, key=lambda p: p.stat().st_size):  # small meshes first; the table is sorted by name
        t0 = time.perf_counter()
        (work / p.stem).mkdir(parents=True, exist_ok=True)
        rec = survey(p, work / p.stem, args, cmd)
        rec["total_s"] = time.perf_counter() - t0
        records.append(rec)
        print(f"{p.name}: P {rec['P'].get('build', rec['P']).get('result')} | "
              f"PP {rec['PP'].get('build', rec['PP']).get('result')} ({rec['total_s']:.0f} s)", flush=True)
        if args.json:
            args.json.write_text(json.dumps(records, indent=1, default=str))
        if out_md is not None:  # rewritten after every mesh, so an interrupted run leaves a partial table
            out_md.write_text(table(records, args.quick, args.max_iter))
    if out_md is None:
        print(table(records, args.quick, args.max_iter))
    if args.workdir is None:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
