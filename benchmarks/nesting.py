"""Nesting benchmark: ppfab's strategies against rectpack, a true-shape library and the area bound, in one run.

Data sets (6000 x 3210 mm glass sheets, 10 mm spacing unless said)
  * ``bench_panels_500`` — ``../shared/data/bench_panels_500.json``, 500 flattened glass panels
    (858.6 m²), the reference setting: rotations 0/90/180/270, no trim (data README: rectpack best of
    616 variants 52 sheets, spyrrow sheet by sheet 53).  Also with free rotation (float glass).
  * ``default glass`` — the glass panels of the bundled default design (``ppfab build`` without a
    design file), with that design's ``[panels]`` and ``[nesting]`` (10 mm trim, free rotation).
  * ``default plates`` — its 219 beam plates (bent strips) on 6000 x 2000 plate, its ``[beam_nesting]``.
  * ``conjugate_roof_P``, ``gitter_PP``, ``conical1_PP`` — glass of P/PP-optimised real meshes
    (``benchmarks/data``, made by ``benchmarks/make_panel_sets.py``), free rotation.

Baselines in the same run
  * rectpack: the best of MaxRects BSSF/BAF/BL, Skyline MWF and Guillotine BSSF-SAS, each with bin
    selection best-fit-first and best-bin-fit and sorting by area and by longer side (20 variants), on
    each part's minimum-area rectangle where the part may turn freely (its bounding box otherwise),
    rectangles inflated by the spacing, 90° turns allowed.
  * spyrrow (``pip install spyrrow``; sparrow / jagua-rs, true shapes, free rotation where allowed):
    strip packing of height = usable sheet width, one worker, seed 0, ``--spyrrow`` seconds.  A strip has no
    sheet edges, so its sheets are ``⌈strip length / usable length⌉`` — a bound no sheet layout
    reaches, not a cutting plan.  (It stops on wall-clock time, so it is not reproducible.)
  * the area bound ``⌈Σ area / sheet area⌉``.

ppfab: every strategy of the table on its own budget (``--budget`` s, the default designs their own),
each result checked by ``verify_nesting``.  Columns: sheets, utilisation (part area / area of the
sheets used), seconds (wall; CPU in parentheses), and the note.

``--budget-check`` instead times the whole nesting stage (``nest`` and ``verify_nesting``) of the
default design's glass at 22x15, 44x30, 66x45 and 88x60 faces against the budget.

Usage::

    python benchmarks/nesting.py                  # everything (about 25 min on 2 cores)
    python benchmarks/nesting.py --budget-check 3 6
    python benchmarks/nesting.py --budget 10 --only bench_panels_500 conical1_PP
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
SETS = REPO / "benchmarks" / "data"
sys.path.insert(0, str(REPO))

from fabrication.flatpart import FlatPart  # noqa: E402
from fabrication.nesting import NestingParams, lower_bound, nest, verify_nesting  # noqa: E402

FREEFORM = ("conjugate_roof_P", "gitter_PP", "conical1_PP")


def bench_parts(free: bool) -> list[FlatPart]:
    data = json.loads((DATA / "bench_panels_500.json").read_text())
    return [FlatPart(f"B{i:03d}", "panel", np.array(p, dtype=float), free_rotation=free) for i, p in enumerate(data)]


def set_parts(name: str) -> list[FlatPart]:
    doc = json.loads((SETS / f"{name}.json").read_text())
    return [FlatPart(f"F{i:04d}", "panel", np.array(p, dtype=float), free_rotation=True)
            for i, p in enumerate(doc["panels"])]


def default_design():
    from fabrication.beams import build_beams
    from fabrication.design import load_design
    from fabrication.panels import make_panels
    from ppfab.geometry import build_geometry
    from ppfab.support.select import support_structure

    d = load_design(None)
    g = build_geometry(d.geometry, d.optimize, d.base_dir)
    glass = [p.flat_part() for p in make_panels(g.mesh, d.section("panels"))]
    s = support_structure(g.mesh, d.section("support"), planar_families=g.planar_families)
    plates = build_beams(s, d.section("beams")).flat_parts()
    return glass, d.section("nesting"), plates, d.section("beam_nesting")


def default_glass_at(faces_u: int, faces_v: int) -> tuple[list[FlatPart], NestingParams]:
    """The default design's glass with ``faces_u x faces_v`` faces (same surface: smaller panels) and its [nesting]."""
    from fabrication.design import load_design
    from fabrication.panels import make_panels
    from ppfab.geometry import build_geometry

    d = load_design(None)
    geo = replace(d.geometry, params={**d.geometry.params, "faces_u": faces_u, "faces_v": faces_v})
    g = build_geometry(geo, d.optimize, d.base_dir)
    return [p.flat_part() for p in make_panels(g.mesh, d.section("panels"))], d.section("nesting")


def budget_check(budgets: list[float], sizes: list[tuple[int, int]]) -> None:
    """Wall and CPU time of the nesting stage (nest + verify_nesting) against ``time_budget``, per size."""
    print(f"{'faces':>8s} {'panels':>6s} {'mode':>10s} {'budget s':>8s} {'wall s':>7s} {'cpu s':>7s} "
          f"{'wall/budget':>11s} {'units/budget':>12s} {'sheets':>6s}")
    for fu, fv in sizes:
        parts, params = default_glass_at(fu, fv)
        for mode in ("auto", "rectangles", "guillotine", "irregular"):
            for b in budgets:
                p = replace(params, time_budget=b, mode=mode)
                t, c = time.perf_counter(), time.process_time()
                res = nest(parts, p)
                verify_nesting(parts, res, p)
                wall, cpu = time.perf_counter() - t, time.process_time() - c
                print(f"{fu:>4d}x{fv:<3d} {len(parts):6d} {mode:>10s} {b:8.1f} {wall:7.2f} {cpu:7.2f} "
                      f"{wall / b:11.2f} {res.work_units / res.work_budget:12.2f} {res.sheets:6d}", flush=True)


def rect_sizes(parts: list[FlatPart], params: NestingParams) -> list[tuple[float, float]]:
    """Minimum-area rectangle of each part free to turn, else its bounding box in its own frame."""
    from fabrication.nesting.catalog import rotation_policy
    from fabrication.nesting.shapes import min_rect_angle, rotate

    out = []
    for p in parts:
        pts = np.asarray(p.outline, dtype=float)
        if rotation_policy(p, params)[0]:
            pts = rotate(pts, min_rect_angle(pts))
        out.append(tuple(np.ptp(pts, axis=0)))
    return out


def rectangle_bound(parts: list[FlatPart], params: NestingParams) -> int:
    """No packing of the rectangles of :func:`rect_sizes` (what rectpack is given) uses fewer sheets:
    ``ceil(Σ (w + s)(h + s) / ((W + s)(H + s)))``, the rectangles and the usable sheet grown by half the
    spacing ``s`` (:func:`fabrication.nesting.lower_bound` for true shapes)."""
    s = params.spacing
    x0, y0, x1, y1 = params.usable()
    total = sum((w + s) * (h + s) for w, h in rect_sizes(parts, params))
    return math.ceil(total / ((x1 - x0 + s) * (y1 - y0 + s)) - 1e-9)


def rectpack_best(parts: list[FlatPart], params: NestingParams) -> tuple[int, str]:
    from rectpack import (SORT_AREA, SORT_LSIDE, GuillotineBssfSas, MaxRectsBaf, MaxRectsBl, MaxRectsBssf,
                          PackingBin, PackingMode, SkylineMwf, newPacker)

    s = params.spacing
    x0, y0, x1, y1 = params.usable()
    W, H = int(math.floor(x1 - x0 + s)), int(math.floor(y1 - y0 + s))
    sizes = rect_sizes(parts, params)
    best = (10 ** 9, "")
    for algo in (MaxRectsBssf, MaxRectsBaf, MaxRectsBl, SkylineMwf, GuillotineBssfSas):
        for bin_algo, bname in ((PackingBin.BFF, "BFF"), (PackingBin.BBF, "BBF")):
            for sort, sname in ((SORT_AREA, "area"), (SORT_LSIDE, "long side")):
                packer = newPacker(mode=PackingMode.Offline, bin_algo=bin_algo, pack_algo=algo, sort_algo=sort,
                                   rotation=True)
                for i, (w, h) in enumerate(sizes):
                    packer.add_rect(int(math.ceil(w + s)), int(math.ceil(h + s)), rid=i)
                packer.add_bin(W, H, count=float("inf"))
                packer.pack()
                if sum(len(b) for b in packer) == len(parts) and len(packer) < best[0]:
                    best = (len(packer), f"{algo.__name__}/{bname}/{sname}")
    return best


def spyrrow_strip(parts: list[FlatPart], params: NestingParams, seconds: int) -> tuple[int, str] | None:
    try:
        import spyrrow
    except ImportError:
        return None
    from fabrication.nesting.catalog import rotation_policy

    x0, y0, x1, y1 = params.usable()
    items = []
    for p in parts:
        free, rots = rotation_policy(p, params)
        items.append(spyrrow.Item(p.part_id, [tuple(map(float, q)) for q in np.asarray(p.outline)], demand=1,
                                  allowed_orientations=None if free else [float(r) for r in rots]))
    inst = spyrrow.StripPackingInstance("bench", float(y1 - y0), items)
    cfg = spyrrow.StripPackingConfig(early_termination=True, total_computation_time=int(seconds), num_workers=1,
                                     seed=0, min_items_separation=float(params.spacing) or None)
    sol = inst.solve(cfg)
    n = int(math.ceil(sol.width / (x1 - x0) - 1e-9))
    return n, f"strip {sol.width / 1000:.2f} m at density {sol.density:.3f}; not a sheet layout"


def run(name: str, parts: list[FlatPart], params: NestingParams, budget: float | None, spy: int) -> list[tuple]:
    area = sum(p.area for p in parts)
    sheet_area = params.sheet[0] * params.sheet[1]
    rows = []
    lb = math.ceil(area / sheet_area - 1e-12)
    rows.append((name, "area lower bound", lb, area / (lb * sheet_area), 0.0, 0.0, f"{len(parts)} parts"))
    lb = lower_bound(parts, params)
    rows.append((name, "spacing lower bound", lb, area / (lb * sheet_area), 0.0, 0.0,
                 "parts grown by half the spacing: no layout uses fewer"))
    lb = rectangle_bound(parts, params)
    rows.append((name, "rectangle lower bound", lb, area / (lb * sheet_area), 0.0, 0.0,
                 "these rectangles grown by half the spacing: no rectangle packer uses fewer"))
    t, c = time.perf_counter(), time.process_time()
    n, how = rectpack_best(parts, params)
    rows.append((name, "rectpack, best of 20", n, area / (n * sheet_area), time.perf_counter() - t,
                 time.process_time() - c, how))
    if spy > 0:
        t, c = time.perf_counter(), time.process_time()
        got = spyrrow_strip(parts, params, spy)
        if got is not None:
            rows.append((name, "spyrrow strip (bound)", got[0], area / (got[0] * sheet_area),
                         time.perf_counter() - t, time.process_time() - c, got[1]))
    p0 = params if budget is None else replace(params, time_budget=budget)
    for mode in ("rectangles", "guillotine", "irregular"):
        p = replace(p0, mode=mode)
        t, c = time.perf_counter(), time.process_time()
        res = nest(parts, p)
        verify_nesting(parts, res, p)
        rows.append((name, f"ppfab {mode}" + ("" if res.mode == mode else f" ({res.mode})"), res.sheets,
                     res.utilisation, time.perf_counter() - t, time.process_time() - c,
                     f"budget {p.time_budget:g} s, greedy {res.history[0][1]}, {res.work_units / 1e6:.1f}M units, "
                     "verified"))
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--budget", type=float, default=30.0, help="ppfab time budget per strategy, s (default 30; "
                                                               "the default design's sets keep their own)")
    ap.add_argument("--spyrrow", type=int, default=30, help="spyrrow seconds per set (0: skip)")
    ap.add_argument("--only", nargs="*", default=None, help="data sets to run (names as printed)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--budget-check", nargs="*", type=float, default=None, metavar="SECONDS",
                    help="instead: time the nesting stage against these budgets at 22x15 ... 88x60 faces")
    args = ap.parse_args(argv)
    if args.budget_check is not None:
        budget_check(args.budget_check or [3.0, 6.0], [(22, 15), (44, 30), (66, 45), (88, 60)])
        return 0
    ref = NestingParams(sheet=[6000.0, 3210.0], margin=0.0, spacing=10.0, rotations=[0.0, 90.0, 180.0, 270.0],
                        time_budget=args.budget, seed=args.seed)
    sets: list[tuple[str, object, NestingParams, float | None]] = [
        ("bench_panels_500", lambda: bench_parts(False), ref, args.budget),
        ("bench_panels_500 free", lambda: bench_parts(True), ref, args.budget)]
    want = set(args.only) if args.only else None
    if want is None or {"default glass", "default plates"} & want:
        glass, gp, plates, bp = default_design()
        sets += [("default glass", lambda: glass, replace(gp, seed=args.seed), None),
                 ("default plates", lambda: plates, replace(bp, seed=args.seed), None)]
    sets += [(n, (lambda n=n: set_parts(n)), ref, args.budget) for n in FREEFORM]
    rows = []
    print(f"{'data':24s} {'method':32s} {'sheets':>6s} {'util':>7s} {'time s':>14s}  note", flush=True)
    for name, parts, params, budget in sets:
        if want is not None and name not in want:
            continue
        got = run(name, parts(), params, budget, args.spyrrow)
        for data, method, sheets, util, sec, cpu, note in got:
            print(f"{data:24s} {method:32s} {sheets:6d} {100 * util:6.1f}% {sec:7.1f} ({cpu:5.1f})  {note}", flush=True)
        rows += got
    print()
    for data in dict.fromkeys(r[0] for r in rows):
        rp = next(r[2] for r in rows if r[0] == data and r[1].startswith("rectpack"))
        mine = [r for r in rows if r[0] == data and r[1].startswith("ppfab")]
        best = min(mine, key=lambda r: r[2])
        print(f"{data}: best ppfab {best[2]} sheets ({best[1]}) vs rectpack {rp}: "
              f"{100 * (rp - best[2]) / rp:+.1f} % fewer sheets")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
