"""The IFC schema validation of ``ppfab verify``: ifcopenshell's validator on the product tree and one shape,
placement, property and property set of each kind (:func:`fabrication.verify.ifc.schema_sample`), the GlobalIds
of every instance, every instance with ``--kernel``.

Each case breaks one instance of a written ``model.ifc`` in the text (a property set with no properties, a point
with five coordinates, an extrusion depth that is text, a GlobalId used twice or malformed) and asks the
validator, through the sample or over every instance, for the finding: the sample is held to what it promises;
what it leaves out (a part's own property set) is found by the check that reads every part's properties.
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
    per_part = ("IfcRelDefinesByProperties", "IfcPropertySetDefinition")
    assert all(r.id() in ids for r in f.by_type("IfcRoot") if not any(r.is_a(c) for c in per_part))
    assert all(e.id() in ids for e in f.by_type("IfcElement"))              # the product tree, every element
    for cls in ("IfcObjectPlacement", *per_part):                            # one of each kind, and fewer
        every_of = f.by_type(cls)
        assert {_kind(i) for i in every_of if i.id() in ids} == {_kind(i) for i in every_of}
        assert sum(i.id() in ids for i in every_of) < len(every_of) // 4
    not_sampled = [i for i in f if not any(i.is_a(c) for c in SAMPLED_CLASSES)]
    assert all(i.id() in ids for i in not_sampled)
    kinds = {_kind(r) for r in f.by_type("IfcRepresentation")}
    seen = {_kind(r) for r in f.by_type("IfcRepresentation") if r.id() in ids}
    assert seen == kinds
    for r in f.by_type("IfcRepresentation"):
        if r.id() in ids:                                                  # a sampled shape with all it references
            assert all(x.id() in ids for x in f.traverse(r) if x.id())


def test_an_empty_property_set_is_found_by_the_sample_or_by_the_parts_check(built, tmp_path):
    """The first property set of its kind emptied: the schema sample finds it.  The last (a part's own, not
    sampled): the ifc check finds the part's properties missing against parts.csv."""
    import shutil

    from fabrication.verify import Verification, load_checks

    assert _findings(built / "model.ifc", every=False) == []
    empty = (r"#\d+=IFCPROPERTYSET\(", lambda s: re.sub(r",\((#\d+,?)+\)\);", ",());", s))
    first = tmp_path / "first.ifc"
    _tamper(built / "model.ifc", first, *empty, which=0)
    found = _findings(first, every=False)
    assert found and any(m.startswith("IfcPropertySet:") for m in found)
    import ifcopenshell

    from fabrication.verify.ifc import schema_sample

    f = ifcopenshell.open(str(built / "model.ifc"))
    sampled = {i.id() for i in schema_sample(f)}
    pset = [p for p in f.by_type("IfcPropertySet") if p.id() not in sampled and p.DefinesOccurrence][-1]
    part = pset.DefinesOccurrence[0].RelatedObjects[0].Name
    copy = tmp_path / "copy"
    shutil.copytree(built, copy)
    _tamper(built / "model.ifc", copy / "model.ifc", rf"#{pset.id()}=IFCPROPERTYSET\(", empty[1])
    assert not any(m.startswith("IfcPropertySet:") for m in _findings(copy / "model.ifc", every=False))
    v = Verification(copy)
    found_v, _ = v.run_check({c.name: c for c in load_checks()}["ifc"])
    assert any(f.element == part and "parts.csv has" in f.message for f in found_v), found_v


@pytest.mark.parametrize("how", ["twice", "malformed"])
def test_a_bad_global_id_outside_the_sample_is_found(built, tmp_path, how):
    """The GlobalId of a part's own property set (not in the sample) set to the first element's, or to text that
    is no compressed GUID: the GlobalId pass over every instance finds it, naming the rule."""
    import ifcopenshell

    from fabrication.verify.ifc import schema_sample

    f = ifcopenshell.open(str(built / "model.ifc"))
    sampled = {i.id() for i in schema_sample(f)}
    target = [p for p in f.by_type("IfcPropertySet") if p.id() not in sampled][-1]
    first = f.by_type("IfcElement")[0].GlobalId
    new_id = first if how == "twice" else "not-a-guid!"
    bad = tmp_path / "model.ifc"
    _tamper(built / "model.ifc", bad, rf"#{target.id()}=IFCPROPERTYSET\(",
            lambda s: re.sub(r"IFCPROPERTYSET\('[^']*'", f"IFCPROPERTYSET('{new_id}'", s))
    found = _findings(bad, every=False)
    want = "IfcRoot.UR1" if how == "twice" else "is not a compressed GUID"
    assert any(m.startswith("IfcPropertySet:") and want in m for m in found), found


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
