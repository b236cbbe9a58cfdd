"""model.3dm with repeated shapes as blocks against one body per part, side by side in one process.

The design (the bundled default, or a design file) is built once; then ``model.3dm`` is written ``--repeat``
times each way (best CPU seconds): as written now (a block per repeated shape, an instance per part) and with
no part counted as repeated (every part its own extrusion or mesh: the file before blocks).  Reported: CPU
seconds of the writer, file size, objects in the file (block bodies included), blocks, and the CPU seconds of
reading each file back with rhino3dm and placing every instance (:func:`fabrication.verify.rhino.placed_objects`).

    OMP_NUM_THREADS=1 python benchmarks/rhino_blocks.py [design.toml] [--faces 44x30] [--repeat 3]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path
from unittest import mock


def best_cpu(fn, repeat: int) -> tuple[float, object]:
    """Best CPU seconds of ``fn()`` over ``repeat`` runs, and its last result."""
    best, out = float("inf"), None
    for _ in range(repeat):
        c = time.process_time()
        out = fn()
        best = min(best, time.process_time() - c)
    return best, out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("design", nargs="?", default=None)
    ap.add_argument("--faces", default=None, help="faces_u x faces_v of the default's [geometry.params], e.g. 44x30")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)

    import tomllib

    import rhino3dm

    import fabrication
    from fabrication import parse_design
    from fabrication.design import DEFAULT_DESIGN
    from fabrication.verify.rhino import placed_objects
    from fabrication.writers import _instances, rhino
    from fabrication.writers._elements import elements

    path = Path(args.design) if args.design else DEFAULT_DESIGN
    doc = tomllib.loads(path.read_text(encoding="utf-8"))
    if args.faces:
        u, v = (int(x) for x in args.faces.lower().split("x"))
        doc["geometry"].setdefault("params", {}).update(faces_u=u, faces_v=v)
    for section in ("nesting", "beam_nesting"):
        doc.setdefault(section, {})["time_budget"] = 0.5
    build = fabrication.build(parse_design(doc, str(path), base_dir=path.parent), allow_large=True)
    empty = _instances.TypePlan({}, {}, {}, {})
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for label, patch in (("blocks (now)", None), ("one body per part", empty)):
            ctx = mock.patch.object(rhino, "plan_types", lambda els, *a, **k: patch) if patch else mock.MagicMock()
            with ctx:
                write, data = best_cpu(lambda: rhino.rhino_model(build, {}).to_bytes(), args.repeat)
            assert isinstance(data, bytes)
            written = Path(tmp) / f"{len(rows)}.3dm"
            written.write_bytes(data)

            def read(written: Path = written):
                f = rhino3dm.File3dm.Read(str(written))
                objects, problems = placed_objects(f)
                assert not problems, problems[:3]
                return f, objects
            read_s, (f, objects) = best_cpu(read, args.repeat)
            rows.append((label, write, len(data) / 1e6, len(f.Objects), len(f.InstanceDefinitions), len(objects),
                         read_s))
    parts = len(elements(build))
    print(f"{path.name}{' at ' + args.faces if args.faces else ''}: {parts:,} parts, best of {args.repeat}")
    print("| model.3dm | write CPU s | MB | objects in the file | blocks | parts + axes + mesh "
          "| read and place CPU s |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for label, write, mb, objs, blocks, placed, read_s in rows:
        print(f"| {label} | {write:.2f} | {mb:.1f} | {objs:,} | {blocks:,} | {placed:,} | {read_s:.2f} |")


if __name__ == "__main__":
    main()
