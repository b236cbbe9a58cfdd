"""``ppfab --help`` and ``ppfab --version`` start without the numerical and CAD libraries (start-up time), and a
signal during start-up (while the heavy libraries are imported) stops a run at once."""

import signal
import subprocess
import sys
import time

import pytest

from conftest import REPO, small_design

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


# A library import that takes a minute (as the CAD kernel's can on a loaded machine or a cold disk): the hook
# writes the marker file when the import starts, then sleeps in the import.
SLOW_IMPORT = """
import pathlib, sys, time

class SlowImport:
    def find_spec(self, name, path=None, target=None):
        if name == "build123d":
            pathlib.Path(sys.argv[1]).write_text("importing")
            time.sleep(60)
        return None

sys.meta_path.insert(0, SlowImport())
from fabrication.cli import main
sys.exit(main(sys.argv[2:]))
"""


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_during_a_slow_import_stops_the_build_at_once(tmp_path, signum):
    """Ctrl-C or SIGTERM while ``ppfab build`` imports its libraries stops it within 2 s (it used to be held
    until every import was done), with the one-line message and 128 + signal, and leaves nothing behind."""
    (tmp_path / "d.toml").write_text(small_design())
    marker = tmp_path / "importing"
    proc = subprocess.Popen([sys.executable, "-c", SLOW_IMPORT, str(marker), "build", str(tmp_path / "d.toml"),
                             "-o", str(tmp_path / "out"), "--quiet"], cwd=REPO, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        t0 = time.monotonic()
        while not marker.exists():
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() - t0 < 120, "the build never reached the import"
            time.sleep(0.02)
        sent = time.monotonic()
        proc.send_signal(signum)
        out, err = proc.communicate(timeout=30)
        took = time.monotonic() - sent
    finally:
        proc.kill()
    name = signal.Signals(signum).name
    assert took < 2.0, f"{took:.1f} s from {name} to exit"
    assert proc.returncode == 128 + signum, err
    assert err == f"ppfab: interrupted ({name})\n", err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.toml", "importing"]    # no output, lock or temp


def test_an_import_error_or_a_swallowed_signal_during_the_imports_is_the_interruption():
    """A C extension interrupted in its initialisation may raise ImportError instead, and a library may catch the
    KeyboardInterrupt and go on: either way the run stops as interrupted by that signal (then 143, not a
    traceback or a build that goes on); an ImportError without a signal stays an ImportError."""
    from fabrication.cli import Interrupted, interruptible_imports
    from fabrication.interrupts import SIGNALS

    try:
        with pytest.raises(Interrupted) as info:
            with interruptible_imports():
                SIGNALS["last"] = signal.SIGTERM          # what the handler records before it raises
                raise ImportError("initialisation of _OCP failed")
        assert info.value.signum == signal.SIGTERM and info.value.__cause__ is None
        with pytest.raises(Interrupted) as info:
            with interruptible_imports():
                SIGNALS["last"] = signal.SIGINT           # recorded, then swallowed by the library
        assert info.value.signum == signal.SIGINT
        with pytest.raises(ImportError):
            with interruptible_imports():
                raise ImportError("no module named build123d")
    finally:
        SIGNALS["last"] = None


# The interruption raised where Python ignores exceptions: the handler runs inside a weak-reference callback (as
# in the import system's module locks), Python reports "Exception ignored in …" and goes on.
SWALLOWED = """
import signal, sys, weakref
from fabrication import progress

start = progress.Progress.start

def start_swallowing(self, stage, detail=""):
    if stage == "quality":
        class Referent:
            pass
        referent = Referent()
        ref = weakref.ref(referent, lambda r: signal.raise_signal(signal.SIGHUP))
        del referent                    # the callback runs here, the handler raises in it, Python ignores that
        print("went on", file=sys.stderr)
    return start(self, stage, detail)

progress.Progress.start = start_swallowing
from fabrication.cli import main
sys.exit(main(sys.argv[1:]))
"""


def test_an_interruption_swallowed_in_a_weakref_callback_still_stops_the_build(tmp_path):
    """SIGHUP whose handler ran inside a weak-reference callback (Python ignores what it raises there; the
    build went on and exited 0) stops the build at its next step: 129, the one-line message and no "Exception
    ignored" report, no output folder, lock or temporary folder."""
    (tmp_path / "d.toml").write_text(small_design())
    r = subprocess.run([sys.executable, "-c", SWALLOWED, "build", str(tmp_path / "d.toml"), "-o",
                        str(tmp_path / "out"), "--quiet"], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert r.stderr == "went on\nppfab: interrupted (SIGHUP)\n", r.stderr       # the swallowing did happen
    assert r.returncode == 128 + signal.SIGHUP
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.toml"]
