"""The handle types of the studio: a 3D handle, a number beside it, and the set of handles of one construction
(the interface every construction's handles implement, :mod:`.handles` and :mod:`.point_handles`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

Params = dict[str, Any]


@dataclass(frozen=True)
class Handle:
    """One handle: ``position (3,)`` in construction units, whether it turns, a label and its RGB colour; a
    plane handle has the plane's ``normal (3,)`` (the studio draws the plane, as the paper's Fig. 12 does)."""

    key: str
    position: np.ndarray
    label: str
    color: tuple[int, int, int]
    rotatable: bool = False
    normal: np.ndarray | None = None


@dataclass(frozen=True)
class Scalar:
    """A number the handle set offers besides the points (e.g. a sphere's radius): ``get(params)``,
    ``set(params, value) -> params``."""

    label: str
    get: Callable[[Params], float]
    set: Callable[[Params, float], Params]


class HandleSet:
    """The handles of one construction (none by default: the sliders still edit every number)."""

    def handles(self, params: Params, grid: Any) -> list[Handle]:
        return []

    def apply(self, params: Params, grid: Any, key: str, position: np.ndarray, rotation: np.ndarray) -> Params:
        """New parameters after handle ``key`` moved to ``position (3,)`` and turned by ``rotation (3, 3)``."""
        raise KeyError(key)

    def scalars(self, params: Params) -> list[Scalar]:
        return []
