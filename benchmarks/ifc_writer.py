"""The IFC writer as ppfab writes it (text, ``IfcText``) beside the same writer filling IfcOpenShell's file.

Builds the bundled default at ``SIZE`` faces (both nesting budgets 0.5 s) once, then writes ``model.ifc`` with each
maker, each in a forked process of its own (so neither inherits the other's memory), one after the other, and
prints per maker the CPU seconds of the writer (model and analysis model made, file written), the peak resident
memory of its process above what it started with (the build's pages it inherited), and whether the two files are the same bytes (exit status 1 if not).

    OMP_NUM_THREADS=1 python benchmarks/ifc_writer.py 44x30
    OMP_NUM_THREADS=1 python benchmarks/ifc_writer.py 22x15 --repeat 3

Measured (docs/performance.md, "model.ifc written as text"): 44 x 30, 26.6 CPU s and +375 MB through IfcOpenShell,
9.3 CPU s and +146 MB as text, the same bytes.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))


def _resident_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    return float("nan")


def _build(size: str):
    from _sized import sized_design

    from fabrication import build

    return build(sized_design(size, 0.5), allow_large=True)


def _write_in_child(b, files, maker_name: str, path: Path) -> tuple[float, float, float]:
    """Write ``path`` with the maker ``maker_name`` in a forked process: its CPU s, its peak resident MB and its
    resident MB when it started (the pages of the build it inherited)."""
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:                                         # the child: write, report, exit without unwinding
        os.close(read)
        try:
            import ifcopenshell

            from fabrication.writers._ifc_text import IfcText
            from fabrication.writers.ifc import ifc_model
            from fabrication.writers.ifc_analysis import add_analysis_model

            maker = IfcText if maker_name == "text" else ifcopenshell.file
            start = _resident_mb()                   # the build's pages, as the child inherits them
            t = time.process_time()
            model = ifc_model(b, files, maker)
            add_analysis_model(model, b)
            model.write(path)
            cpu = time.process_time() - t
            peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
            os.write(write, f"{cpu} {peak} {start}".encode())
        finally:
            os._exit(0)
    os.close(write)
    with os.fdopen(read) as pipe:
        text = pipe.read()
    os.waitpid(pid, 0)
    cpu, peak, start = (float(x) for x in text.split())
    return cpu, peak, start


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("size", help="faces_u x faces_v of the bundled default, e.g. 44x30")
    ap.add_argument("--repeat", type=int, default=1, help="rounds of the two writers, alternating")
    args = ap.parse_args(argv)
    from fabrication.writers import dxf

    from ppfab.errors import PpfabError

    try:
        b = _build(args.size)
    except (PpfabError, ValueError) as exc:
        print(f"ifc_writer: the default at {args.size} does not build: {str(exc).splitlines()[0][:300]}",
              file=sys.stderr)
        return 2
    files = dxf.dxf_files(b)
    with tempfile.TemporaryDirectory() as tmp:
        digest: dict[str, str] = {}                      # digests only: bytes kept here would count in the children
        print(f"model.ifc of the default at {args.size}")
        for round_ in range(args.repeat):
            for name in ("ifcopenshell", "text"):
                path = Path(tmp) / f"{name}.ifc"
                cpu, peak, start = _write_in_child(b, files, name, path)
                digest[name] = hashlib.sha256(path.read_bytes()).hexdigest()
                print(f"  round {round_ + 1}  {name:<13} {cpu:7.2f} CPU s   peak {peak:7.0f} MB, "
                      f"+{peak - start:.0f} above the {start:.0f} MB it started with   "
                      f"{path.stat().st_size / 1e6:.1f} MB written", flush=True)
        same = digest["text"] == digest["ifcopenshell"]
        print("the same bytes" if same else "THE FILES DIFFER")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
