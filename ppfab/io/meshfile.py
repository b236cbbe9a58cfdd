"""OBJ and OFF reading and writing for all-quad meshes.

Reading validates what a fabrication tool relies on and names the first
offence: a path that is empty or holds a control character, a path that is not a regular file (a FIFO,
a device, a folder — refused before anything is read), a file larger than :data:`MAX_MESH_BYTES`
(refused from its size), more vertices than the caller allows (counted from the OFF header or the
OBJ ``v`` lines before parsing), an OFF file holding more or fewer records than its header
announces, non-quad faces (with their line), indices out of range (however many digits), vertices
used by no face, NaN/inf or absurdly large coordinates, repeated corners, duplicate faces, coincident (unwelded) vertices — allowed only
in pairs along a seam, where the boundary edges coincide too, never as a single point where the
surface touches itself — zero-area faces, non-manifold edges (used by more than two faces)
and inconsistent orientation (an edge used twice in the same direction).  A UTF-8 byte-order
mark is skipped.  Writing a :class:`QuadGrid` uses row-major order:
vertex ``v[i, j]`` is line ``i·(n+1) + j``, face ``f[i, j]`` row-major; the OBJ header comment
is kept on one line (:func:`obj_comment`).
"""

from __future__ import annotations

import logging
import os
import re
import stat
from pathlib import Path
from typing import Callable, Iterator

import numpy as np

from ..errors import MeshFileError
from ..mesh import QuadGrid, QuadMesh
from ..topology import grid_face_indices
from .pathtext import path_problem, printable

log = logging.getLogger("ppfab")


_CHUNK = 1 << 20


def _numbered_lines(text: str) -> Iterator[tuple[int, str]]:
    """``enumerate(text.splitlines(), start=1)`` without the list of every line: the text is split in chunks of
    about 1 MiB that end in a newline, and a chunk of blank lines is counted, not split (a file of 200 MB of
    newlines takes seconds and little memory)."""
    start, lineno, n = 0, 1, len(text)
    while start < n:
        end = text.find("\n", start + _CHUNK)
        end = n if end < 0 else end + 1
        chunk = text[start:end]
        if chunk.isspace():
            lineno += len(chunk.splitlines())
        else:
            for raw in chunk.splitlines():
                yield lineno, raw
                lineno += 1
        start = end


def _parse_obj(text: str, path: str) -> tuple[np.ndarray, list[list[int]], list[int]]:
    verts: list[list[float]] = []
    faces: list[list[int]] = []
    lines: list[int] = []
    for lineno, raw in _numbered_lines(text):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        tag, *rest = line.split()
        if tag == "v":
            try:
                verts.append([float(t) for t in rest[:3]])
            except ValueError:
                raise MeshFileError(path, f"line {lineno}: vertex coordinates are not numbers") from None
            if len(rest) < 3:
                raise MeshFileError(path, f"line {lineno}: vertex needs 3 coordinates")
        elif tag == "f":
            try:
                idx = [int(t.split("/")[0]) for t in rest]
            except ValueError:
                raise MeshFileError(path, f"line {lineno}: face indices are not integers") from None
            n = len(verts)
            if 0 in idx:
                raise MeshFileError(path, f"line {lineno}: face uses vertex index 0, but OBJ indices start at 1: "
                                          "the indices look 0-based; add 1 to every face index")
            idx = [i - 1 if i > 0 else n + i for i in idx]
            faces.append(idx)
            lines.append(lineno)
    return np.array(verts, dtype=float).reshape(-1, 3), faces, lines


def _off_tokens(text: str) -> Iterator[tuple[str, int]]:
    """The tokens of an OFF file with their line numbers, comments dropped, one at a time (never all in memory)."""
    for lineno, raw in _numbered_lines(text):
        cut = raw.find("#")
        for m in _TOKEN.finditer(raw if cut < 0 else raw[:cut]):
            yield m.group(), lineno


_TOKEN = re.compile(r"\S+")


def _parse_off(text: str, path: str) -> tuple[np.ndarray, list[list[int]], list[int]]:
    """OFF as a stream of tokens (records may span lines, as in libigl's files), read only as far as the header
    announces, so a file of a few records and millions of extra tokens costs no memory."""
    stream = _off_tokens(text)
    first = next(stream, None)
    if first is None or not first[0].endswith("OFF"):
        raise MeshFileError(path, "not an OFF file (no OFF header)")
    line = first[1]

    def take() -> str:
        nonlocal line
        try:
            token, line = next(stream)
        except StopIteration:
            raise MeshFileError(path, "OFF file is shorter than its header announces") from None
        return token

    try:
        nv, nf = int(take()), int(take())
        if nv < 0 or nf < 0:
            raise MeshFileError(path, f"OFF header announces {nv} vertices and {nf} faces")
        take()                                          # the edge count, unused
        coords = [float(take()) for _ in range(3 * nv)]
        faces, lines = [], []
        for _ in range(nf):
            cnt = int(take())
            lines.append(line)
            if cnt < 0:
                raise ValueError
            faces.append([int(take()) for _ in range(cnt)])
    except ValueError:
        raise MeshFileError(path, f"OFF record near line {line} is not a list of numbers") from None
    extra = next(stream, None)
    if extra is not None:
        raise MeshFileError(path, f"OFF header announces {nv} vertices and {nf} faces, but the file goes on "
                                  f"after face {nf - 1} (line {extra[1]}): fix the counts in the header")
    return np.array(coords, dtype=float).reshape(-1, 3), faces, lines


def _validate(path: str, v: np.ndarray, faces: list[list[int]], lines: list[int]) -> np.ndarray:
    if len(v) == 0:
        raise MeshFileError(path, "no vertices")
    if not faces:
        raise MeshFileError(path, "no faces")
    bad = np.argwhere(~np.isfinite(v))
    if len(bad):
        raise MeshFileError(path, f"vertex {int(bad[0][0])} has a non-finite coordinate (NaN or inf)")
    big = np.argwhere(np.abs(v) > MAX_COORDINATE)
    if len(big):
        k = int(big[0][0])
        raise MeshFileError(path, f"vertex {k} has a coordinate of {float(np.abs(v[k]).max()):.3g}, beyond "
                                  f"±{MAX_COORDINATE:.0e} (check the file's units)")
    sizes = np.array([len(f) for f in faces])
    if np.any(sizes != 4):
        k = int(np.flatnonzero(sizes != 4)[0])
        count = int((sizes != 4).sum())
        raise MeshFileError(path, f"face {k} (line {lines[k]}) has {sizes[k]} corners; "
                                  f"{count} face(s) are not quads — ppfab needs an all-quad mesh")
    nv = len(v)
    try:
        f = np.array(faces, dtype=np.int64)
    except OverflowError:                 # an index beyond 64 bits: name it without converting it
        at = next(j for j, face in enumerate(faces) if any(not 0 <= i < nv for i in face))
        digits = str(next(i for i in faces[at] if not 0 <= i < nv))
        shown = digits if len(digits) <= 24 else f"{digits[:12]}… ({len(digits)} digits)"
        raise MeshFileError(path, f"face {at} (line {lines[at]}) refers to vertex {shown}, which does not exist "
                                  f"(the file has {nv} vertices)") from None
    out = np.flatnonzero((f < 0).any(axis=1) | (f >= len(v)).any(axis=1))
    if len(out):
        raise MeshFileError(path, _index_problem(f, int(out[0]), lines[out[0]], len(v), path))
    rep = np.flatnonzero(np.array([len(set(r)) for r in f.tolist()]) < 4)
    if len(rep):
        raise MeshFileError(path, f"face {int(rep[0])} (line {lines[rep[0]]}) repeats a corner (degenerate quad)")
    srt = np.sort(f, axis=1)
    _, first, counts = np.unique(srt, axis=0, return_index=True, return_counts=True)
    if np.any(counts > 1):
        raise MeshFileError(path, f"face {int(first[counts > 1][0])} appears more than once")
    used = np.unique(f)
    size = float(np.ptp(v[used], axis=0).max()) or 1.0
    _check_coincident(path, v, f, used, size)
    c = v[f]
    area = 0.5 * np.linalg.norm(np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1]), axis=1)
    tiny = area <= 1e-12 * size * size
    if np.any(tiny):
        k = int(np.flatnonzero(tiny)[0])
        raise MeshFileError(path, f"face {k} (line {lines[k]}) has zero area ({int(tiny.sum())} such face(s))")
    he = np.stack([f.ravel(), np.roll(f, -1, axis=1).ravel()], axis=1)
    und = np.sort(he, axis=1)
    uniq, inv, cnt = np.unique(und, axis=0, return_inverse=True, return_counts=True)
    if np.any(cnt > 2):
        e = uniq[np.flatnonzero(cnt > 2)[0]]
        raise MeshFileError(path, f"edge ({int(e[0])}, {int(e[1])}) is shared by {int(cnt.max())} faces (non-manifold)")
    dh, dcnt = np.unique(he, axis=0, return_counts=True)
    if np.any(dcnt > 1):
        e = dh[np.flatnonzero(dcnt > 1)[0]]
        faces_at = np.flatnonzero((he == e).all(axis=1)) // 4
        raise MeshFileError(path, f"faces {int(faces_at[0])} and {int(faces_at[1])} run through edge "
                                  f"({int(e[0])}, {int(e[1])}) in the same direction (inconsistent orientation)")
    if len(used) < nv:
        unused = np.setdiff1d(np.arange(nv), used)
        raise MeshFileError(path, f"vertex {int(unused[0])} is used by no face ({len(unused)} unused vertex(es)); "
                                  "remove the unused vertices (every vertex becomes a node of the structure)")
    return f


def _index_problem(f: np.ndarray, k: int, line: int, nv: int, path: str) -> str:
    """Why face ``k`` refers to a vertex that does not exist, and what to do about it: an OFF file numbered
    from 1 (smallest index 1, largest the vertex count) or an OBJ file numbered from 0 says so."""
    lo, hi = int(f.min()), int(f.max())
    bad = int(next(i for i in f[k] if i < 0 or i >= nv))
    if path.lower().endswith(".obj"):
        return f"face {k} (line {line}) refers to a vertex that does not exist (the file has {nv} vertices)"
    if lo == 1 and hi == nv:
        return (f"face {k} (line {line}) refers to vertex {bad}, but the file has vertices 0…{nv - 1}: the indices "
                f"look 1-based (smallest 1, largest {hi} = the vertex count); OFF indices start at 0, subtract 1 "
                "from every face index")
    return f"face {k} (line {line}) refers to vertex {bad}, which does not exist (vertices 0…{nv - 1})"


def _check_coincident(path: str, v: np.ndarray, f: np.ndarray, used: np.ndarray, size: float) -> None:
    """Coincident vertices are an error unless both lie on the boundary along a seam (where a closed
    surface was cut open, as in surfaces of revolution): there each of the two has a boundary edge that
    coincides with a boundary edge of the other.  Seams are kept and logged; a pair without such an edge
    is a point where the surface touches itself (a figure 8) and is refused."""
    key = np.round(v[used] / (1e-9 * size)).astype(np.int64)
    _, first, inverse, counts = np.unique(key, axis=0, return_index=True, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    dup = np.flatnonzero(counts[inverse] > 1)
    if not len(dup):
        return
    he = np.sort(np.stack([f.ravel(), np.roll(f, -1, axis=1).ravel()], axis=1), axis=1)
    e, cnt = np.unique(he, axis=0, return_counts=True)
    boundary = np.zeros(len(v), dtype=bool)
    bedges = e[cnt == 1]
    boundary[bedges.ravel()] = True
    weld = np.arange(len(v))                          # vertex → the first vertex at its position
    weld[used] = used[first[inverse]]
    welded, twins = np.unique(np.sort(weld[bedges], axis=1), axis=0, return_counts=True)
    on_seam = np.zeros(len(v), dtype=bool)            # welded vertex on a boundary edge that has a twin
    on_seam[welded[twins > 1].ravel()] = True
    for k in dup:
        a, b = int(used[first[inverse[k]]]), int(used[k])
        if a == b:
            continue
        if not (boundary[a] and boundary[b]):
            raise MeshFileError(path, f"vertices {a} and {b} coincide at {v[a].tolist()} (duplicate vertices "
                                      "inside the mesh: weld them before use)")
        if not on_seam[weld[b]]:
            raise MeshFileError(path, f"boundary vertices {a} and {b} coincide at {v[a].tolist()} with no boundary "
                                      "edge in common: the surface touches itself in a point (a figure 8); "
                                      "move them apart or weld them")
    log.info("%s: %d boundary vertices coincide with others (a seam; kept)", path, len(dup) - len(set(inverse[dup])))


MAX_COORDINATE = 1e12
"""Largest coordinate magnitude a mesh file may hold (beyond it squared lengths lose all precision)."""

_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


MAX_MESH_BYTES = 256 << 20
"""Largest mesh file read (256 MiB, about 2.5 million OBJ vertices, ten times ``geometry.max_vertices``):
a larger file is refused from its size, before it is read."""


def regular_file(path: str | os.PathLike, what: str = "file") -> int:
    """The size in bytes of ``path`` if it is a regular file (symbolic links followed); otherwise
    :class:`MeshFileError` — decided from ``stat`` alone, so a FIFO or a device is never opened.  An empty path
    or one holding a NUL or another control character is refused before ``stat`` (:func:`path_problem`)."""
    problem = path_problem(path)
    if problem is not None:
        shown = printable(str(path)) or f"the {what} path"
        raise MeshFileError(shown, f"{problem}; give the path of a {what}")
    try:
        st = os.stat(path)
    except OSError as exc:
        raise MeshFileError(str(path), f"cannot read ({exc.strerror or exc})") from None
    if not stat.S_ISREG(st.st_mode):
        kind = next((name for test, name in _KINDS if test(st.st_mode)), "not a regular file")
        link = f" (a symbolic link to {os.path.realpath(path)})" if os.path.islink(path) else ""
        raise MeshFileError(str(path), f"is {kind}{link}, not a regular {what}; give the path of a {what}")
    return int(st.st_size)


_OBJ_VERTEX = re.compile(rb"^[ \t]*v[ \t]", re.MULTILINE)


def announced_vertices(data: bytes, suffix: str) -> int:
    """The number of vertices a mesh file holds, counted without parsing it: the OFF header's count, or the
    OBJ ``v`` lines (``-1`` when an OFF header cannot be read; the parser then says why)."""
    head = data[:4096].decode("utf-8-sig", errors="replace")
    if suffix == ".off" or head.lstrip().startswith("OFF"):
        tokens = " ".join(line.split("#", 1)[0] for line in head.splitlines()).split()
        try:
            return int(tokens[1])
        except (IndexError, ValueError):
            return -1
    return len(_OBJ_VERTEX.findall(data))


def read_mesh(path: str | os.PathLike, vertex_limit: Callable[[int], None] | None = None) -> QuadMesh:
    """Read an OBJ or OFF file as a :class:`QuadMesh` (quads kept, checked; see module doc).

    ``vertex_limit(n)`` is called with the number of vertices the file holds (:func:`announced_vertices`)
    before it is parsed, and may raise to refuse it.
    """
    size = regular_file(path, "mesh file")
    p = Path(path)
    if size > MAX_MESH_BYTES:
        raise MeshFileError(str(path), f"the file has {size / 2**20:.0f} MiB, more than the "
                                       f"{MAX_MESH_BYTES >> 20} MiB a mesh file may have; give a smaller mesh")
    suffix = p.suffix.lower()
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise MeshFileError(str(path), f"cannot read ({exc.strerror or exc})") from None
    if vertex_limit is not None:
        vertex_limit(announced_vertices(data, suffix))
    text = data.decode("utf-8-sig", errors="replace")
    if suffix == ".off" or text.lstrip().startswith("OFF"):
        v, faces, lines = _parse_off(text, str(path))
    elif suffix == ".obj":
        v, faces, lines = _parse_obj(text, str(path))
    else:
        raise MeshFileError(str(path), f"unknown mesh format '{suffix}' (use .obj or .off)")
    f = _validate(str(path), v, faces, lines)
    return QuadMesh(v, f)


def load_mesh(path: str | os.PathLike, vertex_limit: Callable[[int], None] | None = None) -> QuadMesh:
    """:func:`read_mesh`, with the grid recovered when the mesh is a regular patch.

    The returned mesh keeps the file's own vertex and face order; ``mesh.grid``
    is the recovered :class:`QuadGrid` (with ``vertex_ids`` into the file) or ``None``.
    """
    mesh = read_mesh(path, vertex_limit)
    grid = mesh.try_grid()
    if grid is None:
        return mesh
    return QuadMesh(mesh.vertices, mesh.faces, grid=grid, grid_ids=grid.vertex_ids)


def _fmt(x: float) -> str:
    return np.format_float_positional(x, precision=12, unique=True, trim="-") if abs(x) < 1e15 else repr(float(x))


_LINE_BREAKS = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029]")


def obj_comment(text: str) -> str:
    """``text`` as one OBJ comment line: control characters and every character a reader may take for a
    line break (``str.splitlines`` does for ``\\x1c``–``\\x1e``, ``\\x85``, U+2028, U+2029) become spaces.

    >>> obj_comment("roof\\nv 1 2 3")
    'roof v 1 2 3'
    """
    return _LINE_BREAKS.sub(" ", text)


def _obj_text(vertices: np.ndarray, faces: np.ndarray, header: str) -> str:
    out = [f"# {obj_comment(header)}"] if header else []
    out += ["v " + " ".join(repr(float(c)) for c in row) for row in vertices]
    out += ["f " + " ".join(str(int(i) + 1) for i in row) for row in faces]
    return "\n".join(out) + "\n"


def _off_text(vertices: np.ndarray, faces: np.ndarray) -> str:
    out = ["OFF", f"{len(vertices)} {len(faces)} 0"]
    out += [" ".join(repr(float(c)) for c in row) for row in vertices]
    out += ["4 " + " ".join(str(int(i)) for i in row) for row in faces]
    return "\n".join(out) + "\n"


def _arrays(mesh: QuadGrid | QuadMesh) -> tuple[np.ndarray, np.ndarray]:
    if isinstance(mesh, QuadGrid):
        m1, n1 = mesh.shape
        ids = np.arange(m1 * n1).reshape(m1, n1)
        return mesh.vertices.reshape(-1, 3), grid_face_indices(ids, mesh.closed).reshape(-1, 4)
    return mesh.vertices, mesh.faces


def write_obj(mesh: QuadGrid | QuadMesh, path: str | os.PathLike, header: str = "ppfab") -> None:
    """Write quads to OBJ; a grid in row-major order (deterministic text, ``repr`` floats)."""
    v, f = _arrays(mesh)
    Path(path).write_text(_obj_text(v, f, header), encoding="utf-8")


def write_off(mesh: QuadGrid | QuadMesh, path: str | os.PathLike) -> None:
    """Write quads to OFF; a grid in row-major order."""
    v, f = _arrays(mesh)
    Path(path).write_text(_off_text(v, f), encoding="utf-8")


def write_mesh(mesh: QuadGrid | QuadMesh, path: str | os.PathLike) -> None:
    """Write OBJ or OFF by file suffix."""
    suffix = Path(path).suffix.lower()
    if suffix == ".obj":
        write_obj(mesh, path)
    elif suffix == ".off":
        write_off(mesh, path)
    else:
        raise MeshFileError(str(path), f"unknown mesh format '{suffix}' (use .obj or .off)")
