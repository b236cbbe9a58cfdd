"""Both packages type-check: ``python -m mypy ppfab fabrication`` with the ``[tool.mypy]`` settings of
pyproject.toml reports no error.

The settings ignore missing imports only for third-party modules that ship without type information
(scipy, shapely, mpl_toolkits, OCP; tomli where Python has tomllib), so an untyped import of ppfab or fabrication
itself, a wrong annotation or an unchecked ``None`` fails here.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys

import pytest

from conftest import REPO

pytestmark = pytest.mark.skipif(importlib.util.find_spec("mypy") is None,
                                reason="mypy is not installed (pip install '.[test]' installs it)")


def test_mypy_reports_no_error_on_both_packages():
    proc = subprocess.run([sys.executable, "-m", "mypy", "--config-file", str(REPO / "pyproject.toml"),
                           "ppfab", "fabrication"],
                          cwd=REPO, capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, f"mypy exit {proc.returncode}:\n{proc.stdout}{proc.stderr}"
    assert "Success: no issues found" in proc.stdout, proc.stdout
