"""Figures with matplotlib (Agg): 3D views of meshes and structures, cutting sheets, histograms.

Every function writes a PNG (or returns SVG/PNG bytes) deterministically: fixed size, fixed view,
no timestamps in the metadata.  Polygons go to mplot3d as one array of equal-length polygons (shorter
ones padded by repeating their last vertex): given polygons of different lengths, mplot3d pads them into
``np.empty`` memory and its automatic limits read those uninitialised values — limits that change from
run to run and, when the memory holds a NaN, "Axis limits cannot be NaN or Inf".  The limits are set
from the data here, never automatically.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import TYPE_CHECKING, Iterable, overload

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

_META = {"Software": None}


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _set_equal_3d(ax, pts: np.ndarray) -> None:
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = np.maximum(hi - lo, 1e-3 * float((hi - lo).max() or 1.0))
    ax.set_xlim(lo[0], lo[0] + span[0])
    ax.set_ylim(lo[1], lo[1] + span[1])
    ax.set_zlim(lo[2], lo[2] + span[2])
    ax.set_box_aspect(tuple(span), zoom=1.0)   # true proportions


def padded_polygons(polygons: Iterable[np.ndarray]) -> np.ndarray:
    """Polygons ``(k_i, 3)`` as one array ``(P, max k_i, 3)``, each padded by repeating its last vertex (the
    drawn outline is the same: the extra edges have zero length)."""
    polys = [np.asarray(p, dtype=float) for p in polygons]
    k = max(len(p) for p in polys)
    return np.stack([np.concatenate([p, np.repeat(p[-1:], k - len(p), axis=0)]) for p in polys])


def mesh_figure(quads: np.ndarray, title: str = "", plates: Iterable[np.ndarray] = (),
                axes_segments: np.ndarray | None = None, elev: float = 28, azim: float = -55,
                size: tuple[float, float] = (7.5, 5.5)):
    """A 3D figure of quads ``(F, 4, 3)`` (shaded by their normal), optional beam plates (polygons
    ``(k, 3)``) and node axes ``(A, 2, 3)``."""
    plt = _plt()
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    quads = np.asarray(quads, dtype=float)
    fig = plt.figure(figsize=size, dpi=110)
    ax = fig.add_subplot(projection="3d")
    n = np.cross(quads[:, 2] - quads[:, 0], quads[:, 3] - quads[:, 1])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    light = np.array([0.3, -0.4, 0.87])
    shade = 0.55 + 0.45 * np.abs(n @ light)
    colours = np.column_stack([0.55 * shade, 0.72 * shade, 0.86 * shade, np.full(len(n), 0.85)])
    ax.add_collection3d(Poly3DCollection(quads, facecolors=colours, edgecolors=(0.15, 0.2, 0.3, 0.9),
                                         linewidths=0.4), autolim=False)
    pts = [quads.reshape(-1, 3)]
    plates = list(plates)
    if plates:
        ax.add_collection3d(Poly3DCollection(padded_polygons(plates), facecolors=(0.75, 0.42, 0.2, 0.55),
                                             edgecolors=(0.45, 0.22, 0.1, 0.9), linewidths=0.3), autolim=False)
        pts.append(np.concatenate(plates))
    if axes_segments is not None and len(axes_segments):
        ax.add_collection3d(Line3DCollection(axes_segments, colors=(0.8, 0.1, 0.1, 0.8), linewidths=0.6),
                            autolim=False)
    _set_equal_3d(ax, np.concatenate(pts))
    ax.view_init(elev=elev, azim=azim)
    ax.set_axis_off()
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    return fig


@overload
def save(fig: Figure, path: None = None, fmt: str = "png") -> bytes: ...
@overload
def save(fig: Figure, path: str | Path, fmt: str = "png") -> None: ...
def save(fig: Figure, path: str | Path | None = None, fmt: str = "png") -> bytes | None:
    """Save and close a figure; with no path return the bytes."""
    import warnings

    plt = _plt()
    buf = io.BytesIO()
    meta = {"Software": None} if fmt == "png" else {"Date": None, "Creator": None}
    with warnings.catch_warnings():
        # mplot3d's auto-margins overflow in a float subtraction on some views; harmless for the image
        warnings.simplefilter("ignore", RuntimeWarning)
        fig.savefig(buf, format=fmt, metadata=meta)
    plt.close(fig)
    data = buf.getvalue()
    if path is None:
        return data
    Path(path).write_bytes(data)
    return None


def render_mesh_png(mesh, path: str | Path, title: str = "", **kw) -> None:
    """Render a :class:`~ppfab.mesh.QuadGrid` or :class:`~ppfab.mesh.QuadMesh` to a PNG file."""
    from ppfab.mesh import as_quadmesh

    qm = as_quadmesh(mesh)
    save(mesh_figure(qm.face_corners, title, **kw), path)


def histogram(values: np.ndarray, title: str, xlabel: str, bins: int = 30):
    """A small histogram figure."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(4.2, 2.8), dpi=100)
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    lo, hi = (float(v.min()), float(v.max())) if len(v) else (0.0, 1.0)
    if hi - lo <= 1e-9 * max(abs(lo), abs(hi), 1e-300):
        # (nearly) equal values: bins narrower than the float spacing do not exist ("Too many bins")
        half = 0.5 * max(abs(lo), 1.0) * 1e-3
        bins, lo, hi = 1, lo - half, hi + half
    ax.hist(v, bins=bins if len(v) > 1 else 1, range=(lo, hi), color=(0.3, 0.5, 0.7), edgecolor="white",
            linewidth=0.5)
    ax.set_title(title, fontsize=9)
    ax.set_xlabel(xlabel, fontsize=8)
    ax.set_ylabel("count", fontsize=8)
    ax.tick_params(labelsize=7)
    fig.tight_layout()
    return fig

