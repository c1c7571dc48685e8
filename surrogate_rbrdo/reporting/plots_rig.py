"""Figures of a virtual-rig campaign: Bode with ±2σ over repeats, polar, orbit, Campbell from
run-ups against the model's, FRF with coherence, run-up waterfall; and the summary they read.

:func:`write_rig_report` makes all of them from a :class:`~surrogate_rbrdo.rig.campaign.
CampaignResult` and its truth, and writes ``rig_summary.json``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
from scipy.signal import spectrogram

from surrogate_rbrdo.reporting.figures import pyplot as _plt
from surrogate_rbrdo.reporting.figures import save_figure
from surrogate_rbrdo.rig.campaign import CampaignResult
from surrogate_rbrdo.rig.config import RigConfig
from surrogate_rbrdo.rig.demod import critical_speeds_from_ramp, track_1x
from surrogate_rbrdo.rig.frf import h1_frf, modal_fit
from surrogate_rbrdo.rig.store import open_dataset
from surrogate_rbrdo.rig.truth import Truth
from surrogate_rbrdo.spindle.assembly import build_model
from surrogate_rbrdo.spindle.harmonic import unbalance_response
from surrogate_rbrdo.spindle.modal import campbell


def _save(plt, fig, path: Path) -> Path:
    fig.tight_layout()
    return save_figure(fig, path)


def bode_stats(result: CampaignResult, channel: str) -> dict[str, np.ndarray]:
    """Per speed: mean complex 1x phasor over repeats, and the SD of amplitude and phase."""
    t = result.phasors
    sel = t.array("channel") == channel
    sp = t.array("speed_rpm")[sel]
    X = t.array("re_m")[sel] + 1j * t.array("im_m")[sel]
    speeds = np.unique(sp)
    mean = np.array([X[sp == s].mean() for s in speeds])
    amp_sd = np.array([np.abs(X[sp == s]).std(ddof=1) if (sp == s).sum() > 1 else 0.0
                       for s in speeds])
    ph_sd = np.array([np.degrees(np.angle(X[sp == s] / mean[i])).std(ddof=1)
                      if (sp == s).sum() > 1 else 0.0 for i, s in enumerate(speeds)])
    return {"speed_rpm": speeds, "mean": mean, "amp_sd": amp_sd, "phase_sd_deg": ph_sd}


def plot_bode(result: CampaignResult, curves: dict[str, tuple[np.ndarray, np.ndarray]],
              path: Path, channels: tuple[str, ...] = ("tool_x", "front_x", "rear_x")) -> Path:
    """Amplitude (µm) and phase (deg) vs speed: measured mean ± 2σ over repeats per channel,
    and reference curves ``{label: (speeds_rpm, X (S, n_channels))}``."""
    plt = _plt()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7.5, 6), sharex=True)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, ch in enumerate(channels):
        s = bode_stats(result, ch)
        amp = np.abs(s["mean"]) * 1e6
        c = colors[i % len(colors)]
        a1.fill_between(s["speed_rpm"], amp - 2e6 * s["amp_sd"], amp + 2e6 * s["amp_sd"],
                        color=c, alpha=0.25, lw=0)
        a1.plot(s["speed_rpm"], amp, "o", ms=3, color=c, label=f"{ch} measured (±2σ)")
        ph = np.degrees(np.angle(s["mean"]))
        a2.errorbar(s["speed_rpm"], ph, yerr=2 * s["phase_sd_deg"], fmt="o", ms=3, color=c)
        for k, (label, (sp, X)) in enumerate(curves.items()):
            a1.plot(sp, np.abs(X[:, i]) * 1e6, ("-", "--", ":")[k % 3], color=c, lw=1,
                    label=f"{ch} {label}")
            a2.plot(sp, np.degrees(np.angle(X[:, i])), ("-", "--", ":")[k % 3], color=c, lw=1)
    a1.set_yscale("log")
    a1.set_ylabel("1x amplitude (µm)")
    a2.set_ylabel("1x phase (deg)")
    a2.set_xlabel("speed (rpm)")
    a1.legend(fontsize=7, ncol=2)
    a1.set_title("Bode: measured 1x (mean ± 2σ over repeats) vs FE")
    return _save(plt, fig, path)


def plot_polar(result: CampaignResult, path: Path, channel: str = "tool_x") -> Path:
    """Polar plot of the mean 1x phasor over speed (µm), speeds annotated."""
    plt = _plt()
    s = bode_stats(result, channel)
    X = s["mean"] * 1e6
    fig, ax = plt.subplots(figsize=(5.5, 5.5))
    ax.plot(X.real, X.imag, "-o", ms=3)
    for sp, x in list(zip(s["speed_rpm"], X, strict=True))[:: max(1, len(X) // 8)]:
        ax.annotate(f"{sp:.0f}", (x.real, x.imag), fontsize=7)
    ax.axhline(0, color="0.7", lw=0.5)
    ax.axvline(0, color="0.7", lw=0.5)
    ax.set_aspect("equal")
    ax.set_xlabel("Re X (µm)")
    ax.set_ylabel("Im X (µm)")
    ax.set_title(f"Polar plot of the 1x response, {channel}")
    return _save(plt, fig, path)


def plot_orbit(record, path: Path, target: str = "tool", n_rev: int = 5) -> Path:
    """Orbit (µm) of a steady record at ``target``: raw samples of ``n_rev`` revolutions."""
    plt = _plt()
    x = record.values(f"{target}_x")
    y = record.values(f"{target}_y")
    n = int(min(x.size, n_rev * 60.0 / record.speed_rpm * record.sample_rate_hz))
    fig, ax = plt.subplots(figsize=(5, 5))
    ax.plot((x[:n] - x.mean()) * 1e6, (y[:n] - y.mean()) * 1e6, "-", lw=0.8)
    ax.set_aspect("equal")
    ax.set_xlabel("x (µm)")
    ax.set_ylabel("y (µm)")
    ax.set_title(f"Orbit at {target}, {record.speed_rpm:.0f} rpm (record {record.id})")
    return _save(plt, fig, path)


def plot_campbell_runup(camp, measured: dict[str, list[float]], path: Path) -> Path:
    """The model's Campbell diagram with the critical speeds measured in run-ups/run-downs."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    sp = camp.speeds_rpm
    top = max(sp[-1] / 60.0 * 1.6, 1.0)
    labelled: set[str] = set()
    for k in range(camp.frequency_hz.shape[1]):
        for whirl, ls in (("forward", "-"), ("backward", "--")):
            f = np.where(camp.whirl[:, k] == whirl, camp.frequency_hz[:, k], np.nan)
            if np.any(f < top):
                ax.plot(sp, f, ls, color="0.4", lw=1, label=None if whirl in labelled
                        else f"model, {whirl} whirl")
                labelled.add(whirl)
    hidden = int(np.sum(np.nanmin(camp.frequency_hz, axis=0) >= top))
    ax.plot(sp, sp / 60.0, "k:", lw=1, label="1x")
    ax.plot(camp.critical_speeds_rpm, camp.critical_speeds_rpm / 60.0, "o", mfc="none",
            color="k", ms=9, label="model critical speeds")
    for (label, vals), mk in zip(measured.items(), ("^", "v", "s"), strict=False):
        v = np.asarray(vals)
        ax.plot(v, v / 60.0, mk, ms=7, label=f"measured ({label})")
    ax.set_xlabel("speed (rpm)")
    ax.set_ylabel("frequency (Hz)")
    ax.set_ylim(0, top)
    ax.legend(fontsize=8)
    more = f"\n({hidden} of the model's {camp.frequency_hz.shape[1]} modes lie above " \
        f"{top:.0f} Hz, not shown)" if hidden else ""
    ax.set_title(f"Campbell: model vs critical speeds from run-ups{more}", fontsize=10)
    return _save(plt, fig, path)


def plot_frf(est, fit, path: Path) -> Path:
    """H1 magnitude and coherence of the impact tests; identified modes marked."""
    plt = _plt()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True,
                                 gridspec_kw={"height_ratios": [3, 1]})
    band = (est.freq_hz > 5) & (est.freq_hz < est.freq_hz[-1] * 0.8)
    Hr = est.receptance()
    for j, ch in enumerate(est.responses):
        a1.semilogy(est.freq_hz[band], np.abs(Hr[j, band]), lw=0.9, label=ch)
        a2.plot(est.freq_hz[band], est.coherence[j, band], lw=0.8)
    for f, z in zip(fit.frequency_hz, fit.damping_ratio, strict=True):
        a1.axvline(f, color="k", lw=0.5, ls=":")
        a1.annotate(f"{f:.0f} Hz\nζ={z:.2%}", (f, a1.get_ylim()[1]), fontsize=7, va="top")
    a1.set_ylabel("|H1| as receptance (m/N)")
    a2.set_ylabel("coherence")
    a2.set_xlabel("frequency (Hz)")
    a1.legend(fontsize=8)
    a1.set_title(f"Impact tests: H1 over {est.n_averages} hits")
    return _save(plt, fig, path)


def plot_waterfall(record, path: Path, channel: str = "tool_x") -> Path:
    """Spectrogram of a run-up channel with the 1x line (a waterfall seen from above)."""
    plt = _plt()
    x = record.values(channel)
    f, t, S = spectrogram(x - x.mean(), fs=record.sample_rate_hz, nperseg=2048, noverlap=1024)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    sp = record.speed_at(t)
    keep = f < 1200
    mesh = ax.pcolormesh(sp, f[keep], 10 * np.log10(S[keep] + 1e-40), shading="auto")
    fig.colorbar(mesh, ax=ax, label="PSD (dB re 1 m²/Hz)")
    ax.plot(sp, sp / 60.0, "w:", lw=1, label="1x")
    ax.legend(fontsize=8, loc="upper left")
    ax.set_xlabel("speed (rpm)")
    ax.set_ylabel("frequency (Hz)")
    ax.set_title(f"{record.kind} waterfall (spectrogram), {channel}")
    return _save(plt, fig, path)


def write_rig_report(result: CampaignResult, truth: Truth, out_dir: str | Path
                     ) -> dict[str, Any]:
    """All figures of a campaign and ``rig_summary.json``: critical speeds from the ramps
    (vs the model's), modal fit of the impact tests, 1x statistics; returns the summary."""
    out = Path(out_dir)
    fig_dir = out / "figures"
    fig_dir.mkdir(parents=True, exist_ok=True)
    ds = open_dataset(result.dataset)
    first = ds.load(ds.select(kind="steady")[0])
    prov = first.provenance
    st = truth.apply(*(prov["truth_draws"][k] for k in ("build", "tool", "run")))
    true_model = st.model()
    nominal = build_model(st.geometry, truth.effects, theta_bearings=truth.theta_bearings)
    present = set(result.phasors.array("channel").tolist())
    channels = tuple(c for c in ("tool_x", "front_x", "rear_x") if c in present)
    main = channels[0]
    sp = np.geomspace(min(result.phasors.array("speed_rpm")),
                      max(result.phasors.array("speed_rpm")), 300)
    curves = {}
    for label, m, th in (("truth (noise-free, run 0)", true_model, st.theta),
                         ("model (no hidden effects, nominal θ)", nominal, None)):
        Q = unbalance_response(m, sp, th)[0]
        nodes = {"tool": m.tool_node, "front": m.bearing_nodes[0], "rear": m.bearing_nodes[1]}
        curves[label] = (sp, np.stack([Q[:, nodes[c.split("_")[0]], 0] for c in channels],
                                      axis=1))
    figs = [plot_bode(result, curves, fig_dir / "bode.png", channels),
            plot_polar(result, fig_dir / "polar.png", main)]
    steady = ds.select(kind="steady")
    top = max(steady, key=lambda r: r["speed_rpm"])
    figs.append(plot_orbit(ds.load(top), fig_dir / "orbit.png", main.split("_")[0]))
    summary: dict[str, Any] = {"n_records": result.n_records, "seconds": result.seconds}
    measured: dict[str, list[float]] = {}
    for rid in result.ramps:
        rec = ds.load(rid)
        cs = critical_speeds_from_ramp(track_1x(rec, (main,)), main)
        measured[rec.kind] = [c.speed_rpm for c in cs]
        summary[f"critical_speeds_{rec.kind}_rpm"] = measured[rec.kind]
        summary[f"amplification_factors_{rec.kind}"] = [c.amplification_factor for c in cs]
        if rec.kind == "runup":
            figs.append(plot_waterfall(rec, fig_dir / "waterfall_runup.png", main))
    if result.ramps:
        cb = campbell(nominal, np.linspace(0.0, nominal.geometry.speed_max_rpm * 1.1, 23))
        summary["model_critical_speeds_rpm"] = cb.critical_speeds_rpm.tolist()
        figs.append(plot_campbell_runup(cb, measured, fig_dir / "campbell_runup.png"))
    hits = [ds.load(rid) for rid in result.impacts if "_hit_x" in rid]
    if hits:
        acc = [c.name for c in hits[0].find("acceleration", "tool", "x")]
        est = h1_frf(hits, acc or channels[:2])    # the tool's accelerometer, else probes
        fit = modal_fit(est, (50.0, 0.4 * hits[0].sample_rate_hz))
        summary["impact_modes_hz"] = fit.frequency_hz.tolist()
        summary["impact_damping_ratios"] = fit.damping_ratio.tolist()
        figs.append(plot_frf(est, fit, fig_dir / f"frf_{main}.png"))
    summary["figures"] = [str(p.relative_to(out)) for p in figs]
    (out / "rig_summary.json").write_text(json.dumps(summary, indent=2))
    return summary


def rig_summary(result: CampaignResult, rig: RigConfig, out_dir: str | Path) -> dict[str, Any]:
    """A campaign's report (:func:`write_rig_report` when ``rig.figures``) and its summary:
    ``meta`` (records, dataset, campaign seconds) and ``summary`` rows."""
    summary = write_rig_report(result, rig.truth, out_dir) if rig.figures else {}
    rows = [{"quantity": k, "value": v} for k, v in summary.items()
            if k not in ("figures", "seconds", "n_records")]
    return {"meta": {"n_records": result.n_records, "dataset": "campaign/dataset",
                     "campaign_s_last_session": result.seconds},
            "summary": [{"quantity": "records", "value": result.n_records}, *rows]}
