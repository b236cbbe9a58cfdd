"""The examples carry what they need: they are package data, the meshes they read are bundled beside them
(byte for byte as their README records), and ``ppfab examples`` / ``ppfab build --example`` find them."""

from __future__ import annotations

import hashlib
import re
import subprocess
import sys
import zipfile

import pytest

from fabrication.cli import main
from fabrication.design import load_design
from fabrication.examples import EXAMPLES_DIR, example_path, examples

from conftest import REPO


def test_examples_are_the_repository_examples():
    assert EXAMPLES_DIR.resolve() == (REPO / "examples").resolve()
    assert [e.name for e in examples()] == sorted(p.stem for p in (REPO / "examples").glob("*.toml"))


@pytest.mark.parametrize("example", examples(), ids=lambda e: e.name)
def test_every_input_file_is_inside_the_examples(example):
    """No example reads a file outside the bundled examples (a path such as ``../../shared/…`` would not exist
    once ppfab is installed)."""
    design = load_design(example.path)
    mesh = design.mesh_path()
    if mesh is not None:
        assert mesh.is_file() and mesh.resolve().is_relative_to(EXAMPLES_DIR.resolve()), mesh


def test_bundled_meshes_match_their_provenance():
    readme = (EXAMPLES_DIR / "meshes" / "README.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| `([^`]+)` \| \[([\w.-]+/[\w.-]+)\][^|]*\| `([^`]+)` \| `([0-9a-f]{40})` \| `([0-9a-f]{64})`",
                      readme, re.M)
    files = sorted(p.name for p in (EXAMPLES_DIR / "meshes").iterdir() if p.suffix in (".obj", ".off"))
    assert sorted(r[0] for r in rows) == files and files
    for name, _repo, _path, _commit, digest in rows:
        assert hashlib.sha256((EXAMPLES_DIR / "meshes" / name).read_bytes()).hexdigest() == digest, name


def test_examples_command_lists_every_example(capsys):
    assert main(["examples"]) == 0
    out = capsys.readouterr().out
    for e in examples():
        assert re.search(rf"^{re.escape(e.name)}\s", out, re.M), e.name
    assert main(["examples", "--path", "smallest_roof"]) == 0
    assert capsys.readouterr().out.strip() == str(example_path("smallest_roof"))


def test_unknown_example_is_one_line_with_the_names(capsys, tmp_path):
    assert main(["build", "--example", "smalest_roof", "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("ppfab: error: --example:") and "smallest_roof" in err and "\n" not in err
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_wheel_carries_the_examples_and_their_meshes(tmp_path):
    """``pip wheel .`` packs every example and every mesh it reads (the package-data globs of pyproject)."""
    out = subprocess.run([sys.executable, "-m", "pip", "wheel", str(REPO), "--no-deps", "-q", "-w", str(tmp_path)],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    names = set(zipfile.ZipFile(next(tmp_path.glob("*.whl"))).namelist())
    for e in examples():
        assert f"fabrication/data/examples/{e.name}.toml" in names
        if e.mesh:
            assert f"fabrication/data/examples/{e.mesh}" in names
    assert "fabrication/data/examples/meshes/README.md" in names
