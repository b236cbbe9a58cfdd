"""The glass support, the splices, the welds and repetition, measured independently of the code that made them.

The bite is measured from the strip and gasket *solids* (build123d) and the panes' own 3D outlines with shapely:
each pane edge finds the gasket under it by position alone, and the overlap of its inward ray with the
gasket's top face (projected into the pane's plane) is the bite.  Splices are checked against the beam
pieces' outlines, welds against the plates' planes, panel pairs of the symmetric default against each other.
"""

from __future__ import annotations

import numpy as np
import pytest
from shapely.geometry import LineString, Point, Polygon

from conftest import REPO
from fabrication import load_design, parse_design
from fabrication.pipeline import stages
from fabrication.progress import Progress

DESIGNS = {"default": None, "pp_cauchy": REPO / "examples" / "pp_cauchy.toml",
           "pp_translational": REPO / "examples" / "pp_translational.toml",
           "conical_pp_rotational": REPO / "examples" / "conical_pp_rotational.toml"}
_CACHE: dict = {}


def _stages(name):
    """geometry → support → panels → beams → glazing of a design (cached per test session)."""
    if name not in _CACHE:
        design = load_design(DESIGNS[name])
        p = Progress(quiet=True)
        geometry = stages.stage_geometry(design, p, False)
        support = stages.stage_support(design, geometry, p)
        panels = stages.stage_panels(design, geometry, p)
        beams = stages.stage_beams(design, support, p, panels)
        glazing = stages.stage_glazing(design, support, panels, beams, p)
        _CACHE[name] = (design, support, panels, beams, glazing)
    return _CACHE[name]


def _gasket_tops(glazing) -> tuple[np.ndarray, np.ndarray]:
    """From the solids: ``(G, 4, 3)`` top-face corners of every gasket and ``(G, 3)`` its strip's centre."""
    from fabrication.writers.glazing import strip_solids

    solids = {s.label: np.array([tuple(v) for v in s.vertices()]) for s in strip_solids(glazing)}
    tops, centres = [], []
    for name, pts in solids.items():
        if not name.startswith("GK"):
            continue
        strip = solids["GS" + name[2:]]
        c = strip.mean(axis=0)
        up = pts.mean(axis=0) - c                          # the gasket sits on top of its strip
        up /= np.linalg.norm(up)
        tops.append(pts[np.argsort(-((pts - c) @ up))[:4]])
        centres.append(c)
    return np.array(tops), np.array(centres)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(DESIGNS))
def test_every_pane_edge_bites_on_its_gasket(name):
    design, support, panels, beams, glazing = _stages(name)
    tops, centres = _gasket_tops(glazing)
    assert len(tops) == len(support.edges)
    offset = glazing.params.thickness + glazing.params.gasket_thickness
    min_bite = design.panels.min_bite
    half = 0.5 * glazing.params.width
    smallest = np.inf
    for pane in panels.panels:
        n = pane.frame.normal
        ring = pane.outline_3d() + offset * n                   # the pane's underside, resting on the gaskets
        for k in range(len(ring)):
            a, b = ring[k], ring[(k + 1) % len(ring)]
            mid = 0.5 * (a + b)
            g = int(np.argmin(np.linalg.norm(centres - mid, axis=1)))   # the gasket under it, by position only
            d = (b - a) / np.linalg.norm(b - a)
            inward = np.cross(n, d)
            flat = lambda x: np.stack([(x - a) @ d, (x - a) @ inward], axis=-1)   # noqa: E731
            top = Polygon(flat(tops[g] - np.outer((tops[g] - a) @ n, n))).convex_hull
            length = float(np.linalg.norm(b - a))
            assert Polygon(flat(ring)).contains(Point(0.5 * length, 1.0))      # inward is into the pane
            for s in (0.25, 0.5, 0.75):
                bite = LineString([(s * length, 0.0), (s * length, 10 * half)]).intersection(top).length
                smallest = min(smallest, bite)
                assert bite >= min_bite, f"{pane.part_id} edge {k}: bite {bite:.2f} mm"
                # and no more than the strip's half width beyond the inset (the pane edge lies over the gasket)
                assert bite <= half - 0.5 * design.panels.gap + 1.0
    assert smallest == pytest.approx(glazing.bite_min, abs=0.5)


def test_bite_below_min_bite_stops_the_build_naming_panels_and_edges():
    from fabrication.glazing import BiteError

    design = load_design(DESIGNS["pp_cauchy"])
    doc = dict(design.raw)
    doc["glazing"] = {"width": 40.0}                  # 20 mm half width − 5 mm inset: a bite of about 15 mm
    doc["panels"] = dict(doc.get("panels", {}), min_bite=16.0)
    thin = parse_design(doc, design.source, design.sha256, design.base_dir)
    p = Progress(quiet=True)
    geometry = stages.stage_geometry(thin, p, False)
    support = stages.stage_support(thin, geometry, p)
    panels = stages.stage_panels(thin, geometry, p)
    beams = stages.stage_beams(thin, support, p)
    with pytest.raises(BiteError) as err:
        stages.stage_glazing(thin, support, panels, beams, p)
    text = str(err.value)
    assert "panels.min_bite = 16 mm" in text and " edge " in text and "P-" in text


@pytest.mark.slow
def test_every_split_beam_has_its_splice():
    design, support, panels, beams, glazing = _stages("default")
    pieces: dict[str, list] = {}
    for plate in beams.plates:
        if plate.n_pieces > 1 and not plate.meta.get("segment"):
            pieces.setdefault(plate.beam_id, []).append(plate)
    assert pieces, "the default has split beams"
    by_pair = {s.pieces: s for s in glazing.splices}
    for beam, ps in pieces.items():
        ps.sort(key=lambda q: q.piece)
        for a, b in zip(ps[:-1], ps[1:]):
            s = by_pair[(a.part_id, b.part_id)]
            pa = Polygon(a.outline)
            pb = Polygon(a.frame.to2d(b.frame.to3d(b.outline)))
            plate = Polygon(s.outline)
            assert pa.union(pb).buffer(1e-3).contains(plate)            # on the beam, clear of slots and ends
            inside_a = sum(pa.buffer(-0.5 * s.hole).contains(Point(*h)) for h in s.holes)
            inside_b = sum(pb.buffer(-0.5 * s.hole).contains(Point(*h)) for h in s.holes)
            assert inside_a == inside_b == len(s.holes) // 2 > 0       # half the bolts in each piece
            cut = LineString([a.top[-1], a.bottom[-1]])                  # the pieces' common end
            assert min(cut.distance(Point(*h)) for h in s.holes) >= 1.2 * s.hole - 1e-9
            # EN 1993-1-8 Table 3.3: hole centres at least 1.2 d0 from the cover plate's edges
            edge = min(plate.exterior.distance(Point(*h)) for h in s.holes)
            assert edge >= 1.2 * s.hole - 1e-9
    assert len(glazing.splices) == sum(len(ps) - 1 for ps in pieces.values())
    from fabrication.glazing.rows import beam_joins, splice_rows

    rows = splice_rows(glazing, beams)
    assert len(rows) == 2 * len(glazing.splices)
    joins = beam_joins(glazing)
    for s in glazing.splices:
        assert s.pieces[1] in joins[s.pieces[0]]["joins"].split(";")


@pytest.mark.parametrize("name", ["default", "pp_cauchy", "conical_pp_rotational"])
def test_cover_plates_keep_the_top_clearance_over_their_own_length(name):
    """Each cover plate's top edge lies ``splices.top_clear`` under the beam's top edge where it is closest to it,
    plus ``(t/2 + t_c)·tan λ`` under a glazing strip leaning by ``λ`` over the cut (its underside comes down that
    far over the plate's outer face; rounded up to whole millimetres from 0.25 mm less, so that plates of one cut
    size stay one type), and nowhere closer: that edge moved up (square to itself) by that much less
    0.01 mm stays inside the two pieces' outlines, moved by 0.05 mm more it leaves them (shapely); λ from the
    strips' solids' frames against the plate's plane.  pp_cauchy's plates were 7 mm lower where a crossing slot
    lay a plate's length from the cut; conical_pp_rotational's strips stood 6.4 mm in its cover plates."""
    design, support, panels, beams, glazing = _stages(name)
    plates = {p.part_id: p for p in beams.plates}
    assert glazing.splices
    for s in glazing.splices:
        a, b = plates[s.pieces[0]], plates[s.pieces[1]]
        n = a.plane[:3] / np.linalg.norm(a.plane[:3])
        over = [g for g in glazing.strips if {g.vertices[0], g.vertices[1]} & set(a.nodes.tolist())
                and {g.vertices[0], g.vertices[1]} & set(b.nodes.tolist())]
        lean = max((np.arcsin(abs(g.frame.normal @ n)) for g in over), default=0.0)
        exact = (0.5 * a.thickness + s.thickness) * np.tan(lean)
        drop = float(np.ceil(exact - 0.25 - 1e-9)) if exact > 0.25 else 0.0     # whole mm, 0.25 mm slack
        assert drop == int(drop) and exact - 0.25 <= drop <= exact + 0.75
        clear = design.splices.top_clear + drop
        body = Polygon(a.outline).union(Polygon(a.frame.to2d(b.frame.to3d(b.outline)))).buffer(1e-6)
        ring = np.asarray(s.outline)
        edges = [(ring[k], ring[(k + 1) % len(ring)]) for k in range(len(ring))]
        up_point = np.asarray(a.top[-1])
        p, q = min(edges, key=lambda e: float(np.linalg.norm(0.5 * (e[0] + e[1]) - up_point)))   # its top edge
        d = (q - p) / np.linalg.norm(q - p)
        n = np.array([-d[1], d[0]])
        if n @ (up_point - p) < 0:
            n = -n                                                 # square to the edge, towards the beam's top
        inside = LineString([p + (clear - 0.01) * n, q + (clear - 0.01) * n])
        beyond = LineString([p + (clear + 0.05) * n, q + (clear + 0.05) * n])
        assert body.contains(inside), (s.part_ids, name)
        assert not body.contains(beyond), (s.part_ids, name)


@pytest.mark.slow
def test_weld_dihedrals_are_the_angles_of_the_plates():
    design, support, panels, beams, glazing = _stages("default")
    assert glazing.welds
    planes = {p.part_id: p.plane for p in beams.plates}
    for w in glazing.welds:
        na, nb = planes[w.part][:3], planes[w.to][:3]
        cos = abs(na @ nb) / np.linalg.norm(na) / np.linalg.norm(nb)
        assert w.dihedral_deg == pytest.approx(np.degrees(np.arccos(min(1.0, cos))), abs=1e-6)
        runs = {"T": 2, "corner": 2, "halflap": 4}[w.joint]          # corner welds: both faces of the V
        assert w.length_mm == pytest.approx(runs * design.beams.depth)
        if w.joint != "corner":                                     # T and half-lap: EN 1993-1-8 fillet range
            assert (w.preparation == "double fillet") == (w.dihedral_deg >= 60.0)


def test_the_symmetric_default_pairs_its_panels():
    design = load_design()
    p = Progress(quiet=True)
    panels = stages.stage_panels(design, stages.stage_geometry(design, p, False), p).panels
    by_ij = {q.face_ij: q for q in panels}
    fm = 1 + max(i for i, _ in by_ij)
    fn = 1 + max(j for _, j in by_ij)

    def signature(q):                            # edge lengths and diagonals, in corner order from corner 0
        o = q.outline
        return np.r_[np.linalg.norm(np.roll(o, -1, 0) - o, axis=1), np.linalg.norm(o[2] - o[0]),
                     np.linalg.norm(o[3] - o[1])]

    for (i, j), q in by_ij.items():
        partner = by_ij[(fm - 1 - i, fn - 1 - j)]
        a, b = signature(q), signature(partner)
        best = min(float(np.abs(np.r_[np.roll(a[:4], s), a[4:] if s % 2 == 0 else a[4:][::-1]] - b).max())
                   for s in range(4))
        assert best < 1e-6, f"{q.part_id} and {partner.part_id} differ by {best:.3g} mm"
    from fabrication.repetition import panel_type_counts

    counts = panel_type_counts([q.outline for q in panels], False)
    assert counts["0"] == len(panels) // 2
    assert counts["0"] >= counts["1"] >= counts["2"] >= counts["5"]


def test_strips_are_cut_from_bars_without_overlap():
    from fabrication.glazing.cutlist import cut_bars

    rng = np.random.default_rng(3)
    lengths = {f"S{k}": float(x) for k, x in enumerate(rng.uniform(800, 2500, 60))}
    cuts, bound = cut_bars(lengths, 6000.0, 3.0)
    bars: dict[int, list] = {}
    for c in cuts:
        bars.setdefault(c.bar, []).append(c)
    for b, cs in bars.items():
        cs.sort(key=lambda c: c.start)
        for x, y in zip(cs[:-1], cs[1:]):
            assert y.start >= x.start + x.length + 3.0 - 1e-9
        assert cs[-1].start + cs[-1].length <= 6000.0 + 1e-9
    assert bound <= len(bars) <= (11 * bound) // 9 + 1
    assert len({c.nest_tag for c in cuts}) == len(cuts)


def test_node_types_fall_as_the_tolerance_grows():
    from fabrication.repetition import node_type_counts, node_types

    design, support, panels, beams, glazing = _stages("pp_cauchy")
    from fabrication.nodes import node_records

    records = node_records(beams)
    counts = list(node_type_counts(records).values())
    assert counts == sorted(counts, reverse=True) and counts[0] <= len(records)
    t = node_types(records, 1.0)
    from fabrication.repetition import node_signature

    for k in range(int(t.max()) + 1):                        # every member within 2 × tol of its type's first
        members = np.flatnonzero(t == k)
        ref = node_signature(records[members[0]])
        for m in members[1:]:
            sig = node_signature(records[m])
            assert sig[0] == ref[0] and np.abs(sig[1] - ref[1]).max() <= 1.0 + 1e-9
