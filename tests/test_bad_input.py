"""Each class of bad input gets one clear line naming what is wrong, a non-zero exit, no traceback and no
output folder; the cases that must work despite hostile input (signals, killed runs, text that could break a
file) exit as documented and leave a verified folder or nothing.  The table in docs/bad-input.md is generated
from the same cases (``tests/bad_inputs.py``); cases that need one run in a separate process."""

import re

import pytest

from bad_inputs import CASES, prepare_case, run_case
from conftest import SHARED_DATA, shared_file


@pytest.mark.parametrize("case", CASES, ids=[f"{c.kind}:{c.what}" for c in CASES])
def test_bad_input(tmp_path, case):
    for name in re.findall(re.escape(str(SHARED_DATA)) + r"/([\w.\-]+)", repr(case.files)):
        shared_file(name)                          # a case built on a real mesh of the shared data: skip without it
    prepare_case(case, tmp_path)
    before = sorted(p.name for p in tmp_path.iterdir())
    code, out, err = run_case(case, tmp_path, prepared=True)
    assert code == case.code, err
    assert "Traceback" not in err and "Warning" not in err, err
    if case.code != 0:
        assert err.startswith("ppfab: ") and err.count("\n") == 1, err
        assert case.message in err, err
    else:
        assert err == "", err
        assert case.message in out, out
    if case.check is not None:
        case.check(tmp_path)
    # nothing written beside the inputs (the output folder only appears on success)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(set(before) | set(case.new_files))


def test_rhino_names_what_is_wrong_with_an_outline_it_cannot_make_a_solid_of():
    """A real outline rhino3dm refuses to extrude (a repeated point: a zero-length edge), without any patching:
    the error names the part and the defect, where it used to say only that the extrusion failed."""
    import numpy as np

    from fabrication.writers._elements import Element
    from fabrication.writers.rhino import RhinoModel
    from ppfab.errors import FabricationError
    from ppfab.frame import Frame

    frame = Frame(np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    square = np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 50.0], [0.0, 50.0]])
    model = RhinoModel("t")
    model.add(Element("B-OK", "beam", "rows", "B", square, frame, -6.0, 12.0), "S355")
    assert len(model.f.Objects) == 1
    spoiled = np.insert(square, 2, square[1], axis=0)
    with pytest.raises(FabricationError) as info:
        model.add(Element("B-R0077-S01", "beam", "rows", "B", spoiled, frame, -6.0, 12.0), "S355")
    assert str(info.value) == ("B-R0077-S01: Rhino cannot make a solid of its outline (its outline has a zero-length "
                               "edge: points 1 and 2 of 5 coincide at (100.000, 0.000) mm (1 such edge(s)))")
    assert len(model.f.Objects) == 1                      # nothing half-added
    # a plate bevelled under its strips (two faces: a closed mesh, not an extrusion) with the same defect
    top = square + np.array([[0.0, 0.0], [0.0, 0.0], [-2.0, 0.0], [0.0, 0.0]])
    model.add(Element("B-BEV", "beam", "rows", "B", square, frame, -6.0, 12.0, outline_top=top), "S355")
    assert len(model.f.Objects) == 2
    with pytest.raises(FabricationError) as info:
        model.add(Element("B-R0078-S01", "beam", "rows", "B", spoiled, frame, -6.0, 12.0,
                          outline_top=np.insert(top, 2, top[1], axis=0)), "S355")
    assert str(info.value).startswith("B-R0078-S01: Rhino cannot make a solid of its outline (its outline has a "
                                      "zero-length edge: points 1 and 2 of 5 coincide at (100.000, 0.000) mm")
    assert len(model.f.Objects) == 2


@pytest.mark.parametrize("outline, height, problem", [
    ([[0, 0], [1, 0], [2, 0]], 10.0, "its outline encloses no area (3 points on one line)"),
    ([[0, 0], [1, 0], [1, 1]], 0.0, "its height is 0 mm, not a positive length"),
    ([[0, 0], [1, 0]], 10.0, "its outline has 2 point(s), fewer than 3"),
    ([[0, 0], [1, 0], [1, float("nan")]], 10.0, "its outline has a non-finite coordinate"),
    ([[0, 0], [1, 0], [1, 1]], 10.0, "no defect found in its outline"),
])
def test_outline_problem_names_the_defect(outline, height, problem):
    import numpy as np

    from fabrication.writers._failures import outline_problem

    assert outline_problem(np.array(outline, dtype=float), height) == problem


def test_only_optional_writers_are_guarded_and_disk_errors_keep_their_message(tmp_path):
    """A failing optional writer names its file and the [output] key; a required one is left as it is, and an
    operating-system error (disk full) passes through unchanged to its own one-line message."""
    import errno

    from fabrication.writers import load_writers
    from fabrication.writers._failures import OptionalFileError, guarded
    from fabrication.writers.base import Writer

    writers = {w.name: w for w in load_writers()}
    assert guarded(writers["mesh"]) is writers["mesh"] and guarded(writers["step"]) is writers["step"]

    def fails(exc):
        def write(build, out, files):
            raise exc
        return write

    for name, key, file in (("ifc", "ifc", "model.ifc"), ("rhino", "rhino", "model.3dm"), ("glb", "glb", "model.glb")):
        w = guarded(Writer(name, 1, fails(ValueError("bad polygon")), lambda design: True))
        with pytest.raises(OptionalFileError) as info:
            w.write(None, tmp_path, {})
        assert str(info.value) == (f"{file}: could not be written (ValueError: bad polygon); it is optional: "
                                   f"set [output] {key} = false to build without it")
    disk = guarded(Writer("glb", 1, fails(OSError(errno.ENOSPC, "No space left on device")), lambda design: True))
    with pytest.raises(OSError):
        disk.write(None, tmp_path, {})
    stop = guarded(Writer("rhino", 1, fails(KeyboardInterrupt()), lambda design: True))
    with pytest.raises(KeyboardInterrupt):
        stop.write(None, tmp_path, {})
    assert list(tmp_path.iterdir()) == []


def _element(part_id, outline, kind="beam"):
    import numpy as np

    from fabrication.writers._elements import Element
    from ppfab.frame import Frame

    frame = Frame(np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    return Element(part_id, kind, "rows", "B", np.array(outline, dtype=float), frame, -6.0, 12.0)


def test_glb_names_the_part_whose_prism_cannot_be_meshed():
    """The glTF writer on a real degenerate outline (three points on a line: no cap triangles) names the part and
    the defect; the good part before it is no excuse to go on."""
    from unittest import mock

    from fabrication.writers.glb import glb_bytes
    from ppfab.errors import FabricationError

    good = _element("B-OK", [[0, 0], [100, 0], [100, 50], [0, 50]])
    flat = _element("B-R0001-S02", [[0, 0], [50, 0], [100, 0]])
    with mock.patch("fabrication.writers.glb.elements", lambda build: [good]):
        assert glb_bytes(None, {})[:4] == b"glTF"
    with mock.patch("fabrication.writers.glb.elements", lambda build: [good, flat]), \
            pytest.raises(FabricationError) as info:
        glb_bytes(None, {})
    message = str(info.value)
    assert message.startswith("B-R0001-S02: the glTF mesh of its prism failed (")
    assert message.endswith("; its outline encloses no area (3 points on one line))"), message
