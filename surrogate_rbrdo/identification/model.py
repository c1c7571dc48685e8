"""From identified vectors to the uncertainty model the study uses (``uncertainty.json``).

``fit_uncertainty`` takes the identified coefficients of ``N`` records (``values (N, d)``) and
their speeds and separates

* the deterministic speed trend ``k̄_j(Ω)`` of each coefficient (:func:`fit_trend`, a stated law
  with its parameter covariance and lack-of-fit test),
* the scatter around it, as *factors* ``e_j = value_j / k̄_j(Ω)`` (multiplicative, like the
  study's θ): an MVN of ``e`` (mean ≈ 1), with Shapiro–Wilk, Henze–Zirkler, Mardia and Q–Q R²,
* for comparison with the paper's Table 4, the MVN of the pooled raw values (trend included),
* how much of the scatter is identification error: estimated from the records' own covariances
  (``per_record_cov``: mean identification covariance, physical = total − identification), and
  measured when the truth is known (the virtual rig): ``cov(e − e_true)`` vs ``cov(e_true)``.

The study's θ are stiffness factors per bearing (``study="isotropic"``: the mean of ``k_yy`` and
``k_zz`` of each bearing; ``study="stiffness"``: the four ``k`` separately), ``θ = W e``. At a speed
``Ω`` and with the model's nominal stiffness ``k_ref(Ω)`` of those bearings,
:meth:`IdentifiedUncertainty.random_vector` returns the MVN of
``θ_b = Σ_j W_bj k̄_j(Ω) e_j / k_ref,b(Ω)``: the identified trend relative to the model times the
scatter, plus (by default) the trend's own parameter uncertainty. Without a reference it is
the stiffness itself (N/m).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from surrogate_rbrdo.core.validate import check_choice
from surrogate_rbrdo.identification.trend import TrendFit
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel
from surrogate_rbrdo.uncertainty.mvn import MultivariateNormal

FORMAT = "surrogate_rbrdo.identified_uncertainty"
VERSION = 1
STUDY_FORMS = ("isotropic", "stiffness")
SCATTERS = ("total", "physical")


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


def model_reference(model: SpindleModel, speed_rpm: float, names: Sequence[str]) -> np.ndarray:
    """The model's nominal stiffness (N/m) of each study variable at a speed: the mean diagonal
    stiffness of a bearing (``"front"``) or one coefficient (``"front_k_yy"``)."""
    K, _ = model.bearing_coefficients(np.array([[float(speed_rpm) * RPM]]))
    bearings = [b.name for b in model.geometry.bearings]
    out = []
    for n in names:
        b, _, d = n.partition("_k_")
        if b not in bearings:
            raise ValueError(f"names: {n!r} is not a bearing of the model {bearings}")
        j = bearings.index(b)
        diag = np.diagonal(K[0, 0, j])
        out.append(diag.mean() if not d else diag[{"yy": 0, "zz": 1}[d]])
    return np.asarray(out, dtype=float)


@dataclass(frozen=True, eq=False)
class IdentifiedUncertainty:
    """The identified uncertainty model (module docstring); build it with
    :func:`fit_uncertainty`, store it with :func:`save_uncertainty`."""

    coefficients: tuple[str, ...]
    trends: tuple[TrendFit, ...]
    scatter_mean: np.ndarray
    scatter_cov: np.ndarray
    names: tuple[str, ...]
    weights: np.ndarray
    scatter: str = "total"
    physical_cov: np.ndarray | None = None
    identification_cov: np.ndarray | None = None
    pooled_mean: np.ndarray | None = None
    pooled_cov: np.ndarray | None = None
    tests: dict = field(default_factory=dict)
    variance_split: dict = field(default_factory=dict)
    n_records: int = 0
    speeds_rpm: np.ndarray | None = None
    provenance: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        check_choice("scatter", self.scatter, SCATTERS)
        if self.scatter == "physical" and self.physical_cov is None:
            raise ValueError("scatter = 'physical' is not allowed without physical_cov "
                             "(fit with per_record_cov or truth)")

    @property
    def factor_cov(self) -> np.ndarray:
        """Covariance of the detrended factors ``e`` the study gets (total or physical)."""
        return self.physical_cov if self.scatter == "physical" else self.scatter_cov

    @property
    def mean(self) -> np.ndarray:
        """Mean of the study's θ relative to the identified trend, ``W μ_e`` (≈ 1)."""
        return self.weights @ self.scatter_mean

    @property
    def cov(self) -> np.ndarray:
        """Covariance of the study's θ relative to the identified trend, ``W Σ_e Wᵀ``."""
        return self.weights @ self.factor_cov @ self.weights.T

    def trend(self, speed_rpm) -> np.ndarray:
        """Trend ``k̄_j`` of every coefficient at the speeds, ``(..., d)``."""
        return np.stack([t.predict(speed_rpm) for t in self.trends], axis=-1)

    def random_vector(self, speed_rpm: float, *, reference=None,
                      trend_uncertainty: bool = True) -> MultivariateNormal:
        """The study's θ at one speed as a :class:`MultivariateNormal`.

        Parameters
        ----------
        speed_rpm : float
        reference : array (m,), optional
            Nominal stiffness of each θ variable in the study's model at this speed
            (:func:`model_reference`): θ is then a factor on it. Default: θ in N/m.
        trend_uncertainty : bool
            Add the trend's parameter uncertainty (independent fits per coefficient).
        """
        sp = float(speed_rpm)
        if not np.isfinite(sp) or sp <= 0:
            raise ValueError(f"speed_rpm = {speed_rpm!r} is not allowed: must be finite and > 0")
        m = len(self.names)
        ref = np.ones(m) if reference is None else np.asarray(reference, dtype=float)
        if ref.shape != (m,) or np.any(~np.isfinite(ref) | (ref <= 0)):
            raise ValueError(f"reference = {reference!r} is not allowed: need {m} finite values "
                             f"> 0 (N/m) for {list(self.names)}")
        t = self.trend(sp)
        D = self.weights * t[None, :] / ref[:, None]
        mean = D @ self.scatter_mean
        cov = D @ self.factor_cov @ D.T
        if trend_uncertainty:
            var_t = np.array([tr.predict_std(sp) ** 2 for tr in self.trends])
            Dt = self.weights * self.scatter_mean[None, :] / ref[:, None]
            cov = cov + (Dt * var_t[None, :]) @ Dt.T
        return MultivariateNormal(mean, 0.5 * (cov + cov.T))

    def to_dict(self) -> dict:
        arr = lambda a: None if a is None else np.asarray(a).tolist()  # noqa: E731
        return {"format": FORMAT, "version": VERSION,
                "names": list(self.names), "mean": self.mean.tolist(), "cov": self.cov.tolist(),
                "coefficients": list(self.coefficients), "weights": self.weights.tolist(),
                "scatter": self.scatter,
                "factors": {"mean": self.scatter_mean.tolist(),
                            "cov_total": self.scatter_cov.tolist(),
                            "cov_physical": arr(self.physical_cov),
                            "cov_identification": arr(self.identification_cov)},
                "trend": {c: t.to_dict() for c, t in zip(self.coefficients, self.trends,
                                                          strict=True)},
                "pooled": {"mean": arr(self.pooled_mean), "cov": arr(self.pooled_cov)},
                "tests": self.tests, "variance_split": self.variance_split,
                "n_records": self.n_records, "speeds_rpm": arr(self.speeds_rpm),
                "provenance": self.provenance}

    @classmethod
    def from_dict(cls, d: dict, *, source: str = "uncertainty") -> IdentifiedUncertainty:
        """Inverse of :meth:`to_dict`; a wrong format names the source and the field."""
        if d.get("format") != FORMAT or d.get("version") != VERSION:
            raise ValueError(f"{source}: format = {d.get('format')!r}, version = "
                             f"{d.get('version')!r}: expected {FORMAT!r} version {VERSION}")
        try:
            coeffs = tuple(d["coefficients"])
            f = d["factors"]
            opt = lambda a: None if a is None else np.asarray(a, float)  # noqa: E731
            return cls(coefficients=coeffs,
                       trends=tuple(TrendFit.from_dict(d["trend"][c]) for c in coeffs),
                       scatter_mean=np.asarray(f["mean"], float),
                       scatter_cov=np.asarray(f["cov_total"], float), names=tuple(d["names"]),
                       weights=np.asarray(d["weights"], float), scatter=d["scatter"],
                       physical_cov=opt(f.get("cov_physical")),
                       identification_cov=opt(f.get("cov_identification")),
                       pooled_mean=opt(d["pooled"]["mean"]), pooled_cov=opt(d["pooled"]["cov"]),
                       tests=d.get("tests", {}), variance_split=d.get("variance_split", {}),
                       n_records=int(d.get("n_records", 0)),
                       speeds_rpm=opt(d.get("speeds_rpm")), provenance=d.get("provenance", {}))
        except KeyError as exc:
            raise ValueError(f"{source}: missing field {exc.args[0]!r}") from None


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
