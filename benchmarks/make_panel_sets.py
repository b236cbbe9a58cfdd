"""Freeform glass panel sets for the nesting benchmark, made from real quad meshes.

Each set is the glass of a gridshell on a real mesh from ``../shared/data`` (see its README for the
repositories and commits): the mesh is P- or PP-optimised by ``ppfab.optimize`` (faces planar to
δ_f <= 1e-6, the chosen polyline families planar), scaled to millimetres so that the median edge is
about 1.5 m, and cut into panels by ``fabrication.panels.make_panels`` (20 mm joints, outlines inset by
10 mm, planarity tolerance 0.5 mm).  The outlines are written in the reference-edge frame (first edge
along +x, counter-clockwise), as a flattening along the mesh's own edges gives them.

Written to ``benchmarks/data/<name>.json``::

    {"name": ..., "source": {"repository", "path", "commit", "file"}, "made_with": {...},
     "units": "mm", "panels": [[[x, y], ...], ...]}

Usage::

    python benchmarks/make_panel_sets.py            # all sets
    python benchmarks/make_panel_sets.py conical1   # one
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
OUT = REPO / "benchmarks" / "data"
sys.path.insert(0, str(REPO))

SETS = {
    # name: (file, repository, path in it, commit, families to make planar, scale mesh units -> mm)
    # commit: as far as the data README records it; the sha256 of the file read is stored with each set
    "conjugate_roof_P": ("compas_libigl__inspired_mesh_quads_Conjugate.off", "compas-dev/compas_libigl",
                         "data/libigl-tutorial-data/inspired_mesh_quads_Conjugate.off", "",
                         "rows", 1900.0),
    "gitter_PP": ("libhedra__gitter.off", "avaxman/libhedra", "examples/data/gitter.off", "9e660fb2",
                  "both", 12500.0),
    "conical1_PP": ("DOS__conical1.obj", "WWmore/DOS", "objs/obj_pq/conical1.obj", "", "both", 1500.0),
}


def make_set(name: str) -> dict:
    from fabrication.panels import PanelParams, make_panels
    from ppfab.io import load_mesh
    from ppfab.optimize import optimize

    file, repo, path, commit, families, scale = SETS[name]
    mesh = load_mesh(DATA / file)
    res = optimize(mesh, families=families, target_delta_f=1e-6, target_delta_p=1e-6, max_iterations=300)
    params = PanelParams(gap=20.0, planarity_tolerance=0.5, rotation="quarter")      # reference-edge frame
    panels = make_panels(res.mesh, params, scale=scale)
    outlines = [np.round(p.outline, 3).tolist() for p in panels]
    area = sum(p.area_mm2 for p in panels) / 1e6
    return {
        "name": name,
        "source": {"repository": repo, "path": path, "commit": commit, "file": file,
                   "sha256": hashlib.sha256((DATA / file).read_bytes()).hexdigest()},
        "made_with": {"optimize": {"families": families, "target_delta_f": 1e-6, "target_delta_p": 1e-6,
                                   "delta_f_max": res.delta_f_max, "delta_p_max": res.delta_p_max,
                                   "targets_met": res.targets_met},
                      "scale_mm_per_unit": scale, "panels": {"gap": 20.0, "planarity_tolerance": 0.5,
                                                             "frame": "reference edge"},
                      "script": "benchmarks/make_panel_sets.py"},
        "units": "mm",
        "count": len(outlines),
        "area_m2": round(area, 3),
        "panels": outlines,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*", help=f"sets to make (default: all of {', '.join(SETS)})")
    args = ap.parse_args(argv)
    OUT.mkdir(parents=True, exist_ok=True)
    for name in args.names or list(SETS):
        doc = make_set(name)
        (OUT / f"{name}.json").write_text(json.dumps(doc, separators=(",", ":")) + "\n")
        mf = doc["made_with"]["optimize"]
        print(f"{name}: {doc['count']} panels, {doc['area_m2']:.1f} m², δ_f {mf['delta_f_max']:.1e}, "
              f"δ_P {mf['delta_p_max']:.1e}, targets met {mf['targets_met']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
