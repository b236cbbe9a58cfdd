"""The parts list is made once per build, by the pipeline, before any file exists: every writer that lists parts
(the tables, the report, IFC, Rhino, glTF) reads the build's :class:`~fabrication.model.PartsTable`, and the
cutting-sheet files it names are the ones the DXF writer then writes (a pure function of the nesting,
:func:`fabrication.contract.sheet_files`)."""

from __future__ import annotations

import csv
import tomllib
from pathlib import Path

import ezdxf
import pytest

import fabrication.parts
from fabrication import build, parse_design
from fabrication.contract import (GLASS_SHEET_DIR, GLASS_SHEET_PREFIX, PLATE_SHEET_DIR, PLATE_SHEET_PREFIX,
                                  sheet_files)

from conftest import small_vault


@pytest.fixture(scope="module")
def counted(tmp_path_factory):
    """The small vault built and written with every exchange model and the report, counting the calls that
    make a parts list: ``(build, folder, calls)``."""
    calls = []
    original = fabrication.parts.parts_table

    def counting(b):
        calls.append(1)
        return original(b)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(fabrication.parts, "parts_table", counting)
        mp.setenv("PPFAB_PARALLEL_WRITERS", "0")          # every writer in this process, where the count is
        b = build(parse_design(tomllib.loads(small_vault("parts_once") + "\n[output]\npanels_step = false\n")))
        made = len(calls)
        out = b.write(tmp_path_factory.mktemp("parts") / "out")
    return b, out, made, len(calls)


def test_the_parts_list_is_made_once_by_the_pipeline_and_never_by_a_writer(counted):
    b, out, made, total = counted
    assert made == 1 and total == 1
    for name in ("model.ifc", "model.3dm", "model.glb", "report.html", "parts.csv"):
        assert (out / name).is_file(), name                 # the writers that list parts did run
    with open(out / "parts.csv", newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["part_id"] for r in rows] == [str(r["part_id"]) for r in b.parts]
    assert len(rows) == len(b.parts) > 0


def test_the_sheet_files_the_parts_list_names_are_the_ones_written(counted):
    """Each panel and plate's ``sheet_file`` is a DXF in the folder whose CUT outline carries that part's id (read
    with ezdxf), and the sheet files on disk are exactly :func:`sheet_files` of the nesting."""
    b, out, _, _ = counted
    for directory, prefix, nesting in ((GLASS_SHEET_DIR, GLASS_SHEET_PREFIX, b.nesting.glass),
                                       (PLATE_SHEET_DIR, PLATE_SHEET_PREFIX, b.nesting.plates)):
        names = sheet_files(directory, prefix, nesting.sheets)
        on_disk = sorted(str(p.relative_to(out)) for p in (out / directory).glob(f"{prefix}_*.dxf"))
        assert on_disk == sorted(names) and len(names) == nesting.sheets > 0
    ids_on: dict[str, set[str]] = {}
    for r in b.parts:
        if r["kind"] not in ("panel", "beam"):
            continue
        f = str(r["sheet_file"])
        if f not in ids_on:
            doc = ezdxf.readfile(out / f)
            ids_on[f] = {str(v).removeprefix("part_id=") for e in doc.modelspace().query("LWPOLYLINE[layer=='CUT']")
                         if e.has_xdata("PPFAB") for code, v in e.get_xdata("PPFAB")
                         if code == 1000 and str(v).startswith("part_id=")}
        assert r["part_id"] in ids_on[f], (r["part_id"], f)
    assert len(ids_on) == b.nesting.glass.sheets + b.nesting.plates.sheets


def test_every_column_of_the_parts_list_is_named_in_the_contract(counted):
    """``contract.py`` names every column a build writes (with what it holds), and the file's column order is the
    rule of :func:`fabrication.parts.columns`: the contract's, the known ones in order, the rest sorted."""
    from fabrication.contract import PARTS_CONTRACT_COLUMNS, PARTS_KNOWN_COLUMNS, PARTS_MORE_COLUMNS

    b, out, _, _ = counted
    named = set(PARTS_CONTRACT_COLUMNS) | set(PARTS_KNOWN_COLUMNS) | set(PARTS_MORE_COLUMNS)
    present = {k for r in b.parts for k in r}
    assert present - named == set()
    kinds = {r["kind"] for r in b.parts}
    assert {"panel", "beam", "strip"} <= kinds                      # the vault has glazing strips
    with open(out / "parts.csv", newline="", encoding="utf-8") as fh:
        header = next(csv.reader(fh))
    k = len(PARTS_CONTRACT_COLUMNS)
    assert header[:k] == PARTS_CONTRACT_COLUMNS
    known = [c for c in header[k:] if c in PARTS_KNOWN_COLUMNS]
    rest = [c for c in header[k:] if c not in PARTS_KNOWN_COLUMNS]
    assert header[k:] == known + rest and rest == sorted(rest)
    assert known == [c for c in PARTS_KNOWN_COLUMNS if c in known]
