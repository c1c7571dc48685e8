"""From identified vectors to the uncertainty model the study uses (``uncertainty.json``).

:func:`~surrogate_rbrdo.identification.scatter.fit_uncertainty` takes the identified
coefficients of ``N`` records (``values (N, d)``), their speeds and runs, and separates

* the deterministic speed trend ``k̄_j(Ω)`` of each coefficient (:func:`fit_trend`, a stated law
  with its parameter covariance — cluster-robust over runs, jointly for all coefficients — and
  its lack-of-fit test),
* the scatter around it, as *factors* ``e_j = value_j / k̄_j(Ω)`` (multiplicative, like the
  study's θ): the physical covariance pooled over speeds with the identification error taken
  out (:func:`~surrogate_rbrdo.identification.physical.physical_scatter`; speed dependent if
  the data say so), and the identification covariance at each speed,
* for comparison with the paper's Table 4, the MVN of the pooled raw values (trend included),
* normality tests, and the measured split when the truth is known (the virtual rig).

The study's θ are stiffness factors per bearing (``study="isotropic"``: the mean of ``k_yy`` and
``k_zz`` of each bearing; ``study="stiffness"``: the four ``k`` separately), ``θ = W e``. At a
speed ``Ω``, relative to a model's nominal stiffness ``k_ref(Ω)`` of those bearings,
:meth:`IdentifiedUncertainty.random_vector` is the MVN of
``θ_b = Σ_j W_bj k̄_j(Ω) e_j / k_ref,b(Ω)``: the identified trend relative to the model, times
the scatter at that speed — physical only (``scatter="physical"``, the default when the
identification error is known) or physical plus the identification error *at that speed*
(``"total"``) — plus the trend's own uncertainty.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import stats

from surrogate_rbrdo.core.validate import check_choice
from surrogate_rbrdo.identification.jsonio import arrayed, listed
from surrogate_rbrdo.identification.physical import ScatterFit
from surrogate_rbrdo.identification.trend import TrendFit
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel
from surrogate_rbrdo.uncertainty.mvn import MultivariateNormal

FORMAT = "surrogate_rbrdo.identified_uncertainty"
VERSION = 2
STUDY_FORMS = ("isotropic", "stiffness")
SCATTERS = ("physical", "total")


def study_weights(coefficients: Sequence[str], study: str = "isotropic"
                  ) -> tuple[tuple[str, ...], np.ndarray]:
    """Names of the study's θ and the weights ``W (m, d)`` with ``θ = W e``.

    >>> names, W = study_weights(("front_k_yy", "front_k_zz", "front_c_yy", "front_c_zz"))
    >>> names, W.tolist()
    (('front',), [[0.5, 0.5, 0.0, 0.0]])
    """
    check_choice("study", study, STUDY_FORMS)
    coefficients = tuple(coefficients)
    ks = [c for c in coefficients if "_k_" in c]
    if not ks:
        raise ValueError(f"coefficients = {list(coefficients)} has no stiffness "
                         "'<bearing>_k_<dir>'")
    if study == "stiffness":
        names = tuple(ks)
        groups = [[c] for c in ks]
    else:
        names = tuple(dict.fromkeys(c.split("_k_")[0] for c in ks))
        groups = [[c for c in ks if c.split("_k_")[0] == b] for b in names]
    W = np.zeros((len(names), len(coefficients)))
    for i, g in enumerate(groups):
        for c in g:
            W[i, coefficients.index(c)] = 1.0 / len(g)
    return names, W


def model_reference(model: SpindleModel, speed_rpm, names: Sequence[str], *,
                    effective: bool = False) -> np.ndarray:
    """The model's nominal stiffness (N/m, θ = 1) of each study variable: the mean diagonal
    stiffness of a bearing (``"front"``) or one coefficient (``"front_k_yy"``); ``(m,)`` at one
    speed, ``(S, m)`` at several.

    ``effective``: the real part of the impedance the rotor feels (a housing stage in series
    condensed in; :func:`~surrogate_rbrdo.identification.phasor.effective_coefficients`) instead
    of the bearing's own stiffness, which is what θ multiplies.

    >>> from surrogate_rbrdo.spindle import reference_spindle
    >>> sp = reference_spindle()
    >>> model_reference(sp.model(sp.baseline), [1000.0, 24000.0], ("front",)).round(-5).tolist()
    [[318800000.0], [258500000.0]]
    """
    s = np.atleast_1d(np.asarray(speed_rpm, dtype=float))
    w = s[None, :] * RPM
    K = (model.bearing_impedance(w).real if effective else model.bearing_coefficients(w)[0])[0]
    bearings = [b.name for b in model.geometry.bearings]
    out = []
    for n in names:
        b, _, d = n.partition("_k_")
        if b not in bearings:
            raise ValueError(f"names: {n!r} is not a bearing of the model {bearings}")
        diag = np.diagonal(K[:, bearings.index(b)], axis1=-2, axis2=-1)          # (S, 2)
        out.append(diag.mean(axis=-1) if not d else diag[:, {"yy": 0, "zz": 1}[d]])
    res = np.stack(out, axis=-1)
    return res[0] if np.ndim(speed_rpm) == 0 else res


@dataclass(frozen=True, eq=False)
class IdentifiedUncertainty:
    """The identified uncertainty model (module docstring); build it with
    :func:`~surrogate_rbrdo.identification.scatter.fit_uncertainty`, store it with
    :func:`save_uncertainty`.

    ``trend_cov`` is the joint covariance of all trends' parameters (concatenated in
    ``coefficients`` order; cluster-robust over runs) or ``None`` (then each trend's own
    ``param_cov``, independent). ``reference`` holds the nominal stiffness ``(S, m)`` of the
    model the records were identified against at ``reference_speeds_rpm``: θ defaults to factors
    on it. ``systematic`` ``(S, n_ξ, d)`` is the relative change of each trend at
    ``systematic_speeds_rpm`` for one standard deviation of each systematic source
    (``systematic_sources``; :mod:`.systematic`): part of the trend's uncertainty.
    ``summary_speed_rpm`` is the speed of the top-level ``mean``/``cov`` of the JSON.
    """

    coefficients: tuple[str, ...]
    trends: tuple[TrendFit, ...]
    factor_mean: np.ndarray
    scatter_fit: ScatterFit
    names: tuple[str, ...]
    weights: np.ndarray
    scatter: str = "physical"
    trend_cov: np.ndarray | None = None
    total_cov: np.ndarray | None = None
    pooled_mean: np.ndarray | None = None
    pooled_cov: np.ndarray | None = None
    reference_speeds_rpm: np.ndarray | None = None
    reference: np.ndarray | None = None
    systematic_speeds_rpm: np.ndarray | None = None
    systematic: np.ndarray | None = None
    systematic_sources: tuple[str, ...] = ()
    summary_speed_rpm: float | None = None
    tests: dict = field(default_factory=dict)
    variance_split: dict = field(default_factory=dict)
    n_records: int = 0
    speeds_rpm: np.ndarray | None = None
    provenance: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        check_choice("scatter", self.scatter, SCATTERS)
        if self.scatter == "physical" and not self.scatter_fit.separable:
            raise ValueError("scatter = 'physical' is not allowed: the identification error is "
                             "unknown (fit with per_record_cov); use 'total'")

    def factor_cov_at(self, speed_rpm: float) -> np.ndarray:
        """Covariance of the factors ``e`` the study gets at a speed (``scatter``)."""
        C = self.scatter_fit.physical_at(speed_rpm)
        if self.scatter == "total" and self.scatter_fit.separable:
            C = C + self.scatter_fit.identification_at(speed_rpm)
        return C

    def trend(self, speed_rpm) -> np.ndarray:
        """Trend ``k̄_j`` of every coefficient at the speeds, ``(..., d)``."""
        return np.stack([t.predict(speed_rpm) for t in self.trends], axis=-1)

    @property
    def speed_range_rpm(self) -> tuple[float, float]:
        """The identified speed range: nothing is extrapolated beyond it."""
        sp = self.scatter_fit.speeds_rpm
        return float(sp[0]), float(sp[-1])

    def _check_speed(self, speed_rpm: float) -> float:
        sp = float(speed_rpm)
        lo, hi = self.speed_range_rpm
        if not (np.isfinite(sp) and lo * (1 - 1e-9) <= sp <= hi * (1 + 1e-9)):
            raise ValueError(f"speed_rpm = {speed_rpm!r} is not allowed: the model was "
                             f"identified in [{lo:g}, {hi:g}] rpm (no extrapolation)")
        return sp

    def trend_cov_at(self, speed_rpm: float, *, systematic: bool = True) -> np.ndarray:
        """Covariance ``(d, d)`` of the trends' values at a speed: their statistical estimation
        error (parameter covariance) plus, with ``systematic``, the systematic sources."""
        sp = float(speed_rpm)
        Js = [t.jacobian(sp)[0] for t in self.trends]
        if self.trend_cov is None:
            C = np.diag([J @ t.param_cov @ J for J, t in zip(Js, self.trends, strict=True)])
        else:
            sizes = [J.size for J in Js]
            B = np.zeros((len(Js), sum(sizes)))
            for j, (J, a) in enumerate(zip(Js, np.cumsum([0] + sizes[:-1]), strict=True)):
                B[j, a:a + J.size] = J
            C = B @ self.trend_cov @ B.T
        if systematic and self.systematic is not None and self.systematic.shape[1]:
            G = _interp_rows(self.systematic_speeds_rpm, self.systematic, sp)   # (n_ξ, d)
            t = self.trend(sp)
            C = C + (G.T @ G) * np.outer(t, t)
        return C

    def trend_interval(self, speed_rpm: float, level: float = 0.95
                       ) -> tuple[np.ndarray, np.ndarray]:
        """Interval of each trend at a speed with its statistical and systematic uncertainty:
        ``t`` quantile with Welch–Satterthwaite degrees of freedom (the systematic part has
        infinitely many)."""
        sp = self._check_speed(speed_rpm)
        v_stat = np.diag(self.trend_cov_at(sp, systematic=False))
        v_all = np.diag(self.trend_cov_at(sp))
        dof = np.array([t.dof for t in self.trends])
        with np.errstate(divide="ignore", invalid="ignore"):
            nu = np.where(np.isfinite(dof) & (v_stat > 0), v_all**2 / (v_stat**2 / dof), np.inf)
        q = np.where(np.isfinite(nu), stats.t.ppf(0.5 + level / 2, np.minimum(nu, 1e9)),
                     stats.norm.ppf(0.5 + level / 2))
        m = self.trend(sp)
        return m - q * np.sqrt(v_all), m + q * np.sqrt(v_all)

    def reference_at(self, speed_rpm: float) -> np.ndarray:
        """The stored nominal stiffness of the θ variables at a speed (linear between the stored
        speeds; ``ValueError`` outside them or when none is stored)."""
        if self.reference is None:
            raise ValueError("this uncertainty model stores no reference stiffness: give "
                             "reference= (model_reference(model, speed, names))")
        sp, ref = self.reference_speeds_rpm, self.reference
        if not sp[0] * (1 - 1e-9) <= speed_rpm <= sp[-1] * (1 + 1e-9):
            raise ValueError(f"speed_rpm = {speed_rpm:g} is not allowed: the reference is "
                             f"stored for [{sp[0]:g}, {sp[-1]:g}] rpm (give reference=)")
        return np.array([np.interp(speed_rpm, sp, ref[:, b]) for b in range(ref.shape[1])])

    def random_vector(self, speed_rpm: float, *, reference=None,
                      trend_uncertainty: bool = True) -> MultivariateNormal:
        """The study's θ at one speed as a :class:`MultivariateNormal`.

        Parameters
        ----------
        speed_rpm : float
        reference : array (m,) or "stored" or None
            Nominal stiffness of each θ variable in the study's model at this speed
            (:func:`model_reference`): θ is then a factor on it; ``"stored"``: the reference
            stored with the model; ``None``: θ in N/m.
        trend_uncertainty : bool
            Add the trends' estimation covariance.
        """
        sp = self._check_speed(speed_rpm)
        m = len(self.names)
        if isinstance(reference, str):
            check_choice("reference", reference, ("stored",))
            reference = self.reference_at(sp)
        ref = np.ones(m) if reference is None else np.asarray(reference, dtype=float)
        if ref.shape != (m,) or np.any(~np.isfinite(ref) | (ref <= 0)):
            raise ValueError(f"reference = {reference!r} is not allowed: need {m} finite values "
                             f"> 0 (N/m) for {list(self.names)}")
        t = self.trend(sp)
        D = self.weights * t[None, :] / ref[:, None]
        mean = D @ self.factor_mean
        cov = D @ self.factor_cov_at(sp) @ D.T
        if trend_uncertainty:
            Dt = self.weights * self.factor_mean[None, :] / ref[:, None]
            cov = cov + Dt @ self.trend_cov_at(sp) @ Dt.T
        return MultivariateNormal(mean, 0.5 * (cov + cov.T))

    def by_speed(self, speeds_rpm=None) -> dict:
        """θ (relative to the stored reference if any) at each speed: ``speeds_rpm``, ``mean``
        ``(S, m)``, ``cov`` ``(S, m, m)``; default the campaign's speeds."""
        sp = np.asarray(self.scatter_fit.speeds_rpm if speeds_rpm is None else speeds_rpm, float)
        ref = "stored" if self.reference is not None else None
        rv = [self.random_vector(float(s), reference=ref) for s in sp]
        return {"speeds_rpm": sp.tolist(), "relative_to": "reference" if ref else "N/m",
                "mean": [r.mean.tolist() for r in rv], "cov": [r.cov.tolist() for r in rv]}

    def to_dict(self) -> dict:
        s_sum = self.summary_speed_rpm if self.summary_speed_rpm is not None \
            else float(self.scatter_fit.speeds_rpm[-1])
        top = self.random_vector(s_sum, reference="stored" if self.reference is not None
                                 else None)
        return {"format": FORMAT, "version": VERSION, "names": list(self.names),
                "speed_rpm": s_sum, "mean": top.mean.tolist(), "cov": top.cov.tolist(),
                "relative_to": "reference" if self.reference is not None else "N/m",
                "by_speed": self.by_speed(),
                "coefficients": list(self.coefficients), "weights": self.weights.tolist(),
                "scatter": self.scatter,
                "factors": {"mean": self.factor_mean.tolist(), "cov_total": listed(self.total_cov),
                            "scatter_fit": self.scatter_fit.to_dict()},
                "trend": {c: t.to_dict() for c, t in zip(self.coefficients, self.trends,
                                                          strict=True)},
                "trend_cov": listed(self.trend_cov),
                "systematic": None if self.systematic is None else {
                    "speeds_rpm": listed(self.systematic_speeds_rpm),
                    "sources": list(self.systematic_sources),
                    "relative_change": listed(self.systematic)},
                "reference": None if self.reference is None else {
                    "speeds_rpm": listed(self.reference_speeds_rpm), "stiffness_N_per_m":
                        listed(self.reference)},
                "pooled": {"mean": listed(self.pooled_mean), "cov": listed(self.pooled_cov)},
                "tests": self.tests, "variance_split": self.variance_split,
                "n_records": self.n_records, "speeds_rpm": listed(self.speeds_rpm),
                "provenance": self.provenance}

    @classmethod
    def from_dict(cls, d: dict, *, source: str = "uncertainty") -> IdentifiedUncertainty:
        """Inverse of :meth:`to_dict`; a wrong format names the source and the field."""
        if d.get("format") != FORMAT or d.get("version") != VERSION:
            raise ValueError(f"{source}: format = {d.get('format')!r}, version = "
                             f"{d.get('version')!r}: expected {FORMAT!r} version {VERSION}")
        try:
            coeffs = tuple(d["coefficients"])
            f, ref, sy = d["factors"], d.get("reference") or {}, d.get("systematic") or {}
            return cls(coefficients=coeffs,
                       trends=tuple(TrendFit.from_dict(d["trend"][c]) for c in coeffs),
                       factor_mean=np.asarray(f["mean"], float),
                       scatter_fit=ScatterFit.from_dict(f["scatter_fit"]),
                       names=tuple(d["names"]), weights=np.asarray(d["weights"], float),
                       scatter=d["scatter"], trend_cov=arrayed(d.get("trend_cov")),
                       total_cov=arrayed(f.get("cov_total")),
                       pooled_mean=arrayed(d["pooled"]["mean"]),
                       pooled_cov=arrayed(d["pooled"]["cov"]),
                       reference_speeds_rpm=arrayed(ref.get("speeds_rpm")),
                       reference=arrayed(ref.get("stiffness_N_per_m")),
                       systematic_speeds_rpm=arrayed(sy.get("speeds_rpm")),
                       systematic=arrayed(sy.get("relative_change")),
                       systematic_sources=tuple(sy.get("sources", ())),
                       summary_speed_rpm=float(d["speed_rpm"]), tests=d.get("tests", {}),
                       variance_split=d.get("variance_split", {}),
                       n_records=int(d.get("n_records", 0)),
                       speeds_rpm=arrayed(d.get("speeds_rpm")), provenance=d.get("provenance", {}))
        except KeyError as exc:
            raise ValueError(f"{source}: missing field {exc.args[0]!r}") from None


def _interp_rows(x: np.ndarray, Y: np.ndarray, at: float) -> np.ndarray:
    """``Y[i]`` interpolated linearly in ``x`` at ``at`` (clamped at the ends)."""
    if x.size == 1:
        return Y[0]
    i = int(np.clip(np.searchsorted(x, at), 1, x.size - 1))
    t = float(np.clip((at - x[i - 1]) / (x[i] - x[i - 1]), 0.0, 1.0))
    return (1 - t) * Y[i - 1] + t * Y[i]


def save_uncertainty(model: IdentifiedUncertainty, path: str | Path) -> Path:
    """Write ``uncertainty.json`` (indented JSON of :meth:`IdentifiedUncertainty.to_dict`)."""
    path = Path(path)
    path.write_text(json.dumps(model.to_dict(), indent=1, default=float))
    return path


def load_uncertainty(path: str | Path) -> IdentifiedUncertainty:
    """Read an ``uncertainty.json`` file (or a run folder holding one)."""
    path = Path(path)
    if path.is_dir():
        path = path / "uncertainty.json"
    if not path.is_file():
        raise ValueError(f"uncertainty: {path} does not exist (need an uncertainty.json or a "
                         "run folder with one)")
    return IdentifiedUncertainty.from_dict(json.loads(path.read_text()), source=str(path))
