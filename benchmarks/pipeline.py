"""Stage times, peak memory and growth exponents of ``ppfab build`` on the bundled default at four sizes.

    OMP_NUM_THREADS=1 python benchmarks/pipeline.py [--sizes 22x15,44x30,66x45,88x60] [--budget 0.5]
                                                    [--writers serial|parallel|both] [--design FILE]
                                                    [--baseline TREE] [--jobs N] [--floor] [--paper A0]
    OMP_NUM_THREADS=1 python benchmarks/pipeline.py --per-file 22x15

The default design (or ``--design``) is built at each size ``faces_u x faces_v`` (``[geometry.params]``:
the same surface cut into more, smaller panels) in a fresh subprocess, so that each size has its own peak
memory (``ru_maxrss`` of that process and of its forked processes, and the peak of the whole process tree's
proportional set size sampled every 0.5 s from outside, :mod:`tree_memory`: a forked process's resident set
counts the pages it shares with the build again)
and no import or cache is shared between sizes.  Both nesting budgets are set to ``--budget`` seconds at
every size (the default's 6 + 3 s would make the nesting dominate and hide the other stages; the budget buys
a fixed work count, so the nesting time is about the same at every size and its exponent is near 0).

Printed per size: wall and CPU seconds of every compute stage, of the files stage (all writers; ``files``)
and of the self-check (``verify``), the build's total, the share of files in the total CPU, the peak
resident memory, and one line per writer (CPU s inside the files stage).  CPU counts the build process
and, for parallel writing, its writer processes (``RUSAGE_CHILDREN``).  Then the growth exponent of each
stage: the slope ``b`` of the least-squares fit ``log t = a + b log F`` over the sizes (F = faces).

With ``--writers both`` each size is built twice, serial and parallel writing, side by side in one run; with
``--baseline TREE`` also with the source tree ``TREE`` (e.g. ``git worktree add TREE <commit>``), writing as the
variant it is compared with does (parallel with ``--writers parallel`` or ``both``), and a table of CPU seconds
before → after.  ``--jobs`` runs that many builds at once (CPU seconds are per build; wall
times then include the waiting).  ``--per-file SIZE`` prints only the ms per per-type DXF (by part of the
work, and the document set-up alternatives) and per STEP plate against the kernel writing the same prisms.
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


def _child(size: str, budget: float, parallel: bool, design_path: str | None, floor: bool = False,
           paper: str | None = None) -> None:
    """Build one size in this process and print one JSON line: per stage [wall, cpu], writers, memory; with
    ``floor`` also the CAD kernel's plain write + read of the STEP files just written (``step_floor.py``),
    measured in this process after the build (so the build's peak memory is its own)."""
    import resource
    import tempfile

    from _sized import sized_design

    from fabrication.progress import Progress

    fu, fv = (int(x) for x in size.split("x"))
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
    design = sized_design(size, budget, Path(design_path) if design_path else None, paper)
    from fabrication import build

    prog = Timed()
    monitor = subprocess.Popen([sys.executable, str(ROOT / "benchmarks" / "tree_memory.py"), str(os.getpid())],
                               stdout=subprocess.PIPE, text=True)          # waited for after the CPU is read
    t0, c0 = time.perf_counter(), cpu()
    result = build(design, progress=prog, allow_large=True)
    stages = {k: [prog.times[k], prog.cpu.get(k, 0.0)] for k in prog.times}
    with tempfile.TemporaryDirectory() as tmp:
        w0, cw0 = time.perf_counter(), cpu()
        result.write(Path(tmp) / "out", progress=prog)
        w1, cw1 = time.perf_counter(), cpu()
        t1, c1 = time.perf_counter(), cpu()
        peak = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024)
        monitor.terminate()
        said = monitor.communicate()[0].split()
        tree_mb = float(said[1]) if len(said) == 3 else float("nan")
        floor_rows = []
        if floor:
            sys.path.insert(0, str(ROOT / "benchmarks"))
            from step_floor import measure

            floor_rows = measure(Path(tmp) / "out", 1)
    per_writer = {k: [prog.times[k], prog.cpu.get(k, 0.0)] for k in prog.times if k in names}
    ver = [prog.times.get("verify", 0.0), prog.cpu.get("verify", 0.0)]
    stages["files"] = [w1 - w0 - ver[0], cw1 - cw0 - ver[1]]
    stages["verify"] = ver
    stages["total"] = [t1 - t0, c1 - c0]
    self_mb, kids_mb = peak
    print("RESULT " + json.dumps({"size": size, "faces": fu * fv, "parallel": parallel, "stages": stages,
                                  "floor": floor_rows,
                                  "writers": per_writer, "peak_mb": self_mb, "child_peak_mb": kids_mb,
                                  "tree_pss_mb": tree_mb,
                                  "panels": result.summary.panels, "plates": result.summary.beam_plates,
                                  "glass_sheets": result.summary.glass_sheets,
                                  "plate_sheets": result.summary.plate_sheets}))


def _timed(fn, reps: int) -> float:
    """CPU seconds per call of ``fn``."""
    c0 = time.process_time()
    for _ in range(reps):
        fn()
    return (time.process_time() - c0) / reps


def _per_file(size: str, budget: float) -> None:
    """ms per per-type DXF (by part, and the document set-up alternatives) and ms per STEP plate (with and
    without the writer's own BRepCheck, against the kernel writing the same prisms with nothing else)."""
    import copy
    import io
    import pickle
    import tempfile

    import ezdxf
    from _sized import sized_design

    from fabrication import build
    from fabrication.writers._dxf_dimensions import add_pane_dimensions
    from fabrication.writers.dxf import CuttingSheet, _fixed_metadata, _new_doc
    from fabrication.writers.step import beam_assembly, build_solids, export_step

    b = build(sized_design(size, budget), allow_large=True)
    tmp = Path(tempfile.mkdtemp())
    parts = list(b.nesting.glass_parts)[:200]
    t = dict.fromkeys(("document", "part", "dimensions", "save"), 0.0)
    for k, part in enumerate(parts):
        c0 = time.process_time()
        sheet = CuttingSheet(None, None, f"T{k} ({part.part_id})", "R2010")
        c1 = time.process_time()
        sheet.add_part(part, None)
        c2 = time.process_time()
        add_pane_dimensions(sheet.doc, part.outline)
        c3 = time.process_time()
        sheet.write(tmp / f"t{k}.dxf")
        c4 = time.process_time()
        for key, dt in zip(t, (c1 - c0, c2 - c1, c3 - c2, c4 - c3)):
            t[key] += dt
    n = len(parts)
    print(f"per-type DXF ({n} files of {size}), ms per file: " + ", ".join(f"{k} {1000 * v / n:.2f}" for k, v in t.items())
          + f"; total {1000 * sum(t.values()) / n:.2f}")
    with _fixed_metadata():
        pickled = pickle.dumps(_new_doc())

    def whole_file(k: int, part, from_template: bool, one_write: bool) -> None:
        """One per-type DXF with its document from ``ezdxf.new`` or the unpickled template, saved by
        ``Drawing.saveas`` or into a string written at once (the alternatives tried against the fixed cost)."""
        with _fixed_metadata():
            d = pickle.loads(pickled) if from_template else _new_doc()
        sheet = CuttingSheet.__new__(CuttingSheet)
        sheet.version, sheet.doc, sheet.msp = "R2010", d, d.modelspace()
        sheet.msp.add_text(f"T{k}", height=40.0, dxfattribs={"layer": "LABEL", "insert": (0.0, -80.0)})
        sheet.add_part(part, None)
        add_pane_dimensions(d, part.outline)
        classes = d.classes
        classes.add_required_classes(d.dxfversion)
        ordered = sorted(classes.classes.items())
        classes.classes.clear()
        classes.classes.update(ordered)
        path = tmp / f"v{k}_{int(from_template)}{int(one_write)}.dxf"
        with _fixed_metadata():
            if one_write:
                buf = io.StringIO()
                d.write(buf)
                with open(path, "w", encoding=d.output_encoding, errors="dxfreplace") as fh:
                    fh.write(buf.getvalue())
            else:
                d.saveas(path)

    variants = [(False, False), (True, False), (True, True)]
    spent = [0.0] * len(variants)
    for k, part in enumerate(parts):                # interleaved, the order alternating: fair under load
        for v in (variants if k % 2 else variants[::-1]):
            c0 = time.process_time()
            whole_file(k, part, *v)
            spent[variants.index(v)] += time.process_time() - c0
    same = all(len({(tmp / f"v{k}_{a}{b}.dxf").read_bytes() for a, b in ((0, 0), (1, 0), (1, 1))}) == 1
               for k in range(n))
    print("  whole file, interleaved: " + ", ".join(
        f"{'template' if a else 'ezdxf.new'} + {'one write' if b else 'saveas'} {1000 * t / n:.2f} ms"
        for (a, b), t in zip(variants, spent)) + f" (byte-identical: {same})")
    with _fixed_metadata():
        template = _new_doc()
        s = io.StringIO()
        template.write(s)
    text = s.getvalue()
    pickled = pickle.dumps(template)
    reps = 50
    for label, make in (("ezdxf.new + layers (used)", _new_doc), ("ezdxf.read of a template", lambda: ezdxf.read(io.StringIO(text))),
                        ("deepcopy of a template", lambda: copy.deepcopy(template))):
        c0 = time.process_time()
        for _ in range(reps):
            make()
        print(f"  document set-up, {label}: {1000 * (time.process_time() - c0) / reps:.2f} ms")
    print(f"  document set-up, unpickled template: "
          f"{1000 * _timed(lambda: pickle.loads(pickled), reps):.2f} ms")
    empty = CuttingSheet(None, None, "", "R2010")
    c0 = time.process_time()
    for k in range(reps):
        empty.write(tmp / "empty.dxf")
    print(f"  saving an empty document: {1000 * (time.process_time() - c0) / reps:.2f} ms")

    plates = list(b.beams.plates)
    for check in (True, False):
        c0 = time.process_time()
        export_step(beam_assembly(plates, build_solids(plates, check=check), "bench"), tmp / "beams.step")
        dt = time.process_time() - c0
        print(f"STEP through the kernel, {len(plates)} plates ({'with' if check else 'without'} the writer's "
              f"BRepCheck): {1000 * dt / len(plates):.2f} ms per plate")
    from fabrication.writers.step import beam_tree
    from fabrication.writers.step_template import write_step

    c0 = time.process_time()
    write_step(beam_tree(plates, "bench"), tmp / "beams_template.step")
    print(f"STEP from the template (the build's writer), {len(plates)} plates: "
          f"{1000 * (time.process_time() - c0) / len(plates):.2f} ms per plate")
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakePolygon
    from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism
    from OCP.gp import gp_Pnt, gp_Vec
    from OCP.Interface import Interface_Static
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer
    from OCP.TopoDS import TopoDS_Compound

    c0 = time.process_time()
    Interface_Static.SetIVal_s("write.surfacecurve.mode", 0)        # no p-curves, as ppfab writes
    compound, builder = TopoDS_Compound(), BRep_Builder()
    builder.MakeCompound(compound)
    for p in plates:
        poly = BRepBuilderAPI_MakePolygon()
        for x, y, z in p.frame.to3d(p.outline):
            poly.Add(gp_Pnt(float(x), float(y), float(z)))
        poly.Close()
        face = BRepBuilderAPI_MakeFace(poly.Wire(), True).Face()
        builder.Add(compound, BRepPrimAPI_MakePrism(face, gp_Vec(*map(float, p.frame.normal * p.thickness))).Shape())
    w = STEPControl_Writer()
    w.Transfer(compound, STEPControl_AsIs)
    w.Write(str(tmp / "kernel.step"))
    print(f"STEP kernel baseline (OCP: polygon, face, prism of each plate, one compound, no p-curves, names, "
          f"colours or tree): {1000 * (time.process_time() - c0) / len(plates):.2f} ms per plate")


def _command(size: str, budget: float, parallel: bool, design: str | None, root: Path,
             floor: bool = False, paper: str | None = None) -> list[str]:
    cmd = [sys.executable, str(root / "benchmarks" / "pipeline.py"), "--child", size, "--budget", str(budget)]
    if parallel:
        cmd.append("--parallel")
    if floor and root == ROOT:                  # a baseline tree's benchmark may not know --floor
        cmd.append("--floor")
    if design:
        cmd += ["--design", design]
    if paper:
        cmd += ["--paper", paper]
    return cmd


def run_all(tasks: list[tuple[str, str, bool, Path]], budget: float, design: str | None, jobs: int,
            save: Path | None = None, out: dict | None = None, floor: bool = False, paper: str | None = None) -> dict:
    """Run ``(variant, size, parallel, source tree)`` tasks, ``jobs`` at a time (largest first); variant →
    size → result (added to ``out``, and written to ``save`` after each build)."""
    pending = sorted(tasks, key=lambda t: -int(t[1].split("x")[0]) * int(t[1].split("x")[1]))
    running: list[tuple[tuple, subprocess.Popen]] = []
    out = {} if out is None else out
    while pending or running:
        while pending and len(running) < jobs:
            task = pending.pop(0)
            variant, size, parallel, root = task
            env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONPATH=str(root))
            running.append((task, subprocess.Popen(_command(size, budget, parallel, design, root, floor, paper), env=env,
                                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)))
        time.sleep(1.0)
        for item in [r for r in running if r[1].poll() is not None]:
            running.remove(item)
            (variant, size, _, _), proc = item
            stdout, stderr = proc.communicate()
            line = next((x for x in stdout.splitlines() if x.startswith("RESULT ")), None)
            if line is None:
                print(f"  {variant} {size} failed: {stderr.strip().splitlines()[-1] if stderr.strip() else proc.returncode}")
                continue
            r = json.loads(line[len("RESULT "):])
            out.setdefault(variant, {})[size] = r
            if save is not None:
                save.write_text(json.dumps(out, indent=1))
            print(f"  {variant} {size}: total {r['stages']['total'][1]:.1f} CPU s, files "
                  f"{r['stages']['files'][1]:.1f} CPU s", flush=True)
    return out


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
    mem = "".join(f"{r['peak_mb']:>13.0f} MB{r['child_peak_mb']:>6.0f}" for r in results)
    print(f"{'peak RSS':<10}{mem}   (build process; forked processes, with the pages they share with it)")
    tree = "".join(f"{r.get('tree_pss_mb', float('nan')):>19.0f} MB" for r in results)
    print(f"{'peak PSS':<10}{tree}   (the build and every process below it, summed; tree_memory.py)")
    print(f"\n-- {label}: writers inside the files stage, seconds wall / CPU (CPU of this process only when "
          "parallel) --")
    for w in results[-1]["writers"]:
        cells = "".join(f"{r['writers'].get(w, [0, 0])[0]:>11.2f}{r['writers'].get(w, [0, 0])[1]:>11.2f}"
                        for r in results)
        c = [max(r["writers"].get(w, [0, 0])[1], 1e-3) for r in results]
        print(f"{w:<10}{cells}{'':>9}{exponent(faces, c):>9.2f}")
    print("counts    " + "".join(f"{str(r['panels']) + ' pan ' + str(r['plates']) + ' pl':>22}" for r in results))
    floors = [r for r in results if r.get("floor")]
    if floors:
        print(f"\n-- {label}: the build against the CAD kernel's plain write + read of its STEP files "
              "(step_floor.py, same process, after the build), CPU s --")
        print(f"{'size':<10}{'build':>10}{'floor':>10}{'build/floor':>13}{'verify':>10}{'verify %':>10}"
              f"{'peak RSS':>10}{'peak PSS':>10}")
        for r in floors:
            fl = sum(x["read"] + x["write"] for x in r["floor"])
            tot, ver = r["stages"]["total"][1], r["stages"]["verify"][1]
            print(f"{r['size']:<10}{tot:>10.1f}{fl:>10.1f}{tot / fl:>13.2f}{ver:>10.1f}{100 * ver / tot:>9.1f}%"
                  f"{r['peak_mb']:>10.0f}{r.get('tree_pss_mb', float('nan')):>10.0f}")


def main(argv: list[str]) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="22x15,44x30,66x45,88x60")
    ap.add_argument("--budget", type=float, default=0.5, help="both nesting budgets, s (same at every size)")
    ap.add_argument("--writers", choices=("serial", "parallel", "both", "none"), default="both",
                    help="the variants of this tree (none: only --baseline)")
    ap.add_argument("--design", default=None)
    ap.add_argument("--baseline", default=None, metavar="TREE",
                    help="also build every size with the source tree TREE (serial): the 'before' columns")
    ap.add_argument("--save", default=None, metavar="JSON", help="write every result to JSON")
    ap.add_argument("--reuse", default=None, metavar="JSON",
                    help="results of an earlier --save (same machine and load): only the builds missing there run")
    ap.add_argument("--jobs", type=int, default=1, help="builds run at the same time (CPU times are per build)")
    ap.add_argument("--per-file", default=None, metavar="SIZE",
                    help="only the ms per per-type DXF and per STEP plate at SIZE (e.g. 22x15)")
    ap.add_argument("--floor", action="store_true",
                    help="after each build, the CAD kernel's plain write + read of its STEP files (step_floor.py)")
    ap.add_argument("--paper", default=None,
                    help="[output] paper of every build (A1, the default's, has no room for the key plan's list of "
                         "ids at 88x60: A0)")
    ap.add_argument("--child", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--parallel", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.per_file:
        _per_file(args.per_file, args.budget)
        return
    if args.child:
        _child(args.child, args.budget, args.parallel, args.design, args.floor, args.paper)
        return
    base = Path(args.baseline).resolve() if args.baseline else None
    print(f"ppfab build of {'the bundled default' if not args.design else args.design}; both nesting budgets "
          f"{args.budget:g} s at every size; OMP_NUM_THREADS=1; {os.cpu_count()} cores; one subprocess per size "
          f"and variant, {args.jobs} at a time" + (f"; before = the tree {base}" if base else "")
          + (f"; paper {args.paper}" if args.paper else ""))
    sizes = args.sizes.split(",")
    modes = {"serial": [False], "parallel": [True], "both": [False, True], "none": []}[args.writers]
    tasks = [(("parallel" if m else "serial"), size, m, ROOT) for size in sizes for m in modes]
    if base is not None:               # the tree before, writing as the tree after is compared (table below)
        tasks += [("before", size, True in modes, base) for size in sizes]
    results: dict = json.loads(Path(args.reuse).read_text()) if args.reuse else {}
    tasks = [t for t in tasks if t[1] not in results.get(t[0], {})]
    run_all(tasks, args.budget, args.design, args.jobs, Path(args.save) if args.save else None, results,
            args.floor, args.paper)
    for variant in (["before"] if base else []) + [("parallel" if m else "serial") for m in modes]:
        if all(s in results.get(variant, {}) for s in sizes):
            table([results[variant][s] for s in sizes], variant)
    if base is not None and all(s in results.get(v, {}) for s in sizes
                                for v in ("before", "parallel" if True in modes else "serial")):
        after = "parallel" if True in modes else "serial"
        print(f"\n== CPU seconds, before → {after} (ratio after/before) ==")
        stages = list(results[after][sizes[-1]]["stages"])
        print(f"{'stage':<10}" + "".join(f"{s:>26}" for s in sizes))
        for st in stages:
            cells = ""
            for s in sizes:
                b, a = results["before"][s]["stages"].get(st, [0, 0])[1], results[after][s]["stages"].get(st, [0, 0])[1]
                cells += f"{b:>10.1f} → {a:>7.1f} ({a / b if b else float('nan'):>4.2f})"
            print(f"{st:<10}{cells}")


if __name__ == "__main__":
    main(sys.argv[1:])
