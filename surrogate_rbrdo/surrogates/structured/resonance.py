r"""Physics-structured surrogate of the peak amplitude: critical speed + resonance + flank.

Why: ``y(x, θ)`` (peak tool amplitude over ``[n_min, n_max]``) is a near-step where the first
forward critical speed ``n_c`` crosses ``n_max`` (lightly damped resonance, ζ ≈ 0.3 %): from
~1 µm to ~30 µm within ~20 mm of span. One stationary Kriging of ``y`` (or ``log y``) puts the
step 10–30 mm off (``docs/surrogates.md``). The FE model gives smooth ingredients per joint
point instead (:class:`~surrogate_rbrdo.spindle.evaluate.PointwiseResonance`):
``n_c``, ``A_res`` (the resonance's peak height), ``A_top`` (amplitude at ``n_max``) and ``y``.

Response definition (unchanged: ``y`` = peak over the speed range) and the structured model::

    r      = n_max / n_c                       (r ≥ 1: resonance in the range)
    ŷ      = max( Â_res · ρ_env(r̂, ζ̂),  b̂ )
    ρ(r, ζ) = r² / sqrt((1 - r²)² + (2ζr)²) · 2ζ sqrt(1 - ζ²)

``ρ`` is the single-mode unbalance response (forcing ∝ Ω²) normalised by its maximum, which
lies at ``r_pk = 1 / sqrt(1 - 2ζ²)``; ``ρ_env(r) = max_{r' ≤ r} ρ(r')`` is ``ρ`` below
``r_pk`` and 1 above (the peak over a range ending at ``r`` is the resonance itself once it is
inside). Sub-models (each a Kriging of the log of a positive quantity, fitted by
:func:`~surrogate_rbrdo.surrogates.transformed.fit_transformed`):

* ``nc``: ``log n_c`` on all training points (smooth; decides where the step lies);
* ``ares``: ``log A_res`` on the LHS points with ``r ≥ res_ares_r_min`` and the band points
  (below) with ``r ≥ 1`` (far below the range the resonance's tool-tip height is irrelevant
  and ill-defined; measured: adding the band points with ``r < 1`` doubled the test error of
  ``A_res`` at ``r ≥ 1``, 2.6 % → 7.1 % rms, because ``A_res`` there has narrow dips to a few
  µm, e.g. 3.4 µm at ``r = 0.985`` between neighbours at ~30 µm);
* ``bg``: ``log y`` on the *subcritical* points with ``r ≤ res_bg_r_max`` (the background:
  far from the step ``y`` is the smooth amplitude at ``n_max`` plus other modes);
* ``ζ̂``: effective damping ratio solved from ``A_top / A_res = ρ(r, ζ)`` at subcritical
  points with ``r ≥ res_zeta_r_min`` (the flank). Kriging of ``log ζ`` when at least
  ``res_zeta_min_points`` such points exist, otherwise their geometric mean (a constant).

Options (default off; ``docs/surrogates.md``, run ``struct3``):

* ``nc_local`` (``res_nc_local = w > 0``): a second Kriging of ``log n_c`` fitted only on the
  training points with ``|r - 1| <= w``; it replaces the global ``n̂_c`` wherever the global
  ``r̂`` lies within ``nc_local_band`` (``res_band``) of 1, where the boundary is placed;
* ``bg_only_r > 0`` (``res_bg_only_r``): ``ŷ = b̂`` wherever ``r̂ <= bg_only_r`` (the
  background Kriging is fitted to ``y`` itself there; the SDOF flank overshoots where the
  resonance tail and the background interfere destructively);
* ``ares_local`` (``res_ares_local = w > 0``, needs ``threshold_m`` = δ_lim): a second Kriging
  of ``log A_res`` on the training points with ``r >= 1`` and ``|log A_res - log δ_lim| <= w``;
  it replaces the global ``Â_res`` wherever ``|log Â_res - log δ_lim| <= ares_local_band``
  (``res_band_lim``): P_f of a design whose resonance is within ~1 % of δ_lim needs A_res to
  a fraction of a per cent there.

The θ blocks of every sub-model are cached (one
:class:`~surrogate_rbrdo.surrogates.transformed.TransformedKriging` per sub-model), so a
population × θ sample costs a few matrix products.

"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.protocols import Prediction
from surrogate_rbrdo.surrogates.structured.sdof import (
    bg_only,
    combine,
    combine_bg_only,
    local_band,
    nc_band,
    rho_env,
    select_local,
    select_nc,
    zeta_from_ratio,
)
from surrogate_rbrdo.surrogates.transformed import fit_transformed
from surrogate_rbrdo.surrogates.validation import LOOSummary, loo_cv, validation_metrics

#: Order of :class:`~surrogate_rbrdo.spindle.evaluate.PointwiseResonance` outputs.
RESONANCE_OUTPUTS = ("critical_rpm", "amp_res_m", "amp_top_m", "peak_m")


# ---------------------------------------------------------------------- the fitted model
@dataclass(eq=False)
class ResonanceSurrogate:
    """Structured peak-amplitude surrogate (see the module docstring); metres at the interface.

    A :class:`~surrogate_rbrdo.surrogates.structured.base.SurrogateModel`:
    ``response(x, theta)`` / ``__call__`` → ``(P, N)`` (the sub-models' medians combined),
    ``response_points(Z)``, ``predict(Z)`` → mean/std, ``n_train``, ``info``.

    Attributes
    ----------
    subs : dict
        ``"nc"``, ``"ares"``, ``"bg"`` (or absent) and ``"zeta"`` (or absent: constant
        ``zeta_const``) → fitted log-transform
        :class:`~surrogate_rbrdo.surrogates.transformed.TransformedKriging`.
    rows : dict
        Training-row indices (into ``Z_train``) of each sub-model.
    zeta_const : float
        ζ used when there is no ``"zeta"`` sub-model.
    n_max_rpm : float
    Z_train, Q_train : ndarray
        Joint training points and their FE outputs (``RESONANCE_OUTPUTS`` columns, SI).
    info : dict
    nc_local_band : float
        Half-width in ``r̂`` (global model) where ``"nc_local"`` replaces ``"nc"``.
    bg_only_r : float
        ``ŷ = b̂`` where ``r̂ <= bg_only_r`` (0: off).
    ares_local_center, ares_local_band : float
        ``"ares_local"`` replaces ``"ares"`` where ``|log Â_res - center| <= band``.
    """

    subs: dict[str, Any]
    rows: dict[str, np.ndarray]
    zeta_const: float
    n_max_rpm: float
    Z_train: np.ndarray
    Q_train: np.ndarray
    info: dict[str, Any] = field(default_factory=dict)
    nc_local_band: float = 0.0
    bg_only_r: float = 0.0
    ares_local_center: float = 0.0
    ares_local_band: float = 0.0

    @property
    def n_train(self) -> int:
        """Number of FE training points (one FE call each)."""
        return int(self.Z_train.shape[0])

    @property
    def theta_block_builds(self) -> int:
        return sum(s.theta_block_builds for s in self.subs.values())

    # ------------------------------------------------------------------ grid (hot path)
    def _grid(self, name: str, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        return np.exp(self.subs[name].predict_transformed(x, theta, return_std=False).mean)

    def response(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Predicted ``y`` (m) for designs ``x`` (P, 3) × θ ``(N, 2)`` → ``(P, N)``."""
        s = {k: self._grid(k, x, theta) for k in self.subs}
        return self._combine(self.nc_of(s), self._ares_of(s), s.get("zeta", self.zeta_const),
                             s.get("bg"))

    def _combine(self, nc: np.ndarray, ares: np.ndarray, zeta: Any,
                 bg: np.ndarray | None) -> np.ndarray:
        y = combine(nc, ares, zeta, bg, self.n_max_rpm)
        return combine_bg_only(y, nc, bg, self.n_max_rpm, self.bg_only_r)

    __call__ = response

    # ------------------------------------------------------------------ joint points
    def _points(self, Z: np.ndarray, return_std: bool = True) -> dict[str, Prediction]:
        Z = np.atleast_2d(np.asarray(Z, dtype=float))
        return {k: s.model.predict(Z, return_std=return_std) for k, s in self.subs.items()}

    def sub_predictions(self, Z: np.ndarray) -> dict[str, np.ndarray]:
        """Median of each ingredient at joint points (SI; ``zeta`` constant if no model)."""
        p = self._points(Z, return_std=False)
        out = {k: np.exp(v.mean) for k, v in p.items()}
        out.setdefault("zeta", np.full(np.atleast_2d(Z).shape[0], self.zeta_const))
        return out

    def nc_of(self, s: dict[str, np.ndarray]) -> np.ndarray:
        """``n̂_c`` as used by the combination, from sub-model medians ``s``."""
        return select_nc(s["nc"], s.get("nc_local"), self.n_max_rpm, self.nc_local_band)

    def _ares_of(self, s: dict[str, np.ndarray]) -> np.ndarray:
        return select_local(s["ares"], s.get("ares_local"), self.ares_local_center,
                            self.ares_local_band)

    def nc_points(self, Z: np.ndarray) -> np.ndarray:
        """``n̂_c`` (rpm) at joint points as used by the combination (local model in band)."""
        return self.nc_of(self.sub_predictions(Z))

    def response_points(self, Z: np.ndarray) -> np.ndarray:
        """``ŷ`` (m) at joint points ``Z = [x, θ]`` (n, 5): the quantity of ``response``."""
        s = self.sub_predictions(Z)
        return self._combine(self.nc_of(s), self._ares_of(s), s["zeta"], s.get("bg"))

    def predict(self, Z: np.ndarray) -> Prediction:
        """Mean and std (m) at joint points: delta method in ``log ŷ``, lognormal moments.

        ``log ŷ`` on the active branch (resonance/flank or background) is linearised in the
        sub-models' log outputs, each with its Kriging std (sub-models treated as
        independent; ζ constant has no variance). The branch switch itself (``max``) is not
        smoothed: near ``ŷ_flank = b̂`` the std is that of the larger branch.
        """
        p = self._points(Z)
        ln_nc, s_nc = p["nc"].mean, p["nc"].std
        if "nc_local" in p and self.nc_local_band > 0:
            loc = nc_band(np.exp(ln_nc), self.n_max_rpm, self.nc_local_band)
            ln_nc = np.where(loc, p["nc_local"].mean, ln_nc)
            s_nc = np.where(loc, p["nc_local"].std, s_nc)
        ln_a, s_a = p["ares"].mean, p["ares"].std
        if "ares_local" in p and self.ares_local_band > 0:
            loc = local_band(ln_a, self.ares_local_center, self.ares_local_band)
            ln_a = np.where(loc, p["ares_local"].mean, ln_a)
            s_a = np.where(loc, p["ares_local"].std, s_a)
        if "zeta" in p:
            ln_z, s_z = p["zeta"].mean, p["zeta"].std
        else:
            ln_z = np.full_like(ln_nc, np.log(self.zeta_const))
            s_z = np.zeros_like(ln_nc)
        h = 1e-5

        def log_rho(lnc: np.ndarray, lz: np.ndarray) -> np.ndarray:
            return np.log(rho_env(self.n_max_rpm / np.exp(lnc), np.exp(lz)))

        g_nc = (log_rho(ln_nc + h, ln_z) - log_rho(ln_nc - h, ln_z)) / (2 * h)
        g_z = (log_rho(ln_nc, ln_z + h) - log_rho(ln_nc, ln_z - h)) / (2 * h)
        mu = ln_a + log_rho(ln_nc, ln_z)
        s2 = s_a**2 + (g_nc * s_nc) ** 2 + (g_z * s_z) ** 2
        if "bg" in p:
            use_bg = p["bg"].mean > mu
            if self.bg_only_r > 0:
                use_bg |= bg_only(np.exp(ln_nc), self.n_max_rpm, self.bg_only_r)
            mu = np.where(use_bg, p["bg"].mean, mu)
            s2 = np.where(use_bg, p["bg"].std ** 2, s2)
        mean = np.exp(mu + 0.5 * s2)
        return Prediction(mean=mean, std=mean * np.sqrt(np.expm1(s2)))

    # ------------------------------------------------------------------ validation helpers
    def sub_loo(self) -> dict[str, Any]:
        """Closed-form LOO (:func:`~surrogate_rbrdo.surrogates.validation.loo_cv`) of every
        sub-model, in its own log units."""
        return {k: loo_cv(s.model, method="closed_form") for k, s in self.subs.items()}

    def loo_summary(self) -> LOOSummary:
        """The combined model's LOO (:meth:`loo_points`; metrics of ``log y``) and every
        sub-model's own."""
        sub = self.sub_loo()
        y_tr, y_lo = self.loo_points(sub)
        lm = validation_metrics(np.log(y_tr), np.log(y_lo))
        return LOOSummary("closed_form_combined", self.n_train, lm.r2, lm.rmse, y_tr, y_lo, sub)

    def loo_points(self, sub_loo: dict[str, Any] | None = None
                   ) -> tuple[np.ndarray, np.ndarray]:
        """Closed-form (Dubrule) LOO of the combined model at the training points.

        Each sub-model's value at training row ``i`` is its own LOO prediction when ``i`` is
        among its training rows, its ordinary prediction otherwise; combined by the same rule.
        ``sub_loo``: :meth:`sub_loo` if already computed. Returns ``(y_true, y_loo)`` in metres.
        """
        sub_loo = self.sub_loo() if sub_loo is None else sub_loo
        vals = self.sub_predictions(self.Z_train)
        for k, lo in sub_loo.items():
            vals[k] = vals[k].copy()
            vals[k][self.rows[k]] = np.exp(lo.y_loo)
        y_loo = self._combine(self.nc_of(vals), self._ares_of(vals), vals["zeta"],
                              vals.get("bg"))
        return self.Q_train[:, 3].copy(), y_loo


def _sub_model_data(Q: np.ndarray, cfg: Any, n_max_rpm: float, band: np.ndarray,
                    threshold_m: float | None
                    ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray], float, int]:
    """Training rows and targets of every sub-model, the constant ζ and the flank count."""
    nc, ares, atop, y = Q.T
    r = n_max_rpm / nc
    ares_ok = np.where(band, r >= 1.0, r >= cfg.res_ares_r_min)
    rows = {"nc": np.arange(Q.shape[0]), "ares": np.flatnonzero(ares_ok),
            "bg": np.flatnonzero(r <= cfg.res_bg_r_max)}
    targets = {"nc": nc, "ares": ares, "bg": y, "nc_local": nc, "ares_local": ares}
    if cfg.res_nc_local > 0:
        rows["nc_local"] = np.flatnonzero(np.abs(r - 1.0) <= cfg.res_nc_local)
    if cfg.res_ares_local > 0:
        if threshold_m is None or not threshold_m > 0:
            raise ValueError(f"threshold_m = {threshold_m!r} is not allowed with "
                             "res_ares_local > 0: give delta_lim in metres (> 0)")
        rows["ares_local"] = np.flatnonzero(
            (r >= 1.0) & (np.abs(np.log(ares / threshold_m)) <= cfg.res_ares_local))
    ratio = atop / ares
    zrows = np.flatnonzero((r >= cfg.res_zeta_r_min) & (r < 1.0) & (ratio < 0.9))
    zeta_pts = zeta_from_ratio(ratio[zrows], r[zrows])
    if zrows.size >= cfg.res_zeta_min_points:
        rows["zeta"], targets["zeta"] = zrows, np.zeros(Q.shape[0])
        targets["zeta"][zrows] = zeta_pts
    zeta_const = float(np.exp(np.mean(np.log(zeta_pts)))) if zrows.size else 0.003
    return rows, targets, zeta_const, int(zrows.size)


def fit_resonance_surrogate(Z: np.ndarray, Q: np.ndarray, cfg: Any, *,
                            rng: np.random.Generator, n_max_rpm: float,
                            n_design: int = 3,
                            is_band: np.ndarray | None = None,
                            threshold_m: float | None = None,
                            like: ResonanceSurrogate | None = None,
                            like_mode: str = "warm") -> ResonanceSurrogate:
    """Fit the sub-models of :class:`ResonanceSurrogate` to FE outputs ``Q`` at points ``Z``.

    Parameters
    ----------
    Z : ndarray, shape (n, d + m)
    Q : ndarray, shape (n, 4)
        ``RESONANCE_OUTPUTS`` columns (rpm, m, m, m), all finite and positive.
    cfg : ResonanceOptions
        ``surrogate``, ``n_start`` and the ``res_*`` options are used.
    rng : numpy.random.Generator
    n_max_rpm : float
        Top of the speed range.
    n_design : int
    is_band : ndarray of bool, shape (n,), optional
        Rows added near the boundary (``band_points``); default none.
    threshold_m : float, optional
        δ_lim (m); required when ``cfg.res_ares_local > 0``.
    like : ResonanceSurrogate, optional
        Start from (``like_mode = "warm"``) or keep (``"keep"``) the physical length scales of
        its sub-models (see :func:`~surrogate_rbrdo.surrogates.transformed.fit_transformed`).
    like_mode : {"warm", "keep"}
    """
    Z = np.asarray(Z, dtype=float)
    Q = np.asarray(Q, dtype=float)
    if Q.ndim != 2 or Q.shape != (Z.shape[0], 4) or not np.all(np.isfinite(Q) & (Q > 0)):
        raise ValueError(f"Q with shape {Q.shape} is not allowed: must be ({Z.shape[0]}, 4), "
                         "finite and positive")
    band = np.zeros(Z.shape[0], bool) if is_band is None else np.asarray(is_band, bool)
    if band.shape != (Z.shape[0],):
        raise ValueError(f"is_band with shape {band.shape} is not allowed: must be "
                         f"({Z.shape[0]},)")
    rows, targets, zeta_const, n_zeta = _sub_model_data(Q, cfg, n_max_rpm, band, threshold_m)
    min_rows = Z.shape[1] + 2
    subs: dict[str, Any] = {}
    children = dict(zip(("nc", "ares", "bg", "zeta"), rng.spawn(4), strict=True))
    for k in ("nc_local", "ares_local"):  # spawned after the others: their fits unchanged
        if k in rows:
            children[k] = rng.spawn(1)[0]
    for k in ("nc", "ares", "bg", "zeta", "nc_local", "ares_local"):
        if k not in rows:
            continue
        if rows[k].size < min_rows:
            if k in ("nc", "ares"):
                raise ValueError(f"{k} sub-model has {rows[k].size} training points is not "
                                 f"allowed: need >= {min_rows} (widen the DOE or res_* bounds)")
            rows.pop(k)
            continue
        subs[k] = fit_transformed(Z[rows[k]], targets[k][rows[k]], rng=children[k],
                                  surrogate=cfg.surrogate, transform="log",
                                  n_start=cfg.n_start, n_design=n_design,
                                  like=like.subs.get(k) if like is not None else None,
                                  like_mode=like_mode)
    opts = {"nc_local_band": float(cfg.res_band) if "nc_local" in subs else 0.0,
            "bg_only_r": float(cfg.res_bg_only_r),
            "ares_local_band": float(cfg.res_band_lim) if "ares_local" in subs else 0.0}
    info = {
        "structure": "resonance", "n_train": int(Z.shape[0]),
        "fit_time_s": float(sum(s.info["fit_time_s"] for s in subs.values())),
        "sub_models": {k: {"n_train": int(rows[k].size),
                           "hyperparameters": s.info["hyperparameters"]}
                       for k, s in subs.items()},
        "zeta_const": zeta_const, "zeta_points": n_zeta, "n_band": int(band.sum()),
        **opts,
        "n_max_rpm": float(n_max_rpm), "surrogate": cfg.surrogate, "transform": "log",
        "hyperparameters": {k: s.info["hyperparameters"] for k, s in subs.items()},
    }
    return ResonanceSurrogate(subs=subs, rows={k: rows[k] for k in subs},
                              zeta_const=zeta_const, n_max_rpm=float(n_max_rpm),
                              Z_train=Z, Q_train=Q, info=info, **opts,
                              ares_local_center=float(np.log(threshold_m))
                              if "ares_local" in subs else 0.0)


__all__ = ["RESONANCE_OUTPUTS", "ResonanceSurrogate", "fit_resonance_surrogate"]
