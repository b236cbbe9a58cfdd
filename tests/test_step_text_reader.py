"""verify's text-level STEP reader (``fabrication/verify/_step_text_read.py``) against the CAD kernel on every
STEP file of a real build (beam plates with and without bolt holes, panes, glazing strips, gaskets, splice cover
plates), its parser on hand-written entities, the kernel's load of the product tree with one solid per kind,
and a tampered solid in each file found at the text level."""

from __future__ import annotations

import re
import shutil

import numpy as np
import pytest

from conftest import built_folder, small_vault
from fabrication.verify import Verification
from fabrication.verify._step_read import kernel_sample, read_or_report, read_step_solids, sample_file
from fabrication.verify._step_part21 import Ref, StepTextError, Typed, flat_params, parse_params, read_entities
from fabrication.verify._step_text_read import read_text_solids

built = built_folder("step_text", small_vault("step text", max_length=3000.0))

FILES = ["beams.step", "panels.step", "glazing.step", "splices.step"]


def _apart(a: np.ndarray, b: np.ndarray) -> float:
    """The largest distance from a point of either set to the nearest of the other (scipy's k-d tree)."""
    from scipy.spatial import cKDTree

    return float(max(cKDTree(b).query(a)[0].max(), cKDTree(a).query(b)[0].max()))


def test_parser_reads_strings_lists_and_complex_entities():
    data = b"""ISO-10303-21;
HEADER;
ENDSEC;
DATA;
#1 = PRODUCT('it''s; a (test)','B-U00','',(#8,
  #9));
#2 = ( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );
#3 = CARTESIAN_POINT('',(-1.5E+03,2.,
    3.25));
ENDSEC;
END-ISO-10303-21;
"""
    ents = read_entities(data)
    assert sorted(ents) == [1, 2, 3]
    assert parse_params(ents[1][1]) == ["it's; a (test)", "B-U00", "", [Ref(8), Ref(9)]]
    assert ents[2][0] == "" and [t.name for t in parse_params(ents[2][1])] == ["LENGTH_UNIT", "NAMED_UNIT",
                                                                              "SI_UNIT"]
    assert parse_params(ents[2][1])[2] == Typed("SI_UNIT", [".MILLI.", ".METRE."])
    assert parse_params(ents[3][1])[1] == [-1500.0, 2.0, 3.25]
    assert ents.kind(3) == "CARTESIAN_POINT" and 4 not in ents and ents.get(4) is None
    assert ents.of_kind("PRODUCT", "CARTESIAN_POINT").tolist() == [1, 3]
    with pytest.raises(StepTextError):
        parse_params("('a',(#1,#2)")
    # ids far apart (another writer's numbering): looked up by a table, not an array as long as the largest id
    sparse = read_entities(data.replace(b"#2 =", b"#2000000000 =").replace(b"#3 =", b"#77 ="))
    assert sorted(sparse) == [1, 77, 2000000000] and sparse.kind(2000000000) == "" and 2 not in sparse
    assert parse_params(sparse[77][1])[1] == [-1500.0, 2.0, 3.25]
    # a record cut short (no closing ';' outside its string) and one without parameters are named
    for broken in (data.replace(b"3.25));", b"3.25))"), data.replace(b"'B-U00'", b"'B-U00"),
                   data.replace(b"#3 = CARTESIAN_POINT(", b"#3 = CARTESIAN_POINT;(")):
        with pytest.raises(StepTextError, match="cannot parse the entity"):
            read_entities(broken)


@pytest.mark.parametrize("name", FILES)
def test_text_reader_and_kernel_agree_on_every_solid(built, name):
    """Names, assembly paths, vertices (1e-9 mm), volumes (1e-9 relative) and colours of every solid."""
    path = built / name
    ours = read_text_solids(path)
    theirs = read_step_solids(path, colours=True)
    assert len(ours) == len(theirs) > 0
    for mine, kern in zip(ours, theirs):
        assert (mine.name, mine.path) == (kern.name, kern.path)
        pts = np.array([tuple(p) for p in kern.solid.vertices()])
        assert pts.shape == mine.points.shape
        assert _apart(pts, mine.points) <= 1e-9
        assert mine.volume == pytest.approx(kern.solid.volume, rel=1e-9)
        assert len(mine.faces()) == len(kern.solid.faces())
        planes = sorted(f.area for f in kern.solid.faces() if f.geom_type.name == "PLANE")
        assert np.allclose(sorted(mine.face_area(f) for f in mine.faces() if f.surface == "plane"), planes,
                           rtol=1e-9, atol=1e-6)
        assert mine.problems() == []
        assert (kern.colour is None) == (mine.colour is None) == (name == "splices.step")   # plates uncoloured
        if mine.colour is not None and kern.colour is not None:
            assert np.allclose(mine.colour[:3], kern.colour[:3], atol=1e-9)


def test_text_and_kernel_solids_give_the_same_plate_bodies(built):
    """The thin-prism body of every beam plate (:func:`~fabrication.verify._bodies.body_of`: its largest face, and
    on a plate bevelled under a strip the part of it the opposite face holds too) is the same polygon and
    thickness from the text-level record as from the kernel's solid.  The text-level faces are made anew at each
    call, so the opposite face must be told from the largest one by its place in the shell, not by identity: by
    identity the largest face found itself, and the body of a bevelled plate stood up to 1.42 mm into its strip
    at 88 × 60 faces.  Some plates here are bevelled (their two faces differ)."""
    from fabrication.verify._bodies import _opposite_ring, body_of

    ours = read_text_solids(built / "beams.step")
    theirs = read_step_solids(built / "beams.step")
    bevelled = 0
    for mine, kern in zip(ours, theirs):
        a, b = body_of(mine), body_of(kern.solid)
        assert a.thick == pytest.approx(b.thick, abs=1e-9)
        assert a.flat.area == pytest.approx(b.flat.area, rel=1e-9)         # in frames of their own
        face = max((f for f in mine.faces() if f.surface == "plane"), key=mine.face_area)
        other = _opposite_ring(mine, face, a.n, True)
        assert other is not None
        own = mine.ring(mine.outer_loop(face), 16)
        if len(other) != len(own) or not np.allclose(np.sort(other, axis=0), np.sort(own, axis=0)):
            bevelled += 1
    assert bevelled > 0


def test_every_part_kind_is_covered(built):
    """The build holds every kind of solid ppfab writes, round holes included (cylinders and circles)."""
    names = {n: [s.name for s in read_text_solids(built / n)] for n in FILES}
    assert any(x.startswith("B-") for x in names["beams.step"])
    assert all(x.startswith("P-") for x in names["panels.step"])
    assert {x[:3] for x in names["glazing.step"]} >= {"GS-", "GK-"}
    assert all(x.startswith("SP-") for x in names["splices.step"])
    plates = read_text_solids(built / "splices.step")
    holes = [f for f in plates[0].faces() if f.surface == "cylinder"]
    assert holes and len(plates[0].circle_centres()) == 2 * len(holes)
    beams = read_text_solids(built / "beams.step")
    assert any(f.surface == "cylinder" for s in beams for f in s.faces()), "no beam piece with bolt holes"


@pytest.mark.parametrize("name", FILES)
def test_kernel_loads_the_tree_with_one_solid_per_kind(built, name):
    """The sample file holds every product of the tree but fewer B-reps (one per kind); the kernel reads it
    and agrees with the text-level reader on names, paths, placements, and the kept solids."""
    path = built / name
    solids = read_text_solids(path)
    data = path.read_bytes()
    sample, kept = sample_file(data, solids)
    kinds = len({s.shape_key() for s in solids})
    assert sum(kept) == kinds
    assert sample.count(b"MANIFOLD_SOLID_BREP(") == kinds
    assert sample.count(b"NEXT_ASSEMBLY_USAGE_OCCURRENCE(") == data.count(b"NEXT_ASSEMBLY_USAGE_OCCURRENCE(")
    assert kernel_sample(path, solids) == []


def _tamper_vertex(path, solid_index: int) -> str:
    """Move one vertex of the ``solid_index``-th solid 0.5 mm along x in the file's text; its name."""
    solids = read_text_solids(path)
    target = solids[solid_index]
    data = path.read_bytes()
    ents = read_entities(data)
    shell = parse_params(ents[target.brep][1])[1].id
    face = parse_params(ents[shell][1])[1][0].id
    todo, seen, point = [face], set(), None
    while todo and point is None:                  # the first VERTEX_POINT below the first face
        i = todo.pop(0)
        if i in seen:
            continue
        seen.add(i)
        kind, params = ents[i]
        if kind == "VERTEX_POINT":
            point = parse_params(params)[1].id
            break
        todo.extend(int(x) for x in re.findall(r"#(\d+)", params))
    assert point is not None
    x = parse_params(ents[point][1])[1]
    old = re.compile(rb"#%d\s*=\s*CARTESIAN_POINT\([^;]*;" % point)
    new = b"#%d = CARTESIAN_POINT('',(%r,%r,%r));" % (point, x[0] + 0.5, x[1], x[2])
    changed, n = old.subn(new, data)
    assert n == 1
    path.write_bytes(changed)
    return target.name


@pytest.mark.parametrize("name", FILES)
def test_a_tampered_solid_is_found_at_the_text_level(built, tmp_path, name):
    """One vertex of one solid moved 0.5 mm in the STEP text: the reader finds that solid invalid (a vertex off
    its faces' planes) — and every other solid placing the same B-rep (an instanced shape: the two cover plates
    of a splice), none else — and verify's STEP reading reports it by name; the kernel sample leaves it to the
    text."""
    folder = tmp_path / "copy"
    folder.mkdir()
    shutil.copy(built / name, folder / name)
    solids = read_text_solids(folder / name)
    k = len(solids) // 2
    pid = _tamper_vertex(folder / name, k)
    again = read_text_solids(folder / name)
    assert [s.name for s in again] == [s.name for s in solids]
    bad = [s.name for s in again if s.problems()]
    sharing = [s.name for s in solids if s.brep == solids[k].brep]
    assert pid in sharing and bad == sharing and len(sharing) < len(solids)
    assert "off its face's surface" in " ".join(again[k].problems())
    v = Verification(folder)
    read = read_or_report(v, name)
    assert read is not None and len(read) == len(solids)
    assert any(f.element == pid and "solid is not valid" in f.message for f in v.findings), v.findings


def test_kernel_option_reads_every_solid_with_the_kernel(built):
    v = Verification(built, kernel=True)
    read = read_or_report(v, "panels.step")
    assert read is not None and v.findings == []
    assert all(hasattr(s.solid, "wrapped") for s in read)          # build123d solids
    text = read_or_report(Verification(built), "panels.step")
    assert text is not None and all(isinstance(s.solid.points, np.ndarray) for s in text)


def test_a_file_written_with_p_curves_is_read(built, tmp_path, monkeypatch):
    """Another writer's file (build123d's export with p-curves: every edge a SURFACE_CURVE or SEAM_CURVE over its
    3D line or circle) gives the same solids: vertices to 1e-9 mm, volumes to 1e-9."""
    from build123d import Compound, export_step

    kernel = read_step_solids(built / "splices.step")[:3]
    for s in kernel:
        s.solid.label = s.name
    out = tmp_path / "again.step"
    export_step(Compound(children=[s.solid for s in kernel]), str(out))
    assert b"SURFACE_CURVE(" in out.read_bytes()
    import fabrication.verify._step_breps as breps

    general = []                                   # records the B-rep tables' patterns leave to the full parser
    canonical = breps._canonical
    monkeypatch.setattr(breps, "_canonical", lambda *a: general.append(a[2]) or canonical(*a))
    again = read_text_solids(out)
    assert "CARTESIAN_POINT" in general            # the p-curves' 2D points: read, never taken for vertices
    assert [s.name for s in again] == [s.name for s in kernel]
    for mine, kern in zip(again, kernel):
        assert _apart(np.array([tuple(p) for p in kern.solid.vertices()]), mine.points) <= 1e-9
        assert mine.volume == pytest.approx(kern.solid.volume, rel=1e-9) and mine.problems() == []


def test_a_solid_turned_inside_out_is_found(built, tmp_path):
    """Every face bound of panels.step reversed (each loop runs the other way, the shell's edges still used twice in
    opposite senses): each solid's volume is negative and named, its face areas (kept per B-rep, unsigned) are the
    original's."""
    data = (built / "panels.step").read_bytes()
    flipped = re.sub(rb"(FACE_(?:OUTER_)?BOUND\('[^']*',#\d+,)\.T\.\)", rb"\1.F.)", data)
    assert flipped != data
    (tmp_path / "panels.step").write_bytes(flipped)
    before, after = read_text_solids(built / "panels.step"), read_text_solids(tmp_path / "panels.step")
    assert len(before) == len(after) > 0
    for a, b in zip(before, after):
        assert b.volume == pytest.approx(-a.volume, rel=1e-9)
        assert any("is not positive" in p for p in b.problems()), b.name
        assert sorted(b.face_area(f) for f in b.faces()) == pytest.approx(sorted(a.face_area(f) for f in a.faces()))


def test_records_in_another_layout_give_the_same_solids(built, tmp_path):
    """The B-rep tables are matched chunk by chunk by one pattern per type; records spaced and broken across lines
    as another writer may write them, with lower-case exponents, give the same solids (vertices, faces, volumes)
    as the file as written."""
    data = (built / "splices.step").read_bytes()
    spaced = re.sub(rb"(#\d+ = EDGE_CURVE\('',#\d+),(#\d+)", rb"\1 ,\n  \2", data)
    spaced = re.sub(rb"(ORIENTED_EDGE\('',\*),\*", rb"\1 , * ", spaced)
    spaced = re.sub(rb"(CARTESIAN_POINT\('',\()([-0-9.]+)E([-+]?\d+)", rb"\1\2e\3", spaced)
    spaced = re.sub(rb"(CLOSED_SHELL\('',\()#", rb"\1 #", spaced)
    assert spaced != data and spaced.count(b",\n  #") > 100
    (tmp_path / "splices.step").write_bytes(spaced)
    before, after = read_text_solids(built / "splices.step"), read_text_solids(tmp_path / "splices.step")
    assert [s.name for s in after] == [s.name for s in before]
    for a, b in zip(before, after):
        assert np.array_equal(a.points, b.points)
        assert np.array_equal(a.code.steps, b.code.steps) and np.allclose(a.code.planes, b.code.planes)
        assert b.volume == pytest.approx(a.volume, rel=1e-12) and b.problems() == []


def test_a_brep_reference_to_the_wrong_entity_is_named(built, tmp_path):
    """A face bound pointing at a vertex, and a shell pointing at an entity that is not there, are refused with
    the entity named."""
    data = (built / "panels.step").read_bytes()
    ents = read_entities(data)
    bound = int(ents.of_kind("FACE_OUTER_BOUND")[3])
    vertex = int(ents.of_kind("VERTEX_POINT")[0])
    wrong = re.sub(rb"(#%d = FACE_OUTER_BOUND\('',)#\d+" % bound, rb"\1#%d" % vertex, data)
    assert wrong != data
    (tmp_path / "wrong.step").write_bytes(wrong)
    with pytest.raises(StepTextError, match=f"#{vertex} is a VERTEX_POINT, not an EDGE_LOOP"):
        read_text_solids(tmp_path / "wrong.step")
    shell = int(ents.of_kind("CLOSED_SHELL")[0])
    top = int(ents.ids.max()) + 10
    dangling = re.sub(rb"(#%d = CLOSED_SHELL\('',\()#\d+" % shell, rb"\1#%d" % top, data)
    (tmp_path / "dangling.step").write_bytes(dangling)
    with pytest.raises(StepTextError, match=f"#{top} is referenced but not defined"):
        read_text_solids(tmp_path / "dangling.step")


def test_ranges_concatenates_aranges():
    from fabrication.verify._step_breps import ranges

    starts, counts = np.array([5, 0, 9, 2]), np.array([3, 0, 1, 2])
    assert ranges(starts, counts).tolist() == [5, 6, 7, 9, 2, 3]
    assert ranges(np.zeros(0, int), np.zeros(0, int)).tolist() == []


def test_a_shell_missing_a_face_names_an_edge_of_the_hole(built, tmp_path):
    """One face left out of a pane's closed shell: the edges around the hole are used once; the reader counts
    them (a pane's face is a quad: 4) and names the first its loops reach, an edge of the face left out."""
    data = (built / "panels.step").read_bytes()
    ents = read_entities(data)
    shell = int(ents.of_kind("CLOSED_SHELL")[0])
    faces = parse_params(ents[shell][1])[1]
    gone = faces[-1].id
    edges = set()
    bound = parse_params(ents[gone][1])[1][0].id
    loop = parse_params(ents[bound][1])[1].id
    for oe in parse_params(ents[loop][1])[1]:
        edges.add(parse_params(ents[oe.id][1])[3].id)
    cut = re.sub(rb"(#%d = CLOSED_SHELL\('',\([^)]*),#%d\)" % (shell, gone), rb"\1)", data)
    assert cut != data
    (tmp_path / "panels.step").write_bytes(cut)
    hit = [s for s in read_text_solids(tmp_path / "panels.step") if s.problems()]
    assert hit
    facts = hit[0].facts()
    assert facts.bad_edges == len(edges) == 4 and facts.first_bad_edge in edges
    assert f"(#{facts.first_bad_edge})" in hit[0].problems()[0]


def test_flat_records_split_at_commas_read_as_the_full_parser_reads_them(built):
    """Every record of the built files that the flat reader takes (a product's, an occurrence's, a placement's)
    gives what the full parser gives; records with nested lists, strings holding commas or parentheses, or
    escaped quotes are left to the full parser."""
    taken = 0
    for name in FILES:
        ents = read_entities((built / name).read_bytes())
        for i in ents.of_kind("NEXT_ASSEMBLY_USAGE_OCCURRENCE", "PRODUCT", "PRODUCT_DEFINITION",
                              "CONTEXT_DEPENDENT_SHAPE_REPRESENTATION", "ITEM_DEFINED_TRANSFORMATION",
                              "SHAPE_DEFINITION_REPRESENTATION", "COLOUR_RGB", "AXIS2_PLACEMENT_3D").tolist():
            text = ents[i][1]
            got = flat_params(text)
            if got is not None:
                taken += 1
                assert got == parse_params(text), text
    assert taken > 1000
    assert flat_params("('a',#3,$,*,.T.,.UNSPECIFIED.,-1.5E+03)") == ["a", Ref(3), None, "*", True, ".UNSPECIFIED.",
                                                                      -1500.0]
    for nested in ("('a',(#1,#2))", "('a, b',#3)", "('it''s',#3)", "('(x)',#3)"):
        assert flat_params(nested) is None


def test_each_type_is_read_into_one_table():
    """The reader keeps one row number per entity for all its tables, so no type may be in two layouts."""
    from fabrication.verify._step_breps import LAYOUTS

    types = [t for layout in LAYOUTS.values() for t in layout.types]
    assert len(types) == len(set(types))


def test_a_file_numbered_past_two_to_the_31_reads_the_same(built, tmp_path):
    """Another writer's numbering: every id of splices.step moved past 2³¹ (the tables keep references 32-bit only
    where they fit) gives the same solids."""
    data = (built / "splices.step").read_bytes()
    head, body = data.split(b"DATA;", 1)
    moved = re.sub(rb"#(\d+)", lambda m: b"#%d" % (int(m.group(1)) + 3_000_000_000), body)
    (tmp_path / "splices.step").write_bytes(head + b"DATA;" + moved)
    before, after = read_text_solids(built / "splices.step"), read_text_solids(tmp_path / "splices.step")
    assert [s.name for s in after] == [s.name for s in before] and len(after) > 0
    for a, b in zip(before, after):
        assert b.brep == a.brep + 3_000_000_000
        assert np.array_equal(a.points, b.points) and b.volume == pytest.approx(a.volume, rel=1e-12)


def test_b_reps_measured_in_chunks_give_the_facts_measured_at_once(built, monkeypatch):
    """The reader measures the B-reps a chunk at a time (``FACTS_CHUNK``, to bound its peak memory): in chunks of
    a few B-reps, glazing.step's solids have exactly the volumes, face and loop areas and validity found with
    all B-reps in one chunk, and each its own B-rep's facts."""
    import fabrication.verify._step_text_read as reader

    monkeypatch.setattr(reader, "FACTS_CHUNK", 10**9)
    whole = read_text_solids(built / "glazing.step")
    monkeypatch.setattr(reader, "FACTS_CHUNK", 7)
    chunked = read_text_solids(built / "glazing.step")
    assert len({s.brep for s in whole}) > 3 * 7 and [s.name for s in chunked] == [s.name for s in whole]
    for a, b in zip(whole, chunked):
        assert b.facts() == a.facts() and b.brep == a.brep
    assert len({s.facts().volume for s in chunked}) > 7


@pytest.mark.parametrize("reader", ["text", "kernel"])
def test_a_read_leaves_no_reference_cycle_to_collect(built, reader):
    """Both readers let go of what they read with when they return (the text-level reader the file's text, its
    tables and parsed records; the kernel its document): with the cyclic collector off, nothing either made is
    left in a reference cycle, which would hold it until the next collection (at 88 × 60 faces the text read's
    cycle held glazing.step's text and tables through the kernel's read of its sample)."""
    from conftest import left_for_the_collector

    def read():
        return read_text_solids(built / "splices.step") if reader == "text" else \
            read_step_solids(built / "splices.step", colours=True, leaves=True)

    solids, left = left_for_the_collector(read)
    assert len(solids) > 0 and left == 0
