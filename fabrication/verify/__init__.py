"""``ppfab verify OUT``: re-read a build's files and check them against each other and the output contract.

Each check is one module of this package registered with :func:`check` (an ``order`` says which runs
first: later checks use what earlier ones read into :attr:`Verification.data`); each appends
:class:`Finding` records (file, element, message); a folder passes when there is none.  The checks
re-read files with the real readers: JSON, CSV, the OBJ reader of :mod:`ppfab.io`, ezdxf (with its auditor)
for DXF; STEP with a text-level reader of its own and the CAD kernel on the product tree and one solid of each
kind (every solid with ``kernel``, :mod:`._step_read`).  Adding a check is one new module.
"""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable

from ppfab.finding import Finding
from ppfab.registry import Registry


@dataclass
class Verification:
    """The findings of a verification, what was checked, and the files read so far (``data``); ``kernel``: the
    CAD kernel reads every STEP solid (else a text-level reader, :mod:`._step_read`)."""

    folder: Path
    kernel: bool = False
    findings: list[Finding] = field(default_factory=list)
    checked: list[str] = field(default_factory=list)
    data: dict[str, Any] = field(default_factory=dict)

    def error(self, file: str, element: str, message: str, value: float | None = None,
              limit: float | None = None, code: str = "") -> None:
        """A :class:`~ppfab.finding.Finding` of this verification (``code``: the check's name when omitted)."""
        self.findings.append(Finding(code, file, element, value, limit, message))

    @property
    def ok(self) -> bool:
        return not self.findings

    def read_table(self, rel: str, columns: list[str] | tuple[str, ...] = ()) -> list[dict[str, str]] | None:
        """The rows of the CSV table ``rel``, or ``None`` after a finding that it cannot be read or lacks one of
        ``columns`` (the contract's)."""
        try:
            rows = read_csv(self.folder / rel)
        except (OSError, UnicodeDecodeError, ValueError) as exc:
            self.error(rel, "", f"cannot be read ({exc})")
            return None
        missing = [c for c in columns if rows and c not in rows[0]]
        if missing:
            self.error(rel, "columns", f"missing contract columns {missing}")
            return None
        return rows

    def read_json(self, rel: str) -> Any:
        """The JSON document ``rel`` of the folder, or ``None`` after a finding that it cannot be read."""
        try:
            return json.loads((self.folder / rel).read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            self.error(rel, "", f"cannot be read ({exc})")
            return None


def read_csv(path: Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


@dataclass(frozen=True)
class Check:
    name: str
    order: int
    run: Callable[[Verification], None]


_TABLE: Registry[Check] = Registry("check", "fabrication.verify")
CHECKS: dict[str, Check] = _TABLE.entries


def check(name: str, order: int) -> Callable[[Callable[[Verification], None]], Callable[[Verification], None]]:
    """Decorator registering ``run(verification)`` as the check ``name``."""
    def register(fn: Callable[[Verification], None]) -> Callable[[Verification], None]:
        _TABLE.add(name, Check(name, order, fn))
        return fn
    return register


def load_checks() -> list[Check]:
    """Import every check module of this package (once); the checks in order."""
    return sorted(_TABLE.load().values(), key=lambda c: (c.order, c.name))


SECOND_PROCESS: tuple[str, ...] = ("splices", "glass_order", "bite", "glazing_step", "ifc")
"""Checks that read only what the checks up to :data:`FORK_AFTER` put into :attr:`Verification.data` (the
manifest, the mesh, the parts list, the nodes, the cutting-sheet outlines and the per-type DXFs as read) and put
nothing there that another check reads: on two cores they run in a forked process beside the others.  Chosen
by the CPU seconds of each check on the bundled default (one process, docs/performance.md): at 44 × 30 faces
the fork gets bite 21, ifc 11, splices 6 and glass order 1 (it no longer reads the per-type DXFs: the types
check did) against step 16, panels_step 6, step_geometry 4, rhino and glb 2 each after it here; at 88 × 60
the bite check alone (glazing.step, 21,416 solids) is about a quarter of the whole.  The glazing_step check
reads glazing.step too, and runs beside the bite check so that the file is read once."""

FORK_AFTER = "types"
"""The second process starts once this check (and every check before it) has run in this one: after the
per-type DXFs are read, so the glass order check finds them in ``data["type_dxf"]``."""


def verify(folder: str | Path, parallel: bool | None = None, kernel: bool = False,
           progress: Callable[[int, int, str], None] | None = None) -> Verification:
    """Run every check on an output folder (stopping after the manifest if it cannot be read).

    ``parallel`` (default: on with two cores and fork, :func:`fabrication.writers._parallel.parallel_enabled`)
    runs the checks of :data:`SECOND_PROCESS` in a forked process once :data:`FORK_AFTER` has run; the
    findings and the list of checks are assembled in check order, so the result equals a serial run.  When the
    second process fails (a check raising, the process dying), its checks run again here, so an error is the
    check's own.  ``kernel``: the CAD kernel reads every solid of the STEP files (:attr:`Verification.kernel`).
    ``progress(done, total, what)`` is called as checks finish here (``what``: the check just run, or what is
    being waited for), so a long verify shows its count and time left."""
    v = Verification(Path(folder), kernel=kernel)
    if not v.folder.is_dir():
        v.error(str(folder), "", "is not a folder")
        return v
    from ..writers._parallel import Forked, parallel_enabled

    checks = load_checks()
    if parallel is None:
        parallel = parallel_enabled()
    second = [c for c in checks if parallel and c.name in SECOND_PROCESS]
    first = [c for c in checks if c not in second]
    done: dict[str, tuple[list[Finding], list[str]]] = {}
    child = None
    report = progress or (lambda done_, total_, what_: None)
    try:
        for c in first:
            _run_one(v, c, done)
            report(len(done), len(checks), c.name)
            if not v.data.get("manifest"):
                return v
            if c.name == FORK_AFTER and second:
                try:
                    child = Forked(lambda: _run_all(v, second), "ppfab-verify")
                except OSError:                 # no process to be had: the checks run here
                    child = None
        if child is not None:
            report(len(done), len(checks), f"waiting for {len(second)} checks in a second process")
        outcome: tuple[str, Any] = child.result() if child is not None else ("failed", "no second process")
    finally:
        if child is not None:
            child.close()
    if second:
        if outcome[0] != "ok":                  # no second process, or it failed: run its checks here
            for c in second:
                _run_one(v, c, done)
                report(len(done), len(checks), c.name)
        else:
            done.update(outcome[1])
    v.findings = [f for c in checks if c.name in done for f in done[c.name][0]]
    v.checked = [n for c in checks if c.name in done for n in done[c.name][1]]
    return v


def _run_all(v: Verification, checks: list[Check]) -> dict[str, tuple[list[Finding], list[str]]]:
    """The second process's work: ``checks`` run on its copy of ``v``; what each found and checked."""
    done: dict[str, tuple[list[Finding], list[str]]] = {}
    for c in checks:
        _run_one(v, c, done)
    return done


def _run_one(v: Verification, c: Check, done: dict[str, tuple[list[Finding], list[str]]]) -> None:
    """Run one check and keep what it found and what it says it checked."""
    nf, nc = len(v.findings), len(v.checked)
    c.run(v)
    v.findings[nf:] = [f if f.code else replace(f, code=c.name) for f in v.findings[nf:]]
    done[c.name] = (v.findings[nf:], v.checked[nc:])
