"""welds.csv: every T-joint weld recomputed from the nodes and the plates, every row compared.

At a node whose ``joint`` is ``butt`` (``nodes.csv``), every plate with the role ``end`` is welded to every
plate of another beam with the role ``through`` (:func:`fabrication.glazing.welds.butt_welds`): the dihedral is
the angle between the two plates' planes (``plane`` of ``parts.csv``), the weld runs down both sides of the end
line over the beam depth (length ``2 · beams.depth``), and the preparation and throat follow from the dihedral
and ``beams.thickness`` (:func:`fabrication.glazing.welds.preparation`).  Each recomputed weld must have exactly
one row of ``joint = T`` with the same node, part and ``to``, and that row's dihedral (0.001°), length
(0.01 mm), preparation and throat must be the recomputed ones; a ``T`` row that no weld recomputes is named
too.  At a node where every plate ends, the ``corner`` rows must join every plate there to a plate of another
beam (:func:`check_corner_welds`); every half-lap crossing has its weld row (:func:`check_halflap_welds`).  The
``splice`` rows are the splices check's.
"""

from __future__ import annotations

import numpy as np

from ppfab.planes import angle_between

from ..glazing.welds import preparation
from . import Verification, check
from ._cells import CellReader

LENGTH_TOLERANCE_MM = 0.01
ANGLE_TOLERANCE_DEG = 1e-3


def recompute_t_welds(nodes: list[dict[str, str]], parts: list[dict[str, str]], depth: float,
                      thickness: float) -> dict[tuple[int, str, str], tuple[float, float, str, float]]:
    """``(vertex, end part, through part)`` → ``(dihedral °, length mm, preparation, throat mm)`` of every
    T-joint weld (rows of ``nodes.csv`` and ``parts.csv`` as the nodes and parts checks keep them)."""
    plates = {r["part_id"]: r for r in parts if r["kind"] == "beam"}
    out: dict[tuple[int, str, str], tuple[float, float, str, float]] = {}
    for row in nodes:
        if row.get("joint") != "butt":
            continue
        ids = [b for b in row["beams"].split(";") if b]
        roles = (row.get("roles") or "").split(";")
        if len(roles) != len(ids):
            continue                                           # named by check_welds
        for i in range(len(ids)):
            for j in range(i + 1, len(ids)):
                a, b = plates.get(ids[i]), plates.get(ids[j])
                if a is None or b is None or not a.get("plane") or not b.get("plane"):
                    continue
                if a.get("beam_id") == b.get("beam_id"):
                    continue
                dihedral = plate_dihedral(a, b)
                for (end, re), (through, rt) in (((ids[i], roles[i]), (ids[j], roles[j])),
                                                 ((ids[j], roles[j]), (ids[i], roles[i]))):
                    if re == "end" and rt == "through":
                        prep, throat = preparation(dihedral, thickness)
                        out[(int(row["vertex"]), end, through)] = (dihedral, 2.0 * depth, prep, throat)
    return out


def eval_plane(text: str) -> list[float]:
    """A ``plane`` cell ``[nx, ny, nz, d]`` (checked by the parts check) as numbers."""
    from ._shapes import literal

    return [float(x) for x in literal(text)]


def plate_dihedral(a: dict[str, str], b: dict[str, str]) -> float:
    """Degrees between the planes of two beam plate rows of ``parts.csv``."""
    return float(np.degrees(angle_between(np.array(eval_plane(a["plane"])), np.array(eval_plane(b["plane"])))))


def _joint_rows(rows: list[dict[str, str]], cells: CellReader, joint: str):
    """``(row number, row, node, part, to)`` of the rows of ``welds.csv`` of one ``joint`` kind whose three cells
    read (a bad cell is the cell reader's finding)."""
    for n, r in enumerate(rows, start=1):
        if r.get("joint", "T") != joint:
            continue
        node = cells.integer(n, r, "node", low=0)
        part, to = cells.text(n, r, "part"), cells.text(n, r, "to")
        if node is not None and part is not None and to is not None:
            yield n, r, node, part, to


def _check_sizes(v: Verification, rel: str, cells: CellReader, n: int, r: dict[str, str], weld: str,
                 dihedral: float, length: float, throat: float) -> None:
    """A row's dihedral, length and throat against the recomputed ones; ``weld`` names it in the finding."""
    for column, value, tol in (("dihedral_deg", dihedral, ANGLE_TOLERANCE_DEG),
                               ("weld_length_mm", length, LENGTH_TOLERANCE_MM),
                               ("throat_mm", throat, LENGTH_TOLERANCE_MM)):
        got = cells.number(n, r, column)
        if got is not None and abs(got - value) > tol:
            v.error(rel, f"row {n} column {column}", f"{weld}: {got:g} written, {value:.6g} from the nodes and "
                                                     "plates", value=abs(got - value), limit=tol)


def _check_preparation(v: Verification, rel: str, n: int, r: dict[str, str], weld: str, prep: str,
                       dihedral: float) -> None:
    if r.get("preparation") != prep:
        v.error(rel, f"row {n} column preparation", f"{weld}: {r.get('preparation')!r} written, {prep!r} for a "
                                                    f"dihedral of {dihedral:.2f}°")


@check("welds")
def check_welds(v: Verification) -> None:
    m = v.manifest
    files = m.get("files", {})
    nodes, parts = v.nodes, v.parts
    if nodes is None or parts is None:
        return
    beams = m.get("fabrication", {}).get("beams", {})
    depth, thickness = float(beams.get("depth", 0.0)), float(beams.get("thickness", 0.0))
    nrel = files.get("nodes_csv", "nodes.csv")
    for row in nodes:
        if row.get("joint") == "butt" and len((row.get("roles") or "").split(";")) != len(
                [b for b in row["beams"].split(";") if b]):
            v.error(nrel, row["node_id"], f"roles {row.get('roles')!r} do not name one role per beam "
                                          f"{row['beams']!r}")
    want = recompute_t_welds(nodes, parts, depth, thickness)
    rel = files.get("welds_csv")
    if rel is None:
        if want:
            v.error("manifest.json", "files.welds_csv", f"missing: the nodes and plates make {len(want)} T-joint welds")
        return
    rows = v.read_table(rel)
    if rows is None:
        return
    cells = CellReader(v, rel)
    seen: set[tuple[int, str, str]] = set()
    for n, r, node, part, to in _joint_rows(rows, cells, "T"):
        key = (node, part, to)
        if key not in want:
            v.error(rel, f"row {n}", f"node {node}: no T-joint of {part} ending against {to} there "
                                     "(nodes.csv roles and joint, parts.csv beams)")
            continue
        if key in seen:
            v.error(rel, f"row {n}", f"a second row for the weld of {part} to {to} at node {node}")
        seen.add(key)
        dihedral, length, prep, throat = want[key]
        weld = f"{part} to {to} at node {node}"
        _check_sizes(v, rel, cells, n, r, weld, dihedral, length, throat)
        _check_preparation(v, rel, n, r, weld, prep, dihedral)
    for node, part, to in sorted(set(want) - seen):
        v.error(rel, f"node {node}", f"no row for the T-joint weld of {part} ending against {to} "
                                     f"({want[(node, part, to)][1]:g} mm)")
    check_corner_welds(v, rel, rows, cells, nodes, parts, depth, thickness)
    check_halflap_welds(v, rel, rows, cells, nodes, parts, depth, thickness, bool(beams.get("halflap_welds", True)))
    v.checked.append("welds")


def check_halflap_welds(v: Verification, rel: str, rows: list[dict[str, str]], cells: CellReader,
                        nodes: list[dict[str, str]], parts: list[dict[str, str]], depth: float, thickness: float,
                        welded: bool) -> None:
    """The ``halflap`` rows against the half-lap crossings (``joint = halflap`` nodes, two plates of different
    beams both ``through``): with ``beams.halflap_welds`` one row per crossing, its dihedral the angle between
    the two plates' planes, its length four runs over the depth, its preparation and throat those of that
    dihedral (:func:`fabrication.glazing.welds.preparation`); without it, none."""
    from ..glazing.welds import HALFLAP_RUNS

    plates = {r["part_id"]: r for r in parts if r["kind"] == "beam"}
    crossings: dict[tuple[int, frozenset[str]], float] = {}
    for row in nodes:
        if row.get("joint") != "halflap":
            continue
        ids = [b for b in row.get("beams", "").split(";") if b]
        roles = (row.get("roles") or "").split(";")
        through = [b for b, r in zip(ids, roles) if r == "through" and b in plates and plates[b].get("plane")]
        for i in range(len(through)):
            for j in range(i + 1, len(through)):
                a, b = plates[through[i]], plates[through[j]]
                if a.get("beam_id") != b.get("beam_id"):
                    crossings[(int(row["vertex"]), frozenset((through[i], through[j])))] = plate_dihedral(a, b)
    seen: set[tuple[int, frozenset[str]]] = set()
    for n, r, node, part, to in _joint_rows(rows, cells, "halflap"):
        key = (node, frozenset((part, to)))
        if not welded or key not in crossings or key in seen:
            why = ("beams.halflap_welds is false" if not welded else "a second row for it" if key in seen
                   else "not a half-lap crossing of nodes.csv")
            v.error(rel, f"row {n}", f"node {node}: half-lap weld of {part} and {to}: {why}")
            continue
        seen.add(key)
        dihedral = crossings[key]
        prep, throat = preparation(dihedral, thickness)
        weld = f"half-lap weld of {part} and {to} at node {node}"
        _check_sizes(v, rel, cells, n, r, weld, dihedral, HALFLAP_RUNS * depth, throat)
        _check_preparation(v, rel, n, r, weld, prep, dihedral)
    if welded:
        for node, pair in sorted(set(crossings) - seen, key=lambda k: (k[0], sorted(k[1]))):
            first, second = sorted(pair)
            v.error(rel, f"node {node}", f"no row for the half-lap weld of {first} and {second} "
                                         "(beams.halflap_welds)")


def check_corner_welds(v: Verification, rel: str, rows: list[dict[str, str]], cells: CellReader,
                       nodes: list[dict[str, str]], parts: list[dict[str, str]], depth: float,
                       thickness: float) -> None:
    """The ``corner`` rows against the nodes where every plate ends (``butt``, every role ``end``, plates of at
    least two beams): each such node has rows joining plates of it of different beams, every plate there is in
    one of them, each row's dihedral is the angle between its two plates' planes, its length ``2 · depth``, its
    throat the plate thickness and its preparation the corner weld's; a ``corner`` row at any other node, or
    naming a plate not at it, is named too."""
    from ..glazing.welds import CORNER_PREPARATION

    plates = {r["part_id"]: r for r in parts if r["kind"] == "beam"}
    corners: dict[int, set[str]] = {}
    for row in nodes:
        ids = [b for b in row.get("beams", "").split(";") if b]
        roles = (row.get("roles") or "").split(";")
        beams = {plates[b].get("beam_id") for b in ids if b in plates}
        if row.get("joint") == "butt" and len(roles) == len(ids) >= 2 and all(r == "end" for r in roles) \
                and len(beams) >= 2:
            corners[int(row["vertex"])] = set(ids)
    joined: dict[int, set[str]] = {}
    for n, r, node, part, to in _joint_rows(rows, cells, "corner"):
        at = corners.get(node)
        if at is None or part not in at or to not in at or plates[part].get("beam_id") == plates[to].get("beam_id"):
            v.error(rel, f"row {n}", f"node {node}: {part} and {to} are not two beams' plates ending at a node "
                                     "where every plate ends (nodes.csv roles and joint)")
            continue
        joined.setdefault(node, set()).update((part, to))
        weld = f"corner weld of {part} to {to} at node {node}"
        _check_sizes(v, rel, cells, n, r, weld, plate_dihedral(plates[part], plates[to]), 2.0 * depth, thickness)
        if r.get("preparation") != CORNER_PREPARATION:
            v.error(rel, f"row {n} column preparation", f"{weld}: {r.get('preparation')!r}, not the corner weld's")
    for node, members in sorted(corners.items()):
        loose = sorted(members - joined.get(node, set()))
        if loose:
            v.error(rel, f"node {node}", f"every plate ends here and {', '.join(loose)} is joined to none of the "
                                         "others: no corner weld row")
