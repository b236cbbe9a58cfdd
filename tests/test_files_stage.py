"""Writing on two cores changes no file: a small build written with the per-type DXFs in a second process and
written serially gives the same bytes in every file (no file of a build holds a timing), the same ``files``
table, and a failure in the second process is reported as the writer's own error with nothing left behind."""

import hashlib
from pathlib import Path

import pytest

from conftest import small_design

pytestmark = pytest.mark.skipif(not hasattr(__import__("os"), "fork"), reason="parallel writing needs fork")


def tree(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def small_build():
    from fabrication import build, parse_design
    import tomllib

    return build(parse_design(tomllib.loads(small_design(4, 3))))


def test_parallel_and_serial_writing_give_identical_files(tmp_path, small_build):
    """Two ``ppfab build`` runs of one design, each in a fresh process (as a user runs it), with the second
    process on and off; then the same build written here in one process, serially and in two processes.""" 
    import os
    import subprocess
    import sys

    design = tmp_path / "small.toml"
    design.write_text(small_design(4, 3))
    for flag in ("0", "1"):
        env = dict(os.environ, PPFAB_PARALLEL_WRITERS=flag, OMP_NUM_THREADS="1")
        run = subprocess.run([sys.executable, "-m", "fabrication.cli", "build", str(design), "-o",
                              str(tmp_path / f"out{flag}"), "--quiet"], env=env, capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
    serial, parallel = tree(tmp_path / "out0"), tree(tmp_path / "out1")
    assert len(serial) > 20 and "beams.step" in serial and "manifest.json" in serial
    assert serial == parallel

    from fabrication.progress import Progress
    from fabrication.writers import write_all

    tables = []
    for flag in (False, True):
        folder = tmp_path / f"raw{int(flag)}"
        folder.mkdir()
        tables.append(write_all(small_build, folder, Progress(quiet=True), parallel=flag))
    assert list(tables[0].items()) == list(tables[1].items())          # same keys, values and order
    # STEP aside: the kernel numbers assembly occurrences across exports in one process (their line breaks
    # then differ); the fresh-process builds above compare it
    same = {k: v for k, v in tree(tmp_path / "raw1").items() if not k.endswith(".step") and k != "manifest.json"}
    steps = sorted(k for k in serial if k.endswith(".step"))
    assert steps == ["beams.step", "glazing.step", "panels.step", "splices.step"]
    assert same == {k: v for k, v in serial.items() if k in same} and len(same) == len(serial) - len(steps) - 1
    assert any(k.startswith("splices/") for k in same) and "bites.csv" in same and "welds.csv" in same


@pytest.mark.parametrize("writer, file, parallel", [("dxf_types", "types/T01.dxf", "1"), ("ifc", "model.ifc", "0"),
                                                   ("ifc", "model.ifc", "1")])
def test_a_failing_forked_writer_raises_its_own_error(tmp_path, small_build, monkeypatch, writer, file, parallel):
    """A writer fails in a forked process (the per-type DXFs in the second process on two cores, the IFC file in
    its own on one); the build reruns it here, so the error is its own, and the temporary folder is gone."""
    import dataclasses

    from ppfab.errors import FabricationError

    from fabrication import writers

    calls = []

    def boom(build, out, files):
        calls.append(1)
        raise FabricationError(f"{file}: cannot write")

    writers.load_writers()
    monkeypatch.setitem(writers.WRITERS, writer, dataclasses.replace(writers.WRITERS[writer], write=boom))
    monkeypatch.setenv("PPFAB_PARALLEL_WRITERS", parallel)
    with pytest.raises(FabricationError, match=f"{file}: cannot write"):
        small_build.write(tmp_path / "out")
    assert calls == [1]                                   # the rerun here (the child's call is another process)
    assert [p.name for p in tmp_path.iterdir() if ".tmp-" in p.name or ".lock" in p.name] == []
    assert not (tmp_path / "out").exists()


def _recording_pids(monkeypatch, log: Path, names: tuple[str, ...]) -> None:
    """Wrap the writers ``names`` so that each appends ``"<name> <pid> <parent pid>"`` to ``log`` as it runs (in any
    process)."""
    import dataclasses
    import os

    from fabrication import writers

    writers.load_writers()
    for name in names:
        original = writers.WRITERS[name]

        def write(build, out, files, _name=name, _write=original.write):
            with open(log, "a") as f:
                f.write(f"{_name} {os.getpid()} {os.getppid()}\n")
            return _write(build, out, files)

        monkeypatch.setitem(writers.WRITERS, name, dataclasses.replace(original, write=write))


def test_the_ifc_3dm_and_glb_files_are_written_in_processes_that_end(tmp_path, small_build, monkeypatch):
    """IfcOpenShell keeps every instance of a file it made until the process ends (and openNURBS its heap, and the
    glTF writer's meshes their fragments), so the IFC, 3dm and glTF writers each run in a forked process of their
    own: on one core forked from this one, on two forked from the second process (one after the other, so one
    writer's memory is not under the next one's), never in this one.  Without fork they run here and write the
    same bytes."""
    import os

    from fabrication.progress import Progress
    from fabrication.writers import _parallel, write_all

    names = ("glb", "ifc", "rhino")

    def written(folder: str, parallel: bool) -> dict[str, int]:
        log = tmp_path / f"{folder}.pids"
        out = tmp_path / folder
        out.mkdir()
        write_all(small_build, out, Progress(quiet=True), parallel=parallel)
        runs = [line.split() for line in log.read_text().splitlines()]
        assert sorted(name for name, _, _ in runs) == list(names)          # each ran once
        parents.update({name: int(ppid) for name, _, ppid in runs})
        return {name: int(pid) for name, pid, _ in runs}

    parents: dict[str, int] = {}

    _recording_pids(monkeypatch, tmp_path / "apart.pids", names)
    apart = written("apart", parallel=False)
    assert os.getpid() not in apart.values() and len(set(apart.values())) == 3
    assert all(parents[n] == os.getpid() for n in names)
    _recording_pids(monkeypatch, tmp_path / "second.pids", names)
    second = written("second", parallel=True)
    assert os.getpid() not in second.values() and len(set(second.values())) == 3
    assert parents["glb"] == parents["ifc"] == parents["rhino"] != os.getpid()        # the second process's

    monkeypatch.setattr(_parallel, "fork_available", lambda: False)
    _recording_pids(monkeypatch, tmp_path / "here.pids", names)
    assert set(written("here", parallel=False).values()) == {os.getpid()}
    for name in ("model.ifc", "model.3dm", "model.glb"):
        here = (tmp_path / "here" / name).read_bytes()
        assert len(here) > 10_000
        assert (tmp_path / "apart" / name).read_bytes() == here == (tmp_path / "second" / name).read_bytes()


def test_parallel_writing_is_off_on_one_core_and_by_environment(monkeypatch):
    from fabrication.writers import _parallel

    monkeypatch.delenv("PPFAB_PARALLEL_WRITERS", raising=False)
    monkeypatch.setattr(_parallel, "cores", lambda: 1)
    assert not _parallel.parallel_enabled()
    monkeypatch.setattr(_parallel, "cores", lambda: 2)
    assert _parallel.parallel_enabled()
    monkeypatch.setenv("PPFAB_PARALLEL_WRITERS", "0")
    assert not _parallel.parallel_enabled()



def test_each_writer_writes_exactly_the_files_it_declared(tmp_path, small_build):
    """The writers run one after the other into one folder; after each, the files that appeared are exactly the
    ones its ``declare(build)`` named before anything was written (the manifest's own file aside)."""
    from fabrication.progress import Progress
    from fabrication.writers import declared_files, load_writers, write_all
    from fabrication.writers.base import listed_files

    out = tmp_path / "out"
    out.mkdir()
    enabled = [w for w in load_writers() if w.enabled(small_build.design)]
    table = declared_files(small_build, enabled)
    assert len(enabled) >= 12 and len(listed_files(table)) > 20
    before: set[str] = set()
    for w in enabled:
        note = w.write(small_build, out, table)
        now = {p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()}
        expected = set(listed_files(w.declare(small_build))) | ({"manifest.json"} if w.name == "manifest" else set())
        assert now - before == expected, (w.name, note)
        before = now
    second = tmp_path / "again"
    second.mkdir()
    assert write_all(small_build, second, Progress(quiet=True), parallel=False) == table


def test_a_writer_that_writes_an_undeclared_file_stops_the_build(tmp_path, small_build, monkeypatch):
    """A writer holding to its declaration is checked on every build: one that writes a file it did not declare
    stops the build with one line naming the file, and nothing is written."""
    import dataclasses

    from ppfab.errors import FabricationError

    from fabrication import writers

    writers.load_writers()
    bolts = writers.WRITERS["bolts"]

    def more(build, out, files):
        (out / "stray.txt").write_text("not declared", encoding="utf-8")
        return bolts.write(build, out, files)

    monkeypatch.setitem(writers.WRITERS, "bolts", dataclasses.replace(bolts, write=more))
    with pytest.raises(FabricationError, match=r"not declared \['stray.txt'\]"):
        small_build.write(tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_closing_a_forked_job_kills_a_child_that_ignores_sigterm(monkeypatch):
    """``Forked.close`` terminates a child still running; one that ignores SIGTERM (a handler it inherited before
    it set its own) is killed after ``CLOSE_WAIT_S`` instead of being waited for without end."""
    import signal
    import time

    import fabrication.writers._parallel as par

    def stubborn():
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        time.sleep(60.0)

    monkeypatch.setattr(par, "CLOSE_WAIT_S", 0.5)
    job = par.Forked(stubborn, "ppfab-test")
    time.sleep(0.5)                                   # the child has set its handler
    t0 = time.monotonic()
    job.close()
    assert time.monotonic() - t0 < 10.0
    assert not job._proc.is_alive() and job._proc.exitcode == -signal.SIGKILL
