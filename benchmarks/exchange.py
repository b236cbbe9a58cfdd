"""Seconds each exchange writer adds to a build, on the bundled default (330 panels, 219 plates) or a design file.

The design is built once; then, side by side in one process, each writer writes into a fresh folder ``--repeat``
times (best of the runs, wall clock and CPU), after one untimed run that pays the imports.  Next to the new
writers (IFC, Rhino, glTF, the R12 / R2000 copies) the two changed ones are timed against their previous form:
``beams.step`` + ``panels.step`` as flat compounds without colours (what was written before) against the
assemblies with colours and the canonical style order, and the per-type DXFs without and with dimensions.

    OMP_NUM_THREADS=1 python benchmarks/exchange.py [design.toml] [--repeat 3]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path


def timed(fn, repeat: int) -> tuple[float, float]:
    """Best wall-clock and CPU seconds of ``fn(folder)`` over ``repeat`` runs, each into a new folder."""
    best_wall = best_cpu = float("inf")
    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as tmp:
            w, c = time.perf_counter(), time.process_time()
            fn(Path(tmp))
            best_wall = min(best_wall, time.perf_counter() - w)
            best_cpu = min(best_cpu, time.process_time() - c)
    return best_wall, best_cpu


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("design", nargs="?", default=None)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)

    import numpy as np

    import fabrication
    from fabrication.contract import TYPE_DIR
    from fabrication.writers import dxf, dxf_legacy, glb, ifc, rhino, step
    from fabrication.writers.dxf import write_type_dxfs

    t0 = time.perf_counter()
    b = fabrication.build(fabrication.load_design(args.design))
    print(f"build: {len(b.panels.panels)} panels, {len(b.beams.plates)} plates, {time.perf_counter() - t0:.1f} s")
    files: dict = dxf.dxf_files(b)                      # the sheet file names the parts table refers to
    plates = list(b.beams.plates)
    panels = b.panels.panels
    corners = np.array([p.corners_3d for p in panels])
    ids = [p.part_id for p in panels]
    thickness = b.design.panels.thickness
    name = b.design.info.name

    def step_flat(out: Path) -> None:           # before: flat compounds, no colours
        solids = step.build_solids(plates)
        for s in solids:
            s.color = None
        step.export_step(solids, out / "beams.step")
        step.export_step(step.panel_solids(corners, thickness, ids), out / "panels.step")

    def step_structured(out: Path) -> None:     # now: design → family → beam → plate, coloured
        step.export_step(step.beam_assembly(plates, step.build_solids(plates), name), out / "beams.step")
        step.export_panels_step(corners, out / "panels.step", thickness, ids, name)

    def legacy(version: str):
        def run(out: Path) -> None:
            from fabrication.contract import GLASS_SHEET_DIR, GLASS_SHEET_PREFIX, PLATE_SHEET_DIR, PLATE_SHEET_PREFIX

            nest = b.nesting
            dxf.write_sheet_dxfs(list(nest.glass_parts), nest.glass, out / GLASS_SHEET_DIR, GLASS_SHEET_PREFIX,
                                 name, version)
            dxf.write_sheet_dxfs(list(nest.beam_parts), nest.plates, out / PLATE_SHEET_DIR, PLATE_SHEET_PREFIX,
                                 name, version)
            write_type_dxfs(list(nest.glass_parts), out / TYPE_DIR, version=version, dimensions=True)
        return run

    rows = [
        ("STEP: flat, no colours (before)", step_flat),
        ("STEP: assemblies, colours (now)", step_structured),
        ("per-type DXFs, no dimensions (before)", lambda out: write_type_dxfs(list(b.nesting.glass_parts), out)),
        ("per-type DXFs, dimensioned (now)",
         lambda out: write_type_dxfs(list(b.nesting.glass_parts), out, dimensions=True)),
        ("model.ifc", lambda out: ifc.write_ifc(b, out, dict(files))),
        ("model.3dm", lambda out: rhino.write_rhino(b, out, dict(files))),
        ("model.glb", lambda out: glb.write_glb(b, out, dict(files))),
        ("dxf_r12/ (off by default)", legacy("R12")),
        ("dxf_r2000/ (off by default)", legacy("R2000")),
    ]
    assert dxf_legacy.legacy_versions(b.design) == []
    for _, fn in rows:                                # imports and caches paid here, untimed
        with tempfile.TemporaryDirectory() as tmp:
            fn(Path(tmp))
    print(f"\n| writer | wall s (best of {args.repeat}) | CPU s |\n|---|---|---|")
    for label, fn in rows:
        wall, cpu = timed(fn, args.repeat)
        print(f"| {label} | {wall:.2f} | {cpu:.2f} |")


if __name__ == "__main__":
    main()
