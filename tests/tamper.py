"""Helpers of the tamper tests: a fresh copy of a built folder, the manifest's sha256 updated after a change (as
someone covering their tracks would), the findings of ``ppfab verify``, and CSV rows read and written back."""

from __future__ import annotations

import csv
import hashlib
import io
import json
import shutil

import pytest

from fabrication.cli import main


@pytest.fixture
def copy(built, tmp_path):
    """A copy of the module's ``built`` folder to tamper with."""
    out = tmp_path / "copy"
    shutil.copytree(built, out)
    return out


def reseal(folder, *names):
    """Update the manifest's sha256 of the tampered files, as someone covering their tracks would."""
    m = json.loads((folder / "manifest.json").read_text())
    for name in names:
        m["sha256"][name] = hashlib.sha256((folder / name).read_bytes()).hexdigest()
    (folder / "manifest.json").write_text(json.dumps(m, indent=2))


def findings(folder, capsys) -> str:
    """What ``ppfab verify`` prints for a folder it must fail."""
    capsys.readouterr()
    assert main(["verify", str(folder), "--quiet"]) == 1
    return capsys.readouterr().err


def read_rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def write_rows(path, rows):
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    path.write_text(buf.getvalue())
