"""``ppfab verify OUT``: re-read a build's files and check them against each other and the output contract.

Each check is one module of this package registered with :func:`check`; each appends
:class:`~ppfab.finding.Finding` records (file, element, value, limit, message); a folder passes when there is
none.  What a check reads that another check also needs (the manifest as checked, the mesh, the parts and
node rows, the cutting-sheet outlines, the STEP solids, …) is a typed field of :class:`FolderData`, filled
by the one check that reads that file (:data:`PRODUCERS`); a check asks for it through the
:class:`Verification` property of the same name, which runs the producing check first when it has not run
yet — so no check depends on another having run before it, and each may run in either process
(:data:`REPORT_ORDER` is only the order findings are shown in).  The checks re-read files with the real
readers: JSON, CSV, the OBJ reader of :mod:`ppfab.io`, ezdxf (with its auditor) for DXF; STEP with a
text-level reader of its own and the CAD kernel on the product tree and one solid of each kind (every solid
with ``kernel``, :mod:`._step_read`).  Adding a check is one new module.
"""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, TypeVar

from ppfab.finding import Finding
from ppfab.registry import Registry

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np

    from ppfab.mesh import QuadMesh

    from ..writers.dxf import DXFContent
    from ._step_read import StepSolid
    from .erection import Pass


@dataclass
class FolderData:
    """What the checks of one verification read from the folder and share, each field filled by the check
    :data:`PRODUCERS` names (``None``: that check has not read it, or could not).

    ``manifest``: ``manifest.json`` as checked (``files``, ``mesh`` and ``fabrication`` cleaned: every value of
    the type the contract gives); ``mesh``: ``mesh.obj``; ``parts``: the rows of ``parts.csv`` whose cells the
    parts check could read (``parts_csv_rows``: every row as written); ``nodes``: the readable rows of
    ``nodes.csv``; ``cut``: part id → (sheet file, outline ``(k, 2)`` in sheet mm) of every part on a cutting
    sheet (``dxf_outlines`` the same outlines by part id alone); ``dxf_texts`` / ``dxf_marks`` / ``dxf_trim``:
    per sheet file its texts, reference-mark lines and TRIM outline; ``type_outlines``: panel type id → the
    outline of its per-type DXF; ``dxf``: DXF file → its content as ezdxf read it, or the exception reading it
    raised (:mod:`._dxf_read`: one read per file and process); ``beam_solids``: part id → the solid of ``beams.step``; ``plate_outlines`` /
    ``plate_cut_outlines``: part id → a beam plate's flat outline from its solid (the face, and the union of
    its faces as cut from the sheet); ``step_read``: (file, colours) → the solids read (one read per file and
    process); ``erection_passes``: the sweep of every part along its way in (:mod:`.erection`); ``strip_places``:
    part id → the corners ``(8, 3)`` of a strip's box for either outside, recomputed from the structure
    (:func:`.glazing_step.strip_places`, no file of solids read); ``tables``: CSV file → its rows, read once
(:meth:`Verification.table`); ``parts_by_id``: part id → its readable ``parts.csv`` row
(:meth:`Verification.part_row`); ``seat``: where a pane's underside may lie (:func:`._solids.seat_range`)."""

    manifest: dict[str, Any] | None = None
    mesh: "QuadMesh | None" = None
    parts: list[dict[str, str]] | None = None
    parts_csv_rows: list[dict[str, str]] | None = None
    nodes: list[dict[str, str]] | None = None
    cut: dict[str, tuple[str, "np.ndarray"]] = field(default_factory=dict)
    dxf_outlines: dict[str, "np.ndarray"] = field(default_factory=dict)
    dxf_texts: dict[str, list[Any]] = field(default_factory=dict)
    dxf_marks: dict[str, list[Any]] = field(default_factory=dict)
    dxf_trim: dict[str, Any] = field(default_factory=dict)
    type_outlines: dict[str, "np.ndarray"] = field(default_factory=dict)
    dxf: dict[str, "DXFContent | Exception"] = field(default_factory=dict)
    beam_solids: dict[str, Any] | None = None
    plate_outlines: dict[str, "np.ndarray"] = field(default_factory=dict)
    plate_cut_outlines: dict[str, "np.ndarray"] = field(default_factory=dict)
    step_read: dict[tuple[str, bool], "list[StepSolid] | None"] = field(default_factory=dict)
    erection_passes: list["Pass"] | None = None
    strip_places: dict[str, list["np.ndarray"]] | None = None
    tables: dict[str, list[dict[str, str]]] = field(default_factory=dict)
    parts_by_id: dict[str, dict[str, str]] | None = None
    seat: tuple[float, float] | None = None


PRODUCERS: dict[str, str] = {
    "manifest": "manifest", "mesh": "mesh", "parts": "parts", "parts_csv_rows": "parts", "nodes": "nodes",
    "cut": "dxf", "dxf_outlines": "dxf", "dxf_texts": "dxf", "dxf_marks": "dxf", "dxf_trim": "dxf",
    "type_outlines": "types", "beam_solids": "step", "plate_outlines": "step_geometry",
    "plate_cut_outlines": "step_geometry", "erection_passes": "erection"}
"""Field of :class:`FolderData` → the check that fills it (``dxf`` and ``step_read`` are memos that any
check fills as it reads)."""


@dataclass
class Verification:
    """The findings of a verification, what was checked, and what was read (:attr:`read`); ``kernel``: the
    CAD kernel reads every STEP solid (else a text-level reader, :mod:`._step_read`) and ifcopenshell validates
    every instance of ``model.ifc`` against the schema (else a sample, :func:`.ifc.schema_sample`).

    The properties named like the fields of :class:`FolderData` return that field after its producing check
    has run (here, at the first call, when the check has not run yet: its findings are kept and reported when
    the check's own turn comes, so they are reported once and under its name)."""

    folder: Path
    kernel: bool = False
    findings: list[Finding] = field(default_factory=list)
    checked: list[str] = field(default_factory=list)
    read: FolderData = field(default_factory=FolderData)
    _found: dict[str, tuple[list[Finding], list[str]]] = field(default_factory=dict, repr=False)
    _running: set[str] = field(default_factory=set, repr=False)

    def error(self, file: str, element: str, message: str, value: float | None = None,
              limit: float | None = None, code: str = "") -> None:
        """A :class:`~ppfab.finding.Finding` of this verification (``code``: the check's name when omitted)."""
        self.findings.append(Finding(code, file, element, value, limit, message))

    @property
    def ok(self) -> bool:
        return not self.findings

    def after(self, name: str) -> FolderData:
        """:attr:`read` once the check ``name`` has run in this process (run now when it has not: what it finds
        is kept for its own turn, :meth:`run_check`)."""
        if name not in self._found and name not in self._running:
            c = load_table().get(name)
            if c is not None:
                found, checked = self.findings, self.checked
                self.findings, self.checked = [], []
                self._running.add(name)
                try:
                    c.run(self)
                    self._found[name] = (self._coded(self.findings, name), self.checked)
                finally:
                    self._running.discard(name)
                    self.findings, self.checked = found, checked
        return self.read

    def run_check(self, c: "Check") -> tuple[list[Finding], list[str]]:
        """Run the check ``c`` (or take what it found when another check had it run first): its findings, each
        under its name, and what it says it checked."""
        if c.name not in self._found:
            nf, nc = len(self.findings), len(self.checked)
            self._running.add(c.name)
            try:
                c.run(self)
            finally:
                self._running.discard(c.name)
            got = (self._coded(self.findings[nf:], c.name), self.checked[nc:])
            del self.findings[nf:], self.checked[nc:]
            self._found[c.name] = got
        return self._found[c.name]

    def release_solids(self) -> None:
        """Let go of the solids read from the STEP files (:attr:`FolderData.step_read`, ``beam_solids``) and the
        erection sweep built from them (``erection_passes``), once no check left to run in this process reads
        them (:data:`SOLID_READERS`): at 44 × 30 faces they are 0.5 GB of a serial verify's 1.5 GB.  A check
        that asks for them afterwards has them read again (their producers run again; their findings were kept
        at their turn)."""
        self.read.step_read.clear()
        self.read.beam_solids = None
        self.read.erection_passes = None
        for name in ("beam_solids", "erection_passes"):
            self._found.pop(PRODUCERS[name], None)
        from ._step_read import give_back_memory

        give_back_memory()

    def _field(self, name: str) -> Any:
        """The field ``name`` of :attr:`read` once its producer (:data:`PRODUCERS`) has run."""
        return getattr(self.after(PRODUCERS[name]), name)

    @staticmethod
    def _coded(findings: list[Finding], name: str) -> list[Finding]:
        return [f if f.code else replace(f, code=name) for f in findings]

    @property
    def manifest(self) -> dict[str, Any]:
        """``manifest.json`` as checked; empty when it cannot be read."""
        return self._field("manifest") or {}

    @property
    def mesh(self) -> "QuadMesh | None":
        return self._field("mesh")

    @property
    def parts(self) -> list[dict[str, str]] | None:
        return self._field("parts")

    @property
    def parts_csv_rows(self) -> list[dict[str, str]] | None:
        return self._field("parts_csv_rows")

    @property
    def nodes(self) -> list[dict[str, str]] | None:
        return self._field("nodes")

    @property
    def cut(self) -> dict[str, tuple[str, "np.ndarray"]]:
        return self._field("cut")

    @property
    def dxf_outlines(self) -> dict[str, "np.ndarray"]:
        return self._field("dxf_outlines")

    @property
    def dxf_texts(self) -> dict[str, list[Any]]:
        return self._field("dxf_texts")

    @property
    def dxf_marks(self) -> dict[str, list[Any]]:
        return self._field("dxf_marks")

    @property
    def dxf_trim(self) -> dict[str, Any]:
        return self._field("dxf_trim")

    @property
    def type_outlines(self) -> dict[str, "np.ndarray"]:
        return self._field("type_outlines")

    @property
    def beam_solids(self) -> dict[str, Any] | None:
        return self._field("beam_solids")

    @property
    def plate_outlines(self) -> dict[str, "np.ndarray"]:
        return self._field("plate_outlines")

    @property
    def plate_cut_outlines(self) -> dict[str, "np.ndarray"]:
        return self._field("plate_cut_outlines")

    @property
    def erection_passes(self) -> list["Pass"] | None:
        return self._field("erection_passes")

    def table(self, rel: str) -> list[dict[str, str]]:
        """The rows of the CSV file ``rel`` of the folder, read once per verification and process (the same list
        to every caller: read, do not change it); raises what :func:`read_csv` raises."""
        got = self.read.tables.get(rel)
        if got is None:
            got = self.read.tables[rel] = read_csv(self.folder / rel)
        return got

    def part_row(self, part_id: str) -> dict[str, str] | None:
        """The readable ``parts.csv`` row of ``part_id`` (:attr:`parts`), ``None`` when there is none."""
        if self.read.parts_by_id is None:
            self.read.parts_by_id = {r["part_id"]: r for r in (self.parts or [])}
        return self.read.parts_by_id.get(part_id)

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
    run: Callable[[Verification], None]


_TABLE: Registry[Check] = Registry("check", "fabrication.verify")
CHECKS: dict[str, Check] = _TABLE.entries


def check(name: str) -> Callable[[Callable[[Verification], None]], Callable[[Verification], None]]:
    """Decorator registering ``run(verification)`` as the check ``name``."""
    def register(fn: Callable[[Verification], None]) -> Callable[[Verification], None]:
        _TABLE.add(name, Check(name, fn))
        return fn
    return register


def load_table() -> dict[str, Check]:
    """Import every check module of this package (once); the checks by name."""
    return _TABLE.load()


REPORT_ORDER: tuple[str, ...] = (
    "manifest", "files", "mesh", "crease", "parts", "parts_json", "order", "nodes", "axes", "torsion", "welds",
    "strip_cuts", "dxf", "types", "marking", "glass_order", "summary", "report", "splices", "dxf_legacy", "bolts",
    "dxf_stock", "step", "splice_holes", "panels_step", "bite", "step_geometry", "clash", "glazing_step", "bevels",
    "retention", "erection", "ifc", "placement", "rhino", "glb", "drawings")
"""The order the checks run in here and report in: the folder, the mesh and its creases, the tables, the
sheets, the STEP files, the exchange models, the drawings — what a reader should mend first comes first (the
command prints the first findings).  Presentation only: a check not named here runs and reports after these,
by name, and every check gets what it reads whatever the order (:meth:`Verification.after`)."""

READ_FIRST: tuple[str, ...] = ("manifest", "mesh", "parts", "nodes", "dxf")
"""The checks that fill what most others read (:data:`PRODUCERS`): the second process
(:data:`SECOND_PROCESS`) starts once they have run here, so that it starts with it all read; a matter of time
only."""


def load_checks() -> list[Check]:
    """Every check, in :data:`REPORT_ORDER` (then any other by name)."""
    table = load_table()
    first = [table[n] for n in REPORT_ORDER if n in table]
    return first + sorted((c for c in table.values() if c.name not in REPORT_ORDER), key=lambda c: c.name)


SOLID_READERS: frozenset[str] = frozenset({
    "splices", "step", "splice_holes", "panels_step", "bite", "step_geometry", "clash", "glazing_step", "bevels",
    "retention", "erection"})
"""The checks that read solids of the STEP files (:func:`._step_read.read_or_report`,
:attr:`Verification.beam_solids`, :attr:`Verification.erection_passes`): after the last of them a process runs,
:meth:`Verification.release_solids` lets go of what they read (the exchange models, the drawings and their
checks come after).  A test reads every STEP file once in a verify: a check reading solids that is not named here
would read its file a second time."""


CONFINED: tuple[str, ...] = ("ifc", "rhino", "glb")
"""Checks that run in a forked process of their own which ends with them (:func:`_run_confined`), because the
libraries that read their files keep what they allocated: IfcOpenShell never frees a file's instances, openNURBS
keeps its heap (as the writers of :data:`fabrication.writers._parallel.CONFINED`), and glTF's meshes are read in
batches whose arrays the allocator keeps in fragments.  At 44 × 30 faces a serial verify held +181 MB after the
3dm check and +93 MB after the glb check; on two cores they ran after one another in the second process, which
peaked at 1,227 MB.  None of them fills anything another check reads (:data:`PRODUCERS`)."""


def _run_confined(v: Verification, c: Check) -> tuple[list[Finding], list[str]]:
    """:meth:`Verification.run_check` of ``c`` in a forked process that ends with it, its findings sent back; here
    when fork is not available, no process can be had, or the process fails (so an error raised is the check's
    own)."""
    from ..writers._parallel import in_own_process

    if c.name not in v._found:
        _read_for_confined(v)
        v._found[c.name] = in_own_process(lambda: v.run_check(c), f"ppfab-verify-{c.name}")
    return v._found[c.name]


SHARED_BY_CONFINED: list[Callable[[Verification], Any]] = []
"""What every check of :data:`CONFINED` reads about the parts and works out once per process (registered by the
modules that define it, :func:`shared_by_confined`): the strips' recomputed boxes
(:func:`.glazing_step.strip_places`; at 44 × 30 faces about 2.5 CPU s each time) and the panes' seat
(:func:`._solids.seat_range`)."""


_Work = TypeVar("_Work", bound=Callable[[Verification], Any])


def shared_by_confined(fn: _Work) -> _Work:
    """Decorator adding ``fn(verification)`` to :data:`SHARED_BY_CONFINED`."""
    SHARED_BY_CONFINED.append(fn)
    return fn


def _read_for_confined(v: Verification) -> None:
    """Work out here, once, what :data:`SHARED_BY_CONFINED` names, which each confined check would otherwise work
    out again in its own process (which ends, and takes it with it)."""
    if v.mesh is None or v.parts is None:
        return
    for work in SHARED_BY_CONFINED:
        try:
            work(v)
        except Exception:  # noqa: BLE001 - a table it cannot read: the check that reads it reports that itself
            pass


def _run_releasing(v: Verification, c: Check, checks: list[Check]) -> tuple[list[Finding], list[str]]:
    """:meth:`Verification.run_check` of ``c`` (in a process of its own for the checks of :data:`CONFINED`), then
    :meth:`Verification.release_solids` when ``c`` is the last of ``checks`` (a process's list, in order) to read
    solids (:data:`SOLID_READERS`)."""
    got = _run_confined(v, c) if c.name in CONFINED else v.run_check(c)
    readers = [k.name for k in checks if k.name in SOLID_READERS]
    if readers and c.name == readers[-1]:
        v.release_solids()
    return got


SECOND_PROCESS: tuple[str, ...] = ("types", "marking", "glass_order", "dxf_stock", "placement", "ifc", "rhino",
                                   "glb", "drawings")
"""Checks that run in a forked process beside the others on two cores, once :data:`READ_FIRST` has run here:
none of them reads a STEP file, so every STEP file, and above all glazing.step (74,160 solids at 88 × 60
faces), is read and held in one process only (:data:`SOLID_READERS` all run here).  With the bite check in the
second process and the clash, retention and erection checks here, both processes read glazing.step: at 88 × 60
the process tree held 4.9 GB (docs/performance.md).  The split also balances the CPU: in a serial verify at
88 × 60 the checks named here take about 270 CPU s (ifc 142, rhino 61, types 25, glb 22, drawings 16) and the
STEP checks about 290.  What they read that this process had not read when it forked they read themselves: the
per-type DXFs are read there only, by the types check, and the dxf_stock check, which reads every DXF file,
runs beside it (here it read them a second time: +22 CPU s at 88 × 60)."""


def verify(folder: str | Path, parallel: bool | None = None, kernel: bool = False,
           progress: Callable[[int, int, str], None] | None = None) -> Verification:
    """Run every check on an output folder (stopping after the manifest if it cannot be read).

    ``parallel`` (default: on with two cores and fork, :func:`fabrication.writers._parallel.parallel_enabled`)
    runs the checks of :data:`SECOND_PROCESS` in a forked process once :data:`READ_FIRST` have run; the
    findings and the list of checks are assembled in :data:`REPORT_ORDER`, so the result equals a serial
    run.  When the second process fails (a check raising, the process dying), its checks run again here, so an
    error is the check's own.  ``kernel``: the CAD kernel reads every solid of the STEP files and every
    IFC instance is schema-validated (:attr:`Verification.kernel`).  ``progress(done, total, what)`` is called as checks finish here (``what``:
    the check just run, or what is being waited for), so a long verify shows its count and time left."""
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
            done[c.name] = _run_releasing(v, c, first)
            report(len(done), len(checks), c.name)
            if v.read.manifest is None:
                return _assembled(v, checks, done)
            if second and child is None and all(n in done for n in READ_FIRST if n in CHECKS):
                try:
                    child = Forked(lambda: _run_all(v, second), "ppfab-verify", may_fork=True)
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
                done[c.name] = v.run_check(c)
                report(len(done), len(checks), c.name)
        else:
            done.update(outcome[1])
    return _assembled(v, checks, done)


def _assembled(v: Verification, checks: list[Check], done: dict[str, tuple[list[Finding], list[str]]]
               ) -> Verification:
    """``v`` with the findings and the checked list of every check run, in check order."""
    v.findings = [f for c in checks if c.name in done for f in done[c.name][0]]
    v.checked = [n for c in checks if c.name in done for n in done[c.name][1]]
    return v


def _run_all(v: Verification, checks: list[Check]) -> dict[str, tuple[list[Finding], list[str]]]:
    """The second process's work: ``checks`` run on its copy of ``v``; what each found and checked."""
    return {c.name: _run_releasing(v, c, checks) for c in checks}
