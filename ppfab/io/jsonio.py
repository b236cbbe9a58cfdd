"""JSON form of a grid: shape, closure, vertices, support planes, face image, axes."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

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
    data: dict[str, Any]
    if isinstance(doc, dict):
        data = doc
    else:
        source = str(doc)
        try:
            data = json.loads(Path(doc).read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise MeshFileError(source, f"cannot read grid JSON ({exc})") from None
    try:
        m1, n1 = int(data["rows"]), int(data["cols"])
        v = np.asarray(data["vertices"], dtype=float).reshape(m1, n1, 3)
        extra = {k: np.asarray(data[k], dtype=float) for k in ("support_u", "support_w", "face_image", "axes")
                 if k in data}
        return QuadGrid(v, closed=bool(data.get("closed", False)), support_u=extra.get("support_u"),
                        support_w=extra.get("support_w"), face_image=extra.get("face_image"), axes=extra.get("axes"))
    except (KeyError, ValueError, TypeError) as exc:
        raise MeshFileError(source, f"not a ppfab grid JSON ({exc})") from None
