"""Compare two sets of build folders file by file (sha256): which examples are byte-identical.

    python benchmarks/compare_builds.py BEFORE AFTER

BEFORE and AFTER each hold one output folder per example (as written by ``ppfab build EXAMPLE -o
BEFORE/NAME``).  Prints one line per example: the number of files and either ``identical`` or the files that
differ.  Used to show that a refactoring changed no output (docs/architecture.md).
"""

from __future__ import annotations

import hashlib
import sys
from pathlib import Path


def tree(folder: Path) -> dict[str, str]:
    """Relative path → sha256 of every file below ``folder``."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def main(argv: list[str]) -> int:
    before, after = Path(argv[0]), Path(argv[1])
    differing = 0
    for folder in sorted(p for p in before.iterdir() if p.is_dir()):
        other = after / folder.name
        if not other.is_dir():
            print(f"{folder.name}: missing in {after}")
            differing += 1
            continue
        a, b = tree(folder), tree(other)
        diff = sorted(k for k in set(a) | set(b) if a.get(k) != b.get(k))
        differing += bool(diff)
        print(f"{folder.name}: {len(a)} files, " + ("identical" if not diff else "differ: " + ", ".join(diff[:10])))
    return 1 if differing else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
