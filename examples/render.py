"""Render every example design in this folder to ``docs/images/<name>.png``.

    python examples/render.py [design.toml ...]
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
OUT = HERE.parent / "docs" / "images"


def render(path: Path) -> Path:
    from fabrication.figures import render_mesh_png
    from fabrication.design import load_design
    from ppfab.geometry import build_geometry

    design = load_design(path)
    mesh = build_geometry(design.geometry, design.optimize, design.base_dir).mesh
    OUT.mkdir(parents=True, exist_ok=True)
    target = OUT / f"{path.stem}.png"
    render_mesh_png(mesh, target, title=design.info.name)
    return target


def main(argv: list[str]) -> None:
    paths = [Path(a) for a in argv] or sorted(HERE.glob("*.toml"))
    for p in paths:
        print(render(p))


if __name__ == "__main__":
    main(sys.argv[1:])
