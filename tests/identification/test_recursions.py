"""SG / MISG / RLS / batch LS against independent computations and known answers."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.identification import (
    MISG,
    RECURSIONS,
    RLS,
    SG,
    BatchLS,
    Bounds,
    Regression,
    identify,
)

TRUTH = np.array([2.5e8, 1.0e3])


def _bearing_like(rng, T=600, B=3, noise=0.0):
    """Regressors like a bearing's [x, xdot] (very different magnitudes), y = k x + c xdot."""
    phi = rng.normal(size=(B, T, 2)) * [1e-6, 1e-3]
    y = phi @ TRUTH + noise * 250.0 * rng.normal(size=(B, T))
    return Regression(phi, y, ("k", "c"))


def _ding_sg(phi, y, th0, r0=1.0):
    """Ding's SG written out for one record, without the package (scaled inputs)."""
    th, r = th0.copy(), r0
    for t in range(len(y)):
        r = r + phi[t] @ phi[t]
        th = th + phi[t] * (y[t] - phi[t] @ th) / r
    return th


@pytest.mark.known_answer
def test_noise_free_every_method_recovers_truth():
    reg = _bearing_like(np.random.default_rng(0))
    # SG and MISG (decaying 1/t gain) converge polynomially, RLS and LS at once
    tol = {"sg": 1e-2, "misg": 3e-2, "rls": 1e-8, "batch_ls": 1e-10}
    for name in RECURSIONS:
        m = SG(mu=3.0) if name == "sg" else name     # SG with mu = 1: see the rate test
        res = identify(reg, m, theta0=[2.0e8, 700.0])
        assert np.allclose(res.estimate, TRUTH, rtol=tol[name]), name
        assert res.ok.all()


@pytest.mark.known_answer
def test_batch_ls_equals_lstsq_and_rls_equals_batch():
    reg = _bearing_like(np.random.default_rng(1), noise=0.05)
    ref = np.stack([np.linalg.lstsq(p, y, rcond=None)[0] for p, y in
                    zip(reg.phi, reg.y, strict=True)])
    ls = identify(reg, BatchLS(), theta0=[2.0e8, 700.0])
    rls = identify(reg, RLS(), theta0=[2.0e8, 700.0])
    assert np.allclose(ls.estimate, ref, rtol=1e-10)
    # RLS = LS up to its prior P(0) and the round-off of the P update (c is 0.4 % of y here,
    # its own standard error is ~30 %)
    assert np.allclose(rls.estimate, ref, rtol=1e-4)


@pytest.mark.known_answer
def test_sg_matches_dings_formula_and_misg_p1_is_sg():
    reg = _bearing_like(np.random.default_rng(2), T=300, B=1, noise=0.02)
    th0 = np.array([2.0e8, 700.0])
    res = identify(reg, SG(), theta0=th0, scaling="initial")
    # identify scales parameters by theta0 and y by its RMS: redo that by hand
    ys = np.sqrt(np.mean(reg.y[0] ** 2))
    ref = _ding_sg(reg.phi[0] * th0 / ys, reg.y[0] / ys, np.ones(2)) * th0
    assert np.allclose(res.estimate[0], ref, rtol=1e-12)
    misg1 = identify(reg, MISG(p=1), theta0=th0, scaling="initial")
    assert np.array_equal(misg1.estimate, res.estimate)


@pytest.mark.known_answer
def test_normalised_step_is_nlms():
    rng = np.random.default_rng(3)
    phi = rng.normal(size=(200, 2))
    y = phi @ [1.0, -2.0] + 0.01 * rng.normal(size=200)
    reg = Regression(phi, y)
    m = MISG(p=1, step="normalised", mu=0.5, delta=1e-8)
    res = identify(reg, m, theta0=[1.0, 1.0], scaling="initial")
    ys = np.sqrt(np.mean(y**2))
    th = np.ones(2)
    for t in range(200):
        f = phi[t] / ys
        th = th + 0.5 * f * (y[t] / ys - f @ th) / (1e-8 + f @ f)
    assert np.allclose(res.estimate[0], th, rtol=1e-12)


def test_misg_uses_p_innovations():
    """p = 3 stacks three samples: its first step differs from SG's, later ones too."""
    reg = _bearing_like(np.random.default_rng(4), T=50, B=1)
    a = identify(reg, MISG(p=3), theta0=[2e8, 700.0], stride=1).trajectory
    b = identify(reg, SG(), theta0=[2e8, 700.0], stride=1).trajectory
    assert np.allclose(a[0, 0], b[0, 0])          # one sample in the window: identical
    assert not np.allclose(a[0, 2], b[0, 2])


def test_iterations_to_tolerance_known_trajectory():
    """Batch LS on exact data is exact from the second sample: iterations = 2."""
    reg = _bearing_like(np.random.default_rng(5), T=40, B=2)
    res = identify(reg, BatchLS(), theta0=[2.0e8, 700.0], truth=TRUTH, tol=1e-6, stride=1)
    assert res.reference == "truth"
    assert np.all(res.iterations_to_tol == 2)
    self_ref = identify(reg, BatchLS(), theta0=[2.0e8, 700.0], stride=1, tol=1e-6)
    assert self_ref.reference == "final" and np.all(self_ref.iterations_to_tol == 2)


def test_rls_forgetting_tracks_a_drift():
    rng = np.random.default_rng(6)
    T = 4000
    phi = rng.normal(size=(1, T, 2))
    k = np.linspace(1.0, 0.8, T)                              # slow 20 % drift
    y = phi[..., 0] * k + phi[..., 1] * 0.5 + 0.01 * rng.normal(size=(1, T))
    reg = Regression(phi, y)
    fixed = identify(reg, RLS(), theta0=[1.0, 0.5])
    forget = identify(reg, RLS(forgetting=0.99), theta0=[1.0, 0.5])
    misg = identify(reg, MISG(p=3, forgetting=0.99), theta0=[1.0, 0.5])
    assert abs(forget.estimate[0, 0] - 0.8) < 0.01 < abs(fixed.estimate[0, 0] - 0.8)
    assert abs(misg.estimate[0, 0] - 0.8) < 0.02


def test_projection_and_at_bound_flag():
    reg = _bearing_like(np.random.default_rng(7), B=2)
    box = Bounds.paper(("k", "c"), k_catalog=1.0e8, c_init=1.0e3)   # truth k = 2.5 k_cat
    for m in (SG(), MISG(p=3), RLS(), BatchLS()):
        res = identify(reg, m, theta0=[1.0e8, 1.0e3], bounds=box)
        assert np.all(res.estimate[:, 0] == 1.5e8)
        assert res.at_bound[:, 0].all() and not res.ok.any()
        assert "sits on its bound" in res.flags(0)[0]
        with pytest.raises(ModelError, match="flagged"):
            res.raise_if_flagged()


def test_record_too_short_for_p_raises():
    reg = _bearing_like(np.random.default_rng(8), T=5, B=1)
    with pytest.raises(ValueError, match=r"record has 5 samples: MISG\(p=10\)"):
        identify(reg, MISG(p=10), theta0=[2e8, 700.0])


def test_unexcited_direction_is_flagged_rank_deficient():
    rng = np.random.default_rng(9)
    phi = rng.normal(size=(2, 300, 2)) * [1e-6, 1e-3]
    phi[1, :, 1] = 0.0                                         # no velocity excitation
    y = phi @ TRUTH
    res = identify(Regression(phi, y, ("k", "c")), "misg", theta0=[2e8, 700.0])
    assert res.rank_deficient.tolist() == [False, True]
    assert np.isnan(res.covariance[1]).all() and "rank-deficient" in res.flags(1)[0]


def test_diverging_recursion_is_flagged():
    """Excitation stops halfway: RLS with forgetting winds up (its estimate wanders to
    (−41, 239) for a truth (1, 2)); the weighted information of its window is rank deficient."""
    rng = np.random.default_rng(10)
    T = 2000
    phi = rng.normal(size=(1, T, 2))
    phi[0, T // 2:] *= 1e-6                                    # excitation stops
    y = phi @ np.array([1.0, 2.0]) + 1e-3 * rng.normal(size=(1, T))
    res = identify(Regression(phi, y), RLS(forgetting=0.6), theta0=[1.0, 1.0])
    assert res.rank_deficient[0] and not res.ok[0] and "window" in " ".join(res.flags(0))
    whole = identify(Regression(phi, y), RLS(), theta0=[1.0, 1.0])    # λ = 1 keeps 1st half
    assert whole.ok[0] and np.allclose(whole.estimate[0], [1.0, 2.0], atol=1e-3)
    grow = np.exp(np.linspace(0.0, 8.0, T))                    # a model that does not hold
    res2 = identify(Regression(phi[:, :, :] * 0 + rng.normal(size=(1, T, 2)),
                               rng.normal(size=(1, T)) * grow), SG(), theta0=[1.0, 1.0])
    assert res2.diverged[0]


def test_options_are_checked():
    with pytest.raises(ValueError, match="mu = 2.5 is not allowed with step='normalised'"):
        MISG(step="normalised", mu=2.5)
    with pytest.raises(ValueError, match="step = 'x'"):
        MISG(step="x")
    with pytest.raises(ValueError, match="forgetting"):
        RLS(forgetting=0.3)
    with pytest.raises(ValueError, match="p = 3 is not allowed for SG"):
        SG(p=3)
    with pytest.raises(ValueError, match="unknown recursion 'ga'"):
        identify(_bearing_like(np.random.default_rng(0)), "ga", theta0=[1.0, 1.0])


@pytest.mark.known_answer
@pytest.mark.parametrize(("method", "exponent"), [(SG(), 0.5), (SG(mu=3.0), 1.5),
                                                  (MISG(p=3), 1.5)])
def test_gradient_rate_under_pure_1x_excitation(method, exponent):
    """φ(t) = [cos ωt, sin ωt] (x and ẋ/Ω of a 1x orbit): E φφᵀ = I/2, ‖φ‖² = 1, r(t) = 1 + t,
    so the SG error decays like ∏(1 − μ/(2t)) ∝ t^(−μ/2). With ωΔt small the p stacked
    regressors are nearly collinear and MISG(p) steps like SG with μ = p: t^(−p/2)."""
    T, w = 6400, 0.02
    t = np.arange(T)
    phi = np.stack([np.cos(w * t), np.sin(w * t)], axis=-1)[None]
    reg = Regression(phi, phi[0] @ [1.0, 1.0])
    res = identify(reg, method, theta0=[0.5, 0.5], scaling="initial", stride=1)
    err = np.linalg.norm(res.trajectory[0] - 1.0, axis=1)
    # average over one period around t and 4t to remove the 1x ripple
    per = int(2 * np.pi / w)
    e1, e4 = err[1600 - per:1600].mean(), err[6400 - per:6400].mean()
    assert np.log(e1 / e4) / np.log(4.0) == pytest.approx(exponent, rel=0.08)


def _misg_loop(phi, y, th0, p, mu, lam, step, r0=1.0, delta=1e-8):
    """MISG written out sample by sample (no batching, no scaling, no projection)."""
    th, r = np.array(th0, dtype=float), r0
    for t in range(len(y)):
        a = max(0, t - p + 1)
        Phi, E = phi[a:t + 1], y[a:t + 1] - phi[a:t + 1] @ th
        win = float(np.sum(Phi**2))
        d = lam * r + win if step == "accumulated" else delta + win
        r = lam * r + float(phi[t] @ phi[t])
        th = th + mu * Phi.T @ E / d
    return th


@pytest.mark.known_answer
@pytest.mark.parametrize("p, lam, step, mu", [(3, 1.0, "accumulated", 1.3),
                                              (3, 0.98, "accumulated", 1.0),
                                              (4, 1.0, "normalised", 0.7)])
def test_misg_variants_equal_an_independent_loop(p, lam, step, mu):
    """Review item 14: MISG p > 1, forgetting and the normalised form against a plain loop
    (scaling "initial" with θ0 = 1 in scaled units is the identity up to the output's RMS)."""
    rng = np.random.default_rng(3)
    phi = rng.normal(size=(300, 3))
    y = phi @ [1.0, -2.0, 0.5] + 0.05 * rng.normal(size=300)
    th0 = np.array([0.5, 0.5, 0.5])
    res = identify(Regression(phi, y), MISG(p=p, forgetting=lam, step=step, mu=mu),
                   theta0=th0, scaling="initial")
    ys = np.sqrt(np.mean(y**2))
    ref = _misg_loop(phi * th0 / ys, y / ys, np.ones(3), p, mu, lam, step) * th0
    assert np.allclose(res.estimate[0], ref, rtol=1e-12, atol=1e-14)


@pytest.mark.known_answer
def test_rls_with_forgetting_is_exponentially_weighted_least_squares():
    """Review item 1: RLS with λ = 0.99 and p0 = 1e6 lost symmetry and positive definiteness of
    P (estimates 1.5–5× too scattered). It must equal the closed-form EWLS per record, and its
    scatter over records the theory σ √((1 − λ)/(1 + λ)) / σ_φ."""
    rng = np.random.default_rng(0)
    B, T, lam = 100, 2000, 0.99
    phi = rng.normal(size=(B, T, 2))
    y = phi @ np.array([1.0, 2.0]) + 0.1 * rng.normal(size=(B, T))
    res = identify(Regression(phi, y), RLS(forgetting=lam, p0=1e6), theta0=[1.0, 2.0])
    w = lam ** (T - 1 - np.arange(T))
    ewls = np.stack([np.linalg.solve((p * w[:, None]).T @ p, (p * w[:, None]).T @ yy)
                     for p, yy in zip(phi, y, strict=True)])
    assert np.allclose(res.estimate, ewls, rtol=1e-8, atol=1e-10)
    theory = 0.1 * np.sqrt((1 - lam) / (1 + lam))
    assert np.allclose(res.estimate.std(axis=0), theory, rtol=0.2)
    assert res.ok.all() and res.covariance_kind == "ewls"
    # the sandwich covariance of EWLS against the Monte Carlo scatter over the 100 records
    assert np.allclose(res.std.mean(axis=0), res.estimate.std(axis=0), rtol=0.2)


@pytest.mark.known_answer
def test_reported_covariance_matches_monte_carlo_or_is_absent():
    """Review item 2: batch LS's σ̂²(ΦᵀΦ)⁻¹ is right; SG/MISG have none (was a 4–17×
    understatement); a regression the estimate fits exactly (1× samples of phasors) has none
    from its residual; a given covariance is passed through."""
    rng = np.random.default_rng(1)
    B, T = 400, 500
    phi = rng.normal(size=(B, T, 2)) * [1e-6, 1e-3]
    y = phi @ TRUTH + 50.0 * rng.normal(size=(B, T))
    reg = Regression(phi, y, ("k", "c"))
    ls = identify(reg, BatchLS(), theta0=[2e8, 800.0])
    rel = ls.std.mean(axis=0) / ls.estimate.std(axis=0)
    assert np.allclose(rel, 1.0, atol=0.1) and ls.covariance_kind == "least_squares"
    misg = identify(reg, MISG(p=3), theta0=[2e8, 800.0])
    assert misg.covariance_kind == "none" and np.isnan(misg.covariance).all()
    exact = Regression(phi[:2], phi[:2] @ TRUTH, ("k", "c"))
    ex = identify(exact, BatchLS(), theta0=[2e8, 800.0])
    assert ex.covariance_kind == "exact_fit" and np.isnan(ex.covariance).all()
    given = identify(exact, BatchLS(), theta0=[2e8, 800.0], covariance=np.diag([1e12, 4.0]))
    assert given.covariance_kind == "given" and np.allclose(given.std, [1e6, 2.0])
    with pytest.raises(ValueError, match="covariance has shape"):
        identify(exact, BatchLS(), theta0=[2e8, 800.0], covariance=np.eye(3))


def test_iterations_count_the_initial_estimate():
    """Review item 18: θ0 outside the tolerance needs at least one sample; θ0 inside and never
    leaving needs none."""
    reg = _bearing_like(np.random.default_rng(5), T=40, B=1)
    out = identify(reg, BatchLS(), theta0=[2.0e8, 700.0], truth=TRUTH, tol=1e-6)
    inside = identify(reg, SG(), theta0=TRUTH, truth=TRUTH, tol=1e-6)     # exact data: stays
    assert np.all(out.iterations_to_tol >= 1) and np.all(inside.iterations_to_tol == 0)
