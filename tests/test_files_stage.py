"""Writing on two cores changes no file: a small build written with the per-type DXFs in a second process and
written serially gives the same bytes in every file (no file of a build holds a timing), the same ``files``
table, and a failure in the second process is reported as the writer's own error with nothing left behind."""

import hashlib
from pathlib import Path

import pytest

from conftest import small_design

pytestmark = pytest.mark.skipif(not hasattr(__import__("os"), "fork"), reason="parallel writing needs fork")


def tree(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def small_build():
    from fabrication import build, parse_design
    import tomllib

    return build(parse_design(tomllib.loads(small_design(4, 3))))


def test_parallel_and_serial_writing_give_identical_files(tmp_path, small_build):
    """Two ``ppfab build`` runs of one design, each in a fresh process (as a user runs it), with the second
    process on and off; then the same build written here in one process, serially and in two processes.""" 
    import os
    import subprocess
    import sys

    design = tmp_path / "small.toml"
    design.write_text(small_design(4, 3))
    for flag in ("0", "1"):
        env = dict(os.environ, PPFAB_PARALLEL_WRITERS=flag, OMP_NUM_THREADS="1")
        run = subprocess.run([sys.executable, "-m", "fabrication.cli", "build", str(design), "-o",
                              str(tmp_path / f"out{flag}"), "--quiet"], env=env, capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
    serial, parallel = tree(tmp_path / "out0"), tree(tmp_path / "out1")
    assert len(serial) > 20 and "beams.step" in serial and "manifest.json" in serial
    assert serial == parallel

    from fabrication.pipeline.progress import Progress
    from fabrication.writers import write_all

    tables = []
    for flag in (False, True):
        folder = tmp_path / f"raw{int(flag)}"
        folder.mkdir()
        tables.append(write_all(small_build, folder, Progress(quiet=True), parallel=flag))
    assert list(tables[0].items()) == list(tables[1].items())          # same keys, values and order
    # STEP aside: the kernel numbers assembly occurrences across exports in one process (their line breaks
    # then differ); the fresh-process builds above compare it
    same = {k: v for k, v in tree(tmp_path / "raw1").items() if not k.endswith(".step") and k != "manifest.json"}
    assert same == {k: v for k, v in serial.items() if k in same} and len(same) == len(serial) - 3


def test_a_failing_second_process_raises_the_writers_own_error(tmp_path, small_build, monkeypatch):
    """The per-type DXF writer fails in the forked process; the build reruns it here, so the error is its own,
    and the temporary folder is gone."""
    import dataclasses

    from ppfab.errors import FabricationError

    from fabrication import writers

    calls = []

    def boom(build, out, files):
        calls.append(1)
        raise FabricationError("types/T01.dxf: cannot write")

    writers.load_writers()
    monkeypatch.setitem(writers.WRITERS, "dxf_types", dataclasses.replace(writers.WRITERS["dxf_types"], write=boom))
    monkeypatch.setenv("PPFAB_PARALLEL_WRITERS", "1")
    with pytest.raises(FabricationError, match="T01.dxf: cannot write"):
        small_build.write(tmp_path / "out")
    assert calls == [1]                                   # the rerun here (the child's call is another process)
    assert [p.name for p in tmp_path.iterdir() if ".tmp-" in p.name or ".lock" in p.name] == []
    assert not (tmp_path / "out").exists()


def test_parallel_writing_is_off_on_one_core_and_by_environment(monkeypatch):
    from fabrication.writers import _parallel

    monkeypatch.delenv("PPFAB_PARALLEL_WRITERS", raising=False)
    monkeypatch.setattr(_parallel, "cores", lambda: 1)
    assert not _parallel.parallel_enabled()
    monkeypatch.setattr(_parallel, "cores", lambda: 2)
    assert _parallel.parallel_enabled()
    monkeypatch.setenv("PPFAB_PARALLEL_WRITERS", "0")
    assert not _parallel.parallel_enabled()


def test_dxf_from_the_template_is_byte_identical_to_a_new_document(tmp_path, small_build):
    """Per-type and sheet DXFs built on the unpickled template and saved in one write are the bytes of a document
    made by ``ezdxf.new`` and saved by ``Drawing.saveas`` (the way before the template), for every panel type
    (with dimensions) and every glass sheet of the build, twice in a row (the template is not changed by use)."""
    from fabrication.writers import dxf
    from fabrication.writers._dxf_dimensions import add_pane_dimensions

    parts = list(small_build.nesting.glass_parts)
    assert len(parts) >= 12
    nesting = small_build.nesting.glass
    by_id = {p.part_id: p for p in parts}

    for round_ in range(2):
        for k, part in enumerate(parts[:12]):
            fast = dxf.CuttingSheet(None, None, f"T{k}", "R2010")
            fast.add_part(part, None)
            add_pane_dimensions(fast.doc, part.outline)
            fast.write(tmp_path / f"fast{k}.dxf")
            with dxf._fixed_metadata():
                doc = dxf._new_doc()
            slow = object.__new__(dxf.CuttingSheet)
            slow.version, slow.doc, slow.msp = "R2010", doc, doc.modelspace()
            slow.msp.add_text(dxf.dxf_text(f"T{k}"), height=40.0, dxfattribs={"layer": "LABEL", "insert": (0.0, -80.0)})
            slow.add_part(part, None)
            add_pane_dimensions(slow.doc, part.outline)
            _saveas(slow, tmp_path / f"slow{k}.dxf")
            assert (tmp_path / f"fast{k}.dxf").read_bytes() == (tmp_path / f"slow{k}.dxf").read_bytes(), (round_, k)
    for k, group in enumerate(nesting.by_sheet()):
        fast = dxf.CuttingSheet(nesting.sheet_size, nesting.usable, f"sheet {k}", "R2010")
        with dxf._fixed_metadata():
            doc = dxf._new_doc()
        slow = object.__new__(dxf.CuttingSheet)
        slow.version, slow.doc, slow.msp = "R2010", doc, doc.modelspace()
        w, h = (float(v) for v in nesting.sheet_size)
        x0, y0, x1, y1 = (float(v) for v in nesting.usable)
        slow.msp.add_lwpolyline([(0, 0), (w, 0), (w, h), (0, h)], close=True, dxfattribs={"layer": "SHEET"})
        slow.msp.add_lwpolyline([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], close=True, dxfattribs={"layer": "TRIM"})
        slow.msp.add_text(dxf.dxf_text(f"sheet {k}"), height=40.0, dxfattribs={"layer": "LABEL", "insert": (0.0, -80.0)})
        for pl in group:
            fast.add_part(by_id[pl.part_id], pl)
            slow.add_part(by_id[pl.part_id], pl)
        fast.write(tmp_path / "fast_sheet.dxf")
        _saveas(slow, tmp_path / "slow_sheet.dxf")
        assert (tmp_path / "fast_sheet.dxf").read_bytes() == (tmp_path / "slow_sheet.dxf").read_bytes(), k
    assert dxf.check_sheet_dxf(tmp_path / "fast_sheet.dxf").parts


def _saveas(sheet, path):
    """CuttingSheet.write as it was: the CLASSES sorted, then ``Drawing.saveas`` with fixed metadata."""
    from fabrication.writers import dxf

    classes = sheet.doc.classes
    classes.add_required_classes(sheet.doc.dxfversion)
    ordered = sorted(classes.classes.items())
    classes.classes.clear()
    classes.classes.update(ordered)
    with dxf._fixed_metadata():
        sheet.doc.saveas(path)
