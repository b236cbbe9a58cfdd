"""``joint = "none"`` (plain intersecting plates) is refused by a build before any file is written.

Before, such a build wrote every file and its self-check then rejected them (plates overlapping by 12 mm on
smallest_roof, 3,600 pairs on a circular mesh's one-edge beams), minutes later.  The overlap is measured here
apart from the refusal: the plates at a node, as solids, intersect (manifold3d).
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from conftest import small_vault


def test_plain_crossings_are_refused_before_writing(tmp_path, capsys):
    from fabrication.cli import main

    (tmp_path / "d.toml").write_text(small_vault("plain", joint="none"), encoding="utf-8")
    t = time.process_time()
    code = main(["build", str(tmp_path / "d.toml"), "-o", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and not (tmp_path / "out").exists() and time.process_time() - t < 60.0
    assert len(err) == 1 and "Traceback" not in err[0]
    assert "beams.joint" in err[0] and "'halflap'" in err[0] and "node(s)" in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.toml"]


def test_the_refused_plates_do_intersect():
    """The plates the refusal names at its first node overlap in volume (manifold3d on their prisms), and with
    the half-lap joint of the same design they do not (slots cut)."""
    import manifold3d as m3d

    from fabrication import parse_design
    from fabrication.beams import build_beams
    from fabrication.pipeline.stages import refuse_crossing_plates, stage_geometry, stage_support
    from fabrication.progress import Progress
    from ppfab.errors import DesignError
    import tomllib

    design = parse_design(tomllib.loads(small_vault("plain", joint="none")))
    p = Progress(quiet=True)
    support = stage_support(design, stage_geometry(design, p, False), p)

    def solid(plate):
        f = plate.frame
        outline = np.asarray(plate.outline, dtype=float)
        cs = m3d.CrossSection([outline.tolist()])
        body = m3d.Manifold.extrude(cs, float(plate.thickness))
        R = np.column_stack([f.ex, f.ey, f.normal])
        shift = f.origin - 0.5 * plate.thickness * f.normal
        return body.transform(np.column_stack([R, shift]).tolist())

    for joint, crossing in (("none", True), ("halflap", False)):
        beams = build_beams(support, design.beams.__class__(**{**design.beams.__dict__, "joint": joint}),
                            strict=False)
        if crossing:
            with pytest.raises(DesignError, match="node"):
                refuse_crossing_plates(beams)
        else:
            refuse_crossing_plates(beams)
        node = next(j for j in beams.joints if len(j.parts) > 1 and any(not a[4] for a in j.angles))
        a, b = (beams.by_id[node.parts[0]], next(beams.by_id[q] for q in node.parts[1:]
                                                    if beams.by_id[q].beam_id != beams.by_id[node.parts[0]].beam_id))
        volume = (solid(a) ^ solid(b)).volume()
        assert (volume > 1000.0) if crossing else (volume < 1.0), (joint, volume)
