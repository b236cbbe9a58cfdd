"""Nesting benchmark: ppfab's nesting against rectpack and the area lower bound, in one run.

Data sets
  * ``../shared/data/bench_panels_500.json`` — 500 flattened glass panels (858.6 m²), the
    reference set: 6000 x 3210 mm sheets, 10 mm spacing, rotations 0/90/180/270, no trim.
    Best public tools (data README): rectpack best of 616 variants 52 sheets (85.7 %),
    first-fit shelf 53, spyrrow sheet by sheet 53 (280 s).  Target: <= 49 sheets within 60 s.
  * the glass panels of the bundled example ``examples/default_pp_gridshell.toml``.

Columns: sheets used, utilisation (part area / area of the sheets used), seconds.
Baselines measured in the same run: rectpack on bounding rectangles (the best of a few strong
variants: MaxRects BSSF/BAF/BL, Skyline MWF, Guillotine BSSF-SAS, each with sort by area and
by longer side), and the area lower bound ``ceil(Σ area / sheet area)``.

Usage::

    python benchmarks/nesting.py                 # 60 s budget for ppfab (the reference setting)
    python benchmarks/nesting.py --budget 10     # quicker
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
sys.path.insert(0, str(REPO))

from fabrication.flatpart import FlatPart  # noqa: E402
from fabrication.nesting import NestingParams, nest, verify_nesting  # noqa: E402


def bench_parts() -> list[FlatPart]:
    data = json.loads((DATA / "bench_panels_500.json").read_text())
    return [FlatPart(f"B{i:03d}", "panel", np.array(p, dtype=float)) for i, p in enumerate(data)]


def example_parts() -> list[FlatPart]:
    import tomllib

    from fabrication.panels import PanelParams, make_panels
    from ppfab.constructions import load_all
    from ppfab.constructions.registry import build_construction

    doc = tomllib.loads((REPO / "examples" / "default_pp_gridshell.toml").read_text())
    load_all()
    grid = build_construction(doc["geometry"]["method"], doc["geometry"]["params"])
    panels = make_panels(grid, PanelParams(), scale=float(doc["geometry"].get("scale", 1.0)))
    return [p.flat_part() for p in panels]


def rectpack_best(parts: list[FlatPart], sheet: tuple[float, float], spacing: float) -> tuple[int, str]:
    from rectpack import (SORT_AREA, SORT_LSIDE, GuillotineBssfSas, MaxRectsBaf, MaxRectsBl, MaxRectsBssf,
                          PackingBin, PackingMode, SkylineMwf, newPacker)

    sizes = [np.ptp(np.asarray(p.outline), axis=0) for p in parts]
    W, H = int(math.floor(sheet[0] + spacing)), int(math.floor(sheet[1] + spacing))
    best = (10 ** 9, "")
    for algo in (MaxRectsBssf, MaxRectsBaf, MaxRectsBl, SkylineMwf, GuillotineBssfSas):
        for sort, sname in ((SORT_AREA, "area"), (SORT_LSIDE, "long side")):
            packer = newPacker(mode=PackingMode.Offline, bin_algo=PackingBin.BFF, pack_algo=algo,
                               sort_algo=sort, rotation=True)
            for i, (w, h) in enumerate(sizes):
                packer.add_rect(int(math.ceil(w + spacing)), int(math.ceil(h + spacing)), rid=i)
            packer.add_bin(W, H, count=float("inf"))
            packer.pack()
            placed = sum(len(b) for b in packer)
            if placed == len(parts) and len(packer) < best[0]:
                best = (len(packer), f"{algo.__name__}/{sname}")
    return best


def run(name: str, parts: list[FlatPart], params: NestingParams) -> list[tuple]:
    area = sum(p.area for p in parts)
    sheet_area = params.sheet[0] * params.sheet[1]
    rows = []
    lb = math.ceil(area / sheet_area - 1e-12)
    rows.append((name, "area lower bound", lb, area / (lb * sheet_area), 0.0, ""))
    t = time.perf_counter()
    n, how = rectpack_best(parts, tuple(params.sheet), params.spacing)
    rows.append((name, "rectpack, bounding rectangles", n, area / (n * sheet_area), time.perf_counter() - t, how))
    for mode in ("guillotine", "irregular"):
        p = NestingParams(**{**params.__dict__, "mode": mode})
        res = nest(parts, p)
        verify_nesting(parts, res, p)
        first = res.history[0][1] if res.history else res.sheets
        rows.append((name, f"ppfab {mode}", res.sheets, res.utilisation, res.seconds,
                     f"greedy start {first}, verified"))
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--budget", type=float, default=60.0, help="ppfab time budget per mode, s (default 60)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    ref = NestingParams(sheet=[6000.0, 3210.0], margin=0.0, spacing=10.0, rotations=[0.0, 90.0, 180.0, 270.0],
                        time_budget=args.budget, seed=args.seed)
    rows = run("bench_panels_500", bench_parts(), ref)
    rows += run("example default_pp_gridshell", example_parts(), ref)
    print(f"{'data':30s} {'method':32s} {'sheets':>6s} {'util':>7s} {'time s':>8s}  note")
    for data, method, sheets, util, sec, note in rows:
        print(f"{data:30s} {method:32s} {sheets:6d} {100 * util:6.1f}% {sec:8.2f}  {note}")
    base = {d: s for d, m, s, *_ in rows if m.startswith("rectpack")}
    for data, method, sheets, *_ in rows:
        if method.startswith("ppfab"):
            print(f"{data}: {method} uses {base[data] - sheets:+d} sheets fewer than rectpack "
                  f"({sheets / base[data]:.3f} x)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
