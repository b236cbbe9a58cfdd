"""Reader of the mesh of a build: ``mesh.obj`` (vertices and faces) and, for a regular patch, the grid shape of
``mesh.json``."""

from __future__ import annotations

from pathlib import Path

from ..model import MeshData
from .errors import bad, missing
from .tables import read_json


def read_mesh(folder: Path) -> MeshData:
    """The mesh of the build in ``folder``."""
    path = folder / "mesh.obj"
    if not path.is_file():
        raise missing(path, "the mesh of the build")
    vertices: list[tuple[float, float, float]] = []
    faces: list[tuple[int, ...]] = []
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except UnicodeDecodeError:
        raise bad(path, "not UTF-8 text") from None
    for n, line in enumerate(lines, start=1):
        words = line.split()
        if not words or words[0] not in ("v", "f"):
            continue
        try:
            if words[0] == "v":
                x, y, z = (float(w) for w in words[1:4])
                vertices.append((x, y, z))
            else:
                faces.append(tuple(int(w.split("/")[0]) - 1 for w in words[1:]))
        except ValueError:
            raise bad(path, f"line {n}: cannot read {line.strip()[:60]!r}") from None
    for n, f in enumerate(faces, start=1):
        if len(f) < 3 or min(f) < 0 or max(f) >= len(vertices):
            raise bad(path, f"face {n} refers to vertices {[k + 1 for k in f]}, the file has {len(vertices)}")
    shape, closed = None, False
    grid = folder / "mesh.json"
    if grid.is_file():
        doc = read_json(grid, "the grid of the mesh")
        if isinstance(doc, dict) and isinstance(doc.get("rows"), int) and isinstance(doc.get("cols"), int):
            shape, closed = (doc["rows"], doc["cols"]), bool(doc.get("closed", False))
    return MeshData(tuple(vertices), tuple(faces), shape, closed)
