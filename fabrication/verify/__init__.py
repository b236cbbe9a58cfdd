"""``ppfab verify OUT``: re-read a build's files and check them against each other and the output contract.

Each check is one module of this package registered with :func:`check` (an ``order`` says which runs
first: later checks use what earlier ones read into :attr:`Verification.data`); each appends
:class:`Finding` records (file, element, message); a folder passes when there is none.  The checks
re-read files with the real readers: JSON, CSV, the OBJ reader of :mod:`ppfab.io`, ezdxf (with its auditor)
for DXF and the CAD kernel for STEP.  Adding a check is one new module.
"""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from ppfab.registry import Registry


@dataclass(frozen=True)
class Finding:
    file: str
    element: str
    message: str

    def __str__(self) -> str:
        return f"{self.file}: {self.element}: {self.message}" if self.element else f"{self.file}: {self.message}"


@dataclass
class Verification:
    """The findings of a verification, what was checked, and the files read so far (``data``)."""

    folder: Path
    findings: list[Finding] = field(default_factory=list)
    checked: list[str] = field(default_factory=list)
    data: dict[str, Any] = field(default_factory=dict)

    def error(self, file: str, element: str, message: str) -> None:
        self.findings.append(Finding(file, element, message))

    @property
    def ok(self) -> bool:
        return not self.findings

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


def verify(folder: str | Path) -> Verification:
    """Run every check on an output folder (stopping after the manifest if it cannot be read)."""
    v = Verification(Path(folder))
    if not v.folder.is_dir():
        v.error(str(folder), "", "is not a folder")
        return v
    for c in load_checks():
        c.run(v)
        if not v.data.get("manifest"):
            break
    return v
