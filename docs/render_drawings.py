"""Render the drawings excerpt of the README (docs/images/drawings_key_plan.svg, drawings_node_sheet.svg) from
a small PP vault: the bundled default's face image with 6 × 4 faces.

    python docs/render_drawings.py
"""

from __future__ import annotations

import tempfile
from pathlib import Path

DESIGN = """
[design]
name = "README excerpt: 6 x 4 PP vault"
[geometry]
method = "face_image_curves"
scale = 1000.0
[geometry.params]
g = [[0.0, 0.025], [0.0, 0.0, 0.0001], [0.5], [0.0, 0.0, -0.0125]]
h = [[0.0, 0.0, 0.0001], [0.0, 0.0333333], [0.5], [-8.0, 0.0, -0.0166667]]
u_range = [-4.5, 4.5]
v_range = [-3.0, 3.0]
faces_u = 6
faces_v = 4
[beams]
depth = 150.0
thickness = 12.0
max_length = 3000.0
[panels]
gap = 16.0
[nesting]
time_budget = 0.5
[beam_nesting]
time_budget = 0.5
"""


def main() -> None:
    import fabrication
    from fabrication.drawings import node_sheet_svg, view_svg
    from fabrication.nodetypes import node_types

    images = Path(__file__).resolve().parent / "images"
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "d.toml"
        path.write_text(DESIGN)
        build = fabrication.build(fabrication.load_design(path))
    plan = view_svg("plan", build.panels.panels, build.beams.plates, "Key plan (view from above)", 1200.0)
    (images / "drawings_key_plan.svg").write_text(plan.svg, encoding="utf-8")
    types = node_types(build.nodes.records)
    halflap = next(t for t in types if t.joint == "halflap")
    sheet = node_sheet_svg(halflap, build.beams.params.depth, build.beams.params.thickness, 700.0)
    (images / "drawings_node_sheet.svg").write_text(sheet, encoding="utf-8")


if __name__ == "__main__":
    main()
