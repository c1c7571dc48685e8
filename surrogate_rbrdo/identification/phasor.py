"""The eight bearing coefficients of each record from its 1× phasors (closed form, batched).

At one speed each bearing direction gives one complex equation ``r = (k + iΩc) x`` for two
real unknowns, so the estimate is exact: ``k = Re(r/x)``, ``c = Im(r/x)/Ω``. A thousand records
cost a few array operations (:func:`identify_phasors`).

The covariance comes from the phasor noise by linear propagation: with circular complex noise
on each measured phasor whose real and imaginary parts have standard deviation ``s_m`` each (what
synchronous demodulation of white noise gives: ``s = σ √(2/N)``, the convention of
``rig.phasors.phasor_noise_sd``), ``dZ_j = a_j · dq``, ``a_j = (L_r,j − Z_j L_x,j) / x_j``, and
with ``C = A diag(2 s²) Aᴴ`` (``E|dq_m|² = 2 s_m²``):
``cov(Re Z_i, Re Z_j) = cov(Im Z_i, Im Z_j) = ½ Re C_ij``, ``cov(Re Z_i, Im Z_j) = −½ Im C_ij``.
It is first order in the noise (the ratio ``r/x`` is biased at order ``s²/|x|²``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.identification.condensation import CondensedReactions, coefficient_names
from surrogate_rbrdo.identification.regression import PAPER_C_FACTORS, PAPER_K_FACTORS
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel

#: a journal displacement below this fraction of the record's largest is "not excited"
UNEXCITED_RATIO = 1e-9


def catalog_coefficients(model: SpindleModel, speeds_rpm: np.ndarray) -> np.ndarray:
    """The model's nominal diagonal bearing coefficients ``(S, 8)`` (names
    :func:`~surrogate_rbrdo.identification.condensation.coefficient_names`): the "catalogue"
    ``k`` and the initial damping ``c`` the paper's box is built around.

    >>> from surrogate_rbrdo.spindle import reference_spindle
    >>> sp = reference_spindle()
    >>> cat = catalog_coefficients(sp.model(sp.baseline), [1000.0])
    >>> print(f"{cat[0, 0]:.4g} {cat[0, 2] / cat[0, 0]:.3g}")     # k_yy (Table 3: 3.183e8), c/k
    3.188e+08 4e-06
    """
    sp = np.atleast_1d(np.asarray(speeds_rpm, dtype=float))
    K, C = model.bearing_coefficients(sp[None, :] * RPM)
    K, C = K[0], C[0]                                            # (S, nb, 2, 2)
    d = np.arange(2)
    out = np.concatenate([K[..., d, d], C[..., d, d]], axis=-1)   # (S, nb, 4)
    return out.reshape(sp.size, -1)


@dataclass(frozen=True, eq=False)
class PhasorIdentification:
    """Identified coefficients of ``N`` records.

    Attributes
    ----------
    names : tuple of str
        ``<bearing>_<k|c>_<yy|zz>``.
    speed_rpm : ndarray (N,)
    estimate : ndarray (N, 8)
        SI (N/m, N s/m); projected onto the box if one was given.
    raw : ndarray (N, 8)
        Before projection.
    covariance : ndarray (N, 8, 8) or None
        First-order covariance from ``phasor_sd``.
    at_bound, unexcited : ndarray (N, 8) bool
        Flags: outside the box (and projected onto it); a journal not moving in a direction.
    """

    names: tuple[str, ...]
    speed_rpm: np.ndarray
    estimate: np.ndarray
    raw: np.ndarray
    covariance: np.ndarray | None
    at_bound: np.ndarray
    unexcited: np.ndarray

    @property
    def ok(self) -> np.ndarray:
        return ~(self.at_bound.any(axis=1) | self.unexcited.any(axis=1))

    @property
    def std(self) -> np.ndarray | None:
        if self.covariance is None:
            return None
        return np.sqrt(np.diagonal(self.covariance, axis1=1, axis2=2))

    def flags(self, i: int) -> list[str]:
        """Plain-language flags of record ``i``."""
        out = [f"{self.names[j]}: journal not excited in this direction"
               for j in np.flatnonzero(self.unexcited[i])]
        out += [f"{self.names[j]} = {self.raw[i, j]:.6g} outside the box (set to the bound)"
                for j in np.flatnonzero(self.at_bound[i])]
        return out

    def raise_if_flagged(self) -> PhasorIdentification:
        bad = np.flatnonzero(~self.ok)
        if bad.size:
            raise ModelError(f"{bad.size} of {self.ok.size} records flagged; record "
                             f"{int(bad[0])}: {'; '.join(self.flags(int(bad[0])))}")
        return self


def _bearing_major(Zk: np.ndarray, Zc: np.ndarray) -> np.ndarray:
    """``(N, 2 nb)`` k and c (x, y per bearing) → ``(N, 8)`` in ``coefficient_names`` order."""
    N, m = Zk.shape
    return np.stack([Zk.reshape(N, m // 2, 2), Zc.reshape(N, m // 2, 2)], axis=2).reshape(N, -1)


def _covariance(cr: CondensedReactions, si, x, Z, std, omega) -> np.ndarray:
    A = (cr.Lr[si] - Z[:, :, None] * cr.Lx[si]) / x[:, :, None]     # (N, m, p)
    C = np.einsum("nip,np,njp->nij", A, 2.0 * std**2, A.conj())
    m = Z.shape[1]
    w = omega[:, None, None]
    cov = np.empty((Z.shape[0], 2, m, 2, m))                         # (k|c, i, k|c, j)
    cov[:, 0, :, 0] = 0.5 * C.real
    cov[:, 1, :, 1] = 0.5 * C.real / w**2
    cov[:, 0, :, 1] = -0.5 * C.imag / w
    cov[:, 1, :, 0] = np.swapaxes(cov[:, 0, :, 1], 1, 2)
    # reorder (kind, bearing, dir) → (bearing, kind, dir)
    nb = m // 2
    cov = cov.reshape(-1, 2, nb, 2, 2, nb, 2).transpose(0, 2, 1, 3, 5, 4, 6)
    return cov.reshape(-1, 2 * m, 2 * m)


def identify_phasors(cr: CondensedReactions, phasors: np.ndarray, speeds_rpm: np.ndarray, *,
                     phasor_sd: np.ndarray | float | None = None,
                     catalog: np.ndarray | None = None) -> PhasorIdentification:
    """Identify the eight diagonal bearing coefficients of every record.

    Parameters
    ----------
    cr : CondensedReactions
        The known rotor condensed at (at least) the records' speeds.
    phasors : array (N, 2 np) complex
        Measured 1× amplitudes ``[x, y]`` per probe node (m), keyphasor-referenced.
    speeds_rpm : array (N,)
    phasor_sd : float or array (N, 2 np), optional
        Standard deviation of the real (and of the imaginary) part of each phasor's noise (m),
        as ``rig.phasors.phasor_noise_sd`` gives it: the covariance is then returned.
    catalog : array (N, 8) or (8,), optional
        ``k_catalog`` and ``c_init`` per coefficient (:func:`catalog_coefficients`): estimates
        outside the paper's box are set to the bound and flagged.
    """
    sp = np.atleast_1d(np.asarray(speeds_rpm, dtype=float))
    x, r = cr.reactions(phasors, sp)
    si = cr.speed_index(sp)
    omega = sp * RPM
    scale = np.max(np.abs(x), axis=1, keepdims=True)
    unexc = np.abs(x) <= UNEXCITED_RATIO * np.where(scale > 0, scale, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        Z = np.where(unexc, np.nan, r / np.where(unexc, 1.0, x))
    raw = _bearing_major(Z.real, Z.imag / omega[:, None])
    unexcited = _bearing_major(unexc, unexc)
    cov = None
    if phasor_sd is not None:
        std = np.broadcast_to(np.asarray(phasor_sd, dtype=float), x.shape[:1] + (
            cr.Lx.shape[-1],))
        if np.any(~np.isfinite(std) | (std < 0)):
            raise ValueError("phasor_sd is not allowed: must be finite and >= 0 (m)")
        with np.errstate(invalid="ignore"):
            cov = _covariance(cr, si, np.where(unexc, 1.0, x), np.nan_to_num(Z), std, omega)
        cov[unexcited.any(axis=1)] = np.nan
    est = raw.copy()
    at_bound = np.zeros_like(unexcited)
    if catalog is not None:
        cat = np.broadcast_to(np.asarray(catalog, dtype=float), raw.shape)
        is_k = np.array(["_k_" in n for n in cr.names])
        lo = np.where(is_k, PAPER_K_FACTORS[0], PAPER_C_FACTORS[0]) * cat
        hi = np.where(is_k, PAPER_K_FACTORS[1], PAPER_C_FACTORS[1]) * cat
        with np.errstate(invalid="ignore"):
            at_bound = ~unexcited & ((raw < lo) | (raw > hi))
        est = np.where(unexcited, np.nan, np.clip(raw, lo, hi))
    return PhasorIdentification(names=coefficient_names(cr.bearings), speed_rpm=sp,
                                estimate=est, raw=raw, covariance=cov, at_bound=at_bound,
                                unexcited=unexcited)


__all__ = ["PhasorIdentification", "catalog_coefficients", "identify_phasors"]
