"""model.ifc written as text by ppfab (``fabrication/writers/_ifc_text.py``) against IfcOpenShell's own writer.

IfcOpenShell is the reference: the same calls made of an ``ifcopenshell.file`` and of an ``IfcText`` give the same
bytes — reals and strings one by one (random doubles, strings with quotes, backslashes, control characters,
accents and characters beyond the Basic Multilingual Plane), then the whole ``model.ifc`` of two builds: the bundled
default's roof on a small parameter box with a classification and a name outside ASCII, and a patch of a real
conical PP mesh (``../shared/data/DOI__rot4_def1_sparse_rot.obj``).  The counts the writer reports are checked
against ``by_type`` of IfcOpenShell's reading of the file.
"""

import math
import random
import struct
import tomllib

import numpy as np
import pytest

ifcopenshell = pytest.importorskip("ifcopenshell")

from fabrication.writers._ifc_text import IfcText, real_text, string_text  # noqa: E402

from conftest import shared_file  # noqa: E402


def _doubles(n: int, seed: int = 7) -> list[float]:
    """Doubles of every kind a file may hold: millimetre coordinates, round numbers, powers of ten about the
    switch between plain and scientific notation, integers beyond 2**53, every power of two with its neighbours
    (where the shortest digits that read back need not be the nearest), random bit patterns."""
    rng = random.Random(seed)
    out = [0.0, -0.0, 1.0, 1e-3, 5e-3, 1e-4, 2e-4, 1.5e-4, 1e4, 2e4, 99999.0, 1e5, 123456.0, 1e15, 1e16, 2.0 ** 53,
           2.0 ** 53 + 2.0, 2.0 ** 60, 1e22, 1e23, 5e-324, 1.7976931348623157e308]
    for k in range(-1074, 1024):
        a = 2.0 ** k
        out += [a, -a, math.nextafter(a, 0.0), math.nextafter(a, math.inf)]
    while len(out) < n:
        k = rng.random()
        if k < 0.3:
            v = rng.uniform(-4e4, 4e4)
        elif k < 0.5:
            v = float(rng.randint(-10 ** 7, 10 ** 7)) * 10.0 ** rng.randint(-8, 8)
        elif k < 0.6:
            v = round(rng.uniform(-1e3, 1e3), rng.randint(0, 6))
        elif k < 0.7:
            v = float(rng.randint(-10 ** 20, 10 ** 20))
        else:
            v = struct.unpack("d", struct.pack("Q", rng.getrandbits(64)))[0]
        if math.isfinite(v):
            out.append(v)
    return out


def _data_lines(path) -> list[str]:
    text = path.read_text(encoding="ascii")
    return text[text.index("DATA;\n") + 6:text.index("ENDSEC;\nEND-ISO")].splitlines()


def test_reals_are_written_as_ifcopenshell_writes_them(tmp_path):
    values = _doubles(30_000)
    f = ifcopenshell.file(schema="IFC4")
    for v in values:
        f.create_entity("IfcCartesianPoint", Coordinates=(v,))
    f.write(str(tmp_path / "reals.ifc"))
    theirs = [line[line.index("((") + 2:line.rindex("))")] for line in _data_lines(tmp_path / "reals.ifc")]
    ours = [real_text(v) for v in values]
    assert len(theirs) == len(values)
    assert [(v, a, b) for v, a, b in zip(values, ours, theirs) if a != b] == []
    assert all(float(t.replace(".E", "E")) == v for t, v in zip(ours, values))     # and they read back exactly


def test_strings_are_written_as_ifcopenshell_writes_them(tmp_path):
    rng = random.Random(3)
    pools = [(32, 126), (1, 31), (127, 0x2FF), (0x4E00, 0x4EFF), (0x1F600, 0x1F64F), (39, 39), (92, 92)]
    texts = ["", "plain", "Überdachung Süd", "a'b\\c", "\t\n\x7f", "中文 🙂 é", "🙂🙃"]
    for _ in range(2_000):
        texts.append("".join(chr(rng.randint(*rng.choice(pools))) for _ in range(rng.randint(0, 9))))
    f = ifcopenshell.file(schema="IFC4")
    for t in texts:
        f.create_entity("IfcMaterial", Name=t)
    f.write(str(tmp_path / "strings.ifc"))
    raw = (tmp_path / "strings.ifc").read_text(encoding="ascii")
    theirs = [e[e.index("(") + 1:e.rindex(",$,$)")] for e in raw[raw.index("DATA;\n") + 6:].split(";\n")
              if e.startswith("#")]
    assert [(t, a, b) for t, a, b in zip(texts, map(string_text, texts), theirs) if a != b] == []
    assert len(theirs) == len(texts)


def test_an_entity_with_an_attribute_its_class_lacks_is_refused_and_not_written():
    f = IfcText("IFC4")
    with pytest.raises(ValueError, match="Colour"):
        f.create_entity("IfcMaterial", Name="glass", Colour="green")
    with pytest.raises(ValueError, match="only 3 attributes"):
        f.create_entity("IfcMaterial", "glass", None, None, "a fourth")
    with pytest.raises(ValueError, match="not a number"):
        f.create_entity("IfcCartesianPoint", Coordinates=(0.0, float("nan"), 0.0))
    f.create_entity("IfcMaterial", Name="glass")
    assert f._data.decode() == "#1=IFCMATERIAL('glass',$,$);\n"


def _small_roof():
    """The bundled default on an 8 x 6 box (bevelled plates, every retention part, repeated panes), named
    outside ASCII, with a classification."""
    from fabrication.design import DEFAULT_DESIGN, parse_design

    doc = tomllib.loads(DEFAULT_DESIGN.read_text(encoding="utf-8"))
    doc["design"]["name"] = "Überdachung Süd 🙂"
    doc["geometry"]["params"].update(u_range=[-6.0, 6.0], v_range=[-4.5, 4.5], faces_u=8, faces_v=6)
    doc.setdefault("output", {})["classification"] = {"system": "Uniclass 2015", "edition": "v1.30",
                                                      "panel": "Pr_00_00_00 glass 'float'", "strip": "Pr_00_00_01"}
    for section in ("nesting", "beam_nesting"):
        doc.setdefault(section, {})["time_budget"] = 0.5
    return parse_design(doc, "small roof", "", DEFAULT_DESIGN.parent)


def _real_patch(tmp_path):
    """A patch of a real conical PP mesh, 8 x 7 faces (as ``test_exchange_files_of_a_real_mesh``)."""
    from fabrication.design import parse_design
    from ppfab.io import load_mesh, write_obj
    from ppfab.mesh import QuadGrid

    grid = load_mesh(shared_file("DOI__rot4_def1_sparse_rot.obj")).to_grid()
    write_obj(QuadGrid(np.ascontiguousarray(grid.vertices[20:29, 0:8])), tmp_path / "patch.obj")
    return parse_design({"design": {"name": "rot4 patch", "description": "a real mesh, 'quoted' \\ slashed"},
                         "geometry": {"mesh": str(tmp_path / "patch.obj"), "scale": 3000.0},
                         "beams": {"fallback": "segmented"},
                         "nesting": {"time_budget": 0.5}, "beam_nesting": {"time_budget": 0.5}})


@pytest.mark.parametrize("which", ["small default roof", "real mesh patch"])
def test_model_ifc_is_the_file_ifcopenshell_writes_from_the_same_calls(tmp_path, which):
    import fabrication
    from fabrication.writers import dxf
    from fabrication.writers.ifc import ifc_model
    from fabrication.writers.ifc_analysis import add_analysis_model

    design = _small_roof() if which == "small default roof" else _real_patch(tmp_path)
    b = fabrication.build(design)
    files = dxf.dxf_files(b)
    written = {}
    for name, maker in (("text", IfcText), ("ifcopenshell", ifcopenshell.file)):
        model = ifc_model(b, files, maker)
        add_analysis_model(model, b)
        model.write(tmp_path / f"{name}.ifc")
        written[name] = (model, (tmp_path / f"{name}.ifc").read_bytes())
    ours, theirs = written["text"][1], written["ifcopenshell"][1]
    assert ours == theirs, next((a, b) for a, b in zip(ours.splitlines(), theirs.splitlines()) if a != b)
    kinds = {b"IFCFACETEDBREP(", b"IFCMAPPEDITEM(", b"IFCEXTRUDEDAREASOLID(", b"IFCSTRUCTURALCURVEMEMBER(",
             b"IFCPROPERTYSINGLEVALUE("}
    if which == "small default roof":
        kinds |= {b"IFCCLASSIFICATIONREFERENCE(", b"IFCMECHANICALFASTENER(", b"\\X4\\"}
    assert {k for k in kinds if k not in ours} == set()      # the comparison went through each of these
    read = ifcopenshell.open(str(tmp_path / "text.ifc"))
    model = written["text"][0]
    for cls in ("IfcPlate", "IfcMember", "IfcElementType", "IfcMappedItem", "IfcStructuralCurveMember", "IfcRoot",
                "IfcRepresentationItem"):
        assert model.count(cls) == len(read.by_type(cls)) > 0, cls
    assert read.by_type("IfcProject")[0].Name == design.info.name
    assert read.header.file_name.preprocessor_version.startswith("ppfab ")
