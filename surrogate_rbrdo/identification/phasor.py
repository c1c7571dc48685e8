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

#: without a noise level: a journal displacement below this fraction of the record's largest
#: is "not excited"
UNEXCITED_RATIO = 1e-9
#: with a noise level: a journal displacement below this many noise standard deviations (per
#: component) is "not excited" — the ratio r/x is then dominated by noise (and biased)
MIN_SNR = 5.0
#: a speed whose interior condition number is this many times the static one is "near a pole"
POLE_RATIO = 30.0


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


def effective_coefficients(model: SpindleModel, speeds_rpm: np.ndarray,
                           theta: np.ndarray | None = None) -> np.ndarray:
    """What the diagonal identification measures, ``(S, 8)`` (or ``(B, S, 8)`` for ``theta``
    ``(B, m)``): ``k = Re Z_dd``, ``c = Im Z_dd / Ω`` of the impedance each bearing puts on its
    journal (:meth:`SpindleModel.bearing_impedance`: a housing stage in series is condensed in,
    so this is the bearing *and* its housing, as the rotor feels them).

    Equal to :func:`catalog_coefficients` without a housing stage (θ = 1).

    >>> from surrogate_rbrdo.spindle import reference_spindle
    >>> sp = reference_spindle()
    >>> m = sp.model(sp.baseline)
    >>> bool(np.allclose(effective_coefficients(m, [5000.0]), catalog_coefficients(m, [5000.0])))
    True
    """
    sp = np.atleast_1d(np.asarray(speeds_rpm, dtype=float))
    th = model.check_theta(theta, None if theta is None else np.shape(theta)[0])
    w = np.broadcast_to(sp[None, :] * RPM, (th.shape[0], sp.size))
    Z = model.bearing_impedance(w, th)                          # (B, S, nb, 2, 2)
    d = np.arange(2)
    Zd = Z[..., d, d]                                            # (B, S, nb, 2)
    out = np.concatenate([Zd.real, Zd.imag / w[..., None, None]], axis=-1)
    out = out.reshape(th.shape[0], sp.size, -1)
    return out[0] if theta is None else out


@dataclass(frozen=True, eq=False)
class PhasorIdentification:
    """Identified coefficients of ``N`` records, never clipped, with their quality flags.

    Attributes
    ----------
    names : tuple of str
        ``<bearing>_<k|c>_<yy|zz>``.
    speed_rpm : ndarray (N,)
    estimate : ndarray (N, 8)
        SI (N/m, N s/m), as identified (NaN where a journal is not excited).
    covariance : ndarray (N, 8, 8) or None
        First-order covariance from ``phasor_sd``.
    outside_box : ndarray (N, 8) bool
        Outside the paper's box around the catalogue values (flagged, not clipped).
    unexcited : ndarray (N, 8) bool
        The journal's motion in that direction is below ``MIN_SNR`` times its noise (or
        exactly zero when no noise is given): the coefficient is not identifiable.
    imprecise : ndarray (N, 8) bool
        Relative standard error above ``max_rel_se``.
    near_pole : ndarray (N,) bool
        The speed is near a pole of the condensed rotor
        (:attr:`CondensedReactions.pole_ratio` above ``POLE_RATIO``).
    """

    names: tuple[str, ...]
    speed_rpm: np.ndarray
    estimate: np.ndarray
    covariance: np.ndarray | None
    outside_box: np.ndarray
    unexcited: np.ndarray
    imprecise: np.ndarray
    near_pole: np.ndarray

    @property
    def ok(self) -> np.ndarray:
        """Records with no flag on any coefficient."""
        return self.usable(range(len(self.names))) & ~self.outside_box.any(axis=1)

    def usable(self, columns) -> np.ndarray:
        """Records whose ``columns`` are identifiable and precise and not near a pole (being
        outside the box does not exclude: selecting on the value would cut the tails)."""
        cols = list(columns)
        return ~(self.unexcited[:, cols].any(axis=1) | self.imprecise[:, cols].any(axis=1)
                 | self.near_pole)

    @property
    def std(self) -> np.ndarray | None:
        if self.covariance is None:
            return None
        return np.sqrt(np.diagonal(self.covariance, axis1=1, axis2=2))

    def flag_names(self) -> np.ndarray:
        """Per record and coefficient, ``""`` or the ``;``-joined flags, ``(N, 8)`` str."""
        out = np.full(self.estimate.shape, "", dtype=object)
        for name, arr in (("unexcited", self.unexcited), ("imprecise", self.imprecise),
                          ("outside_box", self.outside_box),
                          ("near_pole", np.broadcast_to(self.near_pole[:, None],
                                                        self.estimate.shape))):
            out = np.where(arr, np.where(out == "", name, out + ";" + name), out)
        return out.astype(str)

    def flags(self, i: int) -> list[str]:
        """Plain-language flags of record ``i``."""
        out = [f"{self.names[j]}: journal motion below {MIN_SNR:g} x its noise (not excited)"
               for j in np.flatnonzero(self.unexcited[i])]
        out += [f"{self.names[j]}: relative standard error above the limit"
                for j in np.flatnonzero(self.imprecise[i] & ~self.unexcited[i])]
        out += [f"{self.names[j]} = {self.estimate[i, j]:.6g} outside the box"
                for j in np.flatnonzero(self.outside_box[i])]
        if self.near_pole[i]:
            out.append(f"{self.speed_rpm[i]:.6g} rpm is near a pole of the condensed rotor")
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


def coefficient_changes(dZ: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """Complex impedance changes ``dZ (N, ..., m)`` (x, y per bearing) → real changes of the
    coefficients ``(N, ..., 2m)`` in :func:`coefficient_names` order (``dk = Re dZ``,
    ``dc = Im dZ / Ω``)."""
    w = np.asarray(omega, dtype=float).reshape((-1,) + (1,) * (dZ.ndim - 1))
    nb = dZ.shape[-1] // 2
    k = dZ.real.reshape(*dZ.shape[:-1], nb, 2)
    c = (dZ.imag / w).reshape(*dZ.shape[:-1], nb, 2)
    return np.stack([k, c], axis=-2).reshape(*dZ.shape[:-1], 2 * dZ.shape[-1])


def impedance_sensitivity(cr: CondensedReactions, si, x, Z) -> np.ndarray:
    """``∂Z_j/∂q_p = (L_r − Z L_x)_jp / x_j`` of every record ``(N, m, p)`` (``Z = r/x`` is
    holomorphic in the phasors)."""
    return (cr.Lr[si] - Z[:, :, None] * cr.Lx[si]) / x[:, :, None]


def _covariance(cr: CondensedReactions, si, x, Z, std, omega, perturbations=None
                ) -> np.ndarray:
    A = impedance_sensitivity(cr, si, x, Z)                          # (N, m, p)
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
    cov = cov.reshape(-1, 2 * m, 2 * m)
    if perturbations is not None:
        g = coefficient_changes(np.einsum("nmp,nrp->nrm", A, perturbations), omega)
        cov = cov + np.einsum("nri,nrj->nij", g, g)
    return cov


def identify_phasors(cr: CondensedReactions, phasors: np.ndarray, speeds_rpm: np.ndarray, *,
                     phasor_sd: np.ndarray | float | None = None,
                     catalog: np.ndarray | None = None,
                     max_rel_se: float = np.inf,
                     perturbations: np.ndarray | None = None) -> PhasorIdentification:
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
        as ``rig.phasors.phasor_noise_sd`` gives it: the covariance is then returned and a
        journal whose motion is below ``MIN_SNR`` times its noise is flagged ``unexcited``.
    catalog : array (N, 8) or (8,), optional
        ``k_catalog`` and ``c_init`` per coefficient (:func:`catalog_coefficients`): estimates
        outside the paper's box are flagged ``outside_box`` (and kept as identified).
    max_rel_se : float
        Coefficients whose relative standard error exceeds it are flagged ``imprecise``.
    perturbations : array (N, r, p) complex, optional
        The phasors' change for one standard deviation of each of ``r`` independent real
        errors besides the noise (e.g. each record's keyphasor phase, ``−i q σ_Δ``): added to
        the covariance at first order.
    """
    sp = np.atleast_1d(np.asarray(speeds_rpm, dtype=float))
    x, r = cr.reactions(phasors, sp)
    si = cr.speed_index(sp)
    omega = sp * RPM
    if phasor_sd is None:
        scale = np.max(np.abs(x), axis=1, keepdims=True)
        unexc = np.abs(x) <= UNEXCITED_RATIO * np.where(scale > 0, scale, 1.0)
        std = None
    else:
        std = np.broadcast_to(np.asarray(phasor_sd, dtype=float), x.shape[:1] + (
            cr.Lx.shape[-1],))
        if np.any(~np.isfinite(std) | (std < 0)):
            raise ValueError("phasor_sd is not allowed: must be finite and >= 0 (m)")
        # per-component noise of x_b = Lx q: E|dx|² = Σ |Lx|² 2 s², per component half of it
        sx = np.sqrt(np.einsum("nij,nj->ni", np.abs(cr.Lx[si]) ** 2, std**2))
        unexc = (np.abs(x) <= MIN_SNR * sx) | (np.abs(x) == 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        Z = np.where(unexc, np.nan, r / np.where(unexc, 1.0, x))
    est = _bearing_major(Z.real, Z.imag / omega[:, None])
    unexcited = _bearing_major(unexc, unexc)
    cov = None
    imprecise = np.zeros_like(unexcited)
    if std is not None:
        with np.errstate(invalid="ignore"):
            cov = _covariance(cr, si, np.where(unexc, 1.0, x), np.nan_to_num(Z), std, omega,
                              None if perturbations is None else np.asarray(perturbations))
        cov[unexcited.any(axis=1)] = np.nan
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = np.sqrt(np.diagonal(cov, axis1=1, axis2=2)) / np.abs(est)
        imprecise = ~unexcited & ~(rel <= max_rel_se)
    outside = np.zeros_like(unexcited)
    if catalog is not None:
        cat = np.broadcast_to(np.asarray(catalog, dtype=float), est.shape)
        is_k = np.array(["_k_" in n for n in cr.names])
        lo = np.where(is_k, PAPER_K_FACTORS[0], PAPER_C_FACTORS[0]) * cat
        hi = np.where(is_k, PAPER_K_FACTORS[1], PAPER_C_FACTORS[1]) * cat
        with np.errstate(invalid="ignore"):
            outside = ~unexcited & ((est < lo) | (est > hi))
    return PhasorIdentification(names=coefficient_names(cr.bearings), speed_rpm=sp,
                                estimate=est, covariance=cov, outside_box=outside,
                                unexcited=unexcited, imprecise=imprecise,
                                near_pole=cr.pole_ratio[si] > POLE_RATIO)


__all__ = ["MIN_SNR", "POLE_RATIO", "PhasorIdentification", "catalog_coefficients",
           "coefficient_changes", "effective_coefficients", "identify_phasors",
           "impedance_sensitivity"]
