"""P support on every shared real mesh: the torsion of its axes, measured apart from the code that made them.

Each mesh of ``../shared/data`` (its README gives repositories and commits) is made P with its rows planar
(``ppfab.optimize``, default parameters), scaled to a 30 m span (mm), and given its P support
(``ppfab.support.p.support_p``, beams 200 mm deep, torsion limit 0.5 mm).  The torsion of every edge is then
recomputed by determinants, not by ppfab (the formula of ``tests/test_support_p_exact.py``): the height of
``v_j + D a_j`` over the plane through ``v_i``,
``v_j`` and ``v_i + D a_i`` is ``|det[e, D a_i, D a_j]| / |e × D a_i|`` (the larger of the two ends), in mm at
beam depth ``D = 200`` mm.  Printed per mesh: whether the optimiser met its targets (δ_P of the rows), the rows
kept as planar beams and those left out (planes more than 30° from the surface normal: their edges become
transverse edges of the strips, so the strips join and go to the penalty solve), the largest torsion on the
transverse edges and on the planar rows' own edges (bounded by how planar the rows are), and the axes' angle to
the vertex normals.

Run:  python benchmarks/p_support_real.py     (about a minute; no timing)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from ppfab.errors import PpfabError  # noqa: E402
from ppfab.io import load_mesh  # noqa: E402
from ppfab.optimize import optimize  # noqa: E402
from ppfab.support.p import support_p  # noqa: E402
from ppfab.support.params import BeamContext  # noqa: E402
from ppfab.support.structure import edge_polyline_index  # noqa: E402
from ppfab.transforms.similarity import transform  # noqa: E402
from test_support_p_exact import height_mm as torsion_mm  # noqa: E402  (the tests' own determinant formula)

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
DEPTH, LIMIT, SPAN = 200.0, 0.5, 30_000.0


def main() -> int:
    print("| mesh | V | rows P: met, max δ_P | rows kept / left out | penalty strips | torsion, transverse edges "
          "(mm) | torsion, planar rows' edges (mm) | axis to normal, median / max (°) |")
    print("|---|---|---|---|---|---|---|---|")
    for path in sorted(DATA.glob("*.obj")) + sorted(DATA.glob("*.off")):
        res = optimize(load_mesh(path), {"families": "rows"})
        mesh = transform(res.mesh, SPAN / float(np.ptp(res.mesh.vertices, axis=0).max()))
        head = (f"| {path.stem} | {len(mesh.vertices)} | {'yes' if res.targets_met else 'no'}, "
                f"{res.delta_p_max:.1e}")
        try:
            s = support_p(mesh, "rows", beams=BeamContext(DEPTH, LIMIT))
        except PpfabError as exc:
            print(f"{head} | refused: {str(exc).split(' (', 1)[0]} | | | | |", flush=True)
            continue
        h = torsion_mm(s.mesh, s.axes)
        on = s.polyline_planar[edge_polyline_index(s.mesh)]
        across = f"{h[~on].max():.1e}" if (~on).any() else "—"
        along = f"{h[on].max():.1e}" if on.any() else "—"
        print(f"{head} | {int(s.polyline_planar.sum())} / {len(s.left_out)} | {s.meta.get('penalty_strips', 0)} | "
              f"{across} | {along} | {np.median(s.normal_angle_deg):.1f} / {s.normal_angle_deg.max():.1f} |",
              flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
