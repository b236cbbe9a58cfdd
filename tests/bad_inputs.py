"""Every class of bad input tried against ppfab, with the message it must get.

Shared by ``tests/test_bad_input.py`` (each row is a test) and ``docs/gen_bad_input.py`` (which writes
the table in ``docs/bad-input.md`` from the messages actually printed).  :func:`run_case` runs a case the
way it needs: in this process (``main(argv)``), or in a separate ``python -m fabrication.cli`` process —
for inputs that could hang a process (FIFOs, devices), for real signals sent to a running build
(``signal:SIGTERM``…), for a build killed with SIGKILL and run again (``kill-then-rerun``) and for two
builds at once (``concurrent``).
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import io
import json
import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, ContextManager
from unittest import mock

from conftest import REPO, SHARED_DATA, small_design

DATA = SHARED_DATA

GEOMETRY = small_design(fast=False)
FAST = "\n[nesting]\ntime_budget = 0.3\n[beam_nesting]\ntime_budget = 0.3\n"

GRID_OBJ = "".join(f"v {x} {y} 0\n" for y in range(3) for x in range(3)) + \
    "f 1 2 5 4\nf 2 3 6 5\nf 4 5 8 7\nf 5 6 9 8\n"
GRID_OFF = "OFF\n9 4 0\n" + "".join(f"{x} {y} 0\n" for y in range(3) for x in range(3)) + \
    "4 0 1 4 3\n4 1 2 5 4\n4 3 4 7 6\n4 4 5 8 7\n"


def _grid_obj(n: int) -> str:
    """An ``n x n``-vertex flat grid as OBJ text."""
    v = "".join(f"v {x} {y} 0\n" for y in range(n) for x in range(n))
    f = "".join(f"f {y * n + x + 1} {y * n + x + 2} {(y + 1) * n + x + 2} {(y + 1) * n + x + 1}\n"
                for y in range(n - 1) for x in range(n - 1))
    return v + f


def _crossing_strip_obj() -> str:
    """A vertical strip along the figure eight x = 3 sin t, y = 3 sin t cos t, t in [−1, π + 1] (27 samples,
    step (π + 2)/26): planar faces, no fold, but it passes through itself at the origin, t = 0 in face
    ⌊1/step⌋ = 5 and t = π in face ⌊(π + 1)/step⌋ = 20."""
    import numpy as np

    t = np.linspace(-1.0, np.pi + 1.0, 27)
    xy = np.c_[3 * np.sin(t), 3 * np.sin(t) * np.cos(t)]
    v = "".join(f"v {float(x)!r} {float(y)!r} {z}\n" for z in (0.0, 1.5) for x, y in xy)
    n = len(t)
    f = "".join(f"f {k + 1} {k + 2} {n + k + 2} {n + k + 1}\n" for k in range(n - 1))
    return v + f


FIGURE_EIGHT_OBJ = ("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\nv 2 2 0\nv 1 2 0\n"
                    "f 1 2 3 4\nf 5 6 7 8\n")
"""Two quads touching in one corner (1, 1) through two different vertices: a figure 8."""


@dataclass(frozen=True)
class Case:
    kind: str          # what class of input
    what: str          # the bad input, in words
    files: dict        # file name → text, written into a temporary folder
    argv: Callable[[Path], list[str]]
    code: int          # expected exit code
    message: str       # substring the one-line error (or, exit 0, the output) must contain
    process: str = ""  # "" in this process; "subprocess", "signal:SIGTERM", "kill-then-rerun", "concurrent"
    setup: Callable[[Path], None] | None = None       # more preparation (FIFOs, symlinks, big files)
    patch: Callable[[], ContextManager] | None = None  # in-process: what to replace while it runs
    check: Callable[[Path], None] | None = None       # more assertions on the folder afterwards
    cwd: str = ""      # folder (relative to the case folder) to run in
    note: str = ""     # what happens, for rows without a message
    new_files: tuple = field(default=())              # names the run may add to the case folder


def build(name: str = "d.toml", out: str = "out", *extra: str) -> Callable[[Path], list[str]]:
    return lambda d: ["build", str(d / name), "-o", str(d / out), "--quiet", *extra]


def check(name: str) -> Callable[[Path], list[str]]:
    return lambda d: ["check", str(d / name)]


def design(text: str, fast: bool = True) -> dict:
    return {"d.toml": text + (FAST if fast else "")}


# -- running a case ------------------------------------------------------------------------------------

def _env() -> dict:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]),
               OMP_NUM_THREADS="1")
    env.pop("PPFAB_DEBUG", None)
    return env


def _popen(argv: list[str], cwd: Path) -> subprocess.Popen:
    # SIGINT restored to its default: a process started in the background inherits it ignored
    return subprocess.Popen([sys.executable, "-m", "fabrication.cli", *argv], cwd=cwd, env=_env(),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _wait_for(found: Callable[[], bool], proc: subprocess.Popen, timeout: float = 240.0) -> None:
    t0 = time.monotonic()
    while not found():
        if proc.poll() is not None:
            raise AssertionError(f"the run ended (exit {proc.returncode}) before it could be interrupted: "
                                 f"{proc.stderr.read() if proc.stderr else ''}")
        if time.monotonic() - t0 > timeout:
            proc.kill()
            raise AssertionError("timed out waiting for the run")
        time.sleep(0.02)


def temp_folders(d: Path) -> list[str]:
    return sorted(p.name for p in d.iterdir() if ".tmp-" in p.name or ".old-" in p.name)


def prepare_case(case: Case, d: Path) -> None:
    """Write the case's files into the folder ``d`` and run its setup."""
    for name, text in case.files.items():
        p = d / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text, encoding="utf-8")
    if case.setup is not None:
        case.setup(d)


def run_case(case: Case, d: Path, prepared: bool = False) -> tuple[int, str, str]:
    """Prepare the case in the folder ``d`` (unless ``prepared``) and run it; returns ``(exit code, stdout,
    stderr)``."""
    if not prepared:
        prepare_case(case, d)
    cwd = d / case.cwd if case.cwd else d
    argv = case.argv(d)
    if not case.process:
        from fabrication.cli import main

        out, err = io.StringIO(), io.StringIO()
        with contextlib.chdir(cwd), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
                (case.patch() if case.patch else contextlib.nullcontext()):
            code = main(argv)
        return code, out.getvalue(), err.getvalue()
    if case.process == "subprocess":
        r = subprocess.run([sys.executable, "-m", "fabrication.cli", *argv], cwd=cwd, env=_env(),
                           capture_output=True, text=True, timeout=300)
        return r.returncode, r.stdout, r.stderr
    proc = _popen(argv, cwd)
    if case.process.startswith("signal:"):
        _wait_for(lambda: any(".tmp-" in n for n in temp_folders(d)), proc)
        proc.send_signal(getattr(signal, case.process.split(":", 1)[1]))
        out, err = proc.communicate(timeout=240)
        return proc.returncode, out, err
    if case.process == "kill-then-rerun":
        _wait_for(lambda: any(".tmp-" in n for n in temp_folders(d)), proc)
        proc.kill()
        proc.communicate(timeout=60)
        assert proc.returncode == -signal.SIGKILL and temp_folders(d), "SIGKILL leaves the temporary folder"
        r = subprocess.run([sys.executable, "-m", "fabrication.cli", *argv], cwd=cwd, env=_env(),
                           capture_output=True, text=True, timeout=600)
        return r.returncode, r.stdout, r.stderr
    if case.process == "concurrent":
        _wait_for(lambda: (d / ".out.lock").exists(), proc)
        r = subprocess.run([sys.executable, "-m", "fabrication.cli", *argv], cwd=cwd, env=_env(),
                           capture_output=True, text=True, timeout=300)
        proc.send_signal(signal.SIGTERM)
        proc.communicate(timeout=240)
        return r.returncode, r.stdout, r.stderr
    raise ValueError(f"unknown process kind {case.process!r}")


# -- preparations and checks -----------------------------------------------------------------------------

def _mkfifo(name: str) -> Callable[[Path], None]:
    return lambda d: os.mkfifo(d / name)


def _symlink(name: str, target: str) -> Callable[[Path], None]:
    return lambda d: os.symlink(target if target.startswith("/") else d / target, d / name)


def _sparse(name: str, size: int) -> Callable[[Path], None]:
    def make(d: Path) -> None:
        with open(d / name, "wb") as fh:
            fh.truncate(size)
    return make


def _edited_build(d: Path) -> None:
    """A folder that was a ppfab build (manifest with the sha256 of its file), then edited by its owner."""
    out = d / "out"
    out.mkdir()
    (out / "parts.csv").write_text("part_id,kind\nP-00,panel\n")
    digest = hashlib.sha256((out / "parts.csv").read_bytes()).hexdigest()
    (out / "manifest.json").write_text(json.dumps({"generator": "ppfab 0.1.0", "sha256": {"parts.csv": digest}}))
    with open(out / "parts.csv", "a") as fh:
        fh.write("P-01,panel\n")


def _kept(path: str, text: str) -> Callable[[Path], None]:
    def check(d: Path) -> None:
        assert (d / path).read_text() == text, f"{path} was changed"
    return check


def _no_leftovers(d: Path) -> None:
    assert temp_folders(d) == [] and not (d / ".out.lock").exists()


def _verified(extra: Callable[[Path], None] | None = None) -> Callable[[Path], None]:
    def check(d: Path) -> None:
        from fabrication.verify import verify

        result = verify(d / "out")
        assert result.ok, [str(f) for f in result.findings[:5]]
        _no_leftovers(d)
        if extra is not None:
            extra(d / "out")
    return check


def _obj_one_header_line(out: Path) -> None:
    text = (out / "mesh.obj").read_text()
    m = json.loads((out / "manifest.json").read_text())["mesh"]
    assert text.count("\nv ") + text.startswith("v ") == m["vertices"] and text.count("\n#") == 0
    assert text.splitlines()[0].startswith("# ") and len(text.splitlines()) == m["vertices"] + m["faces"] + 1


def _dxf_text_clean(out: Path) -> None:
    import ezdxf

    for p in sorted(out.rglob("*.dxf"))[:5]:
        for e in ezdxf.readfile(p).modelspace():
            if e.dxftype() == "TEXT":
                assert not any(ord(c) < 32 for c in e.dxf.text), (p.name, e.dxf.text)


def _csv_formula_quoted(out: Path) -> None:
    import csv

    with open(out / "parts.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    materials = {r["material"] for r in rows if r["kind"] == "beam"}
    assert materials == {"'=HYPERLINK(\"http://x\")"}, materials
    doc = json.loads((out / "parts.json").read_text())
    assert {p["material"] for p in doc["parts"] if p["kind"] == "beam"} == {'=HYPERLINK("http://x")'}


def _marks_on_every_panel(out: Path) -> None:
    from fabrication.writers.dxf import read_sheet_dxf

    files = json.loads((out / "manifest.json").read_text())["files"]["glass_sheets"]
    for rel in files:
        c = read_sheet_dxf(out / rel)
        assert c.marks >= len(c.parts) > 0, (rel, c.marks, len(c.parts))


def _figure_note(out: Path) -> None:
    html = (out / "report.html").read_text()
    assert "could not be drawn (RuntimeError: no display for this figure)" in html


def _disk_full():
    def boom(rows, path):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
    return mock.patch("fabrication.writers.tables.write_parts_csv", boom)


def _figure_fails():
    def boom(*args, **kwargs):
        raise RuntimeError("no display for this figure")
    return mock.patch("fabrication.report.structure_png", boom)


def _numpy_warns():
    import numpy as np

    from ppfab import metrics

    original = metrics.quality

    def noisy(*args, **kwargs):
        np.float64(1.0) / np.float64(0.0)              # RuntimeWarning: divide by zero
        return original(*args, **kwargs)
    return mock.patch("ppfab.metrics.quality", noisy)


def _unextrudable_plate():
    """The first beam plate's outline with its second point repeated (a zero-length edge), as a degenerate end
    cut can leave it: Rhino's extrusion of it fails, the other writers are unaffected."""
    import dataclasses

    import numpy as np

    from fabrication.writers import rhino

    original = rhino.elements

    def spoiled(build):
        els = original(build)
        k = next(i for i, e in enumerate(els) if e.kind == "beam")
        o = np.asarray(els[k].outline, dtype=float)
        els[k] = dataclasses.replace(els[k], outline=np.insert(o, 2, o[1], axis=0))
        return els
    return mock.patch("fabrication.writers.rhino.elements", spoiled)


def _sized(name: str, text: str, size: int) -> Callable[[Path], None]:
    """``name`` holding ``text`` padded with newlines to ``size`` bytes (a sparse tail)."""
    def make(d: Path) -> None:
        with open(d / name, "wb") as fh:
            fh.write(text.encode())
            fh.truncate(size)
    return make


def _deep_arrays(levels: int) -> str:
    return GEOMETRY.replace("faces_u = 5", "faces_u = 5\nnested = " + "[" * levels + "]" * levels)


SIGNAL_DESIGN = design(GEOMETRY)

CASES = [
    # design files
    Case("design file", "malformed TOML", {"d.toml": "[geometry\nmethod = 1\n"}, build(), 2, "malformed TOML"),
    Case("design file", "file missing", {}, build(), 2, "cannot read design file"),
    Case("design file", "unknown key", design(GEOMETRY.replace("scale =", "scael =")), build(), 2,
         "geometry.scael: unknown key (did you mean 'scale'?)"),
    Case("design file", "unknown section", design(GEOMETRY + "[beam]\ndepth = 1\n"), build(), 2,
         "beam: unknown section (did you mean 'beams'?)"),
    Case("design file", "unknown construction method", design(GEOMETRY.replace('"face_image_curves"', '"bisectr"')),
         build(), 2, "geometry.method: unknown method 'bisectr' (did you mean 'bisector'?)"),
    Case("design file", "wrong type", design(GEOMETRY + "[beams]\ndepth = 'deep'\n"), build(), 2,
         "beams.depth: expected a number"),
    Case("design file", "negative thickness", design(GEOMETRY + "[beams]\nthickness = -12.0\n"), build(), 2,
         "beams.thickness: must be > 0"),
    Case("design file", "zero sheet size", design(GEOMETRY + "[nesting]\nsheet = [0.0, 3210.0]\n", False), build(), 2,
         "nesting.sheet[0]: must be > 0"),
    Case("design file", "spacing larger than the sheet",
         design(GEOMETRY + "[nesting]\nsheet = [6000.0, 3210.0]\nspacing = 5000.0\n", False), build(), 2,
         "nesting.spacing: part spacing 5000 mm is not smaller than the usable sheet"),
    Case("design file", "edge trim leaves no sheet", design(GEOMETRY + "[nesting]\nmargin = 2000.0\n", False),
         build(), 2, "nesting.margin: trim"),
    Case("design file", "missing required key", design(GEOMETRY.replace("g = [[0.0, 0.025]", "#")), build(), 2,
         "geometry.params.g: missing required key"),
    Case("design file", "missing [geometry]", design("[design]\nname = 'x'\n"), build(), 2,
         "geometry: missing required section"),
    Case("design file", "both a method and a mesh", design(GEOMETRY.replace("scale =", "mesh = 'x.obj'\nscale =")),
         build(), 2, "give exactly one of 'method'"),
    Case("design file", "beam pieces longer than the plate stock", design(GEOMETRY + "[beams]\nmax_length = 9000.0\n"),
         build(), 2, "beams.max_length: beam pieces up to 9000 mm do not fit"),
    Case("design file", "very large grid (2000 x 2000 faces)",
         design(GEOMETRY.replace("faces_u = 5", "faces_u = 2000").replace("faces_v = 4", "faces_v = 2000")),
         build(), 2, "pass --allow-large to proceed"),
    Case("design file", "output folder exists", {**design(GEOMETRY), "out/keep.txt": "x"}, build(), 2,
         "exists (use --force to replace it)"),
    Case("design file", "5,000 nested arrays in 10 kB (too deep for the TOML reader)", design(_deep_arrays(5000)),
         build(), 2, "d.toml: tables and arrays nested too deep to read (more than 16 levels; a design file needs "
                     "at most 5)"),
    Case("design file", "arrays nested 40 levels deep", design(_deep_arrays(40)), build(), 2,
         "geometry.params.nested[0][0][0][0][0][0][0][0][0][0][0][0][0][0]: tables and arrays nested more than 16 "
         "levels deep"),
    Case("design file", "a design file of 2 MiB", {}, build(), 2,
         "d.toml: 2.0 MiB is not a design file (at most 1 MiB of TOML)", setup=_sized("d.toml", GEOMETRY, 2 << 20)),
    Case("design file", "an empty design path", {}, lambda d: ["build", "", "-o", str(d / "out")], 2,
         "design: the path is empty; give the path of a file or folder"),
    Case("design file", "an empty mesh path (mesh = \"\")", design("[geometry]\nmesh = ''\n"), build(), 2,
         "geometry.mesh: the mesh path is empty; give the path of the mesh file (.obj or .off, relative to the "
         "design file), or a construction with 'method'"),
    Case("design file", "a NUL byte in the mesh path", design('[geometry]\nmesh = "m\\u0000.obj"\n'), build(), 2,
         "geometry.mesh: the path 'm\\x00.obj' holds a NUL byte, which no file name can hold"),
    Case("design file", "a BEL character in a key (escaped when quoted)",
         design(GEOMETRY.replace("scale =", "\"sca\\u0007le\" =")), build(), 2,
         "geometry.sca\\x07le: unknown key (did you mean 'scale'?)"),
    Case("design file", "a grid of 10^12 x 4 faces", design(GEOMETRY.replace("faces_u = 5", "faces_u = " + "1" + "0" * 12)),
         build(), 2, "geometry.params.faces_u: must be <= 4000, got 1000000000000"),
    Case("design file", "a FIFO (named pipe) as the design file", {}, build(), 2,
         "d.toml: is a FIFO (named pipe), not a regular design file", process="subprocess", setup=_mkfifo("d.toml")),
    Case("design file", "a number of 1e308", design(GEOMETRY.replace("scale = 1000.0", "scale = 1e308")), build(),
         2, "geometry.scale: 1e+308 is out of range (numbers up to 1e+15 in size)"),
    Case("design file", "the same nest-tag prefix for glass and plates",
         design(GEOMETRY + "[beam_nesting]\ntag_prefix = 'G'\n", False), build(), 2,
         "beam_nesting.tag_prefix: 'G' is also the glass prefix ([nesting] tag_prefix 'G'): nest tags would repeat"),
    Case("design file", "a nest-tag prefix ending in a digit", design(GEOMETRY + "[nesting]\ntag_prefix = 'G1'\n",
                                                                       False), build(), 2,
         "nesting.tag_prefix: must be ASCII letters and digits ending in a letter, got 'G1'"),
    # the output folder
    Case("output folder", "--force onto a folder holding someone's file", {**design(GEOMETRY), "out/keep.txt": "x"},
         build("d.toml", "out", "--force"), 2, "is not a previous ppfab build (it has no manifest.json of a ppfab build)",
         check=_kept("out/keep.txt", "x")),
    Case("output folder", "--force onto a previous build whose files were edited", design(GEOMETRY),
         build("d.toml", "out", "--force"), 2, "(parts.csv was changed after the build)", setup=_edited_build),
    Case("output folder", "-o . --force inside a project folder",
         {"proj/d.toml": GEOMETRY + FAST, "proj/notes.txt": "mine"},
         lambda d: ["build", "d.toml", "-o", ".", "--force", "--quiet"], 2,
         "output folder . is the current folder or holds it", cwd="proj", check=_kept("proj/notes.txt", "mine")),
    Case("output folder", "--force onto the folder of the design file", {"proj/d.toml": GEOMETRY + FAST},
         lambda d: ["build", str(d / "proj" / "d.toml"), "-o", str(d / "proj"), "--force", "--quiet"], 2,
         "holds the input", check=_kept("proj/d.toml", GEOMETRY + FAST)),
    Case("output folder", "a dangling symbolic link as -o", design(GEOMETRY), build(), 2,
         "is a symbolic link (to", setup=_symlink("out", "nowhere")),
    Case("output folder", "two builds to one output folder at once", SIGNAL_DESIGN, build(), 2,
         "is being written by another ppfab run (pid", process="concurrent", check=_no_leftovers),
    Case("output folder", "disk full while writing", design(GEOMETRY), build(), 1,
         "out/parts.csv: No space left on device; free some space or write elsewhere (nothing was written)", patch=_disk_full,
         check=_no_leftovers),
    Case("output folder", "ppfab optimize -o onto a folder", {"m.obj": GRID_OBJ, "res.obj/keep.txt": "x"},
         lambda d: ["optimize", str(d / "m.obj"), "-o", str(d / "res.obj")], 2, "res.obj: is a folder"),
    # signals during a build
    Case("signal", "SIGTERM during a build", SIGNAL_DESIGN, build(), 128 + signal.SIGTERM,
         "ppfab: interrupted (SIGTERM)", process="signal:SIGTERM", check=_no_leftovers),
    Case("signal", "SIGHUP during a build (terminal closed)", SIGNAL_DESIGN, build(), 128 + signal.SIGHUP,
         "ppfab: interrupted (SIGHUP)", process="signal:SIGHUP", check=_no_leftovers),
    Case("signal", "Ctrl-C (SIGINT) during a build", SIGNAL_DESIGN, build(), 128 + signal.SIGINT,
         "ppfab: interrupted (SIGINT)", process="signal:SIGINT", check=_no_leftovers),
    Case("signal", "SIGKILL during a build, then the same build again", SIGNAL_DESIGN, build(), 0, "",
         process="kill-then-rerun", check=_verified(), new_files=("out",),
         note="the next run removes the killed run's temporary folder (its marker names a dead process) and builds"),
    # mesh files
    Case("mesh file", "unreadable / missing", {}, check("none.obj"), 2, "cannot read"),
    Case("mesh file", "unknown format", {"m.stl": "solid x"}, check("m.stl"), 2, "unknown mesh format '.stl'"),
    Case("mesh file", "/dev/zero as the mesh", design("[geometry]\nmesh = '/dev/zero'\n"), build(), 2,
         "/dev/zero: is a character device, not a regular mesh file", process="subprocess"),
    Case("mesh file", "a .obj symlink to /dev/urandom", {}, check("m.obj"), 2,
         "is a character device (a symbolic link to /dev/urandom), not a regular mesh file", process="subprocess",
         setup=_symlink("m.obj", "/dev/urandom")),
    Case("mesh file", "a FIFO (named pipe) as the mesh", {}, check("m.obj"), 2, "is a FIFO (named pipe)",
         process="subprocess", setup=_mkfifo("m.obj")),
    Case("mesh file", "a file too large for geometry.max_vertices (refused from its size)",
         design("[geometry]\nmesh = 'm.obj'\n"), build(), 2,
         "m.obj: the file has 300 MiB, more than a mesh of geometry.max_vertices = 250000 vertices needs",
         setup=_sparse("m.obj", 300 << 20)),
    Case("mesh file", "more vertices than geometry.max_vertices (counted before parsing and optimising)",
         {"d.toml": "[geometry]\nmesh = 'm.obj'\nmax_vertices = 12\n[optimize]\nfamilies = 'both'\n" + FAST,
          "m.obj": _grid_obj(4)}, build(), 2, "the design makes about 16 vertices (> geometry.max_vertices = 12)"),
    Case("mesh file", "an OFF header announcing 300000 vertices (refused before parsing)",
         {"d.toml": "[geometry]\nmesh = 'm.off'\n" + FAST, "m.off": "OFF\n300000 1 0\n0 0 0\n"}, build(), 2,
         "the design makes about 300000 vertices (> geometry.max_vertices = 250000)"),
    Case("mesh file", "a face index of 10^23 (beyond 64 bits)",
         {"m.obj": GRID_OBJ.replace("f 1 2 5 4", "f 1 2 5 1" + "0" * 23)}, check("m.obj"), 2,
         "m.obj: face 0 (line 10) refers to vertex 99999999999999999999999, which does not exist (the file has "
         "9 vertices)"),
    Case("mesh file", "a face index of 10^23 in an OFF file",
         {"m.off": GRID_OFF.replace("4 0 1 4 3", "4 0 1 4 1" + "0" * 23)}, check("m.off"), 2,
         "m.off: face 0 (line 12) refers to vertex 100000000000000000000000, which does not exist"),
    Case("mesh file", "a vertex used by no face", {"m.obj": GRID_OBJ + "v 7 7 7\n"}, check("m.obj"), 2,
         "m.obj: vertex 9 is used by no face (1 unused vertex(es)); remove the unused vertices"),
    Case("mesh file", "300 MiB for ppfab check (refused from its size)", {}, check("m.obj"), 2,
         "m.obj: the file has 300 MiB, more than a mesh of geometry.max_vertices = 250000 vertices needs",
         setup=_sparse("m.obj", 300 << 20)),
    Case("mesh file", "300 MiB for ppfab check --allow-large (above the hard limit)", {},
         lambda d: ["check", str(d / "m.obj"), "--allow-large"], 2,
         "m.obj: the file has 300 MiB, more than the 256 MiB a mesh file may have; give a smaller mesh",
         setup=_sparse("m.obj", 300 << 20)),
    Case("mesh file", "a NUL byte in the mesh path", {}, lambda d: ["check", str(d / "m\x00.obj")], 2,
         "m\\x00.obj' holds a NUL byte, which no file name can hold; give the path of a file or folder"),
    Case("mesh file", "an escape sequence in the mesh path (escaped when quoted)", {},
         lambda d: ["check", str(d / "m\x1b[31m.obj")], 2,
         "m\\x1b[31m.obj' holds the control character \\x1b; give the path of a file or folder"),
    Case("mesh file", "an OFF header announcing fewer faces than the file holds",
         {"m.off": GRID_OFF.replace("9 4 0", "9 3 0")}, check("m.off"), 2,
         "OFF header announces 9 vertices and 3 faces, but the file goes on after face 2 (line 15)"),
    Case("mesh file", "a UTF-8 byte-order mark before the first v", {"m.obj": "\ufeff" + GRID_OBJ}, check("m.obj"), 0,
         "regular grid 3 x 3", note="read with all 9 vertices"),
    Case("mesh file", "coordinates of 1e308", {"m.obj": GRID_OBJ.replace("v 1 1 0", "v 1e308 1 0")}, check("m.obj"),
         2, "vertex 4 has a coordinate of 1e+308, beyond ±1e+12 (check the file's units)"),
    Case("mesh file", "not quads", {"m.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"}, check("m.obj"), 2,
         "face 0 (line 4) has 3 corners; 1 face(s) are not quads"),
    Case("mesh file", "NaN coordinates", {"m.obj": GRID_OBJ.replace("v 1 1 0", "v 1 nan 0")}, check("m.obj"), 2,
         "vertex 4 has a non-finite coordinate"),
    Case("mesh file", "inf coordinates", {"m.obj": GRID_OBJ.replace("v 1 1 0", "v 1 inf 0")}, check("m.obj"), 2,
         "non-finite coordinate"),
    Case("mesh file", "a figure 8: boundary vertices that coincide but are no seam", {"m.obj": FIGURE_EIGHT_OBJ},
         check("m.obj"), 2, "boundary vertices 2 and 4 coincide at [1.0, 1.0, 0.0] with no boundary edge in common: "
                            "the surface touches itself in a point"),
    Case("mesh file", "duplicate vertices", {"m.obj": GRID_OBJ + "v 1 1 0\nv 1 1 1\nv 2 1 1\nv 2 1 0.5\nf 10 11 12 13\n"},
         check("m.obj"), 2, "vertices 4 and 9 coincide"),
    Case("mesh file", "zero-area face", {"m.obj": "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3 4\n"}, check("m.obj"),
         2, "face 0 (line 5) has zero area"),
    Case("mesh file", "repeated corner", {"m.obj": GRID_OBJ.replace("f 1 2 5 4", "f 1 2 2 4")}, check("m.obj"), 2,
         "repeats a corner"),
    Case("mesh file", "non-manifold edge",
         {"m.obj": GRID_OBJ + "v 1 0 1\nv 1 1 1\nf 2 5 11 10\n"}, check("m.obj"), 2,
         "edge (1, 4) is shared by 3 faces (non-manifold)"),
    Case("mesh file", "inconsistent orientation", {"m.obj": GRID_OBJ.replace("f 2 3 6 5", "f 2 5 6 3")},
         check("m.obj"), 2, "inconsistent orientation"),
    Case("mesh file", "a raw mesh that is not a PP mesh yet",
         design(f"[geometry]\nmesh = '{DATA / 'DOS__heart.obj'}'\nscale = 1000.0\n[support]\nmethod = 'pp'\n"),
         build(), 1, "the mesh file is not a PP mesh yet (max δ_f 1.2e-01, max δ_P rows 7.1e-02 / cols 7.1e-02): "
                     "add an [optimize] section with families = \"both\""),
    # geometry that cannot be fabricated
    Case("geometry", "panels out of plane beyond the tolerance",
         design(f"[geometry]\nmesh = '{DATA / 'compas_libigl__tubemesh.off'}'\nscale = 1000.0\n"), build(), 1,
         "panel(s) deviate from their plane by more than 1 mm: P-U08-V00 117 mm"),
    Case("geometry", "a mesh that passes through itself",
         {"d.toml": "[geometry]\nmesh = 'm.obj'\nscale = 1000.0\n" + FAST, "m.obj": _crossing_strip_obj()},
         build(), 1, "the mesh passes through itself: faces 5 and 20 (OBJ order) meet though they share no corner"),
    Case("geometry", "folded mesh", {"d.toml": "[geometry]\nmesh = 'fold.obj'\n" + FAST,
                                     "fold.obj": "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nv 0.5 0 0.1\n"
                                                 "v 0.5 1 0.1\nf 1 2 3 4\nf 2 5 6 3\nf 5 7 8 6\n"},
         build(), 1, "the mesh is folded"),
    Case("geometry", "beams meeting at too small an angle", design(GEOMETRY + "[beams]\nmin_angle_deg = 89.5\n"),
         build(), 1, "B-U00-S00 and B-W00-S00 meet at node 0 at 86.3° (< min_angle_deg 89.5°)"),
    Case("geometry", "panes without enough bite on their glazing strips", design(GEOMETRY + "[glazing]\nwidth = 30.0\n"),
         build(), 1, "bite less than panels.min_bite = 15 mm on their glazing strip"),
    Case("geometry", "a part larger than the stock sheet",
         design(GEOMETRY + "[nesting]\nsheet = [1500.0, 1000.0]\ntime_budget = 0.3\n", False), build(), 1,
         "part P-U00-V00 (2161.2 x 2061.4 mm) fits no sheet: usable area is 1500.0 x 1000.0 mm, any rotation"),
    # optional files
    Case("optional file", "a beam plate outline Rhino cannot make a solid of (model.3dm)", design(GEOMETRY), build(),
         1, "model.3dm: B-U00-S00: Rhino cannot make a solid of its outline (its outline has a zero-length edge: points 1 and 2 "
         "of", patch=_unextrudable_plate, check=_no_leftovers),
    # text that goes into files
    Case("text", "a design name with a newline and an OBJ vertex line", design(GEOMETRY.replace(
        'name = "small"', 'name = "roof\\nv 1 2 3\\u2028f 1 2 3 4"')), build(), 0, "", check=_verified(_obj_one_header_line),
        new_files=("out",), note="builds; the name stays one comment line in mesh.obj (verified)"),
    Case("text", "a NUL byte and control characters in the design name (DXF TEXT)", design(GEOMETRY.replace(
        'name = "small"', 'name = "roof\\u0000\\u0007 A"')), build(), 0, "", check=_verified(_dxf_text_clean),
        new_files=("out",), note="builds; DXF TEXT without control characters (verified)"),
    Case("text", "a spreadsheet formula as the beam material (CSV injection)",
         design(GEOMETRY + "[beams]\nmaterial = '=HYPERLINK(\"http://x\")'\n"), build(), 0, "",
         check=_verified(_csv_formula_quoted), new_files=("out",),
         note="builds; the CSV cell is written '=HYPERLINK(…), parts.json keeps the text (verified)"),
    Case("design file", "a glass make-up in words, not plies (\"toughened 10 mm\")",
         design(GEOMETRY + "[panels]\nmakeup = \"toughened 10 mm\"\n"), build(), 2,
         "panels.makeup: ply 1 'toughened 10 mm' is not '<mm> <kind>'"),
    Case("design file", "a monolithic make-up on a roof (overhead glazing)",
         design(GEOMETRY + "[panels]\nmakeup = \"10 FT\"\n"), build(), 2,
         "must be laminated safety glass"),
    Case("text", "a mark_size larger than the panels", design(GEOMETRY + "[panels]\nmark_size = 1e6\n"), build(), 0,
         "", check=_verified(_marks_on_every_panel), new_files=("out",),
         note="builds; each panel's mark is reduced to the largest that fits (a warning says so), none is dropped"),
    # figures and warnings
    Case("report", "a small translational design whose node angles are all equal (\"Too many bins\")",
         design("[geometry]\nmethod = 'translational'\nscale = 1000.0\n[geometry.params]\n"
                "a_points = [[-3.0, 0.0], [0.0, 1.0], [3.0, 0.0]]\nb_points = [[-2.0, 0.0], [0.0, 0.5], [2.0, 0.0]]\n"
                "faces_u = 3\nfaces_v = 3\n"), build(), 0, "", check=_verified(), new_files=("out",),
         note="builds; equal values make a one-bin histogram"),
    Case("report", "a figure that cannot be drawn", design(GEOMETRY), build(), 0, "", patch=_figure_fails,
         check=_verified(_figure_note), new_files=("out",),
         note="builds; the report says which figure could not be drawn and why"),
    Case("report", "a numpy RuntimeWarning during a run", {"m.obj": GRID_OBJ}, check("m.obj"), 0, "regular grid 3 x 3",
         patch=_numpy_warns, note="no warning text on stderr (it goes to the log, shown with --verbose)"),
]
