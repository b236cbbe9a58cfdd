"""Output safety: atomic output folders (a failure at any stage leaves nothing behind and never touches an
existing folder) and determinism (same design, same bytes)."""

import hashlib
from pathlib import Path

import pytest

from fabrication.pipeline import stages as pipeline
from fabrication.cli import main

from conftest import small_design

SMALL = small_design()


@pytest.fixture
def small_design(tmp_path):
    p = tmp_path / "small.toml"
    p.write_text(SMALL)
    return p


def tree(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def leftovers(parent: Path) -> list[str]:
    return [p.name for p in parent.iterdir() if p.name.startswith(".") and ".tmp-" in p.name or ".old-" in p.name]


def _writer_names() -> list[str]:
    from fabrication.writers import load_writers

    return [w.name for w in load_writers()]


def _inject(monkeypatch, stage: str, exc: BaseException, writer: bool | None = None) -> None:
    """Make compute stage ``stage`` (``pipeline.stage_<name>``) or the writer ``stage`` raise ``exc``;
    ``writer`` says which when a stage and a writer share the name (``glazing``), else it is found."""
    import dataclasses

    from fabrication import writers

    def boom(*args, **kwargs):
        raise exc

    if writer is None:
        writer = stage not in pipeline.STAGES
    if not writer:
        monkeypatch.setattr(pipeline, f"stage_{stage}", boom)
    else:
        writers.load_writers()
        monkeypatch.setitem(writers.WRITERS, stage, dataclasses.replace(writers.WRITERS[stage], write=boom,
                                                                        enabled=lambda design: True))


def test_stage_list_names_the_stage_functions():
    for name in pipeline.STAGES:
        assert callable(getattr(pipeline, f"stage_{name}"))
    assert _writer_names()[-1] == "manifest"


@pytest.mark.parametrize("kind,stage", [("stage", s) for s in pipeline.STAGES] + [("writer", w) for w in _writer_names()],
                         ids=lambda x: x if x not in ("stage", "writer") else None)
def test_failure_at_any_stage_leaves_no_partial_folder(tmp_path, small_design, monkeypatch, capsys, kind, stage):
    out = tmp_path / "out"
    from fabrication.writers._failures import OPTIONAL_FILES

    _inject(monkeypatch, stage, RuntimeError(f"injected failure in {kind} {stage}"), writer=kind == "writer")
    if kind == "writer" and stage in OPTIONAL_FILES:     # an optional file: one line naming the key that skips it
        capsys.readouterr()
        assert main(["build", str(small_design), "-o", str(out), "--quiet"]) != 0
        err = capsys.readouterr().err.strip()
        key, _file = OPTIONAL_FILES[stage]
        assert "injected failure" in err and key in err and "\n" not in err, err
    else:
        with pytest.raises(RuntimeError, match="injected"):
            main(["build", str(small_design), "-o", str(out), "--quiet"])
    assert not out.exists()
    assert leftovers(tmp_path) == []


def test_failure_never_damages_existing_folder(tmp_path, small_design, monkeypatch):
    out = tmp_path / "out"
    assert main(["build", str(small_design), "-o", str(out), "--quiet"]) == 0
    before = tree(out)
    _inject(monkeypatch, "manifest", KeyboardInterrupt())
    assert main(["build", str(small_design), "-o", str(out), "--quiet", "--force"]) == 130
    assert tree(out) == before
    assert leftovers(tmp_path) == []


def test_existing_folder_needs_force_and_force_keeps_a_users_folder(tmp_path, small_design, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    assert main(["build", str(small_design), "-o", str(out), "--quiet"]) == 2
    assert "--force" in capsys.readouterr().err
    assert (out / "keep.txt").read_text() == "mine"
    # --force replaces only a previous ppfab build: a folder holding someone's file is refused
    assert main(["build", str(small_design), "-o", str(out), "--quiet", "--force"]) == 2
    err = capsys.readouterr().err
    assert "is not a previous ppfab build" in err and err.count("\n") == 1
    assert sorted(p.name for p in out.iterdir()) == ["keep.txt"] and (out / "keep.txt").read_text() == "mine"
    assert leftovers(tmp_path) == []


def test_force_replaces_a_previous_build_and_nothing_else(tmp_path, small_design, capsys):
    out = tmp_path / "out"
    assert main(["build", str(small_design), "-o", str(out), "--quiet"]) == 0
    before = tree(out)
    assert main(["build", str(small_design), "-o", str(out), "--quiet", "--force"]) == 0
    assert tree(out) == before and leftovers(tmp_path) == []
    # a file added to the build, or a file of the build edited, makes it the user's folder
    (out / "notes.txt").write_text("site notes")
    assert main(["build", str(small_design), "-o", str(out), "--quiet", "--force"]) == 2
    assert "notes.txt, which ppfab did not write" in capsys.readouterr().err
    (out / "notes.txt").unlink()
    with open(out / "parts.csv", "a") as fh:
        fh.write("# checked\n")
    assert main(["build", str(small_design), "-o", str(out), "--quiet", "--force"]) == 2
    assert "parts.csv was changed after the build" in capsys.readouterr().err
    assert (out / "parts.csv").read_text().endswith("# checked\n")


def test_two_builds_are_byte_identical(tmp_path, small_design):
    a, b = tmp_path / "a", tmp_path / "b"
    assert main(["build", str(small_design), "-o", str(a), "--quiet"]) == 0
    assert main(["build", str(small_design), "-o", str(b), "--quiet"]) == 0
    ta, tb = tree(a), tree(b)
    assert ta.keys() == tb.keys()
    differ = sorted(k for k in ta if ta[k] != tb[k])
    assert differ == []
    assert any(k.endswith(".dxf") for k in ta) and "beams.step" in ta and "parts.csv" in ta


def test_very_large_grid_is_refused_before_work(tmp_path, capsys):
    p = tmp_path / "big.toml"
    p.write_text(SMALL.replace("faces_u = 5", "faces_u = 2000").replace("faces_v = 4", "faces_v = 2000"))
    assert main(["build", str(p), "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "--allow-large" in err and "GiB" in err and "min" in err
    assert not (tmp_path / "o").exists()


def test_builds_are_identical_whatever_the_hash_seed_folder_and_path_spelling(tmp_path, small_design):
    """Three separate processes: other PYTHONHASHSEED, other working folder, the design and -o spelled
    relative, absolute, with '..' and a trailing slash — the same bytes, and no absolute path in the manifest."""
    import json
    import os
    import subprocess
    import sys

    from conftest import REPO

    (tmp_path / "work").mkdir()
    runs = [("0", tmp_path / "work", "../small.toml", "../out_a"),
            ("12345", tmp_path, str(small_design), str(tmp_path / "nowhere" / ".." / "out_b") + "/"),
            ("random", Path("/"), str(small_design), str(tmp_path / "out_c"))]
    for seed, cwd, design, out in runs:
        env = dict(os.environ, PYTHONHASHSEED=seed, OMP_NUM_THREADS="1",
                   PYTHONPATH=os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]))
        r = subprocess.run([sys.executable, "-m", "fabrication.cli", "build", design, "-o", out, "--quiet"],
                           cwd=cwd, env=env, capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, r.stderr
    trees = [tree(tmp_path / name) for name in ("out_a", "out_b", "out_c")]
    assert trees[0] == trees[1] == trees[2] and len(trees[0]) > 30
    text = (tmp_path / "out_a" / "manifest.json").read_text()
    assert str(tmp_path) not in text and str(REPO) not in text

    def strings(o):
        if isinstance(o, dict):
            for k, x in o.items():
                yield k
                yield from strings(x)
        elif isinstance(o, list):
            for x in o:
                yield from strings(x)
        elif isinstance(o, str):
            yield o

    assert not [s for s in strings(json.loads(text)) if s.startswith("/") or s.startswith("\\\\") or s[1:3] == ":\\\\"]
    assert json.loads(text)["design"]["source"] == "small.toml"
    assert leftovers(tmp_path) == []


def test_a_build_never_ships_files_its_own_verify_rejects(tmp_path, small_design, monkeypatch, capsys):
    """A writer that puts the design name raw into mesh.obj (a newline makes an extra vertex line): the build's
    own verify sees the OBJ disagree with the manifest and nothing is written."""
    from ppfab.io import meshfile

    text = small_design.read_text().replace('name = "small"', 'name = "roof\\nv 1 2 3"')
    small_design.write_text(text)
    monkeypatch.setattr(meshfile, "obj_comment", lambda s: s)
    out = tmp_path / "out"
    assert main(["build", str(small_design), "-o", str(out), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "the files of this build fail ppfab verify, so none were written" in err and "mesh.obj" in err
    assert not out.exists() and leftovers(tmp_path) == []


def test_leftovers_of_killed_runs_are_recognised_safely(tmp_path, small_design):
    """What the next run removes: temporary folders whose marker names a dead process, and previous builds
    moved aside by a dead run (put back when no build took their place). A temporary folder without a
    marker, or whose process still runs, and anything else are kept."""
    import json
    import subprocess
    import sys

    from fabrication.pipeline.folder import AtomicFolder, previous_build_problem
    from fabrication.pipeline.lock import MARKER, process_record, remove_stale

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    pid = int(dead.stdout)
    record = {**process_record(), "pid": pid, "start": ""}
    out = tmp_path / "out"
    stale = tmp_path / ".out.tmp-0000dead"
    stale.mkdir()
    (stale / MARKER).write_text(json.dumps(record))
    (stale / "beams.step").write_text("half")
    alive = tmp_path / ".out.tmp-0000a11e"
    alive.mkdir()
    (alive / MARKER).write_text(json.dumps(process_record()))
    unmarked = tmp_path / ".out.tmp-00000000"
    unmarked.mkdir()
    (unmarked / "keep.txt").write_text("x")
    other = tmp_path / ".other.tmp-0000dead"
    other.mkdir()
    (other / MARKER).write_text(json.dumps(record))
    # a previous build moved aside by the dead run, and no build took its place
    assert main(["build", str(small_design), "-o", str(tmp_path / "prev"), "--quiet"]) == 0
    before = tree(tmp_path / "prev")
    (tmp_path / "prev").rename(tmp_path / f".out.old-{pid}-0000beef")
    # killed between making its folder and writing the marker: nothing in it, or a marker not yet written
    unstarted = tmp_path / ".out.tmp-0000e111"
    unstarted.mkdir()
    half = tmp_path / ".out.tmp-0000e222"
    half.mkdir()
    (half / MARKER).write_text("")
    removed = remove_stale(out.absolute(), previous_build_problem)
    assert removed == [stale, unstarted, half]
    assert alive.exists() and unmarked.exists() and other.exists()
    assert tree(out) == before                                        # put back, unchanged
    # a full run removes the dead one's folder too and replaces the restored build (it is one)
    (stale).mkdir()
    (stale / MARKER).write_text(json.dumps(record))
    with AtomicFolder(out, force=True) as tmp:
        (tmp / "manifest.json").write_text(json.dumps({"generator": "ppfab", "sha256": {}}))
    assert not stale.exists() and sorted(p.name for p in out.iterdir()) == ["manifest.json"]


def test_a_forked_helper_dies_with_its_killed_parent(tmp_path):
    """A parent killed with SIGKILL cleans nothing up: its forked helper (writers, verify) must not live on,
    writing into the temporary folder and holding the output folder's lock (it shares the lock file)."""
    import signal
    import subprocess
    import sys
    import time

    script = (
        "import time, pathlib\n"
        "from fabrication.writers._parallel import Forked\n"
        "def job():\n"
        f"    pathlib.Path({str(tmp_path / 'child.pid')!r}).write_text(str(__import__('os').getpid()))\n"
        "    time.sleep(60)\n"
        "f = Forked(job, 'ppfab-test')\n"
        "time.sleep(60)\n")
    parent = subprocess.Popen([sys.executable, "-c", script])
    t0 = time.monotonic()
    while not (tmp_path / "child.pid").exists() or not (tmp_path / "child.pid").read_text():
        assert time.monotonic() - t0 < 60, "the helper did not start"
        time.sleep(0.02)
    child = int((tmp_path / "child.pid").read_text())
    parent.send_signal(signal.SIGKILL)
    parent.wait(timeout=30)
    t0 = time.monotonic()
    while True:                                   # gone, or a zombie waiting for init to reap it
        try:
            state = open(f"/proc/{child}/stat").read().rsplit(")", 1)[-1].split()[0]
        except OSError:
            break
        if state == "Z":
            break
        assert time.monotonic() - t0 < 10, f"the helper {child} outlived its killed parent (state {state})"
        time.sleep(0.02)


def test_a_failed_build_leaves_no_new_parent_folders(tmp_path, small_design, monkeypatch, capsys):
    _inject(monkeypatch, "nesting", RuntimeError("injected failure in nesting"))
    with pytest.raises(RuntimeError, match="injected"):
        main(["build", str(small_design), "-o", str(tmp_path / "new" / "sub" / "out"), "--quiet"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["small.toml"]
