"""Design files: every rejection is one line naming the key path, exit code 2, no traceback."""

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fabrication.cli import main
from fabrication.design import load_design, parse_design
from ppfab.errors import DesignError

from conftest import small_design

GOOD = small_design(4, 3, name="t", fast=False)

SECTIONS = ("design", "geometry", "output")

CASES = [
    ("[geometry]\nmethod = 'face_image_curves'\nscael = 2\n", "geometry.scael", "did you mean 'scale'"),
    ("[geometry]\nmethod = 'face_image_curve'\n", "geometry.method", "did you mean 'face_image_curves'"),
    ("[geometry]\nmethod = 'face_image_curves'\nscale = -1\n", "geometry.scale", "must be > 0"),
    ("[geometry]\nmethod = 'face_image_curves'\nscale = 'big'\n", "geometry.scale", "expected a number"),
    ("[geometry]\nmethod = 'face_image_curves'\n[geometry.params]\ng = [[0.0]]\n", "geometry.params.g",
     "exactly 4 entries"),
    ("[geometry]\nmethod = 'face_image_curves'\n[geometry.params]\nfaces_u = 0\n", "geometry.params.faces_u",
     "must be >= 2"),
    ("[geometry]\nmethod = 'face_image_curves'\n[geometry.params]\nh = [[1],[1],[1],[1]]\n",
     "geometry.params.g", "missing required key"),
    ("[geometry]\nscale = 2.0\n", "geometry.method", "exactly one of"),
    ("[design]\nname = 't'\n", "geometry", "missing required section"),
    ("[geometri]\nmethod = 'x'\n", "geometri", "did you mean 'geometry'"),
    ("geometry = 3\n", "geometry", "must be a table"),
    ("[geometry]\nmesh = 'a.obj'\nmethod = 'face_image_curves'\n", "geometry.mesh", "exactly one of"),
    ("[geometry]\nmethod = 'face_image_curves'\ntranslate = [1, 2]\n", "geometry.translate", "exactly 3"),
    ("[geometry]\nmethod = 'face_image_curves'\nplanar_families = ['rows', 'diagonals']\n",
     "geometry.planar_families[1]", "must be 'rows' or 'cols'"),
]


@pytest.mark.parametrize("text,key,message", CASES, ids=[c[1] + ":" + c[2][:12] for c in CASES])
def test_bad_design_names_key(tmp_path, capsys, text, key, message):
    p = tmp_path / "d.toml"
    p.write_text(text)
    with pytest.raises(DesignError) as info:
        load_design(p, sections=SECTIONS)
    assert info.value.key == key
    assert message in str(info.value)
    code = main(["build", str(p), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("ppfab: error: ") and err.count("\n") == 1 and key in err and message in err
    assert not (tmp_path / "out").exists()


def test_malformed_toml_and_missing_file(tmp_path, capsys):
    p = tmp_path / "d.toml"
    p.write_text("[geometry\nmethod = 1\n")
    assert main(["build", str(p), "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "malformed TOML" in err and str(p) in err
    assert main(["build", str(tmp_path / "none.toml"), "-o", str(tmp_path / "o")]) == 2
    assert "cannot read design file" in capsys.readouterr().err


def test_good_design_parses_with_defaults(tmp_path):
    p = tmp_path / "d.toml"
    p.write_text(GOOD)
    d = load_design(p, sections=SECTIONS)
    assert d.geometry.scale == 1000.0 and d.geometry.translate == [0.0, 0.0, 0.0]
    assert d.info.name == "t" and len(d.sha256) == 64


toml_scalars = st.one_of(st.integers(-10**6, 10**6), st.floats(allow_nan=True, allow_infinity=True),
                         st.text(max_size=8), st.booleans())
toml_values = st.recursive(toml_scalars, lambda inner: st.lists(inner, max_size=4), max_leaves=8)
keys = st.sampled_from(["method", "mesh", "scale", "translate", "rotate_z_deg", "params", "flip_orientation",
                        "planar_families", "g", "h", "faces_u", "bogus", "max_vertices"])


@settings(max_examples=150, deadline=None)
@given(st.dictionaries(st.sampled_from(["design", "geometry", "output", "beams2"]),
                       st.dictionaries(keys, st.one_of(toml_values, st.dictionaries(keys, toml_values, max_size=3)),
                                       max_size=5), max_size=3))
def test_random_documents_only_raise_design_errors(doc):
    try:
        parse_design(doc, sections=SECTIONS)
    except DesignError as exc:
        assert "\n" not in str(exc)
