"""Tamper matrix of the tables, the report and the manifest's figures: each change is made after the build with
the manifest's sha256 updated (so only a recomputation can catch it), and ``ppfab verify`` names the file and the
row, column or key.  A malformed cell or value is one finding line, exit 1, never a traceback."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from fabrication.cli import main

from tamper import copy, findings, read_rows, reseal, write_rows  # noqa: F401

from conftest import built_folder, small_vault

DESIGN = small_vault("tamper-tables", max_length=5000.0, joint="halflap")
built = built_folder("tamper-tables", DESIGN)


def edit_manifest(folder, change):
    m = json.loads((folder / "manifest.json").read_text())
    change(m)
    (folder / "manifest.json").write_text(json.dumps(m, indent=2))


def lines_of(err: str, file: str) -> list[str]:
    return [line for line in err.splitlines() if f": {file}: " in line]


def test_untampered_copy_has_no_table_findings(copy, capsys):
    capsys.readouterr()
    code = main(["verify", str(copy), "--quiet"])
    err = capsys.readouterr().err
    for name in ("welds.csv", "bites.csv", "strip_cuts.csv", "report.html", "manifest.json"):
        assert not lines_of(err, name), err
    assert code == 0, err


# -- 1. welds.csv ------------------------------------------------------------------------------------------

def test_t_joint_weld_row_removed(copy, capsys):
    rows = read_rows(copy / "welds.csv")
    k = next(i for i, r in enumerate(rows) if r["joint"] == "T")
    gone = rows.pop(k)
    write_rows(copy / "welds.csv", rows)
    reseal(copy, "welds.csv")
    err = findings(copy, capsys)
    assert (f"welds.csv: node {gone['node']}: no row for the T-joint weld of {gone['part']} ending against "
            f"{gone['to']}") in err


def test_t_joint_weld_length_changed(copy, capsys):
    rows = read_rows(copy / "welds.csv")
    k = next(i for i, r in enumerate(rows) if r["joint"] == "T")
    rows[k]["weld_length_mm"] = str(float(rows[k]["weld_length_mm"]) - 20.0)
    write_rows(copy / "welds.csv", rows)
    reseal(copy, "welds.csv")
    err = findings(copy, capsys)
    assert f"welds.csv: row {k + 1} column weld_length_mm: {rows[k]['part']} to {rows[k]['to']}" in err


def test_corner_weld_row_removed(copy, capsys):
    """A node where every plate ends (a corner of the vault) loses its corner weld row: verify names the node and
    the plates left unjoined."""
    rows = read_rows(copy / "welds.csv")
    k = next(i for i, r in enumerate(rows) if r["joint"] == "corner")
    gone = rows.pop(k)
    assert not any(r["joint"] == "corner" and r["node"] == gone["node"] for r in rows)
    write_rows(copy / "welds.csv", rows)
    reseal(copy, "welds.csv")
    err = findings(copy, capsys)
    assert f"welds.csv: node {gone['node']}: every plate ends here and " in err
    line = next(x for x in err.splitlines() if f"welds.csv: node {gone['node']}: every plate ends here" in x)
    assert gone["part"] in line and gone["to"] in line


def test_corner_weld_joining_the_wrong_plate(copy, capsys):
    rows = read_rows(copy / "welds.csv")
    k = next(i for i, r in enumerate(rows) if r["joint"] == "corner")
    node = next(r for r in read_rows(copy / "nodes.csv") if r["vertex"] == rows[k]["node"])
    other = next(r["part_id"] for r in read_rows(copy / "parts.csv")      # a plate not at that node
                 if r["kind"] == "beam" and r["part_id"] not in node["beams"].split(";"))
    rows[k]["to"] = other
    write_rows(copy / "welds.csv", rows)
    reseal(copy, "welds.csv")
    err = findings(copy, capsys)
    assert (f"welds.csv: row {k + 1}: node {rows[k]['node']}: {rows[k]['part']} and {other} are not two beams' "
            "plates ending at a node where every plate ends") in err


def test_halflap_weld_row_removed_and_its_length_changed(copy, capsys):
    rows = read_rows(copy / "welds.csv")
    laps = [i for i, r in enumerate(rows) if r["joint"] == "halflap"]
    assert len(laps) >= 2
    rows[laps[1]]["weld_length_mm"] = str(float(rows[laps[1]]["weld_length_mm"]) / 2)    # two runs, not four
    gone = rows.pop(laps[0])
    write_rows(copy / "welds.csv", rows)
    reseal(copy, "welds.csv")
    err = findings(copy, capsys)
    a, b = sorted((gone["part"], gone["to"]))
    assert f"welds.csv: node {gone['node']}: no row for the half-lap weld of {a} and {b}" in err
    assert f"welds.csv: row {laps[1]} column weld_length_mm: half-lap weld of " in err      # one row earlier now


def test_verify_json_gives_each_finding_its_check_value_and_limit(copy, capsys):
    """``ppfab verify --json``: the tampered weld length is a finding of the ``welds`` check with the difference
    from the recomputed length as its value and the tolerance as its limit; the JSON is the whole of stdout."""
    from fabrication.verify.welds import LENGTH_TOLERANCE_MM

    rows = read_rows(copy / "welds.csv")
    k = next(i for i, r in enumerate(rows) if r["joint"] == "T")
    rows[k]["weld_length_mm"] = str(float(rows[k]["weld_length_mm"]) - 20.0)
    write_rows(copy / "welds.csv", rows)
    reseal(copy, "welds.csv")
    capsys.readouterr()
    assert main(["verify", str(copy), "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["ok"] is False and "welds" in out["checked"]
    mine = [f for f in out["findings"] if f["element"] == f"row {k + 1} column weld_length_mm"]
    assert len(mine) == 1 and mine[0]["code"] == "welds" and mine[0]["file"] == "welds.csv"
    assert mine[0]["value"] == pytest.approx(20.0, abs=1e-3) and mine[0]["limit"] == LENGTH_TOLERANCE_MM
    assert all(f["code"] for f in out["findings"])                    # every finding names its check


# -- 2. bites.csv ------------------------------------------------------------------------------------------

def test_non_minimal_bite_changed(copy, capsys):
    rows = read_rows(copy / "bites.csv")
    # a row with another row of its panel biting no more: raised, it leaves the panel's smallest bite as it was
    k = next(i for i, r in enumerate(rows)
             if any(j != i and q["panel"] == r["panel"] and float(q["bite_mm"]) <= float(r["bite_mm"])
                    for j, q in enumerate(rows)))
    smallest = min(float(q["bite_mm"]) for q in rows if q["panel"] == rows[k]["panel"])
    rows[k]["bite_mm"] = str(float(rows[k]["bite_mm"]) + 2.0)
    assert min(float(q["bite_mm"]) for q in rows if q["panel"] == rows[k]["panel"]) == smallest
    write_rows(copy / "bites.csv", rows)
    reseal(copy, "bites.csv")
    err = findings(copy, capsys)
    assert f"bites.csv: row {k + 1} column bite_mm: {rows[k]['panel']} over mesh edge" in err


def test_bites_row_removed(copy, capsys):
    rows = read_rows(copy / "bites.csv")
    gone = rows.pop(5)
    write_rows(copy / "bites.csv", rows)
    reseal(copy, "bites.csv")
    err = findings(copy, capsys)
    line = next(x for x in lines_of(err, "bites.csv") if "no row for the pane edge" in x)
    assert f"bites.csv: {gone['panel']}: no row" in line and f"(it bites {float(gone['bite_mm']):.3f} mm)" in line


# -- 3. strip_cuts.csv -------------------------------------------------------------------------------------

def test_strip_cut_length_changed(copy, capsys):
    rows = read_rows(copy / "strip_cuts.csv")
    rows[2]["length_mm"] = str(float(rows[2]["length_mm"]) - 5.0)
    write_rows(copy / "strip_cuts.csv", rows)
    reseal(copy, "strip_cuts.csv")
    err = findings(copy, capsys)
    assert f"strip_cuts.csv: row 3 column length_mm: {rows[2]['part_id']}: {float(rows[2]['length_mm']):.3f} written" in err


# -- 4. report.html ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("where", ["summary", "panel row"])
def test_report_text_changed(copy, capsys, where):
    text = (copy / "report.html").read_text(encoding="utf-8")
    if where == "summary":
        old = text.split("<td>glass area</td><td>", 1)[1].split("</td>", 1)[0]          # "37.3 m²"
        new = f"{float(old.split()[0]) + 1.0:.1f} m²"
        text = text.replace(f"<td>glass area</td><td>{old}</td>", f"<td>glass area</td><td>{new}</td>", 1)
        element = "report.html: Summary: glass area: "
    else:
        panel = next(r for r in read_rows(copy / "parts.csv") if r["kind"] == "panel")
        row = text.split(f'<td class="l">{panel["part_id"]}</td>', 1)[1].split("</tr>", 1)[0]
        bad = row.replace(f'<td class="l">{panel["type_id"]}</td>', '<td class="l">T999</td>', 1)
        assert bad != row
        text = text.replace(row, bad, 1)
        element = f"report.html: Panels: {panel['part_id']} column type: 'T999' in the report"
    (copy / "report.html").write_text(text, encoding="utf-8")
    reseal(copy, "report.html")
    err = findings(copy, capsys)
    assert element in err


# -- 5. manifest.json summary and fabrication ------------------------------------------------------------------

@pytest.mark.parametrize("key", ["glass_area_m2", "beam_plates"])
def test_manifest_summary_changed(copy, capsys, key):
    edit_manifest(copy, lambda m: m["summary"].update({key: m["summary"][key] + 1}))
    err = findings(copy, capsys)
    assert f"manifest.json: summary.{key}: " in err and "from the files" in err


def test_manifest_glazing_figure_changed(copy, capsys):
    edit_manifest(copy, lambda m: m["glazing"].update(welds=m["glazing"]["welds"] + 3))
    err = findings(copy, capsys)
    assert "manifest.json: glazing.welds: " in err


def test_manifest_fabrication_changed(copy, capsys):
    def deeper(m):
        m["fabrication"]["beams"]["depth"] += 50.0
        m["fabrication"]["beam_depth"] += 50.0                 # both places, as the build writes it
    edit_manifest(copy, deeper)
    err = findings(copy, capsys)
    assert "manifest.json: fabrication.beams.depth: 200 written, 150 from the rows of parts.csv" in err


def test_manifest_fabrication_alias_changed(copy, capsys):
    edit_manifest(copy, lambda m: m["fabrication"].update(panel_gap=m["fabrication"]["panel_gap"] + 4))
    err = findings(copy, capsys)
    assert "manifest.json: fabrication.panel_gap: 20.0 differs from fabrication.panels.gap 16.0" in err


# -- malformed cells and values: one finding line, exit 1, no traceback ---------------------------------------

def _cell(folder, table, pick, column, value):
    rows = read_rows(folder / table)
    k = next(i for i, r in enumerate(rows) if pick(r))
    rows[k][column] = value
    write_rows(folder / table, rows)
    reseal(folder, table)
    return f"{table}: row {k + 1} column {column}: "


def _frame(folder):
    return _cell(folder, "parts.csv", lambda r: r["kind"] == "beam", "frame", '{"a":1}')


def _face(folder):
    return _cell(folder, "parts.csv", lambda r: r["kind"] == "panel", "face", "x")


def _vertex(folder):
    return _cell(folder, "nodes.csv", lambda r: r["vertex"] == "3", "vertex", "q")


def _axis(folder):
    return _cell(folder, "nodes.csv", lambda r: r["vertex"] == "3", "axis_y", "abc")


def _order_angle(folder):
    return _cell(folder, "glass_order.csv", lambda r: True, "angle_3_deg", "abc")


def _order_quantity(folder):
    return _cell(folder, "glass_order.csv", lambda r: True, "quantity", "")


def _glass_sheets(folder):
    edit_manifest(folder, lambda m: m["files"].update(glass_sheets=5))
    return "manifest.json: files.glass_sheets: must be a file name or a list of file names, got 5"


def _gap_text(folder):
    edit_manifest(folder, lambda m: m["fabrication"]["panels"].update(gap="wide"))
    return "manifest.json: fabrication.panels.gap: 'wide' is not "


def _json_node(folder):
    doc = json.loads((folder / "nodes.json").read_text())
    doc["nodes"][3] = 7
    (folder / "nodes.json").write_text(json.dumps(doc))
    reseal(folder, "nodes.json")
    return "nodes.json: nodes[3]: is not a node record"


@pytest.mark.parametrize("tamper", [_frame, _face, _vertex, _axis, _order_angle, _order_quantity, _glass_sheets,
                                    _gap_text, _json_node],
                         ids=["parts-frame", "parts-face", "nodes-vertex", "nodes-axis", "order-angle",
                              "order-quantity", "files-glass_sheets", "fabrication-gap", "nodes-json-node"])
def test_malformed_value_is_one_finding_not_a_traceback(copy, tamper):
    expected = tamper(copy)
    run = subprocess.run([sys.executable, "-m", "fabrication.cli", "verify", str(copy), "--quiet"],
                         capture_output=True, text=True, timeout=600)
    out = run.stdout + run.stderr
    assert run.returncode == 1, out
    assert "Traceback" not in out
    hits = [line for line in out.splitlines() if expected in line]
    assert len(hits) == 1, out
    assert hits[0].startswith("ppfab: verify: ") and hits[0].index(expected) == len("ppfab: verify: ")
