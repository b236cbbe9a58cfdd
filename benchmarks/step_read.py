"""Reading a STEP file of many small solids back: a flat product tree against one grouped by beam, and
build123d's ``import_step`` against verify's reader (``fabrication/verify/_step_read.py``).

Strips like those of ``glazing.step`` (a 60 × 12 mm rectangle, 300–500 mm long, extruded once, in a frame
turned at random) are written with ppfab's STEP writer as ``n`` solids either directly below the root (the
tree ``glazing.step`` had) or in assemblies of ``--group`` solids (one per beam, as now).  Each file is then
read, side by side in one process and one at a time, by both readers; both walk the product tree to every
solid and its name.  CPU seconds (``OMP_NUM_THREADS=1``; a single thread in any case).

    OMP_NUM_THREADS=1 python benchmarks/step_read.py [--sizes 1000 2000 4000] [--group 140] [--verify-only]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np


def strips(n: int, seed: int = 0) -> list:
    """``n`` strip solids named ``S00000`` …, each a rectangle extruded once in a random frame."""
    from fabrication.writers.step import _placed_prism
    from ppfab.frame import Frame

    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        length = rng.uniform(300.0, 500.0)
        rect = np.array([[0.0, -30.0], [length, -30.0], [length, 30.0], [0.0, 30.0]])
        ex = rng.normal(size=3)
        ex /= np.linalg.norm(ex)
        ey = np.cross(rng.normal(size=3), ex)
        ey /= np.linalg.norm(ey)
        origin = rng.uniform(-20000.0, 20000.0, size=3)
        out.append(_placed_prism(rect, Frame(origin, ex, ey), 0.0, 12.0, f"S{k:05d}"))
    return out


def write(solids: list, path: Path, group: int) -> None:
    from build123d import Compound

    from fabrication.writers.step import export_step

    if group:
        kids = [Compound(children=solids[i:i + group], label=f"B-{i // group:03d}")
                for i in range(0, len(solids), group)]
        export_step(Compound(children=kids, label="strips"), path)
    else:
        export_step(solids, path, name="strips")


def read_build123d(path: Path) -> int:
    from build123d import import_step

    from fabrication.writers.step import named_solids

    return len(named_solids(import_step(str(path))))


def read_verify(path: Path) -> int:
    from fabrication.verify._step_read import read_step_solids

    return len(read_step_solids(path))


def cpu(fn, *args) -> tuple[float, int]:
    t = time.process_time()
    n = fn(*args)
    return time.process_time() - t, n


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 2000, 4000])
    ap.add_argument("--group", type=int, default=140, help="solids per beam assembly (88 × 60 default: 143)")
    ap.add_argument("--verify-only", action="store_true",
                    help="time verify's reader only (build123d's grows as n² on either tree)")
    args = ap.parse_args(argv)
    import build123d  # noqa: F401 - pay the import before timing

    print("| solids | tree | build123d import_step, CPU s | verify reader, CPU s |")
    print("|---|---|---|---|")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.sizes:
            solids = strips(n)
            for group in (0, args.group):
                path = Path(tmp) / f"s{n}_{group}.step"
                write(solids, path, group)
                a, na = cpu(read_build123d, path) if not args.verify_only else (float("nan"), n)
                b, nb = cpu(read_verify, path)
                if not na == nb == n:
                    raise SystemExit(f"read {na} and {nb} solids of {n}")
                tree = "flat" if not group else f"by {group}"
                rows.append((n, group, a, b))
                print(f"| {n} | {tree} | {a:.1f} | {b:.1f} |", flush=True)
                path.unlink()
    if len(args.sizes) > 1:
        for group in (0, args.group):
            pts = [(n, a, b) for n, g, a, b in rows if g == group]
            x = np.log([p[0] for p in pts])
            for col, label in ((1, "build123d"), (2, "verify reader"))[args.verify_only:]:
                slope = np.polyfit(x, np.log([p[col] for p in pts]), 1)[0]
                print(f"growth exponent, {'flat' if not group else f'by {group}'}, {label}: {slope:.2f}")


if __name__ == "__main__":
    main()
