"""JSON form of a grid: shape, closure, vertices, support planes, face image, axes."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from ..errors import MeshFileError
from ..mesh import QuadGrid


def grid_to_json(grid: QuadGrid) -> dict:
    """Plain-data dict (lists of floats) of a grid and its support structure."""
    doc = {
        "format": "ppfab-grid",
        "version": 1,
        "rows": grid.shape[0],
        "cols": grid.shape[1],
        "closed": bool(grid.closed),
        "vertices": grid.vertices.reshape(-1, 3).tolist(),
    }
    for name in ("support_u", "support_w", "face_image", "axes"):
        arr = getattr(grid, name)
        if arr is not None:
            doc[name] = np.asarray(arr).tolist()
    return doc


def grid_from_json(doc: dict | str | os.PathLike) -> QuadGrid:
    """Inverse of :func:`grid_to_json` (accepts the dict or a file path)."""
    source = "<json>"
    if not isinstance(doc, dict):
        source = str(doc)
        try:
            doc = json.loads(Path(doc).read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise MeshFileError(source, f"cannot read grid JSON ({exc})") from None
    try:
        m1, n1 = int(doc["rows"]), int(doc["cols"])
        v = np.asarray(doc["vertices"], dtype=float).reshape(m1, n1, 3)
        extra = {k: np.asarray(doc[k], dtype=float) for k in ("support_u", "support_w", "face_image", "axes") if k in doc}
        return QuadGrid(v, closed=bool(doc.get("closed", False)), **extra)
    except (KeyError, ValueError, TypeError) as exc:
        raise MeshFileError(source, f"not a ppfab grid JSON ({exc})") from None
