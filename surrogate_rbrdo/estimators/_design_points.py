"""Several design points: the search with bulges of Der Kiureghian & Dakessian (1998).

After a design point ``u_j`` (reliability index ``β_j``) is found, the limit-state function is
deflected by a *bulge* around it (Der Kiureghian, A., Dakessian, T. (1998), Multiple design
points in first and second-order reliability, *Structural Safety* 20, 37–49)::

    B_j(u) = s_j (r_j² − ‖u − u_j‖²)²   for ‖u − u_j‖ < r_j,   0 outside,

which lifts ``G`` near ``u_j`` (the surface ``G + Σ B_j = 0`` is pushed away from the origin
there) and leaves it unchanged elsewhere, and the design-point search is repeated on the
deflected function. A point found *outside* every bulge is a further design point of ``G``
itself (``B`` and its gradient vanish there); one found inside a bulge is an artefact of the
bulge and ends the searches from that start. Our reading of the free constants: radius
``r_j = 0.5 β_j`` (the bulges of two design points at least ``β`` apart do not overlap) and
height ``s_j r_j⁴ = ‖∇G(u_j)‖ r_j`` (the surface is pushed out by about ``r_j`` at ``u_j``).

Searches start at the origin (Der Kiureghian & Dakessian) and then at the mirror image
``−u_j`` of every point found (the first, then the others): a search from the origin follows
the gradient at the origin, which points at the first design point again, so a failure region
on the opposite side (a two-sided limit state such as ``|a·u| > β``, a series system of
opposite loads) is only found from there — for each pair of opposite branches (the 10-D
four-branch linear system ``problems.series_linear``: ``3e₂, 3e₁, −3.5e₂, −3.5e₁``).
Only points with ``Φ(−β_j) ≥ 10⁻³ Φ(−β_1)`` are kept (others carry less than 0.1 %
of P_f); every point found gets a bulge. Each deflected search is limited to ``max_iter``
iterations and ends once three iterates in a row lie inside a bulge (it is then sliding on a
bulge: on a limit state with one design point every deflected search does), and the search
stops after ``max_points`` design points.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import special

from surrogate_rbrdo.estimators._minimum import far_side_points
from surrogate_rbrdo.estimators.form import FORM, DesignPoint

#: bulge radius as a fraction of the design point's reliability index
BULGE_RADIUS = 0.5
#: a further design point is kept when Φ(−β_j) ≥ RELEVANCE · Φ(−β_1)
RELEVANCE = 1e-3
#: restarts of a deflected search from a nearer failure point its minimum check found
MAX_RESTARTS = 2


@dataclass(frozen=True)
class Bulge:
    """``B(u) = s (r² − ‖u − centre‖²)²`` inside the ball of radius ``r``, zero outside.

    >>> b = Bulge(np.array([3.0, 0.0]), 1.5, 2.0)
    >>> b(np.array([[3.0, 0.0], [5.0, 0.0]])).tolist(), b.inside(np.array([3.5, 0.0]))
    ([2.0, 0.0], True)
    """

    centre: np.ndarray
    radius: float
    height: float

    def __call__(self, u: np.ndarray) -> np.ndarray:
        d2 = np.sum((u - self.centre) ** 2, axis=1)
        r2 = self.radius**2
        return np.where(d2 < r2, self.height * ((r2 - d2) / r2) ** 2, 0.0)

    def inside(self, u: np.ndarray) -> bool:
        return bool(np.linalg.norm(u - self.centre) < 0.999 * self.radius)

    @classmethod
    def at(cls, dp: DesignPoint) -> Bulge:
        """The bulge around a design point (radius ``0.5 β``, height ``‖∇G‖ r``)."""
        r = BULGE_RADIUS * abs(dp.beta)
        return cls(np.asarray(dp.u_star, dtype=float), r, float(np.linalg.norm(dp.grad)) * r)


class Deflected:
    """``G(u) + Σ B_j(u)``, counting the calls of ``G`` (points outside the domain stay
    ``+inf``)."""

    def __init__(self, G: Any, bulges: list[Bulge]) -> None:
        self.G, self.bulges = G, bulges

    @property
    def calls(self) -> int:
        return self.G.calls

    @property
    def scale(self) -> float:
        return float(getattr(self.G, "scale", 0.0))

    def __call__(self, u: np.ndarray) -> np.ndarray:
        u = np.atleast_2d(u)
        return self.G(u) + sum((b(u) for b in self.bulges), np.zeros(u.shape[0]))


class _InBulges:
    """True once ``n`` iterates in a row lie inside a bulge."""

    def __init__(self, bulges: list[Bulge], n: int = 3) -> None:
        self.bulges, self.n, self.count = bulges, n, 0

    def __call__(self, u: np.ndarray) -> bool:
        inside = any(b.inside(u) for b in self.bulges)
        self.count = self.count + 1 if inside else 0
        return self.count >= self.n


def design_points(G: Any, m: int, first: DesignPoint, form: FORM, *, max_points: int,
                  max_iter: int = 20) -> list[DesignPoint]:
    """The design points of ``G`` (a safe mean point: ``first.beta > 0``), ``first`` first.

    See the module docstring; ``G`` counts its calls, so the searches' cost is in ``G.calls``.
    """
    points, bulges = [first], [Bulge.at(first)]
    if max_points <= 1 or m < 2 or not first.converged or first.beta <= 0:
        return points
    log_p1 = float(special.log_ndtr(-first.beta))
    starts = [np.zeros(m), -np.asarray(first.u_star, dtype=float)]
    while starts and len(points) < max_points:
        u0 = starts.pop(0)
        if any(b.inside(u0) for b in bulges):
            continue                    # the mirror of a point already found
        while len(points) < max_points:
            dp = _search(G, m, bulges, form, u0, first.g_origin, max_iter)
            if dp is None:
                break                   # nothing further from this start
            bulges.append(Bulge.at(dp))
            if special.log_ndtr(-dp.beta) - log_p1 >= np.log(RELEVANCE):
                points.append(dp)
                starts.append(-np.asarray(dp.u_star, dtype=float))
    return points


def design_point_from(G: Any, m: int, points: list[DesignPoint], form: FORM,
                      start: np.ndarray, max_iter: int = 20) -> DesignPoint | None:
    """A further design point found by a search on the deflected function (bulges at
    ``points``) started at ``start`` — e.g. a failure sample far from every known point — or
    None when the search ends in a bulge or does not converge."""
    return _search(G, m, [Bulge.at(p) for p in points], form, np.asarray(start, dtype=float),
                   points[0].g_origin, max_iter)


def _search(G: Any, m: int, bulges: list[Bulge], form: FORM, start: np.ndarray, g0: float,
            max_iter: int) -> DesignPoint | None:
    """One search on the deflected function from ``start``; None unless it converges outside
    every bulge to a local minimum of the distance.

    A converged point is polled (:func:`~._minimum.nearer_point`): at the *corner* where two
    branches of a series system meet, ``G = min(g₁, g₂)`` has a kink whose finite-difference
    gradient (one branch per coordinate) is aligned with ``u``, so iHL-RF stops there — on the
    10-D four-branch linear system at ``(3, 3, 0, …)`` (distance 4.24) instead of the design
    point ``(3, 0, …)`` (3): IS then reported half of P_f with a 1–5 % error. Where the poll
    finds failure points nearer than ``β``, the search restarts from them, deepest first (one
    of the corner's two tilts leads back to the known branch and ends in its bulge, the other to
    the missed one; ``MAX_RESTARTS`` restarts in all); a point that stays a non-minimum is
    dropped."""
    defl = Deflected(G, bulges)
    starts, tries = [start], 0
    while starts and tries <= MAX_RESTARTS:
        dp = form.run(defl, m, start=(starts.pop(0), g0), max_iter=max_iter,
                      stop=_InBulges(bulges))
        tries += 1
        if not dp.converged or not dp.beta > 0 or any(b.inside(dp.u_star) for b in bulges):
            continue
        far = far_side_points(defl, np.asarray(dp.u_star, dtype=float), 1.0)
        if far.shape[0] == 0:
            return dp
        starts = list(far)
    return None


__all__ = ["Bulge", "Deflected", "design_point_from", "design_points"]
