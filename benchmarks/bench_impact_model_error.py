"""The impact fit's model-error tests (``identification.impact``: FRF lack of fit and delay
plausibility) on right models and on a hidden tool interface, at scaled sensor noise.

    PYTHONPATH=$PWD python3 benchmarks/bench_impact_model_error.py ok 0.03 4001 12 3 0.5
    PYTHONPATH=$PWD python3 benchmarks/bench_impact_model_error.py bad 10 4001 12 3 0.5

Arguments: truth (``ok``: the default truth's draws, a model that can represent it; ``bad``: the
hidden tool interface of ``experiments/rig_campaign_trial.toml``, k_t = 3e8 N/m,
k_r = 5e6 N m/rad), noise scale of the hammer and the accelerometer, first seed, number of
rigs, hits per direction, hit length (s). One speed (10 000 rpm), default gains, skews and
quantisation. Prints per rig χ²_J/ν and the delay statistic with their thresholds, the flag,
η's error, SE and z, the fitted delays against the rig's skews, then the count flagged
(docs/identification.md §5b).
"""

from __future__ import annotations

import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

from surrogate_rbrdo.identification.impact import impact_damping
from surrogate_rbrdo.rig import CampaignOptions, open_dataset, reference_truth, run_campaign
from surrogate_rbrdo.rig.sensors import AccelerometerModel, HammerModel, SensorSet
from surrogate_rbrdo.spindle import reference_spindle

HIDDEN = [{"name": "tool_interface", "k_t_N_per_m": 3e8, "k_r_Nm_per_rad": 5e6}]


def main(kind: str, scale: float, seed0: int, n: int, hits: int, dur: float) -> None:
    sp = reference_spindle()
    model = sp.model(sp.baseline)
    sens = SensorSet(hammer=HammerModel(noise_N=0.2 * scale),
                     accelerometer=AccelerometerModel(noise_rms_ms2=0.00015 * 9.80665 * scale))
    truth = reference_truth(hidden=HIDDEN if kind == "bad" else [])
    flagged = 0
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(seed0, seed0 + n):
            p = Path(tmp) / str(seed)
            run_campaign(truth, CampaignOptions(
                speeds_rpm=(10000.0,), repeats=1, runup=None, impacts_per_direction=hits,
                impact_duration_s=dur, sensors=sens), p, rng=np.random.default_rng(seed))
            ds = open_dataset(p / "dataset")
            recs = [ds.load(r) for r in ds.index if r["kind"] == "impact"]
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                res = impact_damping(model, recs)
            pv = recs[0].provenance
            eta = 4e-6 * np.array(pv["truth_draws"]["build"]["damping_factor"])
            err = np.log(res.eta_s / eta)
            sk = pv["sensor_installation"]["skew_s"]
            lof = res.lack_of_fit
            flagged += lof.flagged
            print(f"{kind} x{scale:g} seed {seed} hits {hits}: chi2/nu {lof.chi2_dof:.2f} "
                  f"(thr {lof.threshold:.1f}) delay stat {lof.delay_chi2:.1f} "
                  f"(thr {lof.delay_threshold:.1f}) flagged {lof.flagged}; "
                  f"log eta err {np.round(err, 4)} se {np.round(res.eta_rel_se, 4)} "
                  f"z {np.round(err / res.eta_rel_se, 1)}; delay us "
                  f"{np.round(np.array(lof.delays_s) * 1e6, 3)} rig skew difference "
                  f"{np.round([(sk['hammer'] - sk[f'tool_a{d}']) * 1e6 for d in 'xy'], 3)}",
                  flush=True)
    print(f"{kind} x{scale:g}, {hits} hits of {dur:g} s: flagged {flagged} of {n}")


if __name__ == "__main__":
    a = sys.argv[1:]
    main(a[0], float(a[1]), int(a[2]), int(a[3]), int(a[4]), float(a[5]))
