"""The 1 000-record identification campaign: time per stage (target ≤ 30 s on 2 cores).

50 speeds in 1 000–24 000 rpm × 20 repeats of the reference spindle (baseline design, Table-3
softening), physical scatter of the stiffness factors 1.5 % (front) and 3.3 % (rear), probes
at the bearings. Stages:

1. exact condensation of the rotor at the 50 speeds;
2. synchronous demodulation of raw probe signals (4 channels × ``--seconds`` at 10 kHz, white
   probe noise ``--probe-noise-nm``; a projection on ``e^{−iΩt}`` standing in for the rig's
   demodulation, issue 14) → 1× phasors and their standard errors;
3. the eight coefficients of every record in closed form with their covariance;
4. the paper's route for comparison: MISG(p = 3) on 1 000 samples of the 1× signals of each
   record and bearing direction (4 000 regressions);
5. the uncertainty model (trends, scatter, tests, variance split).

    PYTHONPATH=$PWD python3 benchmarks/bench_identification_campaign.py [--seconds 1.0]
"""

from __future__ import annotations

import argparse
import os
import resource
import time

import numpy as np

from surrogate_rbrdo.identification import (
    MISG,
    catalog_coefficients,
    condense_reactions,
    fit_uncertainty,
    identify,
    identify_phasors,
    model_reference,
    normality_report,
    phasor_time_regression,
)
from surrogate_rbrdo.identification.virtual import phasor_campaign
from surrogate_rbrdo.spindle import reference_spindle
from surrogate_rbrdo.spindle.assembly import RPM


def demodulate(ph: np.ndarray, speeds_rpm: np.ndarray, seconds: float, noise_m: float,
               rng: np.random.Generator, fs: float = 1e4, chunk: int = 50):
    """Raw signals ``Re(X e^{iΩt}) + noise`` per record and channel, demodulated back by a
    least-squares fit of ``a cos Ωt + b sin Ωt`` (exact for any record length, no leakage);
    returns the phasors ``a − i b`` and the standard deviation ``σ √(2/N)`` of the real and of
    the imaginary part of their noise (``rig.phasors.phasor_noise_sd``'s convention)."""
    n = int(seconds * fs)
    t = np.arange(n) / fs
    out = np.empty_like(ph)
    for s in range(0, ph.shape[0], chunk):
        w = speeds_rpm[s:s + chunk, None] * RPM
        e = np.exp(1j * w * t[None, :])                                     # (B, n)
        raw = (ph[s:s + chunk, :, None] * e[:, None, :]).real
        raw += noise_m * rng.standard_normal(raw.shape)
        C = np.stack([e.real, e.imag], axis=1)                              # (B, 2, n)
        G = np.einsum("bin,bjn->bij", C, C)
        ab = np.linalg.solve(G[:, None], np.einsum("bcn,bin->bci", raw, C)[..., None])[..., 0]
        out[s:s + chunk] = ab[..., 0] - 1j * ab[..., 1]
    return out, noise_m * np.sqrt(2.0 / n)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=1.0)
    ap.add_argument("--probe-noise-nm", type=float, default=2.0)
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--figures", default=None, help="folder for the trend and Q-Q figures")
    a = ap.parse_args()
    rng = np.random.default_rng(a.seed)
    sp = reference_spindle()
    m = sp.model(sp.baseline)
    speeds = np.linspace(1000.0, 24000.0, 50)
    camp = phasor_campaign(m, speeds, 20, theta_std=[0.015, 0.033], noise_m=0.0, rng=rng)
    times = {}
    t0 = time.perf_counter()
    cr = condense_reactions(m, speeds)
    times["condensation (50 speeds)"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    ph, se = demodulate(camp.phasors, camp.speeds_rpm, a.seconds, a.probe_noise_nm * 1e-9, rng)
    times[f"demodulation (1 000 records x 4 ch x {a.seconds:g} s)"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    res = identify_phasors(cr, ph, camp.speeds_rpm, phasor_sd=se,
                           catalog=catalog_coefficients(m, camp.speeds_rpm))
    times["8 coefficients + covariance, closed form"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    x, r = cr.reactions(ph, camp.speeds_rpm)
    reg = phasor_time_regression(x, r, camp.speeds_rpm, n_samples=1000)
    mis = identify(reg, MISG(p=3), theta0=[2.5e8, 1e3])
    times["MISG(p=3) on 1x time samples (4 000 x 1 000)"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    k = [0, 1, 4, 5]
    ok = ~(res.at_bound[:, k].any(1) | res.unexcited[:, k].any(1))
    u = fit_uncertainty(res.estimate[ok][:, k], camp.speeds_rpm[ok], [res.names[j] for j in k],
                        per_record_cov=res.covariance[ok][:, k][:, :, k],
                        truth=camp.truth[ok][:, k])
    times["uncertainty model"] = time.perf_counter() - t0
    for name, dt in times.items():
        print(f"{name:48s} {dt:8.3f} s")
    print(f"{'total':48s} {sum(times.values()):8.3f} s  (target 30 s on 2 cores)")
    print(f"peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB; "
          f"load average {os.getloadavg()[0]:.2f}")
    print(f"records ok in k: {ok.mean():.3f}; all 8 ok: {res.ok.mean():.3f}")
    misg_k = mis.estimate[:, 0].reshape(-1, 4)[ok] / camp.truth[ok][:, k] - 1
    closed = res.raw[ok][:, k] / camp.truth[ok][:, k] - 1
    print(f"MISG vs closed form: k relative error RMS {np.sqrt(np.mean(misg_k**2)):.2e} "
          f"(closed form {np.sqrt(np.mean(closed**2)):.2e})")
    print("laws:", u.tests["trend_law"])
    meas = u.variance_split["measured"]
    print("physical std (measured):", np.round(np.sqrt(meas["physical_var"]), 4).tolist(),
          " identification fraction measured:",
          np.round(meas["identification_fraction"], 3).tolist(), " estimated:",
          np.round(u.variance_split["estimated"]["identification_fraction"], 3).tolist())
    for s in (1000.0, 12000.0, 24000.0):
        rv = u.random_vector(s, reference=model_reference(m, s, u.names))
        print(f"theta at {s:6.0f} rpm relative to the model: mean {np.round(rv.mean, 4)}, "
              f"std {np.round(rv.std, 4)}")
    det, pool = u.tests["detrended"], u.tests["pooled"]
    print("| coefficient | pooled mean ± SD (MN/m) | pooled CoV | SW p pooled | detrended CoV "
          "| SW p detrended | Q-Q R² detrended |")
    print("|---|---|---|---|---|---|---|")
    for j, c in enumerate(u.coefficients):
        mu, sd = u.pooled_mean[j], np.sqrt(u.pooled_cov[j, j])
        print(f"| {c} | {mu / 1e6:.2f} ± {sd / 1e6:.2f} | {100 * sd / mu:.2f} % | "
              f"{pool['shapiro'][c]['p_value']:.3g} | "
              f"{100 * np.sqrt(u.scatter_cov[j, j]):.2f} % | {det['shapiro'][c]['p_value']:.3g} "
              f"| {det['qq_r2'][c]:.4f} |")
    print(f"Henze-Zirkler p: pooled {pool['henze_zirkler']['p_value']:.3g}, detrended "
          f"{det['henze_zirkler']['p_value']:.3g}; Mardia skew/kurtosis p (detrended) "
          f"{det['mardia_skewness']['p_value']:.3g} / {det['mardia_kurtosis']['p_value']:.3g}")
    hi = camp.speeds_rpm[ok] >= 5000.0
    fac = res.estimate[ok][:, k] / u.trend(camp.speeds_rpm[ok])
    for label, X, names in (("detrended", fac[hi], u.coefficients),
                            ("study theta", fac[hi] @ u.weights.T, u.names)):
        sub = normality_report(X, names)
        print(f"{label}, speeds >= 5 000 rpm ({hi.sum()} records): SW p "
              f"{[round(t.p_value, 3) for t in sub.shapiro]}, Q-Q R² "
              f"{[round(r, 4) for r in sub.qq_r2]}, Henze-Zirkler p "
              f"{sub.henze_zirkler.p_value:.3g}")
    st = u.tests["study"]
    sw = [round(v["p_value"], 3) for v in st["shapiro"].values()]
    print(f"study theta, all speeds: SW p {sw}, Henze-Zirkler p "
          f"{st['henze_zirkler']['p_value']:.3g}")
    if a.figures:
        from surrogate_rbrdo.reporting.plots_identification import plot_qq, plot_trend

        X, n = res.estimate[ok][:, k], camp.speeds_rpm[ok]
        print("figures:", plot_trend(u, n, X, f"{a.figures}/identification_trend.png",
                                     truth=lambda s: catalog_coefficients(m, [s])[0, k]),
              plot_qq(X / u.trend(n), u.coefficients, f"{a.figures}/identification_qq.png"))


if __name__ == "__main__":
    main()
