"""Every class of bad input tried against ppfab, with the message it must get.

Shared by ``tests/test_bad_input.py`` (each row is a test) and ``docs/gen_bad_input.py`` (which writes
the table in ``docs/bad-input.md`` from the messages actually printed).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from conftest import small_design

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"

GEOMETRY = small_design(fast=False)
FAST = "\n[nesting]\ntime_budget = 0.3\n[beam_nesting]\ntime_budget = 0.3\n"

GRID_OBJ = "".join(f"v {x} {y} 0\n" for y in range(3) for x in range(3)) + \
    "f 1 2 5 4\nf 2 3 6 5\nf 4 5 8 7\nf 5 6 9 8\n"


@dataclass(frozen=True)
class Case:
    kind: str          # what class of input
    what: str          # the bad input, in words
    files: dict        # file name → text, written into a temporary folder
    argv: Callable[[Path], list[str]]
    code: int          # expected exit code
    message: str       # substring the one-line error must contain


def build(name: str = "d.toml") -> Callable[[Path], list[str]]:
    return lambda d: ["build", str(d / name), "-o", str(d / "out"), "--quiet"]


def check(name: str) -> Callable[[Path], list[str]]:
    return lambda d: ["check", str(d / name)]


def design(text: str, fast: bool = True) -> dict:
    return {"d.toml": text + (FAST if fast else "")}


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
    # mesh files
    Case("mesh file", "unreadable / missing", {}, check("none.obj"), 2, "cannot read"),
    Case("mesh file", "unknown format", {"m.stl": "solid x"}, check("m.stl"), 2, "unknown mesh format '.stl'"),
    Case("mesh file", "not quads", {"m.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"}, check("m.obj"), 2,
         "face 0 (line 4) has 3 corners; 1 face(s) are not quads"),
    Case("mesh file", "NaN coordinates", {"m.obj": GRID_OBJ.replace("v 1 1 0", "v 1 nan 0")}, check("m.obj"), 2,
         "vertex 4 has a non-finite coordinate"),
    Case("mesh file", "inf coordinates", {"m.obj": GRID_OBJ.replace("v 1 1 0", "v 1 inf 0")}, check("m.obj"), 2,
         "non-finite coordinate"),
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
    Case("geometry", "folded mesh", {"d.toml": "[geometry]\nmesh = 'fold.obj'\n" + FAST,
                                     "fold.obj": "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nv 0.5 0 0.1\n"
                                                 "v 0.5 1 0.1\nf 1 2 3 4\nf 2 5 6 3\nf 5 7 8 6\n"},
         build(), 1, "the mesh is folded"),
    Case("geometry", "beams meeting at too small an angle", design(GEOMETRY + "[beams]\nmin_angle_deg = 89.5\n"),
         build(), 1, "B-U00-S00 and B-W00-S00 meet at node 0 at 86.3° (< min_angle_deg 89.5°)"),
    Case("geometry", "a part larger than the stock sheet",
         design(GEOMETRY + "[nesting]\nsheet = [1500.0, 1000.0]\ntime_budget = 0.3\n", False), build(), 1,
         "part P-U00-V00 (2185.7 x 2059.7 mm) fits no sheet: usable area is 1500.0 x 1000.0 mm"),
]
