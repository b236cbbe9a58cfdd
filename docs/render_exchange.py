"""Render a build's ``model.ifc`` as read back by ifcopenshell (docs/images/exchange_ifc.png).

The picture is made from the IFC file alone: ifcopenshell's geometry kernel tessellates every ``IfcPlate`` and
``IfcMember`` in world coordinates with the colours of their surface styles, matplotlib draws the triangles.

    ppfab build -o out && python docs/render_exchange.py out [docs/images/exchange_ifc.png]
"""

from __future__ import annotations

import sys
from pathlib import Path


def render(ifc_path: Path, png: Path, elev: float = 32.0, azim: float = -58.0) -> tuple[int, int]:
    """Draw every element of ``ifc_path`` into ``png``; returns (elements, triangles)."""
    import ifcopenshell
    import ifcopenshell.geom
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    f = ifcopenshell.open(str(ifc_path))
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    it = ifcopenshell.geom.iterator(settings, f)
    tris, colours = [], []
    elements = 0
    light = np.array([0.3, -0.4, 0.87])
    light /= np.linalg.norm(light)
    if it.initialize():
        while True:
            shape = it.get()
            g = shape.geometry
            v = np.asarray(g.verts, dtype=float).reshape(-1, 3)
            faces = np.asarray(g.faces, dtype=int).reshape(-1, 3)
            mats = g.materials
            ids = np.asarray(g.material_ids, dtype=int)
            t = v[faces]
            n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
            n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
            shade = 0.55 + 0.45 * np.abs(n @ light)
            for k in range(len(faces)):
                m = mats[ids[k]] if len(mats) and ids[k] >= 0 else None
                rgb = np.array(m.diffuse.components if m is not None else (0.6, 0.6, 0.6))
                alpha = 1.0 - float(m.transparency) if m is not None and m.transparency == m.transparency else 1.0
                colours.append((*(rgb * shade[k]).clip(0, 1), max(alpha, 0.25)))
            tris.extend(t)
            elements += 1
            if not it.next():
                break
    tris_a = np.array(tris)
    lo, hi = tris_a.reshape(-1, 3).min(axis=0), tris_a.reshape(-1, 3).max(axis=0)
    fig = plt.figure(figsize=(12, 4.6), dpi=130)
    for k, (e, title) in enumerate(((elev, "from above"), (-elev, "from below: the beam plates"))):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        ax.add_collection3d(Poly3DCollection(tris_a, facecolors=colours, edgecolors="none"))
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_zlim(lo[2], hi[2])
        ax.set_box_aspect(hi - lo, zoom=0.95)
        ax.view_init(elev=e, azim=azim)
        ax.set_axis_off()
        ax.set_title(title, fontsize=9, y=0.92)
    (project,) = f.by_type("IfcProject")
    fig.suptitle(f"{ifc_path.name} of '{project.Name}' read back by ifcopenshell: {len(f.by_type('IfcPlate'))} "
                 f"IfcPlate, {len(f.by_type('IfcMember'))} IfcMember", fontsize=10)
    fig.subplots_adjust(0, 0, 1, 0.93, wspace=0.0)
    png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(png)
    plt.close(fig)
    return elements, len(tris_a)


def main(argv: list[str] | None = None) -> None:
    args = sys.argv[1:] if argv is None else argv
    folder = Path(args[0]) if args else Path("out")
    png = Path(args[1]) if len(args) > 1 else Path(__file__).resolve().parent / "images" / "exchange_ifc.png"
    n, t = render(folder / "model.ifc", png)
    print(f"{png}: {n} elements, {t} triangles")


if __name__ == "__main__":
    main()
