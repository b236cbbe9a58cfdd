"""Render the drawings excerpt of the README (docs/images/drawings_key_plan.svg, drawings_node_sheet.svg) from
a small PP vault: the bundled default's face image with 6 × 4 faces.

    python docs/render_drawings.py
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from conftest import small_vault  # noqa: E402  (the tests' small vault: one design for the excerpt and the tests)

DESIGN = small_vault("README excerpt: 6 x 4 PP vault")


def main() -> None:
    import fabrication
    from fabrication.drawings import view_svg
    from fabrication.node_sheets import node_sheet_svg
    from fabrication.nodetypes import node_types
    from fabrication.paper import SheetInfo

    images = Path(__file__).resolve().parent / "images"
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "d.toml"
        path.write_text(DESIGN)
        build = fabrication.build(fabrication.load_design(path))
    plan = view_svg("plan", build.panels.panels, build.beams.plates, "Key plan (view from above)", paper="A3",
                    sheet=SheetInfo("6 x 4 PP vault", "Key plan (view from above)", 1, 2, "A3"))
    (images / "drawings_key_plan.svg").write_text(plan.svg, encoding="utf-8")
    types = node_types(build.nodes.records)
    halflap = next(t for t in types if t.joint == "halflap")
    sheet = node_sheet_svg(halflap, build.beams.params.depth, build.beams.params.thickness,
                           sheet=SheetInfo("6 x 4 PP vault", f"Node type {halflap.type_id}", 2, 2, "A3"))
    (images / "drawings_node_sheet.svg").write_text(sheet, encoding="utf-8")


if __name__ == "__main__":
    main()
