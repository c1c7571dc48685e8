"""The linear regression ``y(t) = φ(t)ᵀ θ + v(t)`` and the identification bounds.

A :class:`Regression` holds a batch of independent records (trials, repeats, bearings and
directions): ``phi`` of shape ``(B, T, n)`` and ``y`` of shape ``(B, T)``. Every recursion in
:mod:`surrogate_rbrdo.identification.recursions` reads it; nothing here knows where the
samples came from (the synthetic rigid rotor, the condensed FE rotor, a rig record).

:class:`Bounds` is the box the estimate is projected onto. :meth:`Bounds.paper` is the paper's
box (Sect. 2.1.2): ``k ∈ [0.5, 1.5] k_catalog``, ``c ∈ [0.5, 2.0] c_init``.

>>> import numpy as np
>>> reg = Regression(phi=np.ones((5, 2)), y=np.ones(5), names=("k", "c"))
>>> reg.phi.shape, reg.n_records, reg.n_samples, reg.n_params
((1, 5, 2), 1, 5, 2)
>>> b = Bounds.paper(kinds=("k", "c"), k_catalog=2.0e8, c_init=800.0)
>>> b.lower.tolist(), b.upper.tolist()
([[100000000.0, 400.0]], [[300000000.0, 1600.0]])
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

#: the paper's identification box (Sect. 2.1.2), as factors on k_catalog and c_init
PAPER_K_FACTORS = (0.5, 1.5)
PAPER_C_FACTORS = (0.5, 2.0)


@dataclass(frozen=True, eq=False)
class Regression:
    """A batch of records of the linear regression ``y = φᵀ θ + v``.

    Parameters
    ----------
    phi : array (T, n) or (B, T, n)
        Regressors (information vectors) of ``B`` independent records of ``T`` samples.
    y : array (T,) or (B, T)
        Outputs.
    names : sequence of str
        One name per parameter (``n``).

    Raises
    ------
    ValueError
        Shapes that do not match, non-finite values, fewer than two samples.
    """

    phi: np.ndarray
    y: np.ndarray
    names: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        phi = np.asarray(self.phi, dtype=float)
        y = np.asarray(self.y, dtype=float)
        if phi.ndim == 2:
            phi = phi[None]
        if y.ndim == 1:
            y = y[None]
        if phi.ndim != 3 or y.ndim != 2 or phi.shape[:2] != y.shape:
            raise ValueError(f"phi has shape {np.shape(self.phi)} and y {np.shape(self.y)}: "
                             "need phi (B, T, n) and y (B, T) (or (T, n) and (T,))")
        if not (np.all(np.isfinite(phi)) and np.all(np.isfinite(y))):
            raise ValueError("phi or y contains a non-finite value: a record must be finite")
        if phi.shape[1] < 2:
            raise ValueError(f"a record has {phi.shape[1]} sample(s): need at least 2")
        names = tuple(self.names) or tuple(f"theta{i}" for i in range(phi.shape[2]))
        if len(names) != phi.shape[2]:
            raise ValueError(f"names = {list(names)} has {len(names)} entries: phi has "
                             f"{phi.shape[2]} columns")
        object.__setattr__(self, "phi", phi)
        object.__setattr__(self, "y", y)
        object.__setattr__(self, "names", names)

    @property
    def n_records(self) -> int:
        return int(self.phi.shape[0])

    @property
    def n_samples(self) -> int:
        return int(self.phi.shape[1])

    @property
    def n_params(self) -> int:
        return int(self.phi.shape[2])

    def information(self) -> np.ndarray:
        """``Φᵀ Φ`` per record, ``(B, n, n)``."""
        return np.einsum("btn,btm->bnm", self.phi, self.phi)

    def least_squares(self) -> np.ndarray:
        """Unconstrained least-squares estimate per record, ``(B, n)`` (``lstsq`` per record).

        >>> rng = np.random.default_rng(0)
        >>> phi = rng.normal(size=(50, 2))
        >>> Regression(phi, phi @ [3.0, -1.0]).least_squares().round(12).tolist()
        [[3.0, -1.0]]
        """
        return np.stack([np.linalg.lstsq(p, yy, rcond=None)[0]
                         for p, yy in zip(self.phi, self.y, strict=True)])


def _as_box(name: str, value: np.ndarray | Sequence[float]) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if a.ndim == 1:
        a = a[None]
    if a.ndim != 2:
        raise ValueError(f"{name} has shape {np.shape(value)}: need (n,) or (B, n)")
    return a


@dataclass(frozen=True, eq=False)
class Bounds:
    """A box ``lower ≤ θ ≤ upper`` per parameter (SI units); ``(n,)`` or one row per record.

    The recursions project every update onto it (componentwise clipping). ``±inf`` means
    unbounded.
    """

    lower: np.ndarray
    upper: np.ndarray

    def __post_init__(self) -> None:
        lo, hi = _as_box("lower", self.lower), _as_box("upper", self.upper)
        if lo.shape[-1] != hi.shape[-1]:
            raise ValueError(f"lower has {lo.shape[-1]} columns and upper {hi.shape[-1]}: "
                             "they must match")
        if np.any(np.isnan(lo)) or np.any(np.isnan(hi)) or np.any(lo >= hi):
            raise ValueError(f"bounds lower = {lo.tolist()}, upper = {hi.tolist()} are not "
                             "allowed: need lower < upper (no NaN)")
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)

    @classmethod
    def paper(cls, kinds: Sequence[str], k_catalog: np.ndarray | float,
              c_init: np.ndarray | float) -> Bounds:
        """The paper's box: ``k ∈ [0.5, 1.5] k_catalog``, ``c ∈ [0.5, 2.0] c_init``.

        Parameters
        ----------
        kinds : sequence of {"k", "c"}
            Kind of each parameter, in regression order.
        k_catalog, c_init : float or array (B,)
            Catalogue stiffness (N/m) and initial damping (N s/m), per record if arrays.
        """
        kinds = tuple(kinds)
        bad = [k for k in kinds if k not in ("k", "c")]
        if bad:
            raise ValueError(f"kinds = {list(kinds)} is not allowed: each must be 'k' or 'c'")
        k = np.atleast_1d(np.asarray(k_catalog, dtype=float))[:, None]
        c = np.atleast_1d(np.asarray(c_init, dtype=float))[:, None]
        if np.any(~np.isfinite(k) | (k <= 0)) or np.any(~np.isfinite(c) | (c <= 0)):
            raise ValueError("k_catalog and c_init must be finite and > 0")
        fk, fc = np.asarray(PAPER_K_FACTORS), np.asarray(PAPER_C_FACTORS)
        lo = [k * fk[0] if t == "k" else c * fc[0] for t in kinds]
        hi = [k * fk[1] if t == "k" else c * fc[1] for t in kinds]
        return cls(np.concatenate(lo, axis=1), np.concatenate(hi, axis=1))

    def for_records(self, n_records: int, n_params: int) -> tuple[np.ndarray, np.ndarray]:
        """``lower`` and ``upper`` broadcast to ``(B, n)``; a clear error on a mismatch."""
        lo, hi = self.lower, self.upper
        if lo.shape[-1] != n_params or lo.shape[0] not in (1, n_records) \
                or hi.shape[0] not in (1, n_records):
            raise ValueError(f"bounds have shape {lo.shape}/{hi.shape}: need ({n_params},) or "
                             f"({n_records}, {n_params}) for this regression")
        return (np.broadcast_to(lo, (n_records, n_params)),
                np.broadcast_to(hi, (n_records, n_params)))

    def contains(self, theta: np.ndarray) -> np.ndarray:
        """Whether each row of ``theta`` lies in the box (inclusive)."""
        return np.all((theta >= self.lower) & (theta <= self.upper), axis=-1)
