"""The virtual rig's fast path as a data source of the blind tests (:mod:`.blind`).

Its truth with the default variability (bearing stiffness 5 %, damping 20 % per build;
thermal preload 8 % per run; tool mass 3 %; unbalance per ISO 21940 with random phases), its
sensors (gain 2 %, 10 kHz drivers, skew, 50 nm noise, 16-bit ADC, keyphasor phase errors)
through ``rig.phasors.sample_phasors``, 20 runs × 50 speeds; identified stiffness is emulated
per run (the truth's effective bearing stiffness with 0.4 % error per record, the
identification note's figure) for the sparse baseline. With ``impacts`` (an
:class:`~surrogate_rbrdo.rig.impacts.ImpactPlan`): impact tests at the tool, all in one run
after the 1x runs, through the rig's sensors (``rig.impacts.sample_frfs``). Noise levels
(:data:`FACTORS`) scale the probe noise and the run-to-run thermal scatter by 0.5, 1 and 3.
Used by ``benchmarks/discrepancy_blind.py`` and ``benchmarks/discrepancy_rival_span.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from surrogate_rbrdo.discrepancy.observables import ComplexBlock, MeasuredData, RealBlock
from surrogate_rbrdo.discrepancy.soak import SoakBlock
from surrogate_rbrdo.discrepancy.sweeps import Channel, Sweep
from surrogate_rbrdo.rig.impacts import ImpactPlan, expected_frfs, sample_frfs
from surrogate_rbrdo.rig.phasors import expected_phasors, sample_phasors
from surrogate_rbrdo.rig.sensors import ProbeModel, SensorSet
from surrogate_rbrdo.rig.simulate import ProbeLayout
from surrogate_rbrdo.rig.soak import probe_rise, soak_plan, soak_run_index, sweep_probe_rise
from surrogate_rbrdo.rig.thermal import SoakPlan
from surrogate_rbrdo.rig.truth import Truth, Variability
from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.reference import reference_spindle

#: noise levels: factors on the probe noise and the run-to-run thermal scatter
FACTORS = {"low": 0.5, "default": 1.0, "high": 3.0}


@dataclass(frozen=True)
class RigSource:
    """The virtual rig's fast path as a blind-test data source (see module doc)."""

    speeds_rpm: tuple[float, ...]
    repeats: int
    factor: dict[str, float]
    k_relative: float = 0.004
    impacts: ImpactPlan | None = None
    #: a thermal soak after the impact run (``rig.thermal.SoakPlan``; its speeds not given:
    #: by its rule from the sweep), each of its runs a cold start with its own thermal state
    soak: SoakPlan | None = None
    #: the probes' sensitivity tempco SD (1/K, ``rig.sensors.ProbeModel``; 0: none) and
    #: whether it acts on the sweep (each speed's equilibrium rise) besides the soak
    tempco_sd_per_K: float = 0.0
    tempco_sweep: bool = True

    def parts(self, geometry, effects, noise):
        f = self.factor[noise]
        var = Variability(thermal_preload_cov=0.08 * f)
        tb = tuple(b.name for b in geometry.bearings if b.name != "magnetic_pull")
        tb += ("magnetic_pull",) if len(tb) < len(geometry.bearings) else ()
        truth = Truth(geometry, effects, (), var, tb)
        return truth, SensorSet(probe=ProbeModel(noise_rms_m=50e-9 * f,
                                                 tempco_sd_per_K=self.tempco_sd_per_K,
                                                 tempco_sweep=self.tempco_sweep))

    def measure(self, geometry, effects, noise, seed) -> MeasuredData:
        truth, sensors = self.parts(geometry, effects, noise)
        ss = np.random.SeedSequence(seed)
        rng = np.random.default_rng(ss.spawn(1)[0])
        inst = sensors.install(rng)
        sp = np.asarray(self.speeds_rpm)
        warm = _sweep_gains(truth, sensors, inst, sp)
        recs, ks = [], []
        for r in range(self.repeats):
            st = truth.state(ss, build=0, tool=0, run=r)
            m = st.model()
            recs.append(sample_phasors(m, st.theta, sp, sensors, inst, rng)[0] * warm)
            Z = m.bearing_impedance(sp[None] * RPM, st.theta)[0][:, :2]
            k = np.stack([Z[..., 0, 0].real, Z[..., 1, 1].real], axis=-1)
            ks.append(k * (1 + self.k_relative * rng.normal(size=k.shape)))
        pos = ProbeLayout.of(m).positions_mm
        chans = tuple(Channel(n, pos[n.split("_")[0]], n.split("_")[1])
                      for n in sensors.probe_channels)
        blk = ComplexBlock.from_repeats("unbalance_1x", Sweep.unbalance(sp), chans,
                                        np.array(recs), {"source": "virtual rig fast path"})
        ks = np.array(ks)
        ident = RealBlock("identified_k", sp, ("front", "rear"), ks.mean(0),
                          ks.std(0, ddof=1) / np.sqrt(self.repeats), self.repeats - 1)
        blocks = (blk,) + self._impact_blocks(truth, ss, sensors, inst, chans, pos, rng)
        soaks = self._soaks(truth, ss, sensors, inst, chans, rng,
                            np.abs(np.array(recs)).max(axis=2))
        return MeasuredData(blocks, ident, {"source": "virtual rig", "seed": seed}, soaks)

    def _soaks(self, truth, ss, sensors, inst, chans, rng, amplitude
               ) -> tuple[SoakBlock, ...]:
        """The soak's runs (after the impact run) at its speeds (by default by its rule from
        the sweep as the rig's campaign takes them, ``rig.soak.soak_plan``; ``amplitude``
        (runs, speeds): each run's largest channel amplitude), run ``j`` at
        ``plan.speed_of(j)``: at each time the run's state warmed to the thermal model's
        fraction (``TruthState.warming``), a 1x phasor through the sensors (the probes' gains
        at the outer ring's rise, ``rig.soak.probe_rise``), and the run's outer-ring
        temperature; one block per speed."""
        if self.soak is None:
            return ()
        plan = soak_plan(self.soak, self.speeds_rpm, amplitude)
        t = np.asarray(plan.times_s)
        runs: dict[float, tuple[list, list]] = {s: ([], []) for s in plan.speeds}
        for j in range(plan.runs):
            speed = plan.speed_of(j)
            st = truth.state(ss, build=0, tool=0, run=soak_run_index(self.repeats, j))
            rows = []
            for f in truth.thermal.fraction(t):
                w = st.warming(float(f))
                rows.append(sample_phasors(
                    w.model(), w.theta, np.array([speed]), sensors,
                    inst.warmed(probe_rise(truth, speed, float(f))), rng)[0, 0])
            runs[speed][0].append(rows)
            runs[speed][1].append(truth.thermal.temperature_K(speed, t, rng))
        return tuple(SoakBlock(f"soak_{s:.0f}rpm", s, chans, np.tile(t, (len(Y), 1)),
                               np.array(T), np.array(Y),
                               {"source": "virtual rig fast path (soak)"})
                     for s, (Y, T) in sorted(runs.items()))

    def _impact_blocks(self, truth, ss, sensors, inst, chans, pos, rng, expected=None,
                       noise=""):
        """Impact blocks of the plan: per speed and direction the hits of the impact run (the
        run after the 1x runs: its own thermal state), or with ``expected`` (a truth state) the
        noise-free FRFs with the covariance of the means at ``noise``."""
        plan = self.impacts
        if plan is None:
            return ()
        st = expected or truth.state(ss, build=0, tool=0, run=self.repeats)
        model = st.model()
        out = []
        for s in plan.speeds_rpm:
            f = plan.lines(s)
            for d in plan.directions:
                exc = Channel(f"tool_{d}", pos["tool"], d)
                sweep = Sweep.impact(f, (exc,), s)
                name = f"impact_tool_{d}_{s:.0f}rpm"
                if expected is not None:
                    H = expected_frfs(model, st.theta, s, f, sensors, inst, d)
                    out.append(ComplexBlock(name, sweep, chans, H,
                                            _noise_cov(self, noise, name),
                                            10**9))
                    continue
                recs = sample_frfs(model, st.theta, s, f, sensors, inst, rng, direction=d,
                                   n_hits=plan.hits, duration_s=plan.duration_s)
                out.append(ComplexBlock.from_repeats(
                    name, sweep, chans, recs, {"source": "virtual rig fast path (impacts)",
                                               "speed_rpm": s}, runs=False))
        return tuple(out)

    def expected(self, geometry, effects, noise) -> MeasuredData:
        """Noise-free means of the nominal build; the covariance of the means from 200
        noise-only runs of the nominal truth at this noise level (cached per level)."""
        truth, sensors = self.parts(geometry, effects, noise)
        b = truth.draw_build(np.random.SeedSequence(0))
        b = {**b, "k_factor": [1.0] * len(b["k_factor"]),
             "damping_factor": [1.0] * len(b["damping_factor"]),
             "unbalance_kgm": [truth.permissible_unbalance_kgm() / 2] * 2,
             "unbalance_phase_deg": [0.0, 90.0]}
        st = truth.apply(b, {"mass_factor": 1.0, "interface_factor": [1.0, 1.0]},
                         {"preload_factor": [1.0] * len(b["k_factor"])})
        ideal = replace(sensors, noise=False)
        inst = ideal.install(np.random.default_rng(0))
        sp = np.asarray(self.speeds_rpm)
        y = expected_phasors(st.model(), st.theta, sp, ideal, inst)
        pos = ProbeLayout.of(st.model()).positions_mm
        chans = tuple(Channel(n, pos[n.split("_")[0]], n.split("_")[1])
                      for n in sensors.probe_channels)
        cov = _noise_cov(self, noise, "unbalance_1x")
        blk = ComplexBlock("unbalance_1x", Sweep.unbalance(sp), chans, y, cov, 10**9)
        imp = self._impact_blocks(truth, np.random.SeedSequence(0), ideal, inst, chans, pos,
                                  None, expected=st, noise=noise)
        return MeasuredData((blk,) + imp)


def _sweep_gains(truth, sensors, inst, speeds_rpm) -> np.ndarray | float:
    """Each probe's gain factor ``1 + α ΔT(Ω)`` at each steady speed's equilibrium rise
    (``(S, C)``; 1.0 without tempcos or ``tempco_sweep``; ``rig.soak.sweep_probe_rise``) —
    applied to the sampled phasors, so their noise is scaled by it too (by < 1 % at the
    data-sheet tempco)."""
    rise = sweep_probe_rise(truth, sensors.probe, speeds_rpm)
    if rise is None or not inst.tempco_per_K:
        return 1.0
    a = np.array([inst.tempco_per_K.get(c, 0.0) for c in sensors.probe_channels])
    return 1.0 + rise[:, None] * a[None, :]


_COV: dict = {}


def _noise_cov(src: RigSource, noise: str, block: str) -> np.ndarray:
    """The covariance of a block's means at a noise level: the average of 10 noise-only data
    sets' estimates (cached)."""
    key = (src.speeds_rpm, src.repeats, src.factor[noise], src.impacts)
    if key not in _COV:
        g = reference_spindle().geometry_for(reference_spindle().baseline)
        runs = [replace(src, soak=None).measure(g, reference_spindle().effects, noise,
                                                10_000 + i)
                for i in range(10)]
        _COV[key] = {b.name: np.mean([r.block(b.name).cov for r in runs], axis=0)
                     for b in runs[0].blocks}
    return _COV[key][block]
