"""parts.csv: every cut of a split beam has its pair of splice cover plates, and the splice files hold them.

Consecutive pieces of one beam (``beam_id``, ``piece`` of ``parts.csv``) that share no node were cut inside an
edge (one-edge segments of a segmented beam share their node and are welded there, :mod:`.welds` of the
glazing package): two rows of kind ``splice`` must join them (``joins = "<piece k>;<piece k+1>"``), and every
cover plate must have a solid in ``splices.step`` with ``holes`` bolt holes.
"""

from __future__ import annotations

import ast

from . import Verification, check


def _nodes(row: dict[str, str]) -> set[int]:
    try:
        return {int(x) for x in ast.literal_eval(row.get("nodes") or "[]")}
    except (ValueError, SyntaxError):
        return set()


@check("splices", 35)
def check_splices(v: Verification) -> None:
    rows = v.data.get("parts", [])
    files = v.data.get("manifest", {}).get("files", {})
    beams: dict[str, list[dict[str, str]]] = {}
    for row in rows:
        if row["kind"] == "beam" and row.get("pieces") not in (None, "", "1"):
            beams.setdefault(row.get("beam_id", ""), []).append(row)
    joined: dict[tuple[str, str], list[str]] = {}
    for row in rows:
        if row["kind"] == "splice":
            a, _, b = row.get("joins", "").partition(";")
            joined.setdefault((a, b), []).append(row["part_id"])
    wanted = 0
    for beam, pieces in beams.items():
        pieces.sort(key=lambda r: int(r.get("piece") or 0))
        for a, b in zip(pieces[:-1], pieces[1:]):
            if _nodes(a) & _nodes(b):
                continue                                 # one-edge segments meeting at a node: welded
            wanted += 1
            plates = joined.get((a["part_id"], b["part_id"]), [])
            if len(plates) != 2:
                v.error("parts.csv", f"{a['part_id']}/{b['part_id']}",
                        f"the cut between these pieces of {beam} has {len(plates)} splice cover plate(s), expected 2")
    rel = files.get("splices_step")
    splice_rows = [r for r in rows if r["kind"] == "splice"]
    if splice_rows and rel is None:
        v.error("manifest.json", "files", "parts.csv lists splice cover plates but no splices_step file")
    elif rel is not None:
        from build123d import import_step

        from ..writers.step import named_solids

        try:
            solids = dict(named_solids(import_step(str(v.folder / rel))))
        except Exception as exc:  # noqa: BLE001 - reported as a finding
            v.error(rel, "", f"cannot be read by the CAD kernel ({exc})")
            return
        for r in splice_rows:
            s = solids.get(r["part_id"])
            if s is None:
                v.error(rel, r["part_id"], "cover plate has no solid")
                continue
            holes = int(r.get("holes") or 0)
            inner = len(s.faces()) - 6                       # a plate with h holes: 6 faces + one per hole
            if inner != holes:
                v.error(rel, r["part_id"], f"solid has {inner} hole faces, parts.csv says {holes} holes")
        if len(solids) != len(splice_rows):
            v.error(rel, "", f"{len(solids)} solids for {len(splice_rows)} cover plates in parts.csv")
    v.checked.append("splices")
    v.data["splices_wanted"] = wanted
