"""Normality checks of identified vectors: Shapiro–Wilk per margin, Henze–Zirkler and Mardia
for the joint distribution, and the R² of each normal Q–Q plot.

The multivariate tests are written out here (a few array operations each) rather than taken
from pingouin, whose ``multivariate_normality`` is the same Henze–Zirkler statistic but pulls
pandas, seaborn and statsmodels into the toolkit; statsmodels has no multivariate normality
test. ``tests/identification/test_trend_normality.py`` checks Henze–Zirkler against pingouin
when it is installed (Mardia's statistics are not cross-checked). Henze–Zirkler is the
decision test: it is affine invariant and consistent against every alternative, and was among
the most powerful omnibus tests in Mecklin & Mundfrom's (2005) comparison; Mardia's skewness
and kurtosis are reported beside it because they say *how* the data depart (asymmetric tails
or heavy tails).

>>> import numpy as np
>>> X = np.random.default_rng(0).normal(size=(300, 3))
>>> r = normality_report(X, names=("a", "b", "c"))
>>> r.henze_zirkler.p_value > 0.05, min(r.qq_r2) > 0.99
(True, True)
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy import stats


@dataclass(frozen=True)
class TestResult:
    """A test statistic and its p-value."""

    statistic: float
    p_value: float


@dataclass(frozen=True)
class NormalityReport:
    """Per-margin Shapiro–Wilk and Q–Q R²; joint Henze–Zirkler and Mardia (skew, kurtosis)."""

    names: tuple[str, ...]
    shapiro: tuple[TestResult, ...]
    qq_r2: tuple[float, ...]
    henze_zirkler: TestResult
    mardia_skewness: TestResult
    mardia_kurtosis: TestResult
    n: int

    def to_dict(self) -> dict:
        return {"names": list(self.names), "n": self.n,
                "shapiro": {k: asdict(v) for k, v in zip(self.names, self.shapiro, strict=True)},
                "qq_r2": dict(zip(self.names, self.qq_r2, strict=True)),
                "henze_zirkler": asdict(self.henze_zirkler),
                "mardia_skewness": asdict(self.mardia_skewness),
                "mardia_kurtosis": asdict(self.mardia_kurtosis)}


def _check(X) -> np.ndarray:
    X = np.asarray(X, dtype=float)
    if X.ndim == 1:
        X = X[:, None]
    if X.ndim != 2 or X.shape[0] < X.shape[1] + 2 or X.shape[0] < 3:
        raise ValueError(f"X has shape {np.shape(X)}: need (n, p) with n >= max(3, p + 2)")
    if not np.all(np.isfinite(X)):
        raise ValueError("X contains a non-finite value: drop flagged records first")
    return X


def _mahalanobis_gram(X: np.ndarray) -> np.ndarray:
    """``(x_i − x̄)ᵀ S⁻¹ (x_j − x̄)`` with the biased covariance ``S`` (both tests use it).

    Columns are standardised first (the form is invariant to it), so stiffness (1e8) and
    damping (1e3) columns side by side do not look rank deficient to ``pinv``."""
    D = X - X.mean(axis=0)
    sd = D.std(axis=0)
    D = D / np.where(sd > 0, sd, 1.0)
    S = np.cov(D, rowvar=False, bias=True).reshape(X.shape[1], X.shape[1])
    return D @ np.linalg.pinv(S, hermitian=True) @ D.T


def henze_zirkler(X) -> TestResult:
    """Henze & Zirkler (1990) statistic with its lognormal p-value approximation.

    ``HZ = n [ n⁻² Σ_jk e^{−β² D_jk / 2} − 2 (1 + β²)^{−p/2} n⁻¹ Σ_j e^{−β² D_j / (2(1+β²))}
    + (1 + 2β²)^{−p/2} ]`` with ``β = ((2p + 1) n / 4)^{1/(p+4)} / √2``, ``D_j`` the squared
    Mahalanobis distances to the mean and ``D_jk`` between observations.
    """
    X = _check(X)
    n, p = X.shape
    Gm = _mahalanobis_gram(X)
    Dj = np.diag(Gm)
    Djk = Dj[:, None] + Dj[None, :] - 2.0 * Gm
    b2 = (((2 * p + 1) / 4.0) ** (1.0 / (p + 4)) * n ** (1.0 / (p + 4)) / np.sqrt(2.0)) ** 2
    hz = n * (np.exp(-b2 / 2.0 * Djk).sum() / n**2
              - 2.0 * (1 + b2) ** (-p / 2) * np.exp(-b2 / (2 * (1 + b2)) * Dj).sum() / n
              + (1 + 2 * b2) ** (-p / 2))
    a = 1 + 2 * b2
    wb = (1 + b2) * (1 + 3 * b2)
    b4, b8 = b2**2, b2**4
    mu = 1 - a ** (-p / 2) * (1 + p * b2 / a + p * (p + 2) * b4 / (2 * a**2))
    si2 = (2 * (1 + 4 * b2) ** (-p / 2)
           + 2 * a ** (-p) * (1 + 2 * p * b4 / a**2 + 3 * p * (p + 2) * b8 / (4 * a**4))
           - 4 * wb ** (-p / 2) * (1 + 3 * p * b4 / (2 * wb) + p * (p + 2) * b8 / (2 * wb**2)))
    pmu = np.log(np.sqrt(mu**4 / (si2 + mu**2)))
    psi = np.sqrt(np.log1p(si2 / mu**2))
    return TestResult(float(hz), float(stats.lognorm.sf(hz, psi, scale=np.exp(pmu))))


def mardia(X) -> tuple[TestResult, TestResult]:
    """Mardia's (1970) multivariate skewness ``n b1 / 6 ~ χ²(p(p+1)(p+2)/6)`` and kurtosis
    ``(b2 − p(p+2)) / √(8p(p+2)/n) ~ N(0, 1)`` (two-sided)."""
    X = _check(X)
    n, p = X.shape
    Gm = _mahalanobis_gram(X)
    b1 = float(np.sum(Gm**3)) / n**2
    b2 = float(np.sum(np.diag(Gm) ** 2)) / n
    df = p * (p + 1) * (p + 2) / 6
    skew = TestResult(n * b1 / 6, float(stats.chi2.sf(n * b1 / 6, df)))
    z = (b2 - p * (p + 2)) / np.sqrt(8 * p * (p + 2) / n)
    return skew, TestResult(float(z), float(2 * stats.norm.sf(abs(z))))


def qq_r2(x) -> float:
    """R² of the normal Q–Q plot (squared probability-plot correlation, Filliben 1975)."""
    x = np.asarray(x, dtype=float).ravel()
    (_, _), (_, _, r) = stats.probplot(x, dist="norm")
    return float(r**2)


def normality_report(X, names=None) -> NormalityReport:
    """All the checks on the rows of ``X`` (records × variables)."""
    X = _check(X)
    names = tuple(names) if names is not None else tuple(f"v{i}" for i in range(X.shape[1]))
    if len(names) != X.shape[1]:
        raise ValueError(f"names has {len(names)} entries for {X.shape[1]} columns")
    sw = tuple(TestResult(*map(float, stats.shapiro(X[:, j]))) for j in range(X.shape[1]))
    skew, kurt = mardia(X)
    return NormalityReport(names, sw, tuple(qq_r2(X[:, j]) for j in range(X.shape[1])),
                           henze_zirkler(X), skew, kurt, int(X.shape[0]))


__all__ = ["NormalityReport", "TestResult", "henze_zirkler", "mardia", "normality_report",
           "qq_r2"]
