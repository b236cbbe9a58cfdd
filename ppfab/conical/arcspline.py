"""Arc-spline profiles (paper Remark 4.3): a channel surface's profile made of circular arcs, which turns the
surface into cone patches.

A convex arc spline is a chain of circular arcs joined with a common tangent (G1).  Parametrised by the angle
``θ`` of its outward normal ``u(θ) = (cos θ, sin θ)``, arc ``k`` covers ``θ ∈ [θ_k, θ_{k+1}]`` with centre
``c_k (2,)`` and radius ``ρ_k > 0``: its point with normal ``u(θ)`` is ``c_k + ρ_k u(θ)`` and its support function
is ``h(θ) = c_k·u(θ) + ρ_k``.  Two arcs share their junction point ``c_k + ρ_k u(θ_{k+1}) = c_{k+1} + ρ_{k+1}
u(θ_{k+1})``, so the radii, the junction angles and the first centre fix every centre:
``c_{k+1} = c_k + (ρ_k − ρ_{k+1}) u(θ_{k+1})``.  A closed spline turns once around (``θ`` over 360°) and its
last arc must lead back to the first centre.

In the channel-surface design of §4.2.3 the tangent planes of the cone ``C`` (axis ``a``, normals ``n(θ) =
cos β a + sin β u(θ)``, ``u`` in the cross-section plane ``Π ⊥ a``) meet ``Π`` in lines whose normal angle *is*
the profile angle ``θ``.  A plane with normal ``n(θ)`` whose trace in ``Π`` is the support line of arc ``k``,
``u(θ)·y = h(θ)``, passes through the point ``z_0 + c_k + ρ_k tan β a`` (``z_0`` the origin of ``Π``): the tangent
planes of one arc are those of one cone, so the strip between two planes ``W`` is a union of cone patches
(on a cylinder, ``cos β = 0``, of cylinder patches).  The Laguerre reflections that carry a strip to the next
(Remark 4.4) map a cone patch to a cone patch (planes with normals on a circle tangent to one sphere), so every
strip of the mesh is made of cone patches, one per arc — the surface of Remark 4.3 sampled by tangent planes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import DesignError


def _unit(theta: np.ndarray) -> np.ndarray:
    theta = np.asarray(theta, dtype=float)
    return np.stack([np.cos(theta), np.sin(theta)], axis=-1)


@dataclass(frozen=True)
class ArcSpline:
    """A convex G1 chain of circular arcs in the normal-angle parametrisation.

    ``radii (k,)`` mm (> 0); ``breaks (k + 1,)`` radians, increasing — arc ``i`` has outward normals from
    ``breaks[i]`` to ``breaks[i + 1]``; ``centres (k, 2)``; ``closed``: the spline turns once around.
    """

    radii: np.ndarray
    breaks: np.ndarray
    centres: np.ndarray
    closed: bool = False

    @classmethod
    def from_arcs(cls, arcs, first_centre=(0.0, 0.0), closed: bool = False, key: str = "profile_arcs",
                  scale: float = 1.0) -> "ArcSpline":
        """From ``[[radius, from_deg, to_deg], …]`` (consecutive: each arc starts at the normal angle where the
        last one ended) and the first arc's centre; lengths times ``scale``.  Raises :class:`DesignError` naming
        the arc when the list is not such a chain, and, for a closed spline, when it does not turn once around or
        does not close (the gap in mm)."""
        a = np.asarray(arcs, dtype=float)
        if a.ndim != 2 or a.shape[1] != 3 or len(a) == 0:
            raise DesignError(key, "needs a list of [radius, from_deg, to_deg] arcs")
        for i, (r, t0, t1) in enumerate(a):
            if not r > 0:
                raise DesignError(f"{key}[{i}]", f"radius must be positive, got {r:g}")
            if not t1 > t0:
                raise DesignError(f"{key}[{i}]", f"needs from_deg < to_deg (the normal turns forwards), got "
                                                 f"[{t0:g}, {t1:g}]")
            if i and abs(t0 - a[i - 1, 2]) > 1e-9:
                raise DesignError(f"{key}[{i}]", f"starts at {t0:g}° where arc {i - 1} ended at {a[i - 1, 2]:g}°: "
                                                 f"the arcs must follow each other (G1)")
        if not closed and a[-1, 2] - a[0, 1] >= 360.0:
            raise DesignError(key, f"turns through {a[-1, 2] - a[0, 1]:g}°: an open profile turns less than 360°")
        radii = a[:, 0] * scale
        breaks = np.radians(np.r_[a[:, 1], a[-1, 2]])
        centres = np.empty((len(a), 2))
        centres[0] = np.asarray(first_centre, dtype=float) * scale
        for i in range(1, len(a)):
            centres[i] = centres[i - 1] + (radii[i - 1] - radii[i]) * _unit(breaks[i])
        if closed:
            turn = a[-1, 2] - a[0, 1]
            if abs(turn - 360.0) > 1e-9:
                raise DesignError(key, f"a closed profile turns once around (360°), these arcs turn {turn:g}°")
            back = centres[-1] + (radii[-1] - radii[0]) * _unit(breaks[-1])
            gap = float(np.linalg.norm(back - centres[0]))
            if gap > 1e-9 * max(float(radii.max()), 1.0):
                raise DesignError(key, f"the arcs do not close: the last arc ends {gap:.6g} mm from where the first "
                                       f"begins; change a radius or an angle so that they meet")
        return cls(radii, breaks, centres, closed)

    @property
    def turn(self) -> float:
        """The angle (radians) the normal turns through."""
        return float(self.breaks[-1] - self.breaks[0])

    def support(self, theta: np.ndarray, arc: np.ndarray) -> np.ndarray:
        """``h(θ) = c_k·u(θ) + ρ_k`` of arc ``arc (m,)`` (extended beyond its ends where ``θ`` lies there)."""
        arc = np.asarray(arc, dtype=np.int64)
        return np.einsum("ki,ki->k", self.centres[arc], _unit(theta)) + self.radii[arc]

    def point(self, theta: np.ndarray, arc: np.ndarray) -> np.ndarray:
        """The point ``c_k + ρ_k u(θ)`` of arc ``arc`` with outward normal ``u(θ)``, ``(m, 2)``."""
        arc = np.asarray(arc, dtype=np.int64)
        return self.centres[arc] + self.radii[arc, None] * _unit(theta)

    def faces_per_arc(self, faces: int) -> np.ndarray:
        """``faces`` shared among the arcs in proportion to how far each turns (largest remainder, at least one
        each); raises :class:`DesignError` when there are fewer faces than arcs."""
        k = len(self.radii)
        if faces < k:
            raise DesignError("faces_profile", f"is {faces}, fewer than the {k} arcs of the profile: each arc needs "
                                               f"at least one face")
        share = np.diff(self.breaks) / self.turn * (faces - k)
        out = np.floor(share).astype(np.int64) + 1
        rest = faces - int(out.sum())
        out[np.argsort(-(share - np.floor(share)), kind="stable")[:rest]] += 1
        return out

    def face_angles(self, faces: int) -> tuple[np.ndarray, np.ndarray]:
        """The profile angles ``θ`` (radians) of the faces and the arc each belongs to, in the column layout of
        :func:`ppfab.constructions.conical_spheres.profile_angles`: an arc's normal range cut into equal parts,
        a face at the middle of each; open: a ghost face half a step beyond each end (on the end arc, extended),
        ``faces + 2`` values; closed: ``faces + 1``, column ``b`` is face ``(b − 1) mod faces``."""
        per = self.faces_per_arc(faces)
        theta, arc = [], []
        for i, m in enumerate(per):
            step = (self.breaks[i + 1] - self.breaks[i]) / m
            theta.append(self.breaks[i] + (np.arange(m) + 0.5) * step)
            arc.append(np.full(m, i))
        th, ar = np.concatenate(theta), np.concatenate(arc)
        if self.closed:
            return np.r_[th[-1], th], np.r_[ar[-1], ar]
        first = (self.breaks[1] - self.breaks[0]) / per[0]
        last = (self.breaks[-1] - self.breaks[-2]) / per[-1]
        return (np.r_[th[0] - first, th, th[-1] + last], np.r_[0, ar, len(per) - 1])
