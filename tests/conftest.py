"""Shared fixtures and the zoo of named test meshes (STYLE.md §13)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"
FULL = bool(os.environ.get("PPFAB_FULL"))


def smooth_face_image(m: int, n: int, seed: int = 0, amplitude: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """Generators ``g (m+2, 4)``, ``h (n+2, 4)`` of a fair PP face image: a dome-like patch with a
    seeded smooth perturbation (the face normals turn gently, no folds)."""
    rng = np.random.default_rng(seed)
    s = np.linspace(-0.5, 0.5, m + 2)
    t = np.linspace(-0.5, 0.5, n + 2)
    a, b = rng.uniform(0.6, 1.2, 2)
    cg = rng.normal(scale=amplitude, size=3)
    ch = rng.normal(scale=amplitude, size=3)
    g = np.stack([a * s, cg[0] * s ** 2, 0.5 + 0 * s, -0.5 * a * a * s ** 2 + cg[1] * s ** 3], axis=1)
    h = np.stack([ch[0] * t ** 2, b * t, 0.5 + 0 * t, -0.5 * b * b * t ** 2 + ch[1] * t ** 3], axis=1)
    return g, h


ZOO_SHAPES = {
    "square-8x8": (8, 8, 0),
    "wide-5x17": (5, 17, 1),
    "tall-23x4": (23, 4, 2),
    "big-40x31": (40, 31, 3),
    "tiny-1x1": (1, 1, 4),
}


@pytest.fixture(params=list(ZOO_SHAPES), ids=list(ZOO_SHAPES))
def pp_grid(request):
    from ppfab.faceimage import pp_from_face_image

    m, n, seed = ZOO_SHAPES[request.param]
    g, h = smooth_face_image(m, n, seed)
    return pp_from_face_image(g, h)


def small_design(faces_u: int = 5, faces_v: int = 4, u_range=(-4.0, 4.0), v_range=(-3.0, 3.0),
                 name: str = "small", extra: str = "", fast: bool = True) -> str:
    """A small PP vault (the default's face image, fewer faces) as design-file text, with optional extra
    sections and, when ``fast``, small nesting budgets."""
    text = f"""
[design]
name = "{name}"
[geometry]
method = "face_image_curves"
scale = 1000.0
[geometry.params]
g = [[0.0, 0.025], [0.0, 0.0, 0.0001], [0.5], [0.0, 0.0, -0.0125]]
h = [[0.0, 0.0, 0.0001], [0.0, 0.0333333], [0.5], [-8.0, 0.0, -0.0166667]]
u_range = [{u_range[0]}, {u_range[1]}]
v_range = [{v_range[0]}, {v_range[1]}]
faces_u = {faces_u}
faces_v = {faces_v}
"""
    text += extra
    if fast:
        for section in ("nesting", "beam_nesting"):
            if f"[{section}]" in text:
                text = text.replace(f"[{section}]", f"[{section}]\ntime_budget = 0.5", 1)
            else:
                text += f"\n[{section}]\ntime_budget = 0.5\n"
    return text
