"""Nesting benchmark: ppfab's nesting against rectpack and the area lower bound, in one run.

Data sets
  * ``../shared/data/bench_panels_500.json`` — 500 flattened glass panels (858.6 m²), the
    reference set: 6000 x 3210 mm sheets, 10 mm spacing, rotations 0/90/180/270, no trim.
    Best public tools (data README): rectpack best of 616 variants 52 sheets (85.7 %),
    first-fit shelf 53, spyrrow sheet by sheet 53 (280 s).  Target: <= 49 sheets within 60 s.
  * the glass panels of the bundled example ``examples/default_pp_gridshell.toml``.
  * the beam plates of the bundled default design (``ppfab build`` without a design file):
    219 bent strips ~200 mm deep, 3.0–5.9 m long, on 6000 x 2000 mm plate (10 mm trim and
    spacing), with the design's own 3 s budget.  Extra baseline: the irregular mode's nestled
    rows alone (what irregular did before strip stacking).

Columns: sheets used, utilisation (part area / area of the sheets used), seconds.
Baselines measured in the same run: rectpack on bounding rectangles (the best of a few strong
variants: MaxRects BSSF/BAF/BL, Skyline MWF, Guillotine BSSF-SAS, each with sort by area and
by longer side), and the area lower bound ``ceil(Σ area / sheet area)``.

Usage::

    python benchmarks/nesting.py                 # 60 s budget for ppfab (the reference setting)
    python benchmarks/nesting.py --budget 10     # quicker
    python benchmarks/nesting.py --only beams    # the beam plates only (design budget, 3 s)
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


def beam_parts() -> tuple[list[FlatPart], NestingParams]:
    from fabrication.beams import build_beams
    from fabrication.design import load_design
    from ppfab.geometry import build_geometry
    from ppfab.support.select import support_structure

    d = load_design(None)
    g = build_geometry(d.geometry, d.optimize, d.base_dir)
    s = support_structure(g.mesh, d.section("support"), planar_families=g.planar_families)
    return build_beams(s, d.section("beams")).flat_parts(), d.section("beam_nesting")


def rows_only(parts: list[FlatPart], params: NestingParams) -> tuple[int, float]:
    """The irregular mode's nestled rows alone, full budget (the baseline for strips): sheets, seconds."""
    from fabrication.nesting.catalog import build_catalog
    from fabrication.nesting.engine import UNITS_PER_SECOND, _solve

    t = time.perf_counter()
    cat = build_catalog(parts, params)
    sheets, _, _ = _solve(cat, "rows", params.time_budget * UNITS_PER_SECOND, params.seed, 0, 1)
    return len(sheets), time.perf_counter() - t


def stack_estimate(parts: list[FlatPart], params: NestingParams) -> tuple[int, str]:
    """Sheets that stacked strips need at least, estimated: rows per sheet by thickness, strips per row by length.

    Each strip in a sheet-long row costs its vertical thickness ``t`` (median over the middle 80 %
    of its length, lying along x) plus the spacing; a sheet holds the ``k`` strips whose
    ``Σ (t + s) <= H + s`` (sagitta ignored: optimistic), so at best the ``k`` thinnest.  Two
    strips share a row only if they fit end to end (exact nestling, :func:`pair_gains`);
    rows = strips − pairs (greedy matching).  Estimate = ⌈rows / k⌉.
    """
    from shapely.geometry import LineString, Polygon

    from fabrication.nesting.catalog import build_catalog
    from fabrication.nesting.shapes import pair_gains

    cat = build_catalog(parts, params)
    x0, y0, x1, y1 = params.usable()
    s = params.spacing
    thick, flat = [], []
    for p in range(cat.n_parts):
        o = min(range(cat.part_start[p], cat.part_start[p + 1]), key=lambda k: cat.o_h[k])
        poly = Polygon(cat.orients[o].poly)
        w = cat.orients[o].w
        cuts = [LineString([(x, -1e5), (x, 1e5)]).intersection(poly).length for x in np.linspace(0.1 * w, 0.9 * w, 41)]
        thick.append(float(np.median(cuts)))
        flat.append(o)
    t = np.sort(np.array(thick) + s)
    k = int(np.searchsorted(np.cumsum(t), (y1 - y0) + s + 1e-9, side="right"))
    w = cat.o_w[flat]
    short = [i for i in range(cat.n_parts) if w[i] + w.min() <= cat.L + 50.0]
    poses = [o for i in short for o in range(cat.part_start[i], cat.part_start[i + 1]) if cat.o_w[o] < cat.L / 2 + 100]
    pairs = 0
    if len(poses) > 1:
        G = pair_gains([cat.orients[o].halo for o in poses], np.array([cat.orients[o].w for o in poses]),
                       [cat.orients[o].poly for o in poses], s)
        fit = (cat.o_w[poses][:, None] + cat.o_w[poses][None, :] - G) <= cat.L + 1e-9
        used: set[int] = set()
        for a, b in zip(*np.nonzero(fit)):
            pa, pb = int(cat.o_part[poses[a]]), int(cat.o_part[poses[b]])
            if pa != pb and pa not in used and pb not in used:
                used |= {pa, pb}
                pairs += 1
    rows = cat.n_parts - pairs
    return int(math.ceil(rows / max(k, 1))), f"{rows} rows ({pairs} shared), at most {k} a sheet"


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


def run(name: str, parts: list[FlatPart], params: NestingParams, modes: tuple[str, ...] = ("guillotine", "irregular"),
        baseline_rows: bool = False) -> list[tuple]:
    area = sum(p.area for p in parts)
    sheet_area = params.sheet[0] * params.sheet[1]
    rows = []
    lb = math.ceil(area / sheet_area - 1e-12)
    rows.append((name, "area lower bound", lb, area / (lb * sheet_area), 0.0, ""))
    t = time.perf_counter()
    n, how = rectpack_best(parts, tuple(params.sheet), params.spacing)
    rows.append((name, "rectpack, bounding rectangles", n, area / (n * sheet_area), time.perf_counter() - t, how))
    if baseline_rows:
        est, how = stack_estimate(parts, params)
        rows.append((name, "strip rows estimate", est, area / (est * sheet_area), 0.0, how))
        n, sec = rows_only(parts, params)
        rows.append((name, "ppfab irregular, rows only", n, area / (n * sheet_area), sec, "before strip stacking"))
    for mode in modes:
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
    ap.add_argument("--beam-budget", type=float, default=None,
                    help="budget for the beam plates, s (default: the design's, 3 s)")
    ap.add_argument("--only", choices=("glass", "beams"), default=None, help="run one data set only")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    ref = NestingParams(sheet=[6000.0, 3210.0], margin=0.0, spacing=10.0, rotations=[0.0, 90.0, 180.0, 270.0],
                        time_budget=args.budget, seed=args.seed)
    rows = []
    if args.only != "beams":
        rows += run("bench_panels_500", bench_parts(), ref)
        rows += run("example default_pp_gridshell", example_parts(), ref)
    if args.only != "glass":
        plates, bp = beam_parts()
        bp = NestingParams(**{**bp.__dict__, "seed": args.seed,
                              "time_budget": bp.time_budget if args.beam_budget is None else args.beam_budget})
        rows += run("default design beam plates", plates, bp, ("guillotine", "irregular", "auto"), baseline_rows=True)
    print(f"{'data':30s} {'method':32s} {'sheets':>6s} {'util':>7s} {'time s':>8s}  note")
    for data, method, sheets, util, sec, note in rows:
        print(f"{data:30s} {method:32s} {sheets:6d} {100 * util:6.1f}% {sec:8.2f}  {note}")
    base = {d: s for d, m, s, *_ in rows if m.startswith("rectpack")}
    for data, method, sheets, *_ in rows:
        if method.startswith("ppfab") and "rows only" not in method:
            print(f"{data}: {method} uses {base[data] - sheets:+d} sheets fewer than rectpack "
                  f"({sheets / base[data]:.3f} x)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
