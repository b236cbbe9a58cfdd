"""The IFC schema validation of ``ppfab verify``: ifcopenshell's validator on the product tree and one shape and
property of each kind (:func:`fabrication.verify.ifc.schema_sample`), every instance with ``--kernel``.

Each case breaks one instance of a written ``model.ifc`` in the text (a property set with no properties, a point
with five coordinates, an extrusion depth that is text) and asks the validator, through the sample or over
every instance, for the finding: the sample is held to what it promises, not to what it leaves out.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from conftest import built_folder, small_vault

built = built_folder("ifc_sample", small_vault("ifc_sample"))


def _findings(path: Path, every: bool) -> list[str]:
    """``class of the instance: message`` of every finding of the validation of ``path``."""
    import ifcopenshell
    import ifcopenshell.validate

    from fabrication.verify.ifc import validate_schema

    log = ifcopenshell.validate.json_logger()
    validate_schema(ifcopenshell.open(str(path)), log, every=every)
    out = []
    for s in log.statements:
        inst = s.get("instance")
        out.append(f"{inst.is_a() if inst is not None else '?'}: " + " ".join(str(s.get("message", s)).split()))
    return out


def _tamper(src: Path, dst: Path, pattern: str, repl, which: int = 0) -> str:
    """``src`` with the ``which``-th line matching ``pattern`` (0 first, -1 last) rewritten by ``repl`` into
    ``dst``; returns the instance's id (``#123``)."""
    lines = src.read_text().splitlines(keepends=True)
    hits = [i for i, line in enumerate(lines) if re.match(pattern, line)]
    assert hits, pattern
    i = hits[which]
    new = repl(lines[i])
    assert new != lines[i]
    lines[i] = new
    dst.write_text("".join(lines))
    return lines[i].split("=", 1)[0]


def test_the_sample_is_smaller_than_the_file_and_holds_every_root_and_one_shape_of_each_kind(built):
    import ifcopenshell

    from fabrication.verify.ifc import SAMPLED_CLASSES, _kind, schema_sample

    f = ifcopenshell.open(str(built / "model.ifc"))
    ids = {i.id() for i in schema_sample(f)}
    every = set(f.entity_names())
    assert ids <= every and len(ids) < len(every)
    assert all(r.id() in ids for r in f.by_type("IfcRoot"))               # every GlobalId: the whole product tree
    assert all(p.id() in ids for p in f.by_type("IfcObjectPlacement"))
    not_sampled = [i for i in f if not any(i.is_a(c) for c in SAMPLED_CLASSES)]
    assert all(i.id() in ids for i in not_sampled)
    kinds = {_kind(r) for r in f.by_type("IfcRepresentation")}
    seen = {_kind(r) for r in f.by_type("IfcRepresentation") if r.id() in ids}
    assert seen == kinds
    for r in f.by_type("IfcRepresentation"):
        if r.id() in ids:                                                  # a sampled shape with all it references
            assert all(x.id() in ids for x in f.traverse(r) if x.id())


def test_an_empty_property_set_is_found_by_the_sample(built, tmp_path):
    assert _findings(built / "model.ifc", every=False) == []
    bad = tmp_path / "model.ifc"
    _tamper(built / "model.ifc", bad, r"#\d+=IFCPROPERTYSET\(", lambda s: re.sub(r",\((#\d+,?)+\)\);", ",());", s),
            which=-1)
    found = _findings(bad, every=False)
    assert found and any(m.startswith("IfcPropertySet:") for m in found)


def test_a_point_of_the_first_shape_of_a_kind_with_five_coordinates_is_found_by_the_sample(built, tmp_path):
    import ifcopenshell

    from fabrication.verify.ifc import schema_sample

    f = ifcopenshell.open(str(built / "model.ifc"))
    first = f.by_type("IfcShapeRepresentation")[0]
    point = next(x for x in f.traverse(first) if x.is_a("IfcCartesianPoint"))
    assert point.id() in {i.id() for i in schema_sample(f)}
    bad = tmp_path / "model.ifc"
    _tamper(built / "model.ifc", bad, rf"#{point.id()}=IFCCARTESIANPOINT\(",
            lambda s: re.sub(r"\(\((.*)\)\);", r"((\1,1.,2.));", s))
    found = _findings(bad, every=False)
    assert found and any(m.startswith("IfcCartesianPoint:") for m in found)


def test_every_instance_is_validated_with_kernel(built, tmp_path):
    bad = tmp_path / "model.ifc"
    _tamper(built / "model.ifc", bad, r"#\d+=IFCEXTRUDEDAREASOLID\(", lambda s: re.sub(r",([-0-9.E]+)\);", r",'\1');", s),
            which=-1)
    found = _findings(bad, every=True)
    assert found and any(m.startswith("IfcExtrudedAreaSolid:") for m in found)


@pytest.mark.parametrize("every", [False, True])
def test_the_validated_file_iterates_whole_again(built, every):
    import ifcopenshell
    import ifcopenshell.validate

    from fabrication.verify.ifc import validate_schema

    f = ifcopenshell.open(str(built / "model.ifc"))
    n = len(f.entity_names())
    validate_schema(f, ifcopenshell.validate.json_logger(), every=every)
    assert type(f) is ifcopenshell.file and sum(1 for _ in f) == n
