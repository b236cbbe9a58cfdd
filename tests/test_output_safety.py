"""Never lose a user's file on the output side.

The commit of a build checks the output folder again right before each rename (a folder that appeared, a
previous build that changed while the build was written: refused, the finished build kept in its temporary
folder); the lock file is only ever created new; ``optimize -o`` and ``new -o`` never write over an input
and replace only ppfab's own unchanged files, with ``--force``.  The races are made deterministic with
:data:`fabrication.pipeline.overwrite.COMMIT_HOOKS`: the hook does, on the real file system, what a user
might do at the moment the finished output is about to take its name.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from fabrication.cli import main
from fabrication.pipeline import overwrite
from fabrication.pipeline.folder import remove_build
from fabrication.pipeline.lock import OutputLock, process_record
from fabrication.pipeline.overwrite import rename_noreplace, written_by_ppfab

from conftest import REPO, small_design

MESH = REPO / "tests" / "data" / "meshes" / "compas__hypar.obj"


def tree(folder: Path) -> dict[str, str]:
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def kept_folder(err: str) -> Path:
    """The temporary folder the one-line refusal names."""
    m = re.search(r"the finished build is in (\S+)$", err.strip())
    assert m, err
    return Path(m.group(1))


@pytest.fixture
def design(tmp_path: Path) -> Path:
    p = tmp_path / "small.toml"
    p.write_text(small_design())
    return p


@pytest.fixture
def hook(monkeypatch):
    """Install one commit hook for the test (a fresh list, so nothing leaks into other tests)."""
    hooks: list = []
    monkeypatch.setattr(overwrite, "COMMIT_HOOKS", hooks)
    return hooks.append


def _one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("ppfab: error:") and "Traceback" not in err, err
    return lines[0]


# --- the output folder -------------------------------------------------------------------------------------

def test_a_folder_that_appears_during_the_write_is_left_alone(tmp_path, design, hook, capsys):
    out = tmp_path / "out"

    def user_makes_the_folder(target: Path, tmp: Path) -> None:
        target.mkdir()
        (target / "site-notes.txt").write_text("measured on site\n")

    hook(user_makes_the_folder)
    assert main(["build", str(design), "-o", str(out), "--quiet"]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "appeared while the build was written" in line
    assert sorted(p.name for p in out.iterdir()) == ["site-notes.txt"]
    assert (out / "site-notes.txt").read_text() == "measured on site\n"
    kept = kept_folder(line)
    assert kept.parent == tmp_path and kept.name.startswith(".out.tmp-")
    manifest = json.loads((kept / "manifest.json").read_text())
    assert sorted(manifest["sha256"]) == sorted(k for k in tree(kept) if k != "manifest.json")
    assert len(manifest["sha256"]) > 30
    assert not (tmp_path / ".out.lock").exists()


DRIVER = """
import pathlib, sys, time
from fabrication.pipeline import overwrite
from fabrication.cli import main
ready, go = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
def wait_for_the_user(target, tmp):
    ready.write_text(str(tmp))
    t0 = time.monotonic()
    while not go.exists():
        if time.monotonic() - t0 > 600:
            raise SystemExit("the test did not answer")
        time.sleep(0.02)
overwrite.COMMIT_HOOKS.append(wait_for_the_user)
sys.exit(main(sys.argv[3:]))
"""


def test_a_folder_made_by_another_process_during_the_write_is_left_alone(tmp_path, design):
    """Two processes: the build stops when its files are complete, this test (the user) makes the output
    folder and saves a file into it, then lets the build commit."""
    import time

    out, ready, go = tmp_path / "out", tmp_path / "ready", tmp_path / "go"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.Popen([sys.executable, "-c", DRIVER, str(ready), str(go), "build", str(design), "-o",
                             str(out), "--quiet"], cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    t0 = time.monotonic()
    while not ready.exists() or not ready.read_text():
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() - t0 < 900, "the build did not reach its commit"
        time.sleep(0.05)
    out.mkdir()
    (out / "model.3dm").write_bytes(b"the architect's model")
    go.touch()
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 2, err
    line = _one_error_line(err)
    assert "appeared while the build was written" in line
    assert kept_folder(line) == Path(ready.read_text()) and (kept_folder(line) / "manifest.json").is_file()
    assert sorted(p.name for p in out.iterdir()) == ["model.3dm"]
    assert (out / "model.3dm").read_bytes() == b"the architect's model"


def test_force_refuses_when_a_file_is_saved_into_the_old_build_during_the_write(tmp_path, design, hook, capsys):
    out = tmp_path / "out"
    assert main(["build", str(design), "-o", str(out), "--quiet"]) == 0
    before = tree(out)

    def user_saves_into_the_build(target: Path, tmp: Path) -> None:
        (target / "checked-by-engineer.txt").write_text("ok, JB\n")

    hook(user_saves_into_the_build)
    assert main(["build", str(design), "-o", str(out), "--quiet", "--force"]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "gained checked-by-engineer.txt" in line and "nothing was replaced or removed" in line
    assert (out / "checked-by-engineer.txt").read_text() == "ok, JB\n"
    assert tree(out) == {**before, "checked-by-engineer.txt": tree(out)["checked-by-engineer.txt"]}
    kept = kept_folder(line)
    assert (kept / "manifest.json").is_file()
    assert not [p for p in tmp_path.iterdir() if ".old-" in p.name]


def test_force_refuses_when_a_file_of_the_old_build_is_edited_during_the_write(tmp_path, design, hook, capsys):
    out = tmp_path / "out"
    assert main(["build", str(design), "-o", str(out), "--quiet"]) == 0

    def user_edits_the_parts_list(target: Path, tmp: Path) -> None:
        with open(target / "parts.csv", "a") as fh:
            fh.write("# checked\n")

    hook(user_edits_the_parts_list)
    assert main(["build", str(design), "-o", str(out), "--quiet", "--force"]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "had parts.csv changed" in line
    assert (out / "parts.csv").read_text().endswith("# checked\n")
    assert kept_folder(line).is_dir()


def test_force_still_replaces_an_untouched_previous_build(tmp_path, design, hook):
    """The check does not refuse what it must allow: the hook runs and touches nothing."""
    out = tmp_path / "out"
    assert main(["build", str(design), "-o", str(out), "--quiet"]) == 0
    calls: list[Path] = []
    hook(lambda target, tmp: calls.append(target))
    assert main(["build", str(design), "-o", str(out), "--quiet", "--force"]) == 0
    assert calls == [out.absolute()] and (out / "manifest.json").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "small.toml"]


def test_rename_never_replaces_what_is_at_the_target(tmp_path):
    """The last step of every commit: a folder (even empty), a file or a dangling link at the target stays."""
    src = tmp_path / "src"
    src.mkdir()
    (src / "a.txt").write_text("new")
    empty = tmp_path / "empty"
    empty.mkdir()
    full = tmp_path / "full"
    full.mkdir()
    (full / "mine.txt").write_text("mine")
    link = tmp_path / "link"
    link.symlink_to(tmp_path / "nowhere")
    for dst in (empty, full, link):
        with pytest.raises(FileExistsError):
            rename_noreplace(src, dst)
    assert (src / "a.txt").read_text() == "new" and list(empty.iterdir()) == []
    assert (full / "mine.txt").read_text() == "mine" and os.readlink(link) == str(tmp_path / "nowhere")
    rename_noreplace(src, tmp_path / "free")
    assert (tmp_path / "free" / "a.txt").read_text() == "new" and not src.exists()


def test_remove_build_removes_only_unchanged_listed_files(tmp_path):
    b = tmp_path / "b"
    (b / "dxf").mkdir(parents=True)
    files = {"parts.csv": b"a,b\n", "dxf/s1.dxf": b"0\nEOF\n", "dxf/s2.dxf": b"0\nEOF\n"}
    for rel, data in files.items():
        (b / rel).write_bytes(data)
    sha = {rel: hashlib.sha256(data).hexdigest() for rel, data in files.items()}
    (b / "manifest.json").write_text(json.dumps({"generator": "ppfab 1", "sha256": sha}))
    (b / "dxf" / "notes.txt").write_text("mine")                    # not listed
    (b / "dxf" / "s2.dxf").write_bytes(b"edited")                    # listed, changed
    assert remove_build(b) == ["dxf/notes.txt", "dxf/s2.dxf"]
    assert sorted(p.relative_to(b).as_posix() for p in b.rglob("*")) == [
        "dxf", "dxf/notes.txt", "dxf/s2.dxf", "manifest.json"]
    assert (b / "dxf" / "notes.txt").read_text() == "mine" and (b / "dxf" / "s2.dxf").read_bytes() == b"edited"
    (b / "dxf" / "notes.txt").unlink()
    (b / "dxf" / "s2.dxf").write_bytes(b"0\nEOF\n")
    assert remove_build(b) == [] and not b.exists()


# --- the lock file ---------------------------------------------------------------------------------------

def _build(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]))
    return subprocess.run([sys.executable, "-m", "fabrication.cli", "build", *args, "--quiet"], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=600)


def test_a_planted_lock_symlink_is_refused_and_its_target_untouched(tmp_path, design):
    victim = tmp_path / "thesis.tex"
    victim.write_bytes(b"\\chapter{Gridshells}\n" * 50)
    before = victim.read_bytes()
    (tmp_path / ".out.lock").symlink_to(victim)
    (tmp_path / ".gone.lock").symlink_to(tmp_path / "created-by-lock.txt")
    for name in ("out", "gone"):
        r = _build([str(design), "-o", str(tmp_path / name)], tmp_path)
        assert r.returncode == 2, r.stderr
        line = _one_error_line(r.stderr)
        assert "is a symbolic link" in line and "remove it" in line
        assert not (tmp_path / name).exists()
    assert victim.read_bytes() == before and os.path.islink(tmp_path / ".out.lock")
    assert not (tmp_path / "created-by-lock.txt").exists()


def test_a_foreign_file_at_the_lock_path_is_refused_and_kept(tmp_path):
    lock = tmp_path / ".out.lock"
    lock.write_text("my own notes, not a lock\n")
    with pytest.raises(Exception, match="was not written by ppfab") as info:
        OutputLock(tmp_path / "out").__enter__()
    assert getattr(info.value, "exit_code", 0) == 2
    assert lock.read_text() == "my own notes, not a lock\n"


def test_the_lock_of_a_killed_run_is_replaced_not_reused(tmp_path):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    lock = tmp_path / ".out.lock"
    lock.write_text(json.dumps({**process_record(), "pid": int(dead.stdout), "start": ""}) + "\n")
    ino = lock.stat().st_ino
    link = tmp_path / "second-name"
    os.link(lock, link)                                # a second name of the old file shows it is not rewritten
    with OutputLock(tmp_path / "out"):
        assert json.loads(lock.read_text())["pid"] == os.getpid()
        assert lock.stat().st_ino != ino
    assert not lock.exists() and json.loads(link.read_text())["pid"] == int(dead.stdout)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["second-name"]


def test_the_lock_is_taken_where_the_file_system_has_no_hard_links(tmp_path, monkeypatch):
    import errno

    def no_links(*args, **kwargs):
        raise OSError(errno.EPERM, os.strerror(errno.EPERM))

    monkeypatch.setattr(os, "link", no_links)
    lock = tmp_path / ".out.lock"
    with OutputLock(tmp_path / "out"):
        assert json.loads(lock.read_text())["pid"] == os.getpid()
        assert not [p for p in tmp_path.iterdir() if p.name != ".out.lock"]      # no spare file left
    assert not lock.exists()
    lock.symlink_to(tmp_path / "victim")
    with pytest.raises(Exception, match="is a symbolic link"):
        OutputLock(tmp_path / "out").__enter__()
    assert not (tmp_path / "victim").exists()


# --- single output files ---------------------------------------------------------------------------------

def test_optimize_never_writes_over_its_input(tmp_path, capsys):
    src = tmp_path / "in.obj"
    src.write_bytes(MESH.read_bytes())
    (tmp_path / "hard.obj").hardlink_to(src)
    (tmp_path / "link.obj").symlink_to(src)
    for out in ("in.obj", "hard.obj", "link.obj", "./sub/../in.obj"):
        (tmp_path / "sub").mkdir(exist_ok=True)
        assert main(["optimize", str(src), "-o", str(tmp_path / out), "--force", "--quiet"]) == 2
        line = _one_error_line(capsys.readouterr().err)
        assert f"is the input {src}" in line, line
    assert src.read_bytes() == MESH.read_bytes()
    assert not [p for p in tmp_path.iterdir() if ".tmp-" in p.name]


def test_optimize_replaces_only_its_own_unchanged_output_and_only_with_force(tmp_path, capsys):
    out = tmp_path / "res.obj"
    out.write_text("# my mesh\nv 0 0 0\n")
    for extra in ([], ["--force"]):
        assert main(["optimize", str(MESH), "-o", str(out), "--quiet", *extra]) == 2
        line = _one_error_line(capsys.readouterr().err)
        assert ("--force to replace" in line) if not extra else ("was not written by ppfab" in line)
        assert out.read_text() == "# my mesh\nv 0 0 0\n"
    out.unlink()
    assert main(["optimize", str(MESH), "-o", str(out), "--quiet"]) in (0, 1)
    assert "targets" in capsys.readouterr().err                     # --quiet keeps the one result line
    assert written_by_ppfab(out)
    first = out.read_bytes()
    assert main(["optimize", str(MESH), "-o", str(out), "--quiet"]) == 2               # no --force
    assert "exists" in _one_error_line(capsys.readouterr().err)
    assert out.read_bytes() == first
    assert main(["optimize", str(MESH), "-o", str(out), "--quiet", "--force"]) in (0, 1)
    assert out.read_bytes() == first and written_by_ppfab(out)                    # same input, same bytes
    out.write_bytes(first.replace(b"v ", b"v  ", 1))                              # edited after ppfab wrote it
    assert not written_by_ppfab(out)
    assert main(["optimize", str(MESH), "-o", str(out), "--quiet", "--force"]) == 2
    assert out.read_bytes() == first.replace(b"v ", b"v  ", 1)
    capsys.readouterr()


def test_a_file_that_appears_while_optimize_writes_is_kept(tmp_path, hook, capsys):
    out = tmp_path / "res.off"
    hook(lambda target, tmp: target.write_text("saved by someone\n"))
    assert main(["optimize", str(MESH), "-o", str(out), "--quiet"]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "appeared while ppfab was writing it" in line
    assert out.read_text() == "saved by someone\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["res.off"]


def test_new_replaces_only_an_unedited_starter(tmp_path, capsys):
    out = tmp_path / "d.toml"
    out.write_text("[design]\nname = 'mine'\n")
    for extra in ([], ["--force"]):
        assert main(["new", "-o", str(out), *extra]) == 2
        _one_error_line(capsys.readouterr().err)
        assert out.read_text() == "[design]\nname = 'mine'\n"
    out.unlink()
    assert main(["new", "-o", str(out)]) == 0 and written_by_ppfab(out)
    assert main(["new", "-o", str(out), "--force"]) == 0 and written_by_ppfab(out)
    capsys.readouterr()
    edited = out.read_text().replace('name = "', 'name = "my ', 1)
    out.write_text(edited)
    assert main(["new", "-o", str(out), "--force"]) == 2
    assert "was not written by ppfab, or was changed since" in _one_error_line(capsys.readouterr().err)
    assert out.read_text() == edited
    src = tmp_path / "m.obj"
    src.write_bytes(MESH.read_bytes())
    (tmp_path / "m.toml").symlink_to(src)
    assert main(["new", str(src), "-o", str(tmp_path / "m.toml"), "--force"]) == 2
    assert "is the input" in _one_error_line(capsys.readouterr().err)
    assert src.read_bytes() == MESH.read_bytes()
    assert not [p for p in tmp_path.iterdir() if ".tmp" in p.name]
