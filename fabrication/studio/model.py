"""The studio's state, free of any user interface: the design document being edited, its closed-form
re-solve, the PP check, the live figures, undo/redo and saving.

:class:`StudioModel` holds the design as the TOML document it will be saved as (``doc``).  Every edit
(:meth:`StudioModel.set_param`, :meth:`StudioModel.move_handle`, …) makes a new document and re-solves it
through :func:`ppfab.geometry.build_geometry` (the construction registry's closed-form constructions).  An edit
the construction refuses (invalid parameters, a fold, a cusp) leaves the last valid state in place and is kept
as :attr:`StudioModel.error`; when the refusal is a fold (:class:`~ppfab.errors.FoldError`) with the same face
layout as the shown mesh, :attr:`StudioModel.refused_folds` marks the faces that the refused edit folds.

The PP check is ``δ_P`` (§3.3, :func:`ppfab.metrics.polyline_planarity`) of every polyline of the
families the construction keeps planar.
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ppfab.errors import PpfabError
from ppfab.mesh import QuadGrid

from .figures import Figures, face_corners, figures
from .handles import Handle, handle_set, placement

METRICS = ("planarity", "panel area", "corner angle", "type")
"""What the panels can be coloured by."""


@dataclass(frozen=True)
class Solve:
    """One re-solve: the construction's own grid, the placed grid (mm), δ_P per planar family, figures, the
    folded faces ``(m, n')`` and the time it took (s)."""

    raw: QuadGrid
    placed: QuadGrid
    families: tuple[str, ...]
    delta_p: dict[str, float]
    figures: Figures
    folded: np.ndarray
    seconds: float

    @property
    def delta_p_max(self) -> float:
        return max(self.delta_p.values(), default=0.0)


@dataclass
class History:
    """Undo/redo of documents (each entry a whole design document)."""

    undo: list[dict] = field(default_factory=list)
    redo: list[dict] = field(default_factory=list)
    limit: int = 200


def _section(doc: dict, name: str) -> dict:
    value = doc.get(name, {})
    return value if isinstance(value, dict) else {}


def solve(doc: dict, base_dir: Path | None = None) -> Solve:
    """Re-solve a design document's geometry (closed form for a construction) and measure it.

    Raises :class:`~ppfab.errors.PpfabError` when the construction refuses the parameters.
    """
    from ppfab.geometry import GeometrySpec, build_geometry
    from ppfab.schema import parse_params

    t0 = time.perf_counter()
    spec = parse_params(GeometrySpec, dict(_section(doc, "geometry")), "geometry")
    raw_spec = GeometrySpec(method=spec.method, mesh=spec.mesh, params=spec.params,
                            planar_families=spec.planar_families, max_vertices=spec.max_vertices)
    geometry = build_geometry(raw_spec, base_dir=base_dir, allow_large=False)
    return measure(doc, geometry.mesh, geometry.planar_families, t0)


def measure(doc: dict, raw: Any, families: tuple[str, ...], t0: float | None = None, support: bool = True) -> Solve:
    """The :class:`Solve` of a mesh in construction units (placed by ``doc``'s ``[geometry]``): δ_P of
    ``families``, the figures and the fold marks.  ``support = False`` leaves the support structure out of the
    torsion figure (it is 90 % of the time at 31 × 31: a live frame measures it only when the mesh settles)."""
    from ppfab.folds import folded_faces
    from ppfab.geometry import GeometrySpec
    from ppfab.metrics import polyline_planarity
    from ppfab.schema import parse_params
    from ppfab.transforms.similarity import transform

    from ..nesting.params import NestingParams
    from ..panels.params import PanelParams

    t0 = time.perf_counter() if t0 is None else t0
    spec = parse_params(GeometrySpec, dict(_section(doc, "geometry")), "geometry")
    if not isinstance(raw, QuadGrid):
        grid = raw.grid
        if grid is None:
            raise PpfabError("the studio edits regular quad grids; this mesh file is not one")
        raw = grid
    placed = transform(raw, spec.scale, spec.rotate_z_deg, spec.translate, spec.flip_orientation)
    delta = {}
    for fam in families:
        lines = placed.rows() if fam == "rows" else placed.cols()
        delta[fam] = float(polyline_planarity(lines).max()) if lines.shape[1] >= 3 else 0.0
    nest = parse_params(NestingParams, dict(_section(doc, "nesting")), "nesting")
    gap = parse_params(PanelParams, dict(_section(doc, "panels")), "panels").gap
    beams = _section(doc, "beams")
    x0, y0, x1, y1 = nest.usable()
    figs = figures(placed.vertices, placed.axes, families, placed.closed,
                   (float(nest.sheet[0]), float(nest.sheet[1])), (x1 - x0, y1 - y0),
                   float(beams.get("depth", 200.0)), float(beams.get("max_length", 0.0) or 0.0),
                   float(nest.spacing), float(gap))
    if support:
        figs = _support_torsion(doc, placed, families, figs)
    else:
        import dataclasses

        figs = dataclasses.replace(figs, torsion_of="the mesh's node axes while it moves; the support's when it "
                                                    "settles")
    try:
        folded = np.asarray(folded_faces(placed), dtype=bool)
    except Exception:                            # a grid too small for the fold test: nothing to mark
        folded = np.zeros(face_corners(placed.vertices, placed.closed).shape[:2], dtype=bool)
    return Solve(raw, placed, families, delta, figs, folded, time.perf_counter() - t0)


def _support_torsion(doc: dict, placed: QuadGrid, families: tuple[str, ...], figs: Figures) -> Figures:
    """``figs`` with the torsion of the support structure the build would make of ``placed`` (``[support]``,
    ``[beams] depth``: the largest offset of an axis at beam depth, ``nodes.csv`` ``torsion_mm``); where that
    support cannot be made, the construction's axes stay measured and the figure says why."""
    import dataclasses

    from ppfab.schema import parse_params
    from ppfab.support.params import BeamContext, SupportParams
    from ppfab.support.select import support_structure

    beams = _section(doc, "beams")
    depth = float(beams.get("depth", 200.0))
    try:
        params = parse_params(SupportParams, dict(_section(doc, "support")), "support")
        support = support_structure(placed, params, planar_families=families or None,
                                    beams=BeamContext(depth, float(beams.get("max_torsion_mm", 0.5))))
        torsion = float(np.max(support.torsion_offset(depth), initial=0.0))
    except Exception as exc:                     # the build would refuse: keep the construction's figure, say why
        return dataclasses.replace(figs, torsion_of=f"the construction's axes; no support: {exc}")
    kind = str(support.summary().get("kind", params.method)).upper()
    return dataclasses.replace(figs, torsion_mm=torsion, torsion_of=f"the {kind} support the build makes")


def face_metric(placed: QuadGrid, metric: str) -> np.ndarray:
    """``(m, n')`` value of ``metric`` (one of :data:`METRICS`) per face: ``δ_f`` (§3.3), area (m²), the
    smallest corner angle (degrees) or the panel type index."""
    from ppfab.metrics import face_planarity

    from .figures import panel_types

    c = face_corners(placed.vertices, placed.closed)
    if metric == "planarity":
        return face_planarity(c)
    if metric == "panel area":
        return 0.5e-6 * np.linalg.norm(np.cross(c[..., 2, :] - c[..., 0, :], c[..., 3, :] - c[..., 1, :]), axis=-1)
    if metric == "corner angle":
        from ppfab.metrics import corner_angles
        return corner_angles(c).min(axis=-1)
    if metric == "type":
        return panel_types(c).astype(float)
    raise ValueError(f"unknown metric {metric!r}; one of {', '.join(METRICS)}")


class StudioModel:
    """The design being edited (see the module docstring).

    Parameters
    ----------
    doc : the design document (parsed TOML)
    base_dir : the folder relative paths in it are taken from (the design file's)
    source : the design file it was read from, if any (never overwritten by :meth:`save`, nor is its mesh)
    """

    def __init__(self, doc: dict, base_dir: Path | None = None, source: Path | None = None):
        from .saving import SaveRules

        self.base_dir = base_dir or Path.cwd()
        self.source = source
        self.doc = copy.deepcopy(doc)
        mesh = self.mesh_file()
        self.save_rules = SaveRules(tuple(p for p in (source, mesh) if p is not None))
        self.history = History()
        self.error = ""
        self.refused_folds: np.ndarray | None = None
        self.state = solve(self.doc, self.base_dir)
        self._drag_base: tuple[dict, Solve] | None = None

    @classmethod
    def load(cls, path: str | Path | None) -> "StudioModel":
        """Read a design file (``None``: the bundled default) as :func:`fabrication.design.load_design` does."""
        from ..design import DEFAULT_DESIGN, load_design

        design = load_design(path)
        return cls(design.raw, design.base_dir, Path(DEFAULT_DESIGN if path is None else path))

    def mesh_file(self) -> Path | None:
        """The mesh file the design names (relative paths taken from :attr:`base_dir`), if any."""
        mesh = self.geometry.get("mesh")
        if not isinstance(mesh, str):
            return None
        p = Path(mesh)
        return p if p.is_absolute() else self.base_dir / p

    def outside_files(self) -> list[Path]:
        """The files the design reads from outside its own folder (:attr:`base_dir`), resolved."""
        mesh = self.mesh_file()
        if mesh is None:
            return []
        real = mesh.resolve()
        return [] if real.is_relative_to(self.base_dir.resolve()) else [real]

    # -- what is edited -------------------------------------------------------------------------------
    @property
    def geometry(self) -> dict:
        return _section(self.doc, "geometry")

    @property
    def method(self) -> str | None:
        return self.geometry.get("method")

    @property
    def params(self) -> dict:
        """``[geometry.params]`` with the construction's defaults filled in."""
        from dataclasses import asdict

        from ppfab.constructions import get_construction
        from ppfab.schema import parse_params

        if self.method is None:
            return {}
        record = parse_params(get_construction(self.method).params, self.geometry.get("params", {}), "geometry.params")
        return {**asdict(record), **copy.deepcopy(self.geometry.get("params", {}))}

    def handles(self) -> list[Handle]:
        """The handles in display coordinates (metres of the placed design)."""
        s, R, t = placement(self.geometry)
        out = []
        for h in handle_set(self.method).handles(self.params, self.state.raw):
            normal = None if h.normal is None else R @ h.normal / max(float(np.linalg.norm(h.normal)), 1e-300)
            out.append(Handle(h.key, (s * R @ h.position + t) / 1000.0, h.label, h.color, h.rotatable, normal))
        return out

    # -- edits ----------------------------------------------------------------------------------------
    def _commit(self, doc: dict, record: bool = True) -> bool:
        """Re-solve ``doc``; keep it (and push the old one on the undo stack) when it solves, else keep the
        current state and set :attr:`error`.  Returns whether the edit was taken; an edit that changes
        nothing is taken without an undo step."""
        from ppfab.errors import FoldError

        self.refused_folds = None
        if doc == self.doc:
            self.error = ""
            return True
        try:
            state = solve(doc, self.base_dir)
        except FoldError as exc:
            self.error = str(exc)
            mask = None if exc.mask is None else np.asarray(exc.mask, dtype=bool)
            if mask is not None and mask.shape == self.state.folded.shape:
                self.refused_folds = mask
            return False
        except PpfabError as exc:
            self.error = str(exc)
            return False
        except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
            self.error = f"the construction cannot use these values: {exc}"
            return False
        if record:
            self.history.undo.append(self.doc)
            del self.history.undo[:-self.history.limit]
            self.history.redo.clear()
        self.doc, self.state, self.error = doc, state, ""
        return True

    def set_param(self, key: str, value: Any, record: bool = True) -> bool:
        """Set ``[geometry.params] key`` (or a ``[geometry]`` placement key given as ``geometry.KEY``)."""
        doc = copy.deepcopy(self.doc)
        geo = doc.setdefault("geometry", {})
        if key.startswith("geometry."):
            geo[key.split(".", 1)[1]] = value
        else:
            geo.setdefault("params", {})[key] = value
        return self._commit(doc, record)

    def move_handle(self, key: str, position: np.ndarray, rotation: np.ndarray | None = None,
                    record: bool = True) -> bool:
        """Move handle ``key`` to ``position (3,)`` (display metres) turned by ``rotation (3, 3)`` (world)."""
        s, R, t = placement(self.geometry)
        local = R.T @ ((np.asarray(position, dtype=float) * 1000.0 - t) / s)
        rot = R.T @ (np.eye(3) if rotation is None else np.asarray(rotation, dtype=float)) @ R
        try:
            params = handle_set(self.method).apply(self.params, self.state.raw, key, local, rot)
        except (KeyError, IndexError, ValueError, np.linalg.LinAlgError) as exc:
            self.error = f"handle {key}: {exc}"
            return False
        doc = copy.deepcopy(self.doc)
        doc["geometry"]["params"] = {k: v for k, v in params.items() if v is not None}
        return self._commit(doc, record)

    def begin_drag(self) -> None:
        """Remember the state a handle drag starts from: every :meth:`drag` is taken relative to it."""
        self._drag_base = (copy.deepcopy(self.doc), self.state)

    def drag(self, key: str, position: np.ndarray, rotation: np.ndarray | None = None) -> bool:
        """Move handle ``key`` from where the drag began (not recorded: :meth:`end_drag` records the drag)."""
        base = getattr(self, "_drag_base", None)
        if base is None:
            base = (copy.deepcopy(self.doc), self.state)
            self._drag_base = base
        doc, state = base
        current = (self.doc, self.state)
        self.doc, self.state = doc, state
        ok = self.move_handle(key, position, rotation, record=False)
        if not ok:
            self.doc, self.state = current
        return ok

    def end_drag(self) -> None:
        """Record a finished drag as one undo step."""
        base = getattr(self, "_drag_base", None)
        self._drag_base = None
        if base is not None and base[0] != self.doc:
            self.history.undo.append(base[0])
            del self.history.undo[:-self.history.limit]
            self.history.redo.clear()

    def adopt(self, mesh: Any, families: tuple[str, ...], support: bool = True) -> None:
        """Show ``mesh`` (construction units, e.g. the optimiser's result for ``[optimize]``) as the current
        state; the document is unchanged (a build optimises again from it).  ``support``: see :func:`measure`."""
        self.state = measure(self.doc, mesh, families, support=support)
        self.error, self.refused_folds = "", None

    def set_anchors(self, points: list[list[float]], mesh: Any, families: tuple[str, ...]) -> None:
        """Record live anchors as ``[optimize] anchors`` (``[vertex, x, y, z]``, mesh units) — one undo step —
        and show ``mesh``, the relaxation they hold (a build's optimisation holds them at the same points)."""
        doc = copy.deepcopy(self.doc)
        doc.setdefault("optimize", {})["anchors"] = [[int(p[0]), *map(float, p[1:4])] for p in points]
        if doc != self.doc:
            self.history.undo.append(self.doc)
            del self.history.undo[:-self.history.limit]
            self.history.redo.clear()
            self.doc = doc
        self.adopt(mesh, families)

    def undo(self) -> bool:
        if not self.history.undo:
            return False
        doc = self.history.undo.pop()
        self.history.redo.append(self.doc)
        self.doc, self.state, self.error = doc, solve(doc, self.base_dir), ""
        self.refused_folds = None
        return True

    def redo(self) -> bool:
        if not self.history.redo:
            return False
        doc = self.history.redo.pop()
        self.history.undo.append(self.doc)
        self.doc, self.state, self.error = doc, solve(doc, self.base_dir), ""
        self.refused_folds = None
        return True

    # -- files ----------------------------------------------------------------------------------------
    def save(self, path: str | Path, replace: bool = False) -> Path:
        """Write the design as TOML to exactly ``path`` (a ``.toml`` file in an existing folder) under the
        rules of :mod:`.saving`: never over the design read or its mesh, over a file this studio did not write
        only with ``replace``.  A relative mesh path is made absolute so the saved file reads the same mesh.
        Floats are written with ``repr`` (shortest round trip), so loading the file gives the same numbers and
        the same geometry."""
        import tomli_w

        doc = copy.deepcopy(self.doc)
        mesh = _section(doc, "geometry").get("mesh")
        if mesh is not None and not Path(mesh).is_absolute():
            doc["geometry"]["mesh"] = str((self.base_dir / mesh).resolve())
        return self.save_rules.write(path, tomli_w.dumps(doc), replace)

    def design(self) -> Any:
        """The whole design (every section validated) for the build pipeline."""
        from ..design import parse_design

        return parse_design(copy.deepcopy(self.doc), source="<studio>", base_dir=self.base_dir)
