"""parts.csv and welds.csv: every cut of a split beam has its splice, and the splice files hold them.

Consecutive pieces of one beam (``beam_id``, ``piece`` of ``parts.csv``) that share no node were cut inside an
edge (one-edge segments of a segmented beam share their node and are welded there, :mod:`.welds` of the
glazing package).  Each such cut is spliced either way, never both and never neither:

* bolted: two rows of kind ``splice`` join the pieces (``joins = "<piece k>;<piece k+1>"``), and every cover
  plate has a solid in ``splices.step`` with ``holes`` bolt holes;
* welded: one row of ``welds.csv`` with ``joint = "splice"`` joins them (either order), a full-penetration
  weld of positive length.

A splice weld between pieces that are not neighbours across a cut is a finding too.
"""

from __future__ import annotations

import ast

from . import Verification, check, read_csv


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
                continue                                 # one-edge segments meeting at a node: welded
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
                if not (float(weld.get("weld_length_mm") or 0) > 0 and "full penetration" in weld.get("preparation", "")):
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
