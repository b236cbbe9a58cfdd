"""The README's quick start runs as written: each of its commands, in order, in a fresh folder, ends in a
report that ``ppfab verify`` accepts."""

from __future__ import annotations

import json
import re
import shlex

from fabrication.cli import main

from conftest import REPO


def quickstart_commands() -> list[list[str]]:
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    section = readme.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    block = re.search(r"```bash\n(.*?)\n```", section, re.S)
    assert block, "no bash block in the quick start"
    return [shlex.split(line) for line in block.group(1).splitlines() if line.strip()]


def test_quickstart_from_nothing_to_a_verified_report(tmp_path, monkeypatch, capsys):
    commands = quickstart_commands()
    assert [c[:2] for c in commands] == [["ppfab", "new"], ["ppfab", "build"], ["ppfab", "verify"]]
    monkeypatch.chdir(tmp_path)
    for argv in commands:
        assert main(argv[1:]) == 0, argv
    out = tmp_path / commands[1][commands[1].index("-o") + 1]
    assert (out / "report.html").is_file()
    manifest = json.loads((out / "manifest.json").read_text(encoding="utf-8"))
    assert manifest["summary"]["panels"] == 16
    assert "Warning" not in capsys.readouterr().err
