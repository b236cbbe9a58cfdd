"""The CAD kernel's own cost of the STEP files of a build: the least any build with these files can spend.

    OMP_NUM_THREADS=1 python benchmarks/step_floor.py OUT [--repeat 1]

For every STEP file of the build folder ``OUT`` (``beams.step``, ``panels.step``, ``glazing.step``,
``splices.step``), measured one after another in this process (CPU seconds, ``time.process_time``):

* ``kernel read`` — the kernel's plain reader (``STEPControl_Reader``: parse, then ``TransferRoots`` into
  one compound, no names, no colours, no assembly tree);
* ``kernel write`` — the kernel's plain writer on that compound (``STEPControl_Writer``, as-is, no
  parameter curves, no names, no colours), to a scratch file;
* ``ppfab read`` — the reader of the self-check (``fabrication.verify._step_read``: names and the
  assembly tree on, which is what the checks need).

The two kernel columns are a floor, not a target: a build that writes these solids as STEP and reads them
back in its self-check cannot spend less than ``kernel write + kernel read`` CPU seconds however the rest of
it is written, since both are the kernel's own translators with every option that costs time turned off.
``solids`` counts the solids the kernel read.  Nothing in ``OUT`` is changed.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

FILES = ("beams.step", "panels.step", "glazing.step", "splices.step")


def _kernel_read(path: Path):
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.STEPControl import STEPControl_Reader

    reader = STEPControl_Reader()
    if reader.ReadFile(str(path)) != IFSelect_RetDone:
        raise SystemExit(f"step_floor: {path}: the kernel cannot read it")
    reader.TransferRoots()
    return reader.OneShape()


def _count_solids(shape) -> int:
    from OCP.TopAbs import TopAbs_SOLID
    from OCP.TopExp import TopExp_Explorer

    found, n = TopExp_Explorer(shape, TopAbs_SOLID), 0
    while found.More():
        n += 1
        found.Next()
    return n


def _kernel_write(shape, target: Path) -> None:
    from OCP.Interface import Interface_Static
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

    writer = STEPControl_Writer()
    Interface_Static.SetIVal_s("write.surfacecurve.mode", 0)
    sys.stdout.flush()
    saved = os.dup(1)                                     # the kernel prints its transfer statistics
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            writer.Transfer(shape, STEPControl_AsIs)
            writer.Write(str(target))
    finally:
        os.dup2(saved, 1)
        os.close(saved)


def _cpu(fn, *args):
    t = time.process_time()
    out = fn(*args)
    return out, time.process_time() - t


def measure(folder: Path, repeat: int) -> list[dict]:
    from fabrication.verify._step_read import read_step_solids

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in FILES:
            path = folder / name
            if not path.is_file():
                continue
            best = {"file": name, "read": float("inf"), "write": float("inf"), "ppfab": float("inf")}
            for _ in range(repeat):
                shape, dr = _cpu(_kernel_read, path)
                _, dw = _cpu(_kernel_write, shape, Path(tmp) / name)
                solids, dp = _cpu(read_step_solids, path)
                best.update(solids=_count_solids(shape), ppfab_solids=len(solids), mb=path.stat().st_size / 1e6,
                            read=min(best["read"], dr), write=min(best["write"], dw), ppfab=min(best["ppfab"], dp))
            rows.append(best)
    return rows


def main(argv: list[str]) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("folder", type=Path)
    ap.add_argument("--repeat", type=int, default=1, help="best of this many runs per file")
    args = ap.parse_args(argv)
    rows = measure(args.folder, max(1, args.repeat))
    if not rows:
        raise SystemExit(f"step_floor: {args.folder} holds none of {', '.join(FILES)}")
    print(f"{'file':<14}{'MB':>8}{'solids':>9}{'kernel read':>13}{'kernel write':>14}{'ppfab read':>12}   (CPU s)")
    for r in rows:
        print(f"{r['file']:<14}{r['mb']:>8.1f}{r['solids']:>9}{r['read']:>13.2f}{r['write']:>14.2f}{r['ppfab']:>12.2f}")
    tot = {k: sum(r[k] for r in rows) for k in ("mb", "solids", "read", "write", "ppfab")}
    print(f"{'total':<14}{tot['mb']:>8.1f}{tot['solids']:>9}{tot['read']:>13.2f}{tot['write']:>14.2f}"
          f"{tot['ppfab']:>12.2f}")
    print(f"floor of a build that writes these files and reads them back once: "
          f"{tot['read'] + tot['write']:.1f} CPU s")


if __name__ == "__main__":
    main(sys.argv[1:])
