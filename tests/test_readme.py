"""The README stays true: its two commands are what CI runs, and it documents every design-file key."""

import re
import subprocess
import sys

from conftest import REPO


def test_ci_runs_the_readme_commands():
    readme = (REPO / "README.md").read_text()
    blocks = re.findall(r"```bash\n(.*?)\n```", readme, re.S)
    install, tests = blocks[0].strip(), blocks[1].strip()
    ci = (REPO / ".ci" / "run").read_text()
    assert "pip install . && ppfab build -o" in install
    assert "pip install . && ppfab build -o" in ci
    assert tests in ci


def test_readme_documents_every_design_key():
    out = subprocess.run([sys.executable, str(REPO / "docs" / "gen_reference.py")], capture_output=True, text=True,
                         cwd=REPO)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() in (REPO / "README.md").read_text(), \
        "README design-key tables are stale: run python docs/gen_reference.py --write"


def test_readme_images_and_examples_exist():
    readme = (REPO / "README.md").read_text()
    for path in re.findall(r"\]\(((?:docs|examples)/[^)]+)\)", readme):
        assert (REPO / path).exists(), path
