"""The identification figures are written (content is checked by eye in docs/figures)."""

from __future__ import annotations

import numpy as np

from surrogate_rbrdo.identification import MISG, SG, identify
from surrogate_rbrdo.identification.comparison import synthetic_problem
from surrogate_rbrdo.identification.scatter import fit_uncertainty
from surrogate_rbrdo.identification.synthetic import SyntheticSetting
from surrogate_rbrdo.reporting.plots_identification import plot_convergence, plot_qq, plot_trend


def test_figures_are_written(tmp_path):
    reg, truth, th0, box = synthetic_problem(SyntheticSetting(n_samples=200), 3,
                                             rng=np.random.default_rng(0))
    res = {m.name: identify(reg, m, theta0=th0, bounds=box, stride=5) for m in (SG(), MISG())}
    assert plot_convergence(res, truth, tmp_path / "conv.png").stat().st_size > 1000
    rng = np.random.default_rng(1)
    n = np.repeat(np.linspace(1000, 24000, 10), 12)
    k = 3e8 * (1 - 0.1 * (n / 24000) ** 2)[:, None] * (1 + 0.01 * rng.normal(size=(120, 2)))
    u = fit_uncertainty(k, n, ("front_k_yy", "front_k_zz"))
    assert plot_trend(u, n, k, tmp_path / "trend.png",
                      truth=lambda s: [3e8 * (1 - 0.1 * (s / 24000) ** 2)] * 2).is_file()
    assert plot_qq(k / u.trend(n), u.coefficients, tmp_path / "qq.png").is_file()
