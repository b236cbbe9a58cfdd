"""Reading a designer's surface: a Rhino ``.3dm`` NURBS surface (or trimmed Brep face) with rhino3dm, a
triangle mesh (OBJ, OFF, STL, PLY) with trimesh — into the core's :class:`~ppfab.surface.SurfaceSamples`
in millimetres — and measuring distances to the surface as read, independently of the net built on it.

Units: a ``.3dm`` states its unit system (a ``units`` given as well must agree); a mesh file has none, so
its ``units`` must be declared (``[surface] units``, ``ppfab remesh --units``), defaulting to mm with a
note in the result.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from ppfab.errors import DesignError, MeshFileError
from ppfab.surface import UNITS, SurfaceSamples

if TYPE_CHECKING:
    from ppfab.surface import SurfaceSpec

MESH_SUFFIXES = (".obj", ".off", ".stl", ".ply")
SURFACE_SUFFIXES = (".3dm",) + MESH_SUFFIXES

NURBS_SAMPLES = 61
"""Parameter grid (per direction) on which a NURBS surface is sampled for the fit and the closeness reference."""

TRIM_SAMPLES = 64
"""Points per trim edge of a Brep face."""

MAX_SURFACE_BYTES = 256 << 20
"""A surface file larger than this is refused from its size, before it is read."""

_RHINO_UNITS = {"Millimeters": 1.0, "Centimeters": 10.0, "Decimeters": 100.0, "Meters": 1000.0,
                "Inches": 25.4, "Feet": 304.8}
_UNIT_NAMES = {"Millimeters": "mm", "Centimeters": "cm", "Meters": "m", "Inches": "in", "Feet": "ft",
               "Decimeters": "dm"}


@dataclass(frozen=True)
class SurfaceFile:
    """A surface as read: the samples (mm) and the object to measure distances on.

    kind : ``"nurbs"`` or ``"mesh"``
    samples : the core's :class:`SurfaceSamples`
    native : the rhino3dm surface (``nurbs``) or the trimesh mesh in mm (``mesh``)
    factor : millimetres per file unit
    note : what was assumed (a mesh without declared units)
    """

    kind: str
    samples: SurfaceSamples
    native: Any
    factor: float
    note: str = ""

    def distance(self, points: np.ndarray) -> np.ndarray:
        """Distance (mm) of points ``(M, 3)`` (mm) to the surface as read, independently of the net: on a mesh
        by trimesh's exhaustive closest point (every triangle); on a NURBS surface by Gauss–Newton on the
        surface itself (rhino3dm evaluations, started at the nearest point of a parameter grid)."""
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        if self.kind == "mesh":
            import trimesh

            step = max(1, 4_000_000 // max(1, len(self.native.faces)))
            out = [trimesh.proximity.closest_point_naive(self.native, p[s:s + step])[1]
                   for s in range(0, len(p), step)]
            return np.concatenate(out) if out else np.zeros(0)
        return _nurbs_distance(self.native, p, self.factor)


def _nurbs_distance(srf: Any, p: np.ndarray, factor: float, iterations: int = 12) -> np.ndarray:
    """Distances (mm) of points (mm) to a rhino3dm surface by Gauss–Newton in its parameters."""
    from scipy.spatial import cKDTree

    du, dv = srf.Domain(0), srf.Domain(1)
    n = 61
    grid, _ = _sample_nurbs(srf, n, factor)
    us, vs = np.linspace(du.T0, du.T1, n), np.linspace(dv.T0, dv.T1, n)
    _, k = cKDTree(grid).query(p)
    hu, hv = 1e-6 * (du.T1 - du.T0), 1e-6 * (dv.T1 - dv.T0)

    def at(u: float, v: float) -> np.ndarray:
        q = srf.PointAt(u, v)
        return np.array([q.X, q.Y, q.Z]) * factor

    out = np.empty(len(p))
    for m, (x, start) in enumerate(zip(p, k)):
        u, v = float(us[start // n]), float(vs[start % n])
        for _ in range(iterations):
            s = at(u, v)
            su = (at(min(u + hu, du.T1), v) - at(max(u - hu, du.T0), v)) / (min(u + hu, du.T1) - max(u - hu, du.T0))
            sv = (at(u, min(v + hv, dv.T1)) - at(u, max(v - hv, dv.T0))) / (min(v + hv, dv.T1) - max(v - hv, dv.T0))
            J = np.stack([su, sv], axis=1)
            step = np.linalg.lstsq(J, x - s, rcond=None)[0]
            u = float(np.clip(u + step[0], du.T0, du.T1))
            v = float(np.clip(v + step[1], dv.T0, dv.T1))
        out[m] = float(np.linalg.norm(x - at(u, v)))
    return out


def read_surface(path: str | Path, units: str | None = None, name: str | None = None) -> SurfaceFile:
    """Read a surface file (``.3dm`` or a triangle mesh) into samples in mm.

    Parameters
    ----------
    path : the file
    units : ``mm``/``cm``/``m``/``in``/``ft``: a mesh file's unit; for a ``.3dm`` it must agree with the file's
    name : in a ``.3dm``, the object name to use (default: the only or first surface)
    """
    from ppfab.io.meshfile import regular_file

    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in SURFACE_SUFFIXES:
        raise MeshFileError(str(p), f"is not a surface file this reads ({', '.join(SURFACE_SUFFIXES)})")
    size = regular_file(p, "surface file")
    if size > MAX_SURFACE_BYTES:
        raise MeshFileError(str(p), f"{size / 2**20:.0f} MiB is larger than a surface file this reads "
                                    f"({MAX_SURFACE_BYTES >> 20} MiB)")
    if units is not None and units not in UNITS:
        raise DesignError("surface.units", f"{units!r} is not a unit; valid: {', '.join(UNITS)}")
    if suffix == ".3dm":
        return _read_3dm(p, units, name)
    return _read_mesh(p, units)


def _sample_nurbs(srf: Any, n: int, factor: float) -> tuple[np.ndarray, np.ndarray]:
    """Points ``(n², 3)`` (mm) on a parameter grid of a rhino3dm surface and its triangles."""
    du, dv = srf.Domain(0), srf.Domain(1)
    us = np.linspace(du.T0, du.T1, n)
    vs = np.linspace(dv.T0, dv.T1, n)
    pts = np.array([[(q := srf.PointAt(float(u), float(v))).X, q.Y, q.Z] for u in us for v in vs]) * factor
    ids = np.arange(n * n).reshape(n, n)
    a, b, c, d = ids[:-1, :-1], ids[1:, :-1], ids[1:, 1:], ids[:-1, 1:]
    tri = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return pts, tri


def _curve_points(curve: Any, n: int, reverse: bool = False) -> np.ndarray:
    dom = curve.Domain
    ts = np.linspace(dom.T0, dom.T1, n)
    pts = np.array([[(q := curve.PointAt(float(t))).X, q.Y, q.Z] for t in ts])
    return pts[::-1] if reverse else pts


def _read_3dm(p: Path, units: str | None, name: str | None) -> SurfaceFile:
    import rhino3dm

    model: Any = rhino3dm.File3dm.Read(str(p))
    if model is None:
        raise MeshFileError(str(p), "cannot be read as a Rhino .3dm file")
    unit = str(model.Settings.ModelUnitSystem).split(".")[-1]
    if unit not in _RHINO_UNITS:
        if units is None:
            raise MeshFileError(str(p), f"the file's unit system is {unit}; declare the units ([surface] units "
                                        "or --units: mm, cm, m, in, ft)")
        factor = UNITS[units]
    else:
        factor = _RHINO_UNITS[unit]
        if units is not None and abs(UNITS[units] - factor) > 1e-12 * factor:
            raise DesignError("surface.units", f"{units!r} disagrees with the unit system of {p} "
                                               f"({_UNIT_NAMES[unit]}); leave units out for a .3dm")
    found: list[tuple[Any, str]] = []
    for obj in model.Objects:
        g = obj.Geometry
        label = obj.Attributes.Name or ""
        if name is not None and label != name:
            continue
        if isinstance(g, rhino3dm.Brep) or isinstance(g, rhino3dm.Surface):
            found.append((g, label))
    if not found:
        what = f"no surface or Brep named {name!r}" if name else "no NURBS surface or Brep face"
        raise MeshFileError(str(p), f"holds {what}; export the roof surface into the file")
    geom: Any = found[0][0]
    label = found[0][1]
    loops: list[np.ndarray] = []
    if isinstance(geom, rhino3dm.Brep):
        faces: Any = geom.Faces
        edges: Any = geom.Edges
        if len(faces) != 1:
            raise MeshFileError(str(p), f"the Brep {label or '(unnamed)'} has {len(faces)} faces; "
                                        "give a single-face surface (or name one with [surface] object)")
        face = faces[0]
        srf = face.UnderlyingSurface()
        for k in range(len(face.Loops)):
            loop = face.Loops[k]
            pieces = [_curve_points(edges[loop.Trims[t].EdgeIndex], TRIM_SAMPLES,
                                    bool(loop.Trims[t].IsReversed))[:-1]
                      for t in range(loop.TrimCount) if loop.Trims[t].EdgeIndex >= 0]
            if pieces:
                loops.append(np.concatenate(pieces) * factor)
    else:
        srf = geom
    pts, tri = _sample_nurbs(srf, NURBS_SAMPLES, factor)
    if not loops:                                       # an untrimmed surface: its parameter rectangle
        g = pts.reshape(NURBS_SAMPLES, NURBS_SAMPLES, 3)
        loops = [np.concatenate([g[:-1, 0], g[-1, :-1], g[:0:-1, -1], g[0, :0:-1]])]
    source = f"{p.name}: {type(geom).__name__}{' ' + repr(label) if label else ''}"
    unit_name = _UNIT_NAMES.get(unit, units or "mm")
    return SurfaceFile("nurbs", SurfaceSamples(pts, tri, tuple(loops), unit_name, source), srf, factor)


GUIDE_SAMPLES = 65
"""Points a guide curve of a ``.3dm`` is sampled at, evenly in its parameter (a polyline keeps its own points)."""


def layer_curves(path: str | Path, layers: Sequence[str], factor: float) -> list[list[np.ndarray]]:
    """Per name of ``layers`` (a layer's name or full path), the curves on that layer of a ``.3dm`` as polylines
    ``(m, 3)`` in mm (``factor``: mm per file unit, the surface's as read), the file read once.

    Raises
    ------
    DesignError : the file is not a ``.3dm``, has no such layer (its layers are named), or no curve on it
    """
    import rhino3dm

    p = Path(path)
    if p.suffix.lower() != ".3dm":
        raise DesignError("surface.guide_layers", f"{p.name} is not a .3dm: only a Rhino file has layers; give the "
                                                  "guide curves as row_guides / column_guides")
    model: Any = rhino3dm.File3dm.Read(str(p))
    if model is None:
        raise MeshFileError(str(p), "cannot be read as a Rhino .3dm file")
    table = [model.Layers[k] for k in range(len(model.Layers))]
    objects = [(obj.Attributes.LayerIndex, obj.Geometry) for obj in model.Objects]
    found = []
    for layer in layers:
        wanted = {k for k, lay in enumerate(table) if layer in (lay.Name, lay.FullPath)}
        if not wanted:
            names = ", ".join(repr(lay.FullPath or lay.Name) for lay in table) or "none"
            raise DesignError("surface.guide_layers", f"{p.name} has no layer {layer!r} (its layers: {names})")
        out = []
        for index, g in objects:
            if index not in wanted or not isinstance(g, rhino3dm.Curve):
                continue
            if isinstance(g, rhino3dm.PolylineCurve):
                pts = np.array([[(q := g.Point(i)).X, q.Y, q.Z] for i in range(g.PointCount)])
            else:
                pts = _curve_points(g, GUIDE_SAMPLES)
            out.append(pts * factor)
        if not out:
            raise DesignError("surface.guide_layers", f"layer {layer!r} of {p.name} holds no curve: draw the guide "
                                                      "curves on it (lines, polylines, arcs or NURBS curves)")
        found.append(out)
    return found


def with_layer_guides(spec: "SurfaceSpec", path: str | Path, surface: "SurfaceFile") -> "SurfaceSpec":
    """``spec`` with the guide curves of its ``guide_layers`` read from the ``.3dm`` ``path`` (:func:`layer_curves`,
    in the units ``surface`` — that file as read — was scaled by) as ``row_guides`` (and ``column_guides``);
    unchanged without ``guide_layers``."""
    from dataclasses import replace

    if spec.guide_layers is None:
        return spec
    curves = layer_curves(path, spec.guide_layers, surface.factor)
    return replace(spec, guide_layers=None, row_guides=[c.tolist() for c in curves[0]],
                   column_guides=[c.tolist() for c in curves[1]] if len(curves) > 1 else None)


METRES_BELOW = 500.0
"""A triangle mesh that states no units and is narrower than this (in its own units) is read as metres: a roof
under half a metre wide is not one (the same guess for ``ppfab new``, ``ppfab remesh`` and a build)."""


def _read_mesh(p: Path, units: str | None) -> SurfaceFile:
    import trimesh

    try:
        loaded = trimesh.load(str(p), force="mesh", process=True)
    except Exception as exc:                            # trimesh raises many kinds on a malformed file
        raise MeshFileError(str(p), f"cannot be read as a triangle mesh ({type(exc).__name__}: "
                                    f"{str(exc).splitlines()[0] if str(exc) else 'no detail'})") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise MeshFileError(str(p), "holds no faces; give a triangle (or polygon) mesh of the surface")
    raw = np.asarray(loaded.vertices, dtype=float)
    note = ""
    if units is None:
        wide = float(np.ptp(raw, axis=0).max())
        guess = "m" if wide < METRES_BELOW else "mm"
        note = (f"{p.name} states no units: {wide:.4g} units wide, read as {guess} (a mesh under "
                f"{METRES_BELOW:g} units wide is taken as metres; declare [surface] units or --units otherwise)")
    factor = UNITS[units or guess]
    mesh = trimesh.Trimesh(raw * factor, np.asarray(loaded.faces), process=False)
    loops = tuple(mesh.vertices[lp] for lp in boundary_loops(mesh))
    samples = SurfaceSamples(mesh.vertices, mesh.faces, loops, units or guess, f"{p.name}: triangle mesh")
    return SurfaceFile("mesh", samples, mesh, factor, note)


def boundary_loops(mesh: Any) -> list[np.ndarray]:
    """The boundary loops of a trimesh mesh as vertex index arrays: its directed edges used by one face
    (trimesh's ``group_rows`` on the sorted edges), chained head to tail."""
    import trimesh

    single = trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1)
    directed = np.asarray(mesh.edges)[single]
    nxt: dict[int, list[int]] = {}
    for a, b in directed.tolist():
        nxt.setdefault(a, []).append(b)
    loops = []
    for a0 in sorted(nxt):
        while nxt.get(a0):
            loop = [a0]
            a = nxt[a0].pop()
            while a != a0 and nxt.get(a):
                loop.append(a)
                a = nxt[a].pop()
            if len(loop) >= 3:
                loops.append(np.array(loop))
    return loops
