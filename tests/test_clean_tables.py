"""parts.csv, nodes.csv and glass_order.csv load cleanly: every cell is a plain value or one JSON value (double
quotes, parsed by ``json.loads``), and no column name shadows an attribute of a pandas DataFrame."""

from __future__ import annotations

import csv
import json
import tomllib

import numpy as np
import pytest

from conftest import small_design

# public attributes and methods of pandas.DataFrame (pandas 2.x) — checked against dir() when pandas is installed
DATAFRAME_ATTRIBUTES = set("""
T abs add add_prefix add_suffix agg aggregate align all any apply applymap asfreq asof assign astype at at_time
attrs axes backfill between_time bfill bool boxplot clip columns combine combine_first compare convert_dtypes copy
corr corrwith count cov cummax cummin cumprod cumsum describe diff div divide dot drop drop_duplicates droplevel
dropna dtypes duplicated empty eq equals eval ewm expanding explode ffill fillna filter first first_valid_index
flags floordiv from_dict from_records ge get groupby gt head hist iat idxmax idxmin iloc index infer_objects info
insert interpolate isetitem isin isna isnull items iterrows itertuples join keys kurt kurtosis last
last_valid_index le loc lt map mask max mean median melt memory_usage merge min mod mode mul multiply ndim ne
nlargest notna notnull nsmallest nunique pad pct_change pipe pivot pivot_table plot pop pow prod product quantile
query radd rank rdiv reindex reindex_like rename rename_axis reorder_levels replace resample reset_index
rfloordiv rmod rmul rolling round rpow rsub rtruediv sample select_dtypes sem set_axis set_flags set_index shape
shift size skew sort_index sort_values squeeze stack std style sub subtract sum swapaxes swaplevel tail take
to_clipboard to_csv to_dict to_excel to_feather to_hdf to_html to_json to_latex to_markdown to_numpy to_orc
to_parquet to_period to_pickle to_records to_sql to_stata to_string to_timestamp to_xarray to_xml transform
transpose truediv truncate tz_convert tz_localize unstack update value_counts values var where xs
""".split())

TABLES = ("parts.csv", "nodes.csv", "glass_order.csv")


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    from fabrication import build, parse_design

    out = tmp_path_factory.mktemp("tables") / "out"
    build(parse_design(tomllib.loads(small_design(faces_u=4, faces_v=3)))).write(out)
    return out


def _rows(path):
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def _dataframe_attributes() -> set[str]:
    try:
        import pandas
    except ImportError:
        return DATAFRAME_ATTRIBUTES
    return {a for a in dir(pandas.DataFrame) if not a.startswith("_")}


@pytest.mark.parametrize("name", TABLES)
def test_no_column_shadows_a_dataframe_attribute(built, name):
    header = next(csv.reader(open(built / name, encoding="utf-8")))
    assert len(header) == len(set(header))
    assert not set(header) & _dataframe_attributes(), f"{name}: {sorted(set(header) & _dataframe_attributes())}"


@pytest.mark.parametrize("name", TABLES)
def test_every_cell_is_plain_or_json(built, name):
    rows = _rows(built / name)
    assert rows
    structured = 0
    for row in rows:
        assert None not in row, f"{name}: a row has more cells than the header"
        for col, cell in row.items():
            assert "\n" not in cell and "\r" not in cell
            if cell[:1] in ("[", "{"):
                json.loads(cell)                      # a structured cell is one JSON value
                structured += 1
            else:
                assert "{'" not in cell and "['" not in cell, f"{name} {col}: Python literal {cell!r}"
    if name == "parts.csv":
        assert structured >= 3 * sum(r["kind"] == "beam" for r in rows)     # nodes, frame, plane of every plate


def test_plate_cells_parse_to_their_geometry(built):
    """A plate's ``frame`` is an orthonormal frame whose normal is its ``plane`` normal, and ``nodes`` lists
    vertices of ``nodes.csv`` that name this plate among their beams."""
    rows = [r for r in _rows(built / "parts.csv") if r["kind"] == "beam"]
    nodes = {int(r["vertex"]): r["beams"].split(";") for r in _rows(built / "nodes.csv")}
    for r in rows:
        f = {k: np.asarray(v, dtype=float) for k, v in json.loads(r["frame"]).items()}
        m = np.stack([f["x_dir"], f["y_dir"], f["normal"]])
        assert np.allclose(m @ m.T, np.eye(3), atol=1e-9)
        plane = np.asarray(json.loads(r["plane"]), dtype=float)
        assert abs(abs(plane[:3] @ f["normal"]) - 1.0) < 1e-9
        assert abs(plane[:3] @ f["origin"] + plane[3]) < 1e-6           # the frame's origin lies on the plane
        for k in json.loads(r["nodes"]):
            assert r["part_id"] in nodes[int(k)]


def test_panel_flags_column_replaces_flags(built):
    header = next(csv.reader(open(built / "parts.csv", encoding="utf-8")))
    assert "panel_flags" in header and "flags" not in header
    doc = json.loads((built / "parts.json").read_text(encoding="utf-8"))
    assert "panel_flags" in doc["columns"] and all("flags" not in p for p in doc["parts"])


def test_pandas_reads_every_cell(built):
    pandas = pytest.importorskip("pandas")
    for name in TABLES:
        df = pandas.read_csv(built / name)
        assert len(df) == len(_rows(built / name))
    parts = pandas.read_csv(built / "parts.csv")
    for col in ("x", "y", "rotation_deg", "area_mm2"):
        assert parts[col].dtype.kind == "f"
    beams = parts[parts["kind"] == "beam"]
    assert all(isinstance(json.loads(c), dict) for c in beams["frame"])


def test_verify_reads_builds_written_before_the_rename(built, tmp_path):
    """The readers of ``ppfab verify`` take a plate frame written as a Python literal (builds of 0.1.0) too."""
    import ast

    from fabrication.verify._shapes import frame_of, literal

    row = next(r for r in _rows(built / "parts.csv") if r["kind"] == "beam")
    old = repr(json.loads(row["frame"]))
    assert old.startswith("{'") and literal(old) == ast.literal_eval(old) == json.loads(row["frame"])
    a, b = frame_of({"frame": old}), frame_of(row)
    assert a is not None and b is not None and all(np.array_equal(a[k], b[k]) for k in a)


def test_the_sheet_column_is_an_integer_column(built):
    """``sheet`` is 1-based on the cutting-sheet parts (panels, beam plates) and 0 on every other part, so a typed
    reader gets integers (pandas: int64, where empty cells made it float64); the open_build reader gives a
    placement exactly to the parts on a sheet."""
    from fabrication import open_build
    from fabrication.contract import NOT_ON_A_SHEET, SHEET_KINDS

    rows = _rows(built / "parts.csv")
    kinds = {r["kind"] for r in rows}
    assert kinds - set(SHEET_KINDS)                                  # strips, retention parts … are there
    for r in rows:
        assert r["sheet"].isdigit(), (r["part_id"], r["sheet"])
        on_sheet = int(r["sheet"]) != NOT_ON_A_SHEET
        assert on_sheet == (r["kind"] in SHEET_KINDS), r["part_id"]
        assert bool(r["x"]) == on_sheet and bool(r["sheet_file"]) == on_sheet
    try:
        import pandas
    except ImportError:
        pandas = None
    if pandas is not None:
        assert str(pandas.read_csv(built / "parts.csv")["sheet"].dtype) == "int64"
    package = open_build(built)
    placed = {p.part_id for p in package.parts if p.placement is not None}
    assert placed == {r["part_id"] for r in rows if r["kind"] in SHEET_KINDS}


def test_every_table_has_the_columns_the_contract_names(built):
    """Each CSV of a build has exactly the header ``contract.TABLE_COLUMNS`` gives its file, in order;
    ``parts.csv`` the contract's columns first, then known and further columns each named in the contract,
    sorted as it says."""
    from fabrication import contract

    found = sorted(p.relative_to(built).as_posix() for p in built.rglob("*.csv"))
    assert len(found) >= 8
    for rel in found:
        with open(built / rel, newline="", encoding="utf-8") as fh:
            header = next(csv.reader(fh))
        if rel == "parts.csv":
            known = [c for c in contract.PARTS_KNOWN_COLUMNS if c in header]
            more = sorted(c for c in header if c in contract.PARTS_MORE_COLUMNS)
            assert header == contract.PARTS_CONTRACT_COLUMNS + known + more, rel
        else:
            assert header == contract.TABLE_COLUMNS[rel], rel
