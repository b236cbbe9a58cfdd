"""Beam plates of a 20 × 30-face PP mesh: build and export all beams, one extrusion per plate,
next to the same plates made with one boolean cut per slot (the baseline), in the same run.

Both versions start from the same plate outlines (``fabrication.beams``): ppfab draws the half-lap
slots into the 2D outline and extrudes it once; the baseline extrudes the outline without slots
and cuts a slot prism out of the solid for every slot.  The script checks that both give the same
volumes and valid solids, then prints a table and the ratios.

    python benchmarks/beams.py [faces_u faces_v] [--max-length MM]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path


def boolean_plate(plate):
    """Baseline: the plate without slots, extruded, then one boolean cut per slot."""
    from fabrication.writers.step import _placed_prism

    t = plate.thickness
    solid = _placed_prism(plate.body, plate.frame, -0.5 * t, t, plate.part_id)
    for sl in plate.slots:
        solid = solid - _placed_prism(sl.polygon(), plate.frame, -0.5 * t - 1.0, t + 2.0, "slot")
    solid.label = plate.part_id
    return solid


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("faces", nargs="*", type=int, default=[20, 30])
    ap.add_argument("--max-length", type=float, default=0.0, help="split beams longer than this (mm), 0 = never")
    args = ap.parse_args(argv)
    fu, fv = (args.faces + [30])[:2] if len(args.faces) == 1 else args.faces[:2]

    t0 = time.perf_counter()
    import build123d  # noqa: F401  (imported once up front so no row pays for it)
    t_import = time.perf_counter() - t0

    from fabrication.beams import BeamParams, build_beams
    from fabrication.beams.samples import sample_pp_grid
    from fabrication.writers.step import _is_valid, check_step, export_step, plate_solid
    from ppfab.support.pp import support_pp

    grid = sample_pp_grid(fu, fv)
    rows: list[tuple[str, float]] = []

    t0 = time.perf_counter()
    support = support_pp(grid)
    rows.append(("support structure (U_i ∩ W_j)", time.perf_counter() - t0))
    t0 = time.perf_counter()
    beams = build_beams(support, BeamParams(max_length=args.max_length))
    rows.append(("plate outlines, joints, checks", time.perf_counter() - t0))
    plates = list(beams.plates)
    n_slots = sum(len(p.slots) for p in plates)

    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        solids = [plate_solid(p) for p in plates]
        t_solids = time.perf_counter() - t0
        t0 = time.perf_counter()
        invalid = [p.part_id for p, s in zip(plates, solids) if not _is_valid(s)]
        t_valid = time.perf_counter() - t0
        t0 = time.perf_counter()
        export_step(solids, Path(tmp) / "beams.step")
        t_export = time.perf_counter() - t0
        t0 = time.perf_counter()
        check = check_step(Path(tmp) / "beams.step", plates)
        t_check = time.perf_counter() - t0
        if not check.ok:
            raise SystemExit("beams.step check failed: " + "; ".join(check.problems))

        t0 = time.perf_counter()
        base = [boolean_plate(p) for p in plates]
        t_bool = time.perf_counter() - t0
        t0 = time.perf_counter()
        bad = [p.part_id for p, s in zip(plates, base) if not _is_valid(s)]
        t_bool_valid = time.perf_counter() - t0
        t0 = time.perf_counter()
        export_step(base, Path(tmp) / "beams_boolean.step")
        t_bool_export = time.perf_counter() - t0

    vol_err = max(abs(a.volume - b.volume) / a.volume for a, b in zip(solids, base))
    print(f"Beams of a {fu} x {fv}-face PP mesh: {len(plates)} plates, {n_slots} half-lap slots "
          f"(import build123d {t_import:.1f} s, not counted)")
    print(f"{'stage':<44}{'time [s]':>10}{'ms/plate':>10}")
    for name, t in rows:
        print(f"{name:<44}{t:>10.3f}{1000 * t / len(plates):>10.2f}")
    print(f"{'solids: one extrusion per plate':<44}{t_solids:>10.3f}{1000 * t_solids / len(plates):>10.2f}")
    print(f"{'  validity check (BRepCheck)':<44}{t_valid:>10.3f}{1000 * t_valid / len(plates):>10.2f}")
    print(f"{'  STEP export (no p-curves)':<44}{t_export:>10.3f}{1000 * t_export / len(plates):>10.2f}")
    print(f"{'  STEP re-import check':<44}{t_check:>10.3f}{1000 * t_check / len(plates):>10.2f}")
    print(f"{'baseline: extrusion + one cut per slot':<44}{t_bool:>10.3f}{1000 * t_bool / len(plates):>10.2f}")
    print(f"{'  validity check (BRepCheck)':<44}{t_bool_valid:>10.3f}{1000 * t_bool_valid / len(plates):>10.2f}")
    print(f"{'  STEP export of the baseline solids':<44}{t_bool_export:>10.3f}"
          f"{1000 * t_bool_export / len(plates):>10.2f}")
    ours = t_solids + t_export
    theirs = t_bool + t_bool_export
    print(f"solids: {t_bool / t_solids:.1f}x faster than per-slot cuts; solids + export: {theirs / ours:.1f}x")
    print(f"largest relative volume difference {vol_err:.1e}; invalid solids: {len(invalid)} (ours), "
          f"{len(bad)} (baseline)")
    if vol_err > 1e-6 or invalid:
        raise SystemExit("the two versions differ or a solid is invalid")


if __name__ == "__main__":
    main()
