"""The memory and CPU of verify's read of one STEP file of a built folder: ``read_or_report`` (the text-level
reader, then the CAD kernel on the file's product tree with one solid of each kind) in a fresh process, as the
first check reading it does.  Printed per tree: CPU seconds of the read, the process's resident size before it
(the libraries loaded), at its peak, and after it with the solids kept (a collection run first), MB.

With ``--baseline TREE`` the same read runs with the source tree ``TREE`` too (e.g. ``git worktree add TREE
<commit>``), the two one after the other, ``--repeat`` times each, alternating: side by side in one run.

    OMP_NUM_THREADS=1 python benchmarks/step_read_memory.py FOLDER [--file glazing.step] [--baseline TREE]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_CHILD = r"""
import gc, json, resource, sys, time
from pathlib import Path

def rss():
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS"):
                return int(line.split()[1]) // 1024
    return -1

import build123d  # noqa: F401 - the libraries a verify has loaded before its first STEP read
from fabrication.verify import Verification
from fabrication.verify._step_read import read_or_report

gc.collect()
before = rss()
v = Verification(Path(sys.argv[1]))
t = time.process_time()
got = read_or_report(v, sys.argv[2])
cpu = time.process_time() - t
gc.collect()
print(json.dumps({"cpu": cpu, "before": before, "after": rss(),
                  "peak": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024,
                  "solids": len(got or []), "findings": len(v.findings)}))
"""


def measure(tree: Path, folder: Path, name: str) -> dict:
    """One read in a fresh process importing ppfab from ``tree``."""
    env = dict(os.environ, PYTHONPATH=str(tree), OMP_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", _CHILD, str(folder), name], env=env, cwd=tree,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", type=Path)
    ap.add_argument("--file", default="glazing.step")
    ap.add_argument("--baseline", type=Path, default=None, metavar="TREE")
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args()
    trees = [("now", ROOT)] + ([("before", args.baseline.resolve())] if args.baseline else [])
    print(f"{args.file} of {args.folder}: read_or_report in a fresh process; CPU s, resident MB")
    print(f"{'tree':<8} {'CPU s':>7} {'before':>7} {'peak':>7} {'kept':>7} {'solids':>7} {'findings':>8}")
    for _ in range(args.repeat):
        for label, tree in reversed(trees):
            r = measure(tree, args.folder.resolve(), args.file)
            print(f"{label:<8} {r['cpu']:7.1f} {r['before']:7d} {r['peak']:7d} {r['after'] - r['before']:7d} "
                  f"{r['solids']:7d} {r['findings']:8d}", flush=True)


if __name__ == "__main__":
    main()
