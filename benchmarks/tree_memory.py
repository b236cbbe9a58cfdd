"""The peak memory of a process and its descendants together, sampled from outside (Linux).

    python benchmarks/tree_memory.py PID [--every 0.5]

Every ``--every`` seconds it adds up the proportional set size (``Pss`` of ``/proc/<pid>/smaps_rollup``) of the
process ``PID`` and of every process below it (not itself), and on SIGTERM or SIGINT (or when ``PID`` has ended)
prints one line ``TREE_PSS_PEAK_MB <peak> <samples>`` and exits.

Why PSS: a forked process starts with its parent's pages and shares them until either writes; its resident
set (and its ``ru_maxrss``) counts every shared page again, so the peak of a parent plus the peak of its
forked writer or checker over-states what the machine held.  PSS charges a page shared by n processes 1/n to
each, so the sum over the tree is the memory the tree holds.  Sampling can miss a peak shorter than the
interval; the build's own ``ru_maxrss`` is printed beside it.

Run by :mod:`pipeline` as its own process, so its reads are not counted in the build's CPU time.
"""

from __future__ import annotations

import os
import signal
import sys
import time


def descendants(root: int) -> list[int]:
    """``root`` and every process below it (from the parent ids in ``/proc/*/stat``)."""
    parent: dict[int, int] = {}
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat", "rb") as fh:
                stat = fh.read()
        except OSError:
            continue
        fields = stat[stat.rindex(b")") + 2:].split()          # after the command name, which may hold spaces
        parent[int(name)] = int(fields[1])
    tree, todo = [], [root]
    while todo:
        pid = todo.pop()
        tree.append(pid)
        todo.extend(p for p, pp in parent.items() if pp == pid)
    return tree


def pss_kb(pid: int) -> int:
    """The proportional set size of ``pid`` in kB (0 when it has ended)."""
    try:
        with open(f"/proc/{pid}/smaps_rollup") as fh:
            for line in fh:
                if line.startswith("Pss:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


def main() -> None:
    root = int(sys.argv[1])
    every = float(sys.argv[sys.argv.index("--every") + 1]) if "--every" in sys.argv else 0.5
    me = os.getpid()
    peak, samples, stop = 0, 0, False

    def finish(*_: object) -> None:
        nonlocal stop
        stop = True

    signal.signal(signal.SIGTERM, finish)
    signal.signal(signal.SIGINT, finish)
    while not stop and os.path.exists(f"/proc/{root}"):
        total = sum(pss_kb(p) for p in descendants(root) if p != me)
        peak, samples = max(peak, total), samples + 1
        time.sleep(every)
    print(f"TREE_PSS_PEAK_MB {peak / 1024:.0f} {samples}", flush=True)


if __name__ == "__main__":
    main()
