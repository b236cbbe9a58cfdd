"""Shared fixtures and the zoo of named test meshes (STYLE.md §13)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("PPFAB_SHARED_DATA", REPO.parent / "shared" / "data"))


def shared_file(name: str) -> Path:
    """The path of a real mesh or data file of the shared data folder (``../shared/data`` beside the clone, or
    ``$PPFAB_SHARED_DATA``); the calling test is skipped, with the path it looked for, when the file is absent."""
    path = SHARED_DATA / name
    if not path.is_file():
        pytest.skip(f"shared data file {name} not found in {SHARED_DATA} (place the shared data folder beside the "
                    f"clone or set PPFAB_SHARED_DATA)")
    return path
FULL = bool(os.environ.get("PPFAB_FULL"))


def write_patch_obj(vertices: np.ndarray, ids: np.ndarray, path: Path) -> Path:
    """Write the patch of a recovered grid as an OBJ file: the ``vertices (N, 3)`` at the grid positions ``ids
    (rows, cols)`` (a slice of ``QuadMesh.grid_ids``), row-major, one quad per grid cell; returns ``path``."""
    rows, cols = ids.shape
    v = np.asarray(vertices)[ids.reshape(-1)]
    text = [f"v {float(x)!r} {float(y)!r} {float(z)!r}" for x, y, z in v]
    text += [f"f {a} {a + cols} {a + cols + 1} {a + 1}" for i in range(rows - 1) for j in range(cols - 1)
             for a in [i * cols + j + 1]]
    path.write_text("\n".join(text) + "\n")
    return path


def wait_for(cond, timeout: float = 30.0, what: str = "condition", poll: float = 0.1):
    """The first truthy value of ``cond()``, polled every ``poll`` s; an AssertionError naming ``what`` after
    ``timeout`` s (the studio's tests wait on a server thread or a browser)."""
    import time

    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        value = cond()
        if value:
            return value
        time.sleep(poll)
    raise AssertionError(f"timed out waiting for {what}")


def left_for_the_collector(job) -> tuple[object, int]:
    """``job()`` 's result and how many objects it left in reference cycles: run once to warm the caches, then
    again with the cyclic collector off, which then collects what that run left (0 when it let go of all it
    made on return)."""
    import gc

    job()
    gc.collect()
    gc.disable()
    try:
        got = job()
        return got, gc.collect()
    finally:
        gc.enable()


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


def small_vault(name: str, max_length: float = 3000.0, joint: str | None = None) -> str:
    """The 6 × 4 PP vault the end-to-end, tamper, drawing and marking tests build (depth 150 mm, 12 mm plates,
    16 mm joints, fast nesting), with ``beams.max_length`` and, when given, ``beams.joint``."""
    joint_line = f'joint = "{joint}"\n' if joint else ""
    return small_design(6, 4, u_range=(-4.5, 4.5), name=name, extra=f"""
[beams]
depth = 150.0
thickness = 12.0
{joint_line}max_length = {max_length}
[panels]
gap = 16.0
""")


def built_folder(name: str, text: str):
    """A module fixture ``built``: the design ``text`` built once by ``ppfab build`` into a folder of its own
    (the build's exit status asserted), returned as that folder's path."""

    @pytest.fixture(scope="module")
    def built(tmp_path_factory) -> Path:
        from fabrication.cli import main

        root = tmp_path_factory.mktemp(name)
        (root / "d.toml").write_text(text)
        out = root / "out"
        assert main(["build", str(root / "d.toml"), "-o", str(out), "--quiet"]) == 0
        return out

    return built


WAVY_SPHERES = np.array([[0, 0, 2, 5.0], [8, 3, 3, 6], [16, -2, 2.5, 5.5], [24, 0, 2, 4.5], [30, 2, 3, 5]])
"""Control spheres ``(x, y, z, r)`` of a wavy channel surface (conical P tests)."""


def conical_zoo() -> dict:
    """Conical P and PP grids with their planar families: a P mesh from spheres (§4.2.3), PP meshes from
    spheres touching a plane (§4.2.4), from eq. (11) and from two principal sections (§4.1.2)."""
    from ppfab.constructions.conical_pp import Series, conical_pp_grid
    from ppfab.constructions.conical_sections import sections_grid
    from ppfab.constructions.conical_spheres import channel_mesh, touching_radii

    c = np.array([[0, 0, 6.0], [10, 0, 8], [20, 0, 7.5], [30, 0, 6]])
    x = np.linspace(-15, 15, 9)
    y = np.linspace(-10, 10, 7)
    return {
        "P-spheres": (channel_mesh(WAVY_SPHERES, 12, 10, (-80, 80)), ("rows",)),
        "PP-spheres": (channel_mesh(np.c_[c, touching_radii(c, [0, 0, 1.0, 0])], 12, 10, (-80, 80)), ("rows", "cols")),
        "PP-eq11": (conical_pp_grid(Series(cos=[-10.0]), Series(cosh=[-20.0], poly=[0, 0, 1.0]),
                                    np.linspace(-.6, .6, 12), np.linspace(-.4, .4, 9), frame="z_up"), ("rows", "cols")),
        "PP-sections": (sections_grid(np.c_[x, 8 - x ** 2 / 30], np.c_[y, 8 - y ** 2 / 20], 12, 9, d=3.0),
                        ("rows", "cols")),
    }
