"""A surface → a quad net on it: :func:`remesh` (``sections``, ``principal``, ``conjugate`` or ``pp``), with what it
measured.

Examples
--------
>>> import numpy as np
>>> from ppfab.surface import SurfaceSamples, SurfaceSpec, remesh
>>> x, y = np.meshgrid(np.linspace(0, 12000, 41), np.linspace(0, 8000, 31), indexing="ij")
>>> z = 2000 - 2e-5 * (x - 6000) ** 2 - 3e-5 * (y - 4000) ** 2 + 1e-5 * (x - 6000) * (y - 4000)
>>> pts = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
>>> ids = np.arange(41 * 31).reshape(41, 31)
>>> tri = np.concatenate([np.stack([ids[:-1, :-1], ids[1:, :-1], ids[1:, 1:]], -1).reshape(-1, 3),
...                       np.stack([ids[:-1, :-1], ids[1:, 1:], ids[:-1, 1:]], -1).reshape(-1, 3)])
>>> r = remesh(SurfaceSamples(pts, tri), SurfaceSpec(path="dome.obj", spacing=2000.0))
>>> r.summary()["faces"], r.net.dropped_outside, r.planarity_mm < 1e-9
(18, 6, True)
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import DesignError, GeometryError
from ..mesh import as_quadmesh
from ..metrics import conjugacy_defect
from .conjugate import conjugate_net
from .curvature import quad_twist
from .families import PencilPlanes
from .heightfield import HeightField, fit_height_field
from .plan import PlanFrame, plan_frame
from .pp import pp_net, quad_warp
from .principal import principal_net
from .samples import SurfaceSamples
from .sections import SectionsNet, sections_net
from .spec import NETS, SurfaceSpec

CELL_PER_SPACING = 8
"""Plan cells of the height-field fit per panel ``spacing``."""

BALANCED = 0.25
"""Panel edges within ``±BALANCED`` of the spacing need no re-seeding."""

MAX_FIT_DEVIATION = 0.15
"""A height field whose fit misses a sample by more than this many ``spacing`` is refused: the surface overhangs
or closes on itself (a real funicular shell with steep sides: 0.07; an overhanging or closed one: 0.9–70)."""


@dataclass(frozen=True)
class RemeshResult:
    """The net on the surface and the numbers a designer checks.

    net : the :class:`SectionsNet` (its ``mesh`` in mm)
    frame : the plan frame (sections are ``x = const`` in it)
    height_field : the fitted ``z = f(x, y)``
    fit_deviation_mm : largest distance (in z of the frame) of the samples from the fitted height field
    planarity_mm : largest distance of a section row's vertex from its plane, before any optimisation
    panel_size_min, panel_size_max : shortest and longest kept edge, as a fraction of ``spacing``
    seconds : CPU time of the fit and the net
    seeding : how the seeds and planes were placed: ``"uniform"`` (spacing along the middle lines),
        ``"scaled"`` (both steps scaled so the extremes straddle the spacing), ``"strips"`` (each strip on
        its own, :mod:`.balance`; sections and principal nets)
    fan_out : the largest ratio of the longest to the shortest section edge within one strip between two
        neighbouring conjugate curves: no choice of seeds narrows a strip's range below it (a quad net has
        no T-junctions to end or start a curve)
    twist : (F,) per kept face, ``|II(a, b)| / (|a||b| max|κ|)`` of its two directions in the fitted
        surface's second fundamental form: 0 for a conjugate net (how far a PP optimisation must move it)
    umbilics : (U, 3) umbilics found near the outline of a principal net (world, mm)
    warp : (F,) per kept face the normal part of its mixed difference ``c0 − c1 + c2 − c3``, mm (0: planar)
    guide_deviation_deg : (conjugate net) the largest plan angle of a net direction from its guide inside the
        outline; ``None`` for the other nets
    planes_tried : with ``search_planes``: how many section plane normals were tried, refused ones included
        (0: none searched)
    tilt_max_deg : the largest angle between a vertex's section plane and the fitted surface's normal there
        (rows, and columns of a pp net); ``None`` for a net with no planar family.  A P support leaves rows
        further than :data:`SECTION_TILT_DEG` out of the planar beams
    pencil_axis : the plan point ``[x, y]`` (mm) of the vertical axis the section planes pass through, ``None``
        for parallel planes
    """

    net: SectionsNet
    frame: PlanFrame
    height_field: HeightField
    fit_deviation_mm: float
    planarity_mm: float
    panel_size_min: float
    panel_size_max: float
    seconds: float
    seeding: str = "uniform"
    fan_out: float = 1.0
    twist: np.ndarray = field(default_factory=lambda: np.zeros(0))
    umbilics: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    warp: np.ndarray = field(default_factory=lambda: np.zeros(0))
    guide_deviation_deg: float | None = None
    planes_tried: int = 0
    tilt_max_deg: float | None = None
    pencil_axis: list[float] | None = None

    def summary(self) -> dict:
        """Plain data (``--json`` of ``ppfab remesh``)."""
        n = self.net
        v = np.asarray(n.mesh.vertices).reshape(-1, 3)
        return {"vertices": int(len(v)), "faces": int(n.grid_faces.sum()), "faces_total": n.faces_total,
                "dropped_outside": n.dropped_outside, "dropped_sliver": n.dropped_sliver,
                "dropped_island": n.dropped_island, "planar_family": n.planar_family,
                "section_normal": None if self.pencil_axis is not None else self.frame.axes[0].tolist(),
                "pencil_axis": self.pencil_axis,
                "fit_deviation_mm": self.fit_deviation_mm, "planarity_mm": self.planarity_mm,
                "panel_size_min": self.panel_size_min, "panel_size_max": self.panel_size_max,
                "seconds": self.seconds, "seeding": self.seeding, "fan_out": self.fan_out,
                "twist_median": float(np.median(self.twist)) if len(self.twist) else 0.0,
                "twist_max": float(self.twist.max()) if len(self.twist) else 0.0,
                "umbilics_mm": np.round(self.umbilics, 1).tolist(),
                "warp_mm_max": float(self.warp.max()) if len(self.warp) else 0.0,
                "guide_deviation_deg": self.guide_deviation_deg, "planes_tried": self.planes_tried,
                "tilt_max_deg": self.tilt_max_deg,
                "conjugacy_defect": conjugacy_defect(n.mesh)}


def remesh(samples: SurfaceSamples, spec: SurfaceSpec) -> RemeshResult:
    """Build the net of ``spec.net`` on a sampled surface (mm).

    Raises
    ------
    GeometryError : the surface is not a height field over the plan of the sections (its fit misses a sample
        by more than :data:`MAX_FIT_DEVIATION` × spacing), or the net degenerates (the message gives the place
        in mm)
    DesignError : a net kind that is not built
    GeometryError : (principal) an umbilic inside the outline; (conjugate) the pair nearest the guides
        closing up; (pp) the two plane families far from conjugate
    """
    t0 = time.process_time()
    if spec.net not in NETS:
        raise DesignError("surface.net", f"{spec.net!r} is not a net ppfab builds; use one of {', '.join(NETS)}")
    if spec.search_planes and spec.net in SEARCHED:
        best = search_planes(samples, spec)
        return replace(best, seconds=time.process_time() - t0)
    frame = plan_frame(samples.points, spec.plane_normal)
    local = frame.to_local(samples.points)
    hf = fit_height_field(local, spec.spacing / CELL_PER_SPACING, spec.smoothing * spec.spacing)
    miss = np.abs(hf.f(local[:, 0], local[:, 1]) - local[:, 2])
    fit_dev = float(np.max(miss))
    if fit_dev > MAX_FIT_DEVIATION * spec.spacing:
        w = samples.points[int(np.argmax(miss))]
        raise GeometryError(
            f"the surface is not a height field over its plan: the fitted heights miss its points by up to "
            f"{fit_dev:.0f} mm (at ({w[0]:.0f}, {w[1]:.0f}, {w[2]:.0f}) mm; more than {MAX_FIT_DEVIATION:g} × "
            f"the spacing): it overhangs or closes on itself there; remesh a part of it that is a roof over its "
            "plan (crop it) or turn it so that its top faces up", element=f"({w[0]:.0f}, {w[1]:.0f}, {w[2]:.0f})",
            value=fit_dev)
    loops = [frame.to_local(b)[:, :2] for b in samples.boundary]
    seeding, twist, found, off = "uniform", None, np.zeros((0, 3)), None
    if spec.net == "principal":
        net, twist, found, seeding = principal_net(hf, frame, loops, spec.spacing, spec.min_face)
    elif spec.net == "conjugate":
        net, twist, seeding, off = conjugate_net(hf, frame, loops, spec.spacing, spec.min_face, spec.guides,
                                                 spec.row_guides, spec.column_guides)
    elif spec.net == "pp":
        net, twist, _ = pp_net(hf, frame, loops, spec.spacing, spec.min_face, spec.second_normal, spec.max_warp)
    else:
        family = None if spec.pencil_axis is None else \
            PencilPlanes(frame, frame.to_local(np.array([*spec.pencil_axis, 0.0]))[:2])
        net, seeding = _balanced_sections(hf, frame, loops, spec, family)
    if twist is None:
        twist = _twist_of(net, frame, hf)
    planarity = planarity_mm(net)
    sizes = np.concatenate([net.edge_lengths_rows, net.edge_lengths_cols]) / spec.spacing
    return RemeshResult(net, frame, hf, fit_dev, planarity, float(sizes.min()), float(sizes.max()),
                        time.process_time() - t0, seeding, fan_out(net), twist, found, quad_warp(_corners(net)), off,
                        tilt_max_deg=section_tilt_deg(net, frame, hf),
                        pencil_axis=list(spec.pencil_axis) if spec.pencil_axis is not None else None)


SECTION_TILT_DEG = 30.0
"""A section plane further than this from the surface normal at a vertex makes a row the P support leaves out of
the planar beams (``[support] max_normal_angle_deg``, default 30°): :func:`search_planes` prefers nets within it."""


def section_tilt_deg(net: SectionsNet, frame: PlanFrame, hf: HeightField) -> float | None:
    """The largest angle (degrees) between a vertex's section plane and the fitted surface's normal there, over
    the planar families of ``net``; ``None`` when it has none."""
    v = np.asarray(net.mesh.vertices).reshape(-1, 3)
    local = frame.to_local(v)
    up = np.stack([-hf.fx(local[:, 0], local[:, 1]), -hf.fy(local[:, 0], local[:, 1]), np.ones(len(v))], axis=1)
    normal = up @ frame.axes
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    worst: float | None = None
    for planes, index in ((net.planes, net.row_of_vertex), (net.planes_cols, net.col_of_vertex)):
        if planes is None or index is None:
            continue
        n = planes[index][:, :3]
        s = np.abs(np.einsum("ij,ij->i", n, normal)) / np.linalg.norm(n, axis=1)
        tilt = float(np.degrees(np.arcsin(np.clip(s, 0.0, 1.0))).max())
        worst = tilt if worst is None else max(worst, tilt)
    return worst


SEARCHED = ("sections", "conjugate")
"""The nets whose section planes (or guides) ``search_planes`` turns."""

SEARCH_COARSE_DEG = 15.0
"""First pass of :func:`search_planes`: plane normals this far apart in plan over half a turn."""

SEARCH_FINE_DEG = 2.5
"""Second pass: this far apart within one coarse step either side of the best."""


def search_planes(samples: SurfaceSamples, spec: SurfaceSpec) -> RemeshResult:
    """The net of ``spec`` (``sections`` or ``conjugate``) whose edges stay nearest the spacing, over vertical
    section planes turned in plan (the conjugate net's guides turned with them).

    Every :data:`SEARCH_COARSE_DEG` over half a turn from the start direction (``plane_normal``, or the longer
    plan direction), then every :data:`SEARCH_FINE_DEG` within one coarse step of the best.  Among the nets with
    at least four fifths of the most quads any of them kept (a net that keeps its edges by dropping panels is
    not better), one whose section planes stay within :data:`SECTION_TILT_DEG` of the surface normals (rows
    a P support keeps as planar beams) is better than one that does not (the less beyond, the better), and then
    the one with the smaller worst edge ``max |log(edge / spacing)|``.  Nets
    that refuse (a degenerate direction) are skipped.

    Raises
    ------
    GeometryError : every direction refused (the first refusal's message)
    """
    start = plan_frame(samples.points, spec.plane_normal).axes
    base = float(np.degrees(np.arctan2(start[0, 1], start[0, 0])))
    turn0 = None
    if spec.guides is not None and spec.net == "conjugate":
        g = [np.asarray(v, dtype=float) for v in spec.guides]
        turn0 = [float(np.degrees(np.arctan2(v[1], v[0]))) - base for v in g]
    found: dict[float, RemeshResult] = {}
    tried: set[float] = set()
    first_error: GeometryError | None = None

    def attempt(angle: float) -> None:
        nonlocal first_error
        key = round(angle % 180.0, 6)
        if key in tried:
            return
        tried.add(key)
        a = np.radians(base + key)
        normal = [float(np.cos(a)), float(np.sin(a)), 0.0]
        guides = None
        if spec.net == "conjugate":
            offsets = turn0 if turn0 is not None else [0.0, 90.0]
            guides = [[float(np.cos(np.radians(base + key + o))), float(np.sin(np.radians(base + key + o))), 0.0]
                      for o in offsets]
        try:
            found[key] = remesh(samples, replace(spec, plane_normal=normal, guides=guides, search_planes=False))
        except GeometryError as exc:
            first_error = first_error or exc

    def best() -> tuple[float, RemeshResult] | None:
        if not found:
            return None
        most = max(int(r.net.grid_faces.sum()) for r in found.values())
        ok = [(k, r) for k, r in found.items() if r.net.grid_faces.sum() >= 0.8 * most]
        return min(ok, key=lambda kr: (max((kr[1].tilt_max_deg or 0.0) - SECTION_TILT_DEG, 0.0),
                                       _worst(kr[1].net, spec.spacing), kr[0]))

    for k in np.arange(0.0, 180.0, SEARCH_COARSE_DEG):
        attempt(float(k))
    first = best()
    if first is None:
        assert first_error is not None
        raise first_error
    for k in np.arange(-SEARCH_COARSE_DEG + SEARCH_FINE_DEG, SEARCH_COARSE_DEG, SEARCH_FINE_DEG):
        attempt(first[0] + float(k))
    chosen = best()
    assert chosen is not None
    return replace(chosen[1], planes_tried=len(tried))


def _balanced_sections(hf: HeightField, frame: PlanFrame, loops: list[np.ndarray], spec: SurfaceSpec,
                       family: PencilPlanes | None = None) -> tuple[SectionsNet, str]:
    """The sections net (parallel planes, or the pencil ``family``) with the seeding that keeps its edges nearest
    the spacing."""
    net = sections_net(hf, frame, loops, spec.spacing, spec.min_face, family=family)
    # the conjugate curves fan out or converge away from the middle: scale the two steps so that each
    # family's shortest and longest edge straddle the spacing (geometric mean 1), if that narrows the range
    # without losing more than a fifth of the panels
    g = tuple(float(np.sqrt(e.min() * e.max())) / spec.spacing for e in (net.edge_lengths_rows,
                                                                       net.edge_lengths_cols))
    first, seeding = net, "uniform"
    candidates = []
    if max(abs(np.log(g[0])), abs(np.log(g[1]))) > 0.02:
        candidates.append(("scaled", sections_net(hf, frame, loops, spec.spacing, spec.min_face,
                                                  (1.0 / g[0], 1.0 / g[1]), family=family)))
    # every strip balanced on its own (seeds and planes chosen on a dense net): kept when it narrows the range
    if _worst(first, spec.spacing) > np.log(1.0 / (1.0 - BALANCED)):
        candidates.append(("strips", sections_net(hf, frame, loops, spec.spacing, spec.min_face, balance=True,
                                                  family=family)))
    for how, other in candidates:
        if _worst(other, spec.spacing) < _worst(net, spec.spacing) and \
                other.grid_faces.sum() >= 0.8 * first.grid_faces.sum():
            net, seeding = other, how
    return net, seeding


def _corners(net: SectionsNet) -> np.ndarray:
    """``(F, 4, 3)`` world corners of the net's faces."""
    qm = as_quadmesh(net.mesh)
    return np.asarray(qm.vertices)[np.asarray(qm.faces)]


def _twist_of(net: SectionsNet, frame: PlanFrame, hf: HeightField) -> np.ndarray:
    """Per kept face (row-major) the twist of its two directions in the fitted surface's second form."""
    return quad_twist(hf, frame.to_local(_corners(net)))


def planarity_mm(net: SectionsNet) -> float:
    """The largest distance of a vertex from the plane of its row (and of its column, when the columns are
    planar too), mm; 0 for a net with no planar family."""
    v = np.asarray(net.mesh.vertices).reshape(-1, 3)
    worst = 0.0
    for planes, index in ((net.planes, net.row_of_vertex), (net.planes_cols, net.col_of_vertex)):
        if planes is not None and index is not None:
            p = planes[index]
            worst = max(worst, float(np.max(np.abs(np.einsum("ij,ij->i", v, p[:, :3]) + p[:, 3]))))
    return worst


def fan_out(net: SectionsNet) -> float:
    """The largest ``max / min`` of the section edges (rows) of the kept faces within one strip (a column
    of faces between two neighbouring curves of the other family)."""
    strip = np.argwhere(net.grid_faces)[:, 1]          # kept faces in row-major order, as the edge lengths
    e = net.edge_lengths_rows
    worst = 1.0
    for j in np.unique(strip):
        ej = e[strip == j].ravel()
        worst = max(worst, float(ej.max() / max(float(ej.min()), 1e-300)))
    return worst


def _worst(net: SectionsNet, spacing: float) -> float:
    """The largest ``|log(edge / spacing)|`` over the kept edges of both families."""
    e = np.concatenate([net.edge_lengths_rows, net.edge_lengths_cols]) / spacing
    return float(np.abs(np.log(e)).max())
