"""The geometry core never imports the fabrication layer or heavy CAD/file libraries (DESIGN.md)."""

import subprocess
import sys

from conftest import REPO

BLOCKED = ["build123d", "ezdxf", "matplotlib", "spyrrow", "rectpack", "fabrication", "OCP"]


def test_core_imports_without_fabrication_libraries():
    code = f"""
import sys, pkgutil, importlib
for name in {BLOCKED!r}:
    sys.modules[name] = None
import ppfab
mods = []
for info in pkgutil.walk_packages(ppfab.__path__, 'ppfab.'):
    if info.name.startswith('ppfab.cli'):
        continue
    importlib.import_module(info.name)
    mods.append(info.name)
from ppfab.constructions import load_all
load_all()
print(len(mods))
"""
    out = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert int(out.stdout.strip()) >= 8


def test_version_is_instant_and_light():
    code = "import sys; from ppfab.cli import main\n" \
           "try:\n    main(['--version'])\nexcept SystemExit:\n    pass\n" \
           "print(','.join(m for m in " + repr(BLOCKED) + " if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("ppfab ")
    assert out.stdout.splitlines()[-1] == ""  # none of the heavy modules was imported
