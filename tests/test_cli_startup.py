"""``ppfab --help`` and ``ppfab --version`` start without the numerical and CAD libraries (start-up time)."""

import subprocess
import sys

from conftest import REPO

HEAVY = ("scipy", "numpy", "build123d", "OCP", "ezdxf", "matplotlib", "shapely", "trimesh", "ifcopenshell",
         "rhino3dm", "tqdm")


def test_help_imports_no_heavy_library():
    code = ("import sys\nfrom fabrication.cli import main\n"
            "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            f"print(sorted(m for m in {HEAVY!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip().splitlines()[-1] == "[]"
    assert "new" in out.stdout and "examples" in out.stdout
