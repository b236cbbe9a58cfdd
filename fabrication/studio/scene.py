"""The studio's colours and the geometry of its gizmos: the panels' colour ramp and legend, a support plane drawn
as a square, a handle's rotation from its quaternion."""

from __future__ import annotations

from typing import Any

import numpy as np

# a perceptual ramp (viridis at five stops), blue = low, yellow = high
_RAMP = np.array([[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]], dtype=float)
FOLD_RGB = (230, 30, 30)


def ramp(values: np.ndarray, bounds: tuple[float, float] | None = None) -> np.ndarray:
    """``(k, 3)`` uint8 colours of ``values (k,)`` on the ramp, scaled from ``bounds`` (default: their min and
    max)."""
    x = np.asarray(values, dtype=float)
    finite = np.isfinite(x)
    lo, hi = (float(x[finite].min()), float(x[finite].max())) if finite.any() else (0.0, 1.0)
    if bounds is not None:
        lo, hi = bounds
    t = np.clip((np.nan_to_num(x, nan=lo) - lo) / (hi - lo if hi > lo else 1.0), 0, 1) * (len(_RAMP) - 1)
    k = np.minimum(t.astype(int), len(_RAMP) - 2)
    f = (t - k)[:, None]
    return ((1 - f) * _RAMP[k] + f * _RAMP[k + 1]).astype(np.uint8)


METRIC_UNITS = {"planarity": ("δ_f (§3.3)", ""), "panel area": ("panel area", " m²"),
                "corner angle": ("smallest corner angle", "°"), "type": ("panel type", "")}
"""What each colouring shows and its unit."""


def legend_html(metric: str, values: np.ndarray, folds: bool = False) -> str:
    """The colour legend of the panels: the ramp from its low to its high end with the values there (the fixed
    0 … 1e-3 scale of δ_f), the number of types for ``type``, and the fold colour when faces fold."""
    label, unit = METRIC_UNITS.get(metric, (metric, ""))
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    if metric == "type":
        body = f"{label}: {int(x.max()) + 1 if x.size else 0} types, one colour each"
    else:
        lo, hi = (0.0, 1e-3) if metric == "planarity" else ((float(x.min()), float(x.max())) if x.size else (0, 0))
        stops = ", ".join(f"rgb({int(r)},{int(g)},{int(b)})" for r, g, b in _RAMP)
        top = " and above" if metric == "planarity" else ""
        body = (f"{label}<div style='height:10px;margin:2px 0;background:linear-gradient(to right,{stops})'></div>"
                f"<span style='float:left'>{lo:.3g}{unit}</span><span style='float:right'>{hi:.3g}{unit}{top}</span>"
                "<div style='clear:both'></div>")
    if folds:
        r, g, b = FOLD_RGB
        body += f"<div><span style='color:rgb({r},{g},{b})'>&#9632;</span> folded faces</div>"
    return f"<div style='font-size:12px'>{body}</div>"


def plane_square(centre: np.ndarray, normal: np.ndarray, half: float) -> tuple[np.ndarray, np.ndarray]:
    """A square ``2·half`` wide in the plane through ``centre (3,)`` with ``normal (3,)``: vertices ``(4, 3)``
    float32 and two triangles ``(2, 3)``."""
    n = np.asarray(normal, dtype=float) / max(float(np.linalg.norm(normal)), 1e-300)
    a = np.cross(n, [0.0, 0.0, 1.0] if abs(n[2]) < 0.9 else [1.0, 0.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(n, a)
    c = np.asarray(centre, dtype=float)
    verts = np.array([c - half * a - half * b, c + half * a - half * b, c + half * a + half * b,
                      c - half * a + half * b], dtype=np.float32)
    return verts, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)


def quat_matrix(wxyz: Any) -> np.ndarray:
    """The rotation matrix ``(3, 3)`` of a unit quaternion ``(w, x, y, z)``."""
    w, x, y, z = np.asarray(wxyz, dtype=float) / max(float(np.linalg.norm(wxyz)), 1e-300)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
