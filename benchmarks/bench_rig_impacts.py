"""The rig's impact records, side by side: step by step (every hit simulated on its own, the
recurrence over every fine step — the code before's stepping, here as a 1 N hit scaled by the
peak, which equals a hit simulated at its peak to 1e-12: tests/rig/test_impacts.py), the free
decay in closed form (each hit still simulated on its own), and the campaign's way (one
simulation per speed and direction, scaled by each hit's peak). Prints the CPU per record of
each, the ratios, the fine outputs' largest difference from the step-by-step ones (relative to
their RMS) and whether the records' samples are identical, then the load average.

    PYTHONPATH=$PWD python3 benchmarks/bench_rig_impacts.py [--config experiments/discrepancy.toml]

The truth, sensors and impact plan are the config's ``[rig]`` (default: the shipped discrepancy
run's: 20 hits × x/y × 0, 10 000, 20 000 rpm). No timed asserts: it prints.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from surrogate_rbrdo.rig.campaign import _extras, _root_seed
from surrogate_rbrdo.rig.integrate import IntegratorOptions, SpeedProfile, simulate
from surrogate_rbrdo.rig.simulate import ProbeLayout, hammer_pulse, impact_record, impact_response
from surrogate_rbrdo.runner.execute import prepare


def _cpu(make):
    c = time.process_time()
    out = make()
    return time.process_time() - c, out


def _fine(model, theta, sensors, speed, direction, closed_form):
    """The integrator's fine outputs of a 300 N hit: probes' displacements, accelerations."""
    lay = ProbeLayout.of(model)
    fs = 4 * sensors.daq.sample_rate_hz
    tf = np.arange(int(fs)) / fs
    f = hammer_pulse(tf, 0.05, 300.0, sensors.hammer.pulse_ms * 1e-3)[:, None]
    tool = 4 * lay.nodes["tool"]
    s = simulate(model, SpeedProfile.constant(speed), tf, lay.dofs(sensors), theta=theta,
                 unbalance=False, force_dofs=np.array([tool + (direction == "y")]), force=f,
                 acc_dofs=np.array([tool, tool + 1]),
                 options=IntegratorOptions(closed_form=closed_form))
    return s.q, s.acc


def _hit(model, st, o, inst, speed, direction, closed_form):
    """One hit simulated on its own (the same stream for either integrator path)."""
    opts = IntegratorOptions(closed_form=closed_form)
    resp = impact_response(model, st.theta, o.sensors, inst, direction=direction,
                           speed_rpm=speed, duration_s=o.impact_duration_s, options=opts)
    return impact_record(model, st.theta, o.sensors, inst, np.random.default_rng(7), rid="hit",
                         provenance={}, direction=direction, speed_rpm=speed,
                         duration_s=o.impact_duration_s, response=resp)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="experiments/discrepancy.toml")
    args = ap.parse_args()
    print(f"load average at start {os.getloadavg()}")
    rig = prepare(args.config).plan.rig.rig
    truth, o = rig.truth, rig.options
    root = _root_seed(np.random.default_rng(0))
    inst = o.sensors.install(np.random.default_rng(1))
    st = truth.state(root, build=0, tool=0, run=0)
    model = st.model()
    cases = [(s, d) for s in o.impact_speeds_rpm for d in ("x", "y")]
    _fine(model, st.theta, o.sensors, 0.0, "x", True)                 # warm-up
    rows = {"step by step": 0.0, "closed form": 0.0}
    worst, same = 0.0, True
    for speed, d in cases:
        recs = []
        for label, cf in (("step by step", False), ("closed form", True)):
            cpu, rec = _cpu(lambda cf=cf, speed=speed, d=d: _hit(model, st, o, inst, speed, d, cf))
            rows[label] += cpu / len(cases)
            recs.append(rec)
        same &= bool(np.array_equal(recs[0].data, recs[1].data))
        old, new = (_fine(model, st.theta, o.sensors, speed, d, cf) for cf in (False, True))
        for a, b in zip(new, old, strict=True):            # displacements, accelerations
            worst = max(worst, float(np.max(np.abs(a - b)) / np.sqrt(np.mean(b**2))))
    hits = [make for rid, make in _extras(truth, st, o, inst, root, 0, 0) if "_hit" in rid]
    cpu, _ = _cpu(lambda: [make() for make in hits])
    rows[f"shared ({len(hits)} hits, {len(cases)} simulations)"] = cpu / len(hits)
    base = rows["step by step"]
    print(f"{'impact record':<40} {'CPU ms':>8} {'ratio':>7}")
    for name, t in rows.items():
        print(f"{name:<40} {1e3 * t:8.1f} {base / t:7.1f}")
    print(f"closed form vs step by step, fine outputs of {len(cases)} hits: max |diff| / RMS "
          "(displacements, accelerations each) "
          f"{worst:.2e}; the records' samples identical: {same}")
    print(f"load average at end {os.getloadavg()}")


if __name__ == "__main__":
    main()
