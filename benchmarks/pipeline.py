"""Stage times, peak memory and growth exponents of ``ppfab build`` on the bundled default at four sizes.

    OMP_NUM_THREADS=1 python benchmarks/pipeline.py [--sizes 22x15,44x30,66x45,88x60] [--budget 0.5]
                                                    [--writers serial|parallel|both] [--design FILE]

The default design (or ``--design``) is built at each size ``faces_u x faces_v`` (``[geometry.params]``:
the same surface cut into more, smaller panels) in a fresh subprocess, so that each size has its own peak
memory (``ru_maxrss`` of that process, and of its writer processes when the files are written in parallel)
and no import or cache is shared between sizes.  Both nesting budgets are set to ``--budget`` seconds at
every size (the default's 6 + 3 s would make the nesting dominate and hide the other stages; the budget buys
a fixed work count, so the nesting time is about the same at every size and its exponent is near 0).

Printed per size: wall and CPU seconds of every compute stage, of the files stage (all writers; ``files``)
and of the self-check (``verify``), the build's total, the share of files in the total CPU, the peak
resident memory, and one line per writer (CPU s inside the files stage).  CPU counts the build process
and, for parallel writing, its writer processes (``RUSAGE_CHILDREN``).  Then the growth exponent of each
stage: the slope ``b`` of the least-squares fit ``log t = a + b log F`` over the sizes (F = faces).

With ``--writers both`` each size is built twice, serial then parallel writing, side by side in one run.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _child(size: str, budget: float, parallel: bool, design_path: str | None) -> None:
    """Build one size in this process and print one JSON line: per stage [wall, cpu], writers, memory."""
    import resource
    import tempfile
    import tomllib

    from fabrication import parse_design
    from fabrication.design import DEFAULT_DESIGN
    from fabrication.pipeline.progress import Progress

    fu, fv = (int(x) for x in size.split("x"))
    path = Path(design_path) if design_path else DEFAULT_DESIGN
    doc = tomllib.loads(path.read_text(encoding="utf-8"))
    doc["geometry"].setdefault("params", {}).update(faces_u=fu, faces_v=fv)
    for section in ("nesting", "beam_nesting"):
        doc.setdefault(section, {})["time_budget"] = budget
    doc.setdefault("output", {})
    os.environ["PPFAB_PARALLEL_WRITERS"] = "1" if parallel else "0"

    def cpu() -> float:
        s = resource.getrusage(resource.RUSAGE_SELF)
        c = resource.getrusage(resource.RUSAGE_CHILDREN)
        return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime

    class Timed(Progress):
        """Progress that also records the CPU seconds of each stage."""

        def __init__(self) -> None:
            super().__init__(quiet=True)
            self.cpu: dict[str, float] = {}
            self._c0 = 0.0

        def start(self, stage: str, detail: str = "") -> None:
            self._c0 = cpu()
            super().start(stage, detail)

        def done(self, summary: str = "") -> None:
            self.cpu[self._stage] = self.cpu.get(self._stage, 0.0) + cpu() - self._c0
            super().done(summary)

    import fabrication.writers as writers

    names = {w.name for w in writers.load_writers()}
    design = parse_design(doc, str(path), "", path.resolve().parent)
    from fabrication import build

    prog = Timed()
    t0, c0 = time.perf_counter(), cpu()
    result = build(design, progress=prog, allow_large=True)
    stages = {k: [prog.times[k], prog.cpu.get(k, 0.0)] for k in prog.times}
    with tempfile.TemporaryDirectory() as tmp:
        w0, cw0 = time.perf_counter(), cpu()
        result.write(Path(tmp) / "out", progress=prog)
        w1, cw1 = time.perf_counter(), cpu()
    t1, c1 = time.perf_counter(), cpu()
    per_writer = {k: [prog.times[k], prog.cpu.get(k, 0.0)] for k in prog.times if k in names}
    ver = [prog.times.get("verify", 0.0), prog.cpu.get("verify", 0.0)]
    stages["files"] = [w1 - w0 - ver[0], cw1 - cw0 - ver[1]]
    stages["verify"] = ver
    stages["total"] = [t1 - t0, c1 - c0]
    self_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    kids_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    print("RESULT " + json.dumps({"size": size, "faces": fu * fv, "parallel": parallel, "stages": stages,
                                  "writers": per_writer, "peak_mb": self_mb, "child_peak_mb": kids_mb,
                                  "panels": result.summary.panels, "plates": result.summary.beam_plates,
                                  "glass_sheets": result.summary.glass_sheets,
                                  "plate_sheets": result.summary.plate_sheets}))


def run_size(size: str, budget: float, parallel: bool, design: str | None) -> dict:
    env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    cmd = [sys.executable, __file__, "--child", size, "--budget", str(budget)]
    if parallel:
        cmd.append("--parallel")
    if design:
        cmd += ["--design", design]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
    line = next((x for x in out.stdout.splitlines() if x.startswith("RESULT ")), None)
    if line is None:
        raise SystemExit(f"size {size} failed:\n{out.stderr[-3000:]}")
    return json.loads(line[len("RESULT "):])


def exponent(faces: list[int], times: list[float]) -> float:
    """Slope of the least-squares line through (log F, log t)."""
    import numpy as np

    x, y = np.log(np.asarray(faces, float)), np.log(np.maximum(np.asarray(times, float), 1e-6))
    return float(np.polyfit(x, y, 1)[0]) if len(x) > 1 else float("nan")


def table(results: list[dict], label: str) -> None:
    stages = [k for k in results[-1]["stages"] if k not in ("files", "verify", "total")] + ["files", "verify", "total"]
    print(f"\n== {label} writing: seconds per stage, wall / CPU ==")
    print(f"{'stage':<10}" + "".join(f"{r['size'] + ' (' + str(r['faces']) + ')':>22}" for r in results)
          + f"{'exp wall':>9}{'exp CPU':>9}")
    faces = [r["faces"] for r in results]
    for s in stages:
        cells = "".join(f"{r['stages'].get(s, [0, 0])[0]:>11.2f}{r['stages'].get(s, [0, 0])[1]:>11.2f}" for r in results)
        w = [r["stages"].get(s, [0, 0])[0] for r in results]
        c = [r["stages"].get(s, [0, 0])[1] for r in results]
        print(f"{s:<10}{cells}{exponent(faces, w):>9.2f}{exponent(faces, c):>9.2f}")
    share = "".join(f"{100 * r['stages']['files'][1] / r['stages']['total'][1]:>21.1f}%" for r in results)
    print(f"{'files %':<10}{share}   (share of the total CPU)")
    mem = "".join(f"{r['peak_mb']:>15.0f} MB{r['child_peak_mb']:>4.0f}" if r["parallel"] else f"{r['peak_mb']:>19.0f} MB"
                  for r in results)
    print(f"{'peak RSS':<10}{mem}   (build process{'; writer processes' if results[0]['parallel'] else ''})")
    print(f"\n-- {label}: writers inside the files stage, seconds wall / CPU (CPU of this process only when "
          "parallel) --")
    for w in results[-1]["writers"]:
        cells = "".join(f"{r['writers'].get(w, [0, 0])[0]:>11.2f}{r['writers'].get(w, [0, 0])[1]:>11.2f}"
                        for r in results)
        c = [max(r["writers"].get(w, [0, 0])[1], 1e-3) for r in results]
        print(f"{w:<10}{cells}{'':>9}{exponent(faces, c):>9.2f}")
    print("counts    " + "".join(f"{str(r['panels']) + ' pan ' + str(r['plates']) + ' pl':>22}" for r in results))


def main(argv: list[str]) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="22x15,44x30,66x45,88x60")
    ap.add_argument("--budget", type=float, default=0.5, help="both nesting budgets, s (same at every size)")
    ap.add_argument("--writers", choices=("serial", "parallel", "both"), default="both")
    ap.add_argument("--design", default=None)
    ap.add_argument("--child", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--parallel", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        _child(args.child, args.budget, args.parallel, args.design)
        return
    print(f"ppfab build of {'the bundled default' if not args.design else args.design}; both nesting budgets "
          f"{args.budget:g} s at every size; OMP_NUM_THREADS=1; {os.cpu_count()} cores; one subprocess per size")
    modes = {"serial": [False], "parallel": [True], "both": [False, True]}[args.writers]
    results: dict[bool, list[dict]] = {m: [] for m in modes}
    for size in args.sizes.split(","):
        for m in modes:                     # serial and parallel side by side at each size
            results[m].append(run_size(size, args.budget, m, args.design))
            r = results[m][-1]
            print(f"  {size} {'parallel' if m else 'serial'}: total {r['stages']['total'][1]:.1f} CPU s, "
                  f"files {r['stages']['files'][1]:.1f} CPU s", flush=True)
    for m in modes:
        table(results[m], "parallel" if m else "serial")


if __name__ == "__main__":
    main(sys.argv[1:])
