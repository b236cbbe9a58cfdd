"""parts.csv and welds.csv: every cut of a split beam has its splice, and the splice files hold them.

Consecutive pieces of one beam (``beam_id``, ``piece`` of ``parts.csv``) that share no node were cut inside an
edge (one-edge segments of a segmented beam, and the parts of a column ``[beams] segment = ["blocked"]`` cut at
a node, share their node and are welded there, :mod:`.welds` of the glazing package).  Each such cut is
spliced either way, never both and never neither:

* bolted: two rows of kind ``splice`` join the pieces (``joins = "<piece k>;<piece k+1>"``), and every cover
  plate has a solid in ``splices.step`` with ``holes`` bolt holes;
* welded: one row of ``welds.csv`` with ``joint = "splice"`` joins them (either order), a full-penetration
  weld of positive length.

A splice weld between pieces that are not neighbours across a cut is a finding too.

Every cover plate solid is where the joined pieces put it (:func:`check_plate_place`): the pieces' outlines
are their cutting outlines (DXF) mapped back through placement and frame into the first piece's frame, the cut
is the edge the two share (top point ``c``, down the cut ``s``), the top edge ``u`` the first piece's edge
into ``c``; the plate lies flat on a face of the beam plate (``t/2 ≤ |z| ≤ t/2 + t_c``, one plate on each
face), centred on the cut (its corners' mean on the cut line) and ``splices.top_clear`` under the top edge,
plus ``(t/2 + t_c)·tan λ`` rounded up to whole millimetres (:func:`fabrication.glazing.splices.strip_drop`)
where the glazing strips over the cut lean by ``λ`` off the plate (bevels.csv; its three decimals of a degree
are allowed for at a rounding boundary).
The check runs after the dxf check (order 56), whose outlines it reads.

Every per-type cover plate DXF (``splices/<type>.dxf``) holds one CUT outline whose XDATA names its type (the
file's name) and the number of cover plates of that type in parts.csv, with the sides of that type's plates in
splices.step, and one CUT circle of ``hole_mm`` per bolt hole (:func:`check_splice_dxfs`).
"""

from __future__ import annotations

import ast
from dataclasses import dataclass

import numpy as np

from ..glazing.splices import strip_drop
from . import Verification, check, read_csv
from ._shapes import boundary_distance, face_outline, frame_of, number, solid_points, to_frame

PLACE_TOL = 0.01

LEAN_STEP = float(np.radians(0.0005))
"""Half the last place of bevels.csv's ``lean_deg`` (three decimals), radians: the lean read back may be this far
from the build's, which moves the cover plate's whole-millimetre drop only at a rounding boundary."""
"""How far (mm) a cover plate may be from where the pieces put it (the build measures its clearances from the
pieces' outlines grown by 1 µm)."""


def _nodes(row: dict[str, str]) -> set[int]:
    try:
        return {int(x) for x in ast.literal_eval(row.get("nodes") or "[]")}
    except (ValueError, SyntaxError):
        return set()


def _splice_welds(v: Verification, files: dict) -> dict[frozenset[str], dict[str, str]]:
    """The ``joint = "splice"`` rows of welds.csv by the pair of pieces they join."""
    rel = files.get("welds_csv")
    if rel is None:
        return {}
    try:
        rows = read_csv(v.folder / rel)
    except OSError as exc:
        v.error(rel, "", f"cannot be read ({exc})")
        return {}
    return {frozenset((r["part"], r["to"])): r for r in rows if r.get("joint") == "splice"}


@check("splices")
def check_splices(v: Verification) -> None:
    rows = (v.parts or [])
    files = v.manifest.get("files", {})
    beams: dict[str, list[dict[str, str]]] = {}
    for row in rows:
        if row["kind"] == "beam" and row.get("pieces") not in (None, "", "1"):
            beams.setdefault(row.get("beam_id", ""), []).append(row)
    joined: dict[tuple[str, str], list[str]] = {}
    for row in rows:
        if row["kind"] == "splice":
            one, _, other = row.get("joins", "").partition(";")
            joined.setdefault((one, other), []).append(row["part_id"])
    welded = _splice_welds(v, files)
    wanted = 0
    cuts: set[frozenset[str]] = set()
    for beam, pieces in beams.items():
        pieces.sort(key=lambda r: int(r.get("piece") or 0))
        pairs = list(zip(pieces[:-1], pieces[1:]))
        last = (pieces[-1]["part_id"], pieces[0]["part_id"])
        if len(pieces) > 2 and (frozenset(last) in welded or last in joined):
            pairs.append((pieces[-1], pieces[0]))                # a closed beam's last cut
        for a, b in pairs:
            if _nodes(a) & _nodes(b):
                continue                                 # pieces meeting at a node: welded there
            wanted += 1
            key = frozenset((a["part_id"], b["part_id"]))
            cuts.add(key)
            plates = joined.get((a["part_id"], b["part_id"]), [])
            weld = welded.get(key)
            where = f"{a['part_id']}/{b['part_id']}"
            if weld is not None and plates:
                v.error("parts.csv", where, f"the cut between these pieces of {beam} has both {len(plates)} cover "
                                            "plate(s) and a splice weld in welds.csv")
            elif weld is not None:
                if not (number(weld.get("weld_length_mm"), 0.0) > 0 and "full penetration" in weld.get("preparation", "")):
                    v.error("welds.csv", where, f"the splice weld of {beam} is not a full-penetration weld of positive "
                                                f"length ({weld.get('preparation')!r}, {weld.get('weld_length_mm')} mm)")
            elif len(plates) != 2:
                v.error("parts.csv", where,
                        f"the cut between these pieces of {beam} has {len(plates)} splice cover plate(s), expected 2 "
                        "(or a splice weld in welds.csv)")
    for key in welded:
        if key not in cuts:
            v.error("welds.csv", "/".join(sorted(key)), "splice weld between pieces that share no cut of one beam")
    rel = files.get("splices_step")
    splice_rows = [r for r in rows if r["kind"] == "splice"]
    if splice_rows and rel is None:
        v.error("manifest.json", "files", "parts.csv lists splice cover plates but no splices_step file")
    elif rel is not None:
        from ._step_read import read_or_report

        read = read_or_report(v, rel)
        if read is None:
            return
        solids = {s.name: s.solid for s in read}
        sides: dict[str, list[str]] = {}
        strips = StripsOverCuts.of(v)
        for r in splice_rows:
            s = solids.get(r["part_id"])
            if s is None:
                v.error(rel, r["part_id"], "cover plate has no solid")
                continue
            holes_cell = number(r.get("holes") or 0)
            if not float(holes_cell).is_integer():
                v.error("parts.csv", r["part_id"], f"holes {r.get('holes')!r} is not a whole number")
                continue
            holes = int(holes_cell)
            inner = len(s.faces()) - 6                       # a plate with h holes: 6 faces + one per hole
            if inner != holes:
                v.error(rel, r["part_id"], f"solid has {inner} hole faces, parts.csv says {holes} holes")
            check_plate_place(v, rel, r, s, sides, strips)
        for joins, names in sorted(sides.items()):
            if sorted(names) != ["+", "-"]:
                v.error(rel, joins.replace(";", "/"), f"cover plates lie on faces {names} of the beam plate, expected "
                                                      "one on each face")
        check_splice_dxfs(v, files.get("splice_dxfs", []), splice_rows, solids)
        if len(solids) != len(splice_rows):
            v.error(rel, "", f"{len(solids)} solids for {len(splice_rows)} cover plates in parts.csv")
    v.checked.append("splices")


def _piece_outline(v: Verification, pid: str, frame: dict[str, np.ndarray]) -> np.ndarray | None:
    """The cutting outline of beam piece ``pid`` mapped back into 3D and then into ``frame`` (2D)."""
    from ._solids import reference_outline

    row = v.part_row(pid)
    ref = reference_outline(v, row) if row is not None else None
    return None if ref is None else to_frame(ref, frame)[:, :2]


def _cut(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The cut between two pieces' outlines (2D, one frame): its top point, the unit direction down the cut and
    the unit direction of the first piece's top edge into the cut; ``None`` when they share no edge."""
    near = boundary_distance(a, b) <= 1e-3
    k = len(a)
    for i in range(k):
        j = (i + 1) % k
        if near[i] and near[j]:
            top, low = (i, j) if a[i, 1] >= a[j, 1] else (j, i)
            s = a[low] - a[top]
            prev = (top - 1) % k if (top + 1) % k == low else (top + 1) % k
            u = a[top] - a[prev]
            return a[top], s / np.linalg.norm(s), u / np.linalg.norm(u)
    return None


def check_plate_place(v: Verification, rel: str, row: dict[str, str], solid, sides: dict[str, list[str]],
                      strips: StripsOverCuts) -> None:
    """One cover plate solid against the pieces it joins (module docstring)."""
    pid = row["part_id"]
    first, _, second = row.get("joins", "").partition(";")
    piece = v.part_row(first)
    frame = frame_of(piece) if piece is not None else None
    if frame is None:
        return
    a, b = _piece_outline(v, first, frame), _piece_outline(v, second, frame)
    if a is None or b is None:
        return
    cut = _cut(a, b)
    if cut is None:
        v.error("parts.csv", pid, f"the pieces {first} and {second} it joins share no cut edge")
        return
    c, s, u = cut
    fab = v.manifest.get("fabrication", {})
    t = float(fab.get("beam_thickness", 0.0))
    tc = number(row.get("thickness_mm"), 0.0)
    z = to_frame(solid_points(solid), frame)[:, 2]
    side = "+" if z.mean() > 0 else "-"
    sides.setdefault(row.get("joins", ""), []).append(side)
    az = np.abs(z)
    if len(z) == 0 or abs(az.min() - 0.5 * t) > PLACE_TOL or abs(az.max() - 0.5 * t - tc) > PLACE_TOL \
            or z.min() * z.max() < 0:
        v.error(rel, pid, f"solid spans z = {z.min():.4g} … {z.max():.4g} mm in {first}'s frame, expected "
                          f"{0.5 * t:g} … {0.5 * t + tc:g} mm on one face of the beam plate")
        return
    ring = face_outline(solid, frame["normal"])
    if ring is None:
        v.error(rel, pid, "solid has no face in the beam plate's plane")
        return
    q = to_frame(ring, frame)[:, :2]
    across = np.array([-s[1], s[0]])
    off = float((q.mean(axis=0) - c) @ across)
    if abs(off) > PLACE_TOL:
        v.error(rel, pid, f"cover plate is {abs(off):.3g} mm off the cut between {first} and {second} "
                          "(centred on it in the build)")
    down = np.array([u[1], -u[0]])
    down = down if down @ s > 0 else -down
    clear = float(((q - c) @ down).min())
    raised, lean = _raise_at_cut(v, first, second, strips)
    base = float(fab.get("splices", {}).get("top_clear", 0.0)) + raised
    drops = {strip_drop(t, tc, max(0.0, lean + k * LEAN_STEP)) for k in (-1, 0, 1)}     # bevels.csv's rounding
    want = base + strip_drop(t, tc, lean)
    if all(abs(clear - (base + d)) > PLACE_TOL for d in drops):
        v.error(rel, pid, f"cover plate is {clear:.4g} mm under the top edge of {first}, splices.top_clear is "
                          f"{want:g} mm")


@dataclass(frozen=True)
class StripsOverCuts:
    """What :func:`_raise_at_cut` reads, gathered once per check: the strips ending at each node (part id and
    both end nodes, ``edge_nodes`` of ``parts.csv``) and the ``bevels.csv`` rows of each strip with their row
    numbers."""

    at_node: dict[int, list[tuple[str, frozenset[int]]]]
    bevels: dict[str, list[tuple[int, dict[str, str]]]]

    @classmethod
    def of(cls, v: Verification) -> "StripsOverCuts":
        rel = v.manifest.get("files", {}).get("bevels_csv")
        if rel is None or not (v.folder / rel).is_file():
            return cls({}, {})
        at_node: dict[int, list[tuple[str, frozenset[int]]]] = {}
        for r in (v.parts or []):
            if r.get("kind") == "strip":
                ends = frozenset(int(k) for k in r.get("edge_nodes", "").split(";") if k.strip().lstrip("-").isdigit())
                if len(ends) == 2:
                    for k in ends:
                        at_node.setdefault(k, []).append((r["part_id"], ends))
        bevels: dict[str, list[tuple[int, dict[str, str]]]] = {}
        for i, row in enumerate(v.table(rel)):
            bevels.setdefault(row.get("strip", ""), []).append((i, row))
        return cls(at_node, bevels)


def _raise_at_cut(v: Verification, first: str, second: str, strips: StripsOverCuts) -> tuple[float, float]:
    """``(Δ, λ)`` at the cut between two pieces, from bevels.csv for the strips over the cut (their
    ``edge_nodes`` one node of either piece): how far (mm) the cutting outline's top edge stands above the plate's
    (the ``delta_mm`` of the first strip in bevels.csv that bevels the piece's top edge,
    :mod:`fabrication.beams.bevel_cut`, else 0) and the largest lean (radians, ``lean_deg``) of those strips off
    the plate, whose underside comes down ``(t/2 + t_c)·tan λ`` over a cover plate's outer face."""
    one, two = v.part_row(first), v.part_row(second)
    if not strips.bevels or one is None or two is None:
        return 0.0, 0.0
    try:
        a, b = ({int(k) for k in ast.literal_eval(r.get("nodes", "[]"))} for r in (one, two))
    except (ValueError, SyntaxError, TypeError):
        return 0.0, 0.0
    over = {pid for k in a for pid, ends in strips.at_node.get(k, ()) if ends & b}
    bevelled = bool(number(one.get("bevels"), 0.0))     # else the piece keeps a square top edge
    raised, lean = 0.0, 0.0
    for _, row in sorted((r for pid in over for r in strips.bevels.get(pid, ())), key=lambda r: r[0]):
        lean = max(lean, float(np.radians(number(row.get("lean_deg"), 0.0))))
        if bevelled and row.get("bevel", "square") != "square" and not raised:
            raised = number(row.get("delta_mm"), 0.0)
    return raised, lean


def _sides(ring: np.ndarray) -> np.ndarray:
    """Side lengths of a closed polygon, sorted."""
    return np.sort(np.linalg.norm(np.roll(ring, -1, axis=0) - ring, axis=1))


def check_splice_dxfs(v: Verification, rels: list[str], rows: list[dict[str, str]], solids: dict) -> None:
    """The per-type cover plate DXFs against parts.csv and splices.step (module docstring)."""
    from ._dxf_read import dxf_content

    by_type: dict[str, list[dict[str, str]]] = {}
    for r in rows:
        by_type.setdefault(r.get("type_id", ""), []).append(r)
    seen = set()
    for rel in rels:
        tid = rel.rsplit("/", 1)[-1].removesuffix(".dxf")
        seen.add(tid)
        try:
            content = dxf_content(v, rel)
        except Exception as exc:  # noqa: BLE001 - reported as a finding
            v.error(rel, "", f"cannot be read as DXF ({exc})")
            continue
        outlines = content.parts                  # the LWPOLYLINEs on CUT
        circles = content.circles
        members = by_type.get(tid, [])
        if len(outlines) != 1 or not members:
            v.error(rel, tid, f"{len(outlines)} CUT outlines for {len(members)} cover plate(s) of this type in "
                              "parts.csv, expected one outline")
            continue
        xdata = outlines[0].xdata
        if xdata.get("part_id") != tid or xdata.get("quantity") != str(len(members)):
            v.error(rel, tid, f"XDATA names type {xdata.get('part_id')!r} x {xdata.get('quantity')}, parts.csv has "
                              f"{len(members)} cover plate(s) of type {tid}")
        holes = int(number(members[0].get("holes"), -1))
        diameter = number(members[0].get("hole_mm"))
        if len(circles) != holes or any(abs(c.diameter - diameter) > 1e-6 for c in circles):
            v.error(rel, tid, f"{len(circles)} CUT circles of diameter(s) "
                              f"{sorted({round(c.diameter, 3) for c in circles})} mm, parts.csv says "
                              f"{holes} holes of {diameter:g} mm")
        ring = np.asarray(outlines[0].points, dtype=float)
        solid = solids.get(members[0]["part_id"])
        piece = v.part_row(members[0].get("joins", "").split(";")[0])
        frame = frame_of(piece) if piece is not None else None
        face = face_outline(solid, frame["normal"]) if solid is not None and frame is not None else None
        if face is not None and frame is not None:
            want = _sides(to_frame(face, frame)[:, :2])
            got = _sides(ring)
            if got.shape != want.shape or np.abs(got - want).max() > PLACE_TOL:
                v.error(rel, tid, f"outline sides {np.round(got, 2).tolist()} mm differ from the cover plate "
                                  f"{members[0]['part_id']} in splices.step ({np.round(want, 2).tolist()} mm)")
    for tid in sorted(set(by_type) - seen):
        if rels:
            v.error("manifest.json", tid, "cover plate type has no DXF in files.splice_dxfs")
