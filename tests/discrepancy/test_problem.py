"""Residuals: the unbalance solved exactly inside, the measurement chain, the priors."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy.fit import fit, fit_batch, jacobian
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.nuisance import NuisanceOptions
from surrogate_rbrdo.discrepancy.observables import ComplexBlock, MeasuredData
from surrogate_rbrdo.discrepancy.problem import Problem, _times_2x2
from surrogate_rbrdo.discrepancy.sweeps import Sweep
from surrogate_rbrdo.discrepancy.synthetic import default_channels

U = np.array([4e-6 * np.exp(0.7j), 9e-6 * np.exp(-2.0j)])


def _data(fm, sweep, theta, noise=1e-12, gain=None, tau=0.0, seed=0):
    """Noise-level records of the model's own response (a known answer)."""
    rng = np.random.default_rng(seed)
    G = fm.response(sweep, theta[None], np.ones((1, 2)))[0]
    y = G @ U
    w = sweep.freq_rad_s[:, None]
    g = np.ones(y.shape[1]) if gain is None else gain
    y = y * g / (1 + 1j * w * tau)
    rec = y[None] + noise * (rng.normal(size=(10,) + y.shape)
                             + 1j * rng.normal(size=(10,) + y.shape))
    return MeasuredData((ComplexBlock.from_repeats("unbalance_1x", sweep, fm.channels, rec),))


@pytest.fixture(scope="module")
def model(spindle):
    sp, g = spindle
    return ForwardModel(g, sp.effects, default_channels(g), (0.0, 350.0))


@pytest.mark.known_answer
def test_unbalance_and_stiffness_come_back_exactly(model):
    sw = Sweep.unbalance(np.linspace(2000, 24000, 12))
    data = _data(model, sw, np.array([0.93, 1.04]))
    prob = Problem(model, data)
    par = prob.parametrisation()
    f = fit(prob, par, par.x0())
    assert np.allclose(np.exp(f.x[:2]), [0.93, 1.04], rtol=1e-6)
    assert np.allclose(f.evaluation.unbalance[0][0], U, rtol=1e-6)


@pytest.mark.known_answer
def test_channel_gains_and_time_constants_are_recalibrated(model):
    sw = Sweep.unbalance(np.linspace(2000, 24000, 12))
    gain = np.array([1.02, 0.99, 1.0, 1.01, 0.97, 1.0])
    tau0 = 1 / (2 * np.pi * 1e4)
    data = _data(model, sw, np.ones(2), gain=gain, tau=tau0, noise=1e-13)
    prob = Problem(model, data, nuisance=NuisanceOptions(gain_sd=0.02, bandwidth_hz=1e4,
                                                          delay_sd_s=1e-6))
    par = prob.parametrisation()
    f = fit(prob, par, par.x0(), max_nfev=200)
    rows = par.rows(f.x[None])
    # gains are known up to a common factor the unbalance takes: compare ratios
    assert np.allclose(rows.gain[0] / rows.gain[0, 0], gain / gain[0], rtol=1e-5)
    assert np.allclose(rows.tau[0], tau0, rtol=1e-3)


def test_model_vector_and_residuals_agree(model):
    sw = Sweep.unbalance(np.linspace(2000, 24000, 8))
    data = _data(model, sw, np.array([1.1, 0.9]), noise=1e-9)
    prob = Problem(model, data, nuisance=NuisanceOptions(gain_sd=0.02))
    par = prob.parametrisation()
    x = par.x0()
    x[3] = 0.01
    ev = prob.evaluate(par, x[None])
    u = tuple(v[0] for v in ev.unbalance)
    m = prob.model_vector(par, x[None], u)[0]
    b = prob.blocks[0]
    y = np.stack([b.mean.real, b.mean.imag], -1).reshape(-1)
    W = prob.whiten[0].reshape(-1, 2, 2)
    r = np.einsum("nij,nj->ni", W, (y - m[:y.size]).reshape(-1, 2)).reshape(-1)
    assert np.allclose(r, ev.residuals[0, :y.size])
    assert np.allclose(ev.residuals[0, y.size:], -m[y.size:])   # priors: (μ − p)/σ


@pytest.mark.known_answer
def test_impact_run_state_and_hammer_calibration_come_back(model):
    """1x data at θ and FRFs at standstill and 12 000 rpm from another run (θ e^a) through a
    hammer with gain 1.01 and skew 0.3 µs: the fit returns θ, the impact run's factors and the
    hammer's gain and skew (its prior is weak against noise-free data)."""
    sw = Sweep.unbalance(np.linspace(2000, 24000, 12))
    theta, run = np.array([0.93, 1.04]), np.array([1.02, 0.985])
    blocks = list(_data(model, sw, theta).blocks)
    tool = model.channels[0]
    rng = np.random.default_rng(3)
    for rpm in (0.0, 12000.0):
        si = Sweep.impact(np.linspace(100.0, 1400.0, 14), (tool,), rpm)
        H = model.response(si, (theta * run)[None], np.ones((1, 2)))[0][..., 0]
        H = H / (1.01 * np.exp(1j * si.freq_rad_s * 0.3e-6))[:, None]
        rec = H[None] + 1e-7 * np.abs(H).max() * (rng.normal(size=(8,) + H.shape)
                                                   + 1j * rng.normal(size=(8,) + H.shape))
        blocks.append(ComplexBlock.from_repeats(f"impact_{rpm:.0f}", si, model.channels, rec,
                                                runs=False))
    data = MeasuredData(tuple(blocks))
    opts = NuisanceOptions(force_gain_sd=0.01, force_delay_sd_s=0.2e-6, impact_theta_sd=0.1)
    prob = Problem(model, data, nuisance=opts)
    par = prob.parametrisation()
    assert par.force_names == ("log_force_gain", "force_delay", "log_theta_impact_front",
                               "log_theta_impact_rear")
    f = fit(prob, par, par.x0(), max_nfev=200)
    rows = par.rows(f.x[None])
    assert np.allclose(rows.theta[0], theta, rtol=1e-5)
    assert np.allclose(rows.theta_impact[0], run, rtol=1e-5)
    assert rows.force[0, 0] == pytest.approx(1.01, rel=1e-5)
    assert rows.force[0, 1] == pytest.approx(0.3e-6, rel=1e-3)
    # without impact tests there are no force parameters
    assert Problem(model, _data(model, sw, theta), nuisance=opts).parametrisation(
    ).force_names == ()


@pytest.mark.known_answer
def test_the_fit_keeps_the_solvers_last_jacobian_only_where_it_is_the_same(model):
    """The fit returns the Jacobian the solver asked for at its end point instead of a new
    one: bit for bit what recomputing it there gives (same rows, same residual)."""
    sw = Sweep.unbalance(np.linspace(2000, 24000, 9))
    prob = Problem(model, _data(model, sw, np.array([1.1, 0.9]), noise=1e-9, seed=4))
    par = prob.parametrisation()
    f = fit(prob, par, par.x0(), max_nfev=40)
    ev = prob.evaluate(par, f.x[None])
    J, _ = jacobian(prob, par, f.x, ev.residuals[0])
    assert np.array_equal(f.jac, J)
    assert np.array_equal(f.evaluation.residuals, ev.residuals)
    assert f.chi2 == float(ev.chi2[0])


def test_the_written_out_2x2_products_equal_einsum():
    rng = np.random.default_rng(5)
    W, V = rng.normal(size=(7, 3, 2, 2)), rng.normal(size=(4, 7, 3, 2, 5))
    assert np.array_equal(_times_2x2(W, V), np.einsum("xcij,bxcjk->bxcik", W, V))


def _with_frf(fm, theta):
    """The model's own 1x response and a standstill FRF at the tool (noise-level records)."""
    data = _data(fm, Sweep.unbalance(np.linspace(2000, 24000, 12)), theta)
    tool = fm.channels[0]
    sw = Sweep.impact(np.linspace(100.0, 1400.0, 14), (tool,))
    H = fm.response(sw, theta[None], np.ones((1, 2)))[0][..., 0]
    rng = np.random.default_rng(3)
    rec = H[None] + 1e-10 * (rng.normal(size=(10,) + H.shape)
                             + 1j * rng.normal(size=(10,) + H.shape))
    frf = ComplexBlock.from_repeats("impact_tool_x", sw, fm.channels, rec, runs=False)
    return MeasuredData(data.blocks + (frf,))


@pytest.mark.known_answer
def test_only_keeps_the_1x_rows_and_the_priors_they_need(model):
    """``Problem.only`` is the same problem on the 1x block: its residuals are the full
    problem's 1x rows, and the priors of the force channel (only FRFs see it) are gone."""
    data = _with_frf(model, np.array([0.95, 1.03]))
    opts = NuisanceOptions(force_gain_sd=0.01)
    full = Problem(model, data, nuisance=opts)
    sub = full.only("unbalance_1x")
    pf, ps = full.parametrisation(), sub.parametrisation()
    assert pf.force_names == ("log_force_gain",) and ps.force_names == ()
    x = pf.x0() + 0.01
    rf = full.evaluate(pf, x[None]).residuals[0]
    rs = sub.evaluate(ps, x[None, :len(ps.names)]).residuals[0]
    n1 = 2 * data.blocks[0].mean.size
    assert sub.n_obs == full.n_obs - 2 * data.blocks[1].mean.size - 1
    np.testing.assert_array_equal(rs[:n1], rf[:n1])


@pytest.mark.known_answer
def test_fit_batch_walks_every_start_back_to_the_truth(model):
    """Batched Levenberg–Marquardt steps from three perturbed starts on the model's own
    response: every start reaches the true stiffness factors (noise 1e-12 m)."""
    data = _data(model, Sweep.unbalance(np.linspace(2000, 24000, 12)), np.array([0.93, 1.04]))
    prob = Problem(model, data)
    par = prob.parametrisation()
    truth = np.log([0.93, 1.04])
    X0 = par.x0()[None].repeat(3, axis=0)
    X0[:, :2] = truth + np.array([[0.1, -0.1], [-0.15, 0.05], [0.05, 0.15]])
    X, chi = fit_batch(prob, par, X0, n_iter=12)
    assert np.allclose(np.exp(X[:, :2]), [0.93, 1.04], rtol=1e-4)
    assert np.all(chi < 1e-3 * prob.evaluate(par, X0).chi2)


def _reference_lm(prob, par, X, n_iter):
    """Levenberg–Marquardt as :func:`fit_batch` documents it, in the same batched arithmetic
    but with every row's Jacobian recomputed at every step (what it did before it kept the
    Jacobians of rows that did not move)."""
    lo, hi = par.bounds()
    X = np.clip(np.array(X, dtype=float), lo, hi)
    B, n = X.shape
    r = prob.evaluate(par, X).residuals
    chi = np.sum(r**2, axis=1)
    lam, eye = np.full(B, 1e-3), np.eye(n)
    refused = 0
    for _ in range(n_iter):
        J = np.stack([jacobian(prob, par, X[b], r[b])[0].T for b in range(B)])
        A = np.einsum("bio,bjo->bij", J, J)
        g = np.einsum("bio,bo->bi", J, r)
        d = np.sqrt(np.maximum(np.einsum("bii->bi", A), 1e-300))
        M = A / (d[:, :, None] * d[:, None, :]) + lam[:, None, None] * eye[None]
        step = -np.linalg.solve(M + 1e-12 * eye[None], (g / d)[..., None])[..., 0] / d
        Xn = np.clip(X + step, lo, hi)
        rn = prob.evaluate(par, Xn).residuals
        cn = np.sum(rn**2, axis=1)
        ok = cn < chi
        refused += int(np.sum(~ok))
        X[ok], r[ok], chi[ok] = Xn[ok], rn[ok], cn[ok]
        lam = np.where(ok, lam / 3, lam * 10)
    return X, chi, refused


@pytest.mark.known_answer
def test_fit_batch_equals_steps_with_every_jacobian_recomputed(model):
    """A row whose step is refused keeps its Jacobian: the rows and χ² are those of the
    method with every Jacobian recomputed (enough steps that some are refused at the
    optimum)."""
    data = _data(model, Sweep.unbalance(np.linspace(2000, 24000, 12)), np.array([0.93, 1.04]),
                 noise=1e-8)
    prob = Problem(model, data)
    par = prob.parametrisation()
    X0 = par.x0()[None].repeat(3, axis=0)
    X0[:, :2] += np.array([[0.6, -0.5], [-0.4, 0.45], [0.35, 0.6]])
    X, chi = fit_batch(prob, par, X0, n_iter=14)
    Xr, chir, refused = _reference_lm(prob, par, X0, 14)
    assert refused > 0
    np.testing.assert_array_equal(X, Xr)
    np.testing.assert_array_equal(chi, chir)


@pytest.mark.known_answer
def test_a_fit_finished_from_its_start_evaluates_nothing_twice(model):
    """``fit(start=f)`` from a short fit's end point reaches the same point as a fit that
    evaluates that point again, with one residual row and one Jacobian fewer."""
    sw = Sweep.unbalance(np.linspace(2000, 24000, 9))
    prob = Problem(model, _data(model, sw, np.array([1.1, 0.9]), noise=1e-9, seed=4))
    par = prob.parametrisation()
    short = fit(prob, par, par.x0(), max_nfev=3)
    again = fit(prob, par, short.x, max_nfev=40)
    seeded = fit(prob, par, short.x, max_nfev=40, start=short)
    assert np.array_equal(seeded.x, again.x) and seeded.chi2 == again.chi2
    assert np.array_equal(seeded.jac, again.jac)
    assert again.nfev - seeded.nfev == 1 + par.x0().size
    assert np.allclose(np.exp(seeded.x[:2]), [1.1, 0.9], rtol=1e-4)


@pytest.mark.known_answer
def test_rows_solved_in_a_recent_call_are_not_solved_again(model, monkeypatch):
    """A Jacobian's rows that move only a channel gain share the point's physics: solved for
    the point's residual, they are taken from the problem's recent rows — the same numbers
    as a problem that solves everything afresh, with fewer rows solved."""
    data = _with_frf(model, np.array([0.95, 1.03]))
    opts = NuisanceOptions(gain_sd=0.02)
    prob, fresh = Problem(model, data, nuisance=opts), Problem(model, data, nuisance=opts)
    par = prob.parametrisation()
    assert par.names[4].startswith("log_gain")
    x = par.x0() + 0.01
    solved = []
    real = type(model).responses

    def counting(self, sweeps, theta, *a, **k):
        solved.append(theta[0].shape[0])
        return real(self, sweeps, theta, *a, **k)

    prob.evaluate(par, x[None])
    X = np.vstack([x[None], x[None] + 0.02 * np.eye(x.size)[:6]])   # θ, damping, gains
    monkeypatch.setattr(type(model), "responses", counting)
    ev = prob.evaluate(par, X)
    assert solved == [4]                    # θ (2), damping (2); x's own physics is known
    monkeypatch.undo()
    ref = fresh.evaluate(par, X)
    np.testing.assert_array_equal(ev.residuals, ref.residuals)
    for a, b in zip(ev.predictions, ref.predictions, strict=True):
        np.testing.assert_array_equal(a, b)
    assert prob.only("unbalance_1x").__dict__.get("_recent") is None
