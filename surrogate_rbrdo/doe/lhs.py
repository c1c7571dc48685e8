"""Latin hypercube designs with a maximin (φ_p) optimisation, and space-filling metrics.

The optimiser is the Morris & Mitchell (1995) column-exchange search on the φ_p criterion
(``φ_p = (Σ_{i<j} d_ij^{-p})^{1/p}``, smaller is better; as ``p → ∞`` minimising it maximises the
minimum pairwise distance). Each iteration swaps two entries of one column, which keeps the design
a Latin hypercube, and is accepted when φ_p decreases. Distances are measured in the unit cube so
that every variable counts equally whatever its unit.

>>> import numpy as np
>>> rng = np.random.default_rng(1)
>>> U = lhs(10, [[0.0, 1.0]] * 2, rng=rng)
>>> bins = np.floor(U * 10).astype(int)          # one point per stratum in every column
>>> bool(np.all(np.sort(bins, axis=0) == np.arange(10)[:, None]))
True
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import pdist

from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive

LHS_CRITERIA = ("maximin", "random")


def check_bounds(bounds: object, name: str = "bounds") -> np.ndarray:
    """Return ``bounds`` as a float array of shape ``(d, 2)`` with finite ``lower < upper``.

    >>> check_bounds([[0, 1], [2, 1]])
    Traceback (most recent call last):
    ...
    ValueError: bounds[1] = [2.0, 1.0] is not allowed: lower must be < upper
    """
    b = np.asarray(bounds, dtype=float)
    if b.ndim != 2 or b.shape[1] != 2 or b.shape[0] < 1:
        raise ValueError(
            f"{name} has shape {b.shape} is not allowed: must be (d, 2) with d >= 1 rows "
            "[lower, upper]"
        )
    if not np.all(np.isfinite(b)):
        raise ValueError(f"{name} = {b.tolist()} is not allowed: must be finite")
    bad = np.flatnonzero(b[:, 0] >= b[:, 1])
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"{name}[{i}] = {b[i].tolist()} is not allowed: lower must be < upper")
    return b


def to_unit(X: np.ndarray, bounds: object) -> np.ndarray:
    """Map points from the box ``bounds`` to the unit cube.

    >>> to_unit(np.array([[5.0]]), [[0.0, 10.0]])
    array([[0.5]])
    """
    b = check_bounds(bounds)
    return (np.asarray(X, dtype=float) - b[:, 0]) / (b[:, 1] - b[:, 0])


def from_unit(U: np.ndarray, bounds: object) -> np.ndarray:
    """Map points from the unit cube to the box ``bounds``.

    >>> from_unit(np.array([[0.5]]), [[0.0, 10.0]])
    array([[5.]])
    """
    b = check_bounds(bounds)
    return b[:, 0] + np.asarray(U, dtype=float) * (b[:, 1] - b[:, 0])


def min_distance(X: np.ndarray, bounds: object | None = None) -> float:
    """Smallest pairwise Euclidean distance (in the unit cube if ``bounds`` is given).

    >>> min_distance(np.array([[0.0, 0.0], [3.0, 4.0], [0.0, 1.0]]))
    1.0
    """
    X = np.asarray(X, dtype=float)
    if bounds is not None:
        X = to_unit(X, bounds)
    return float(pdist(X).min())


def phi_p(X: np.ndarray, p: float = 50.0, bounds: object | None = None) -> float:
    """Morris–Mitchell space-filling criterion ``(Σ_{i<j} d_ij^{-p})^{1/p}`` (smaller is better).

    Computed as ``(1/d_min) * (Σ (d_min/d_ij)^p)^{1/p}`` to avoid overflow for large ``p``.

    >>> round(phi_p(np.array([[0.0], [1.0], [3.0]]), p=1.0), 6)   # 1/1 + 1/2 + 1/3
    1.833333
    """
    X = np.asarray(X, dtype=float)
    if bounds is not None:
        X = to_unit(X, bounds)
    d = pdist(X)
    dmin = d.min()
    if dmin == 0.0:
        return float("inf")
    return float(np.sum((dmin / d) ** p) ** (1.0 / p) / dmin)


def _random_lhs(n: int, d: int, rng: np.random.Generator) -> np.ndarray:
    perms = np.argsort(rng.random((n, d)), axis=0)
    return (perms + rng.random((n, d))) / n


def _maximin_search(U: np.ndarray, iterations: int, p: float,
                    rng: np.random.Generator) -> np.ndarray:
    """Greedy column-exchange search on φ_p with incremental distance updates."""
    n, d = U.shape
    U = U.copy()
    D = np.sqrt(((U[:, None, :] - U[None, :, :]) ** 2).sum(-1))
    np.fill_diagonal(D, np.inf)
    scale = D.min()
    W = (scale / D) ** p                     # scaled d^-p, zero on the diagonal
    total = W.sum() / 2.0
    cols = rng.integers(0, d, size=iterations)
    pairs = rng.integers(0, n, size=(iterations, 2))
    for k, (i, j) in zip(cols, pairs, strict=True):
        if i == j:
            continue
        Ui, Uj = U[i].copy(), U[j].copy()
        Ui[k], Uj[k] = Uj[k], Ui[k]
        di = np.sqrt(((U - Ui) ** 2).sum(1))
        dj = np.sqrt(((U - Uj) ** 2).sum(1))
        di[[i, j]] = np.inf
        dj[[i, j]] = np.inf
        wi, wj = (scale / di) ** p, (scale / dj) ** p
        new = total - W[i].sum() - W[j].sum() + W[i, j] + wi.sum() + wj.sum() + W[i, j]
        if new < total:
            U[i], U[j] = Ui, Uj
            W[i], W[:, i] = wi, wi
            W[j], W[:, j] = wj, wj
            W[i, j] = W[j, i] = (scale / np.linalg.norm(Ui - Uj)) ** p
            total = W.sum() / 2.0
    return U


def lhs(n: int, bounds: object, *, rng: np.random.Generator, criterion: str = "maximin",
        iterations: int = 2000, p: float = 50.0) -> np.ndarray:
    """Seeded Latin hypercube design of ``n`` points in the box ``bounds``.

    Parameters
    ----------
    n : int
        Number of points; at least ``d + 1`` (the smallest design a Kriging model with a constant
        trend and ``d`` length scales can be fitted on).
    bounds : array_like, shape (d, 2)
        ``[lower, upper]`` per variable, ``lower < upper``.
    rng : numpy.random.Generator
        Source of randomness (required).
    criterion : {"maximin", "random"}
        ``"maximin"`` optimises φ_p (≈ maximin distance) by column exchanges; ``"random"`` returns
        the plain random Latin hypercube.
    iterations : int
        Number of exchange proposals of the maximin search.
    p : float
        Exponent of φ_p.

    Returns
    -------
    ndarray, shape (n, d)

    Examples
    --------
    >>> import numpy as np
    >>> b = [[1000.0, 3000.0], [300.0, 750.0], [50.0, 80.0], [0.5, 1.5], [0.5, 1.5]]
    >>> X = lhs(20, b, rng=np.random.default_rng(0))
    >>> X.shape, bool(np.all((X >= np.array(b)[:, 0]) & (X <= np.array(b)[:, 1])))
    ((20, 5), True)
    >>> lhs(3, b, rng=np.random.default_rng(0))
    Traceback (most recent call last):
    ...
    ValueError: n = 3 is not allowed: must be an integer >= 6 (dimension + 1 = 5 + 1)
    """
    rng = require_rng(rng)
    b = check_bounds(bounds)
    d = b.shape[0]
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < d + 1:
        raise ValueError(
            f"n = {n!r} is not allowed: must be an integer >= {d + 1} "
            f"(dimension + 1 = {d} + 1)"
        )
    check_choice("criterion", criterion, LHS_CRITERIA)
    iterations = check_int("iterations", iterations, minimum=0)
    check_positive("p", p)
    U = _random_lhs(int(n), d, rng)
    if criterion == "maximin":
        U = _maximin_search(U, iterations, p, rng)
    return from_unit(U, b)
