"""Does any candidate uncertainty model give the reference problem a μ–σ trade-off? (full FE)

Run:  OMP_NUM_THREADS=1 python benchmarks/fe_uncertainty_scenarios.py [--n-k 16] [--n-jobs 2]

Issue 5 §5 asks for a reference problem whose RBRDO fronts have ≥ 10 non-dominated designs.
With θ = bearing-stiffness factors (6 % scatter) the FE ground truth has none
(``benchmarks/fe_design_lines.py``). This script asks the same question, on a grid of designs
over the whole box, for the other uncertainty models named in docs/paper-study.md:

* ``stiffness``      θ = [k_f, k_r] only (the reference model; both unbalance planes fixed)
* ``tool_random``    + tool-holder residual unbalance as a random 2-D vector (zero mean, rms
  magnitude ``--tool-ratio`` × the plane's nominal unbalance): a new holder/angle per tool change
* ``tool_angle``     + fixed magnitudes, uniformly random angle of the tool plane relative to
  the motor plane (the holder is clamped at an arbitrary angle)
* ``bearing_damping`` bearing damping factors lognormal (CoV ``--damping-cov``), independent of
  stiffness (the paper identifies c separately); unbalance fixed
* ``iso_mass``       stiffness only, but each design's residual unbalance is the ISO 21940-11
  grade for *its own* rotor mass (the reference fixes it at the baseline mass), so thicker,
  heavier shafts pay in excitation

The unbalance scenarios use linear superposition of the FE responses to unit unbalance in each
plane (exact for the linear model) on a geometric grid of ``--n-speeds`` speeds; the peak of
each realisation is refined by the vertex of the parabola in 1/A² through the three grid
points around the grid maximum (exact for one resonant mode). ``bearing_damping`` runs the
library's peak search per sample. For each scenario it prints the designs that are
non-dominated in (μ_y, σ_y) among the grid, with P_f(y > δ_lim).
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402
from joblib import Parallel, delayed  # noqa: E402

from surrogate_rbrdo.optimization.pareto import nondominated  # noqa: E402
from surrogate_rbrdo.spindle.assembly import build_model  # noqa: E402
from surrogate_rbrdo.spindle.harmonic import (  # noqa: E402
    _parabola_peak,
    orbit_amplitude,
    peak_tool_amplitude,
    unbalance_response,
)
from surrogate_rbrdo.spindle.reference import reference_spindle  # noqa: E402
from surrogate_rbrdo.study import TABLE4_STD  # noqa: E402

STD = np.array(TABLE4_STD)   # the paper's Table 4 CoVs of the bearing stiffness


def plane_responses(sp, x, k, speeds):
    """Complex tool-tip (X, Y) per unit unbalance in each plane: (planes, N_k, S, 2)."""
    m = sp.model(np.asarray(x, float))
    out = []
    for j in range(m.unbalance.size):
        unit = np.zeros_like(m.unbalance)
        unit[j] = 1.0
        q = unbalance_response(replace(m, unbalance=unit), speeds, k)
        out.append(q[..., m.tool_node, :2])
    return np.stack(out), m.unbalance.real.copy(), m.rotor_mass_kg


def damping_samples(sp, x, k, c):
    """Peak tool amplitude (m) with bearing damping factors ``c`` (N, 2) and stiffness ``k``."""
    g = sp.geometry_for(np.asarray(x, float))
    y = np.empty(k.shape[0])
    for i in range(k.shape[0]):
        bs = tuple(replace(b, law=replace(b.law, damping_eta_s=b.law.damping_eta_s * c[i, j]))
                   for j, b in enumerate(g.bearings))
        m = build_model(replace(g, bearings=bs), sp.effects, theta_bearings=sp.theta_bearings)
        y[i] = peak_tool_amplitude(m, k[i]).amplitude[0]
    return y


def grid_peak(amp, speeds):
    """Peak over the last axis, refined at interior maxima by the 1/A² parabola vertex."""
    j = np.argmax(amp, axis=-1)
    best = np.take_along_axis(amp, j[..., None], -1)[..., 0]
    jj = np.clip(j, 1, amp.shape[-1] - 2)
    x3 = np.stack([speeds[jj + d] for d in (-1, 0, 1)])
    y3 = np.stack([np.take_along_axis(amp, (jj + d)[..., None], -1)[..., 0] for d in (-1, 0, 1)])
    xv, uv = _parabola_peak(x3, 1.0 / y3**2)
    with np.errstate(invalid="ignore", divide="ignore"):
        vert = 1.0 / np.sqrt(np.where(uv > 0, uv, np.nan))
    ok = (j == jj) & (xv > x3[0]) & (xv < x3[2]) & (vert > best)
    return np.where(ok, vert, best)


def front(mu, sd):
    """Indices of the (μ, σ)-non-dominated designs, sorted by μ."""
    idx = np.flatnonzero(nondominated(np.column_stack([mu, sd])))
    return idx[np.argsort(mu[idx], kind="stable")]


def report(name, X, y_um, delta_lim_um):
    mu, sd = y_um.mean(1), y_um.std(1, ddof=1)
    pf = (y_um > delta_lim_um).mean(1)
    nd = front(mu, sd)
    print(f"\n[{name}] non-dominated designs: {len(nd)} of {len(X)}")
    print("   F_N   L_mm  D_mm     mu_um    sd_um   sd/mu    P_f")
    for i in nd:
        F, L, D = X[i]
        print(f"  {F:5.0f} {L:6.1f} {D:5.1f} {mu[i]:9.3f} {sd[i]:8.4f} {sd[i] / mu[i]:7.3f} "
              f"{pf[i]:6.3f}")
    res = np.flatnonzero(mu > 3.0)
    if res.size:
        print(f"  resonant designs (mu > 3 um): {res.size}, sd/mu "
              f"{np.min(sd[res] / mu[res]):.4f} .. {np.max(sd[res] / mu[res]):.4f}; "
              "non-dominated among them only (a box without subcritical designs):")
        for i in res[front(mu[res], sd[res])]:
            F, L, D = X[i]
            print(f"  {F:5.0f} {L:6.1f} {D:5.1f} {mu[i]:9.3f} {sd[i]:8.4f} "
                  f"{sd[i] / mu[i]:7.3f} {pf[i]:6.3f}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n-k", type=int, default=16, help="stiffness samples")
    ap.add_argument("--n-z", type=int, default=48, help="unbalance realisations per k sample")
    ap.add_argument("--n-speeds", type=int, default=400)
    ap.add_argument("--tool-ratio", type=float, default=1.0)
    ap.add_argument("--damping-cov", type=float, default=0.2)
    ap.add_argument("--delta-lim-um", type=float, default=19.5)
    ap.add_argument("--preloads", type=float, nargs="+", default=[1000.0, 2000.0, 3000.0])
    ap.add_argument("--spans", type=float, nargs=3, default=[300.0, 750.0, 10],
                    metavar=("START", "STOP", "NUM"))
    ap.add_argument("--diameters", type=float, nargs=3, default=[50.0, 80.0, 7],
                    metavar=("START", "STOP", "NUM"))
    ap.add_argument("--skip-damping", action="store_true")
    ap.add_argument("--n-jobs", type=int, default=2)
    args = ap.parse_args()
    rng = np.random.default_rng(11)
    k = 1.0 + STD * rng.standard_normal((args.n_k, 2))
    spans = np.linspace(args.spans[0], args.spans[1], int(args.spans[2]))
    diams = np.linspace(args.diameters[0], args.diameters[1], int(args.diameters[2]))
    X = np.array([[F, L, D] for F in args.preloads for L in spans for D in diams])
    speeds = np.geomspace(1000.0, 24000.0, args.n_speeds)
    t = time.time()
    sp = reference_spindle()
    out = Parallel(n_jobs=args.n_jobs)(delayed(plane_responses)(sp, x, k, speeds) for x in X)
    H = np.stack([o[0] for o in out])  # (P, planes, N_k, S, 2)
    U = out[0][1]
    print(f"grid {len(X)} designs x {args.n_k} stiffness samples x {args.n_speeds} speeds; "
          f"plane unbalances {np.round(U * 1e6, 3).tolist()} g mm; FE {time.time() - t:.0f} s")

    def peaks(u_motor, u_tool):  # u_*: (N_z,) complex -> (P, N_k * N_z) in um
        q = (u_motor[None, None, :, None, None] * H[:, 1, :, None]
             + u_tool[None, None, :, None, None] * H[:, 0, :, None])
        return grid_peak(orbit_amplitude(q[..., 0], q[..., 1]), speeds).reshape(len(X), -1) * 1e6

    ones = np.ones(1, complex)
    y_k = peaks(U[1] * ones, U[0] * ones)
    report("stiffness", X, y_k, args.delta_lim_um)
    mass = np.array([o[2] for o in out])
    m_base = sp.model(sp.baseline).rotor_mass_kg
    report(f"iso_mass (U per design's rotor mass {mass.min():.1f}-{mass.max():.1f} kg, "
           f"baseline {m_base:.1f} kg)", X, y_k * (mass / m_base)[:, None], args.delta_lim_um)
    s = args.tool_ratio * U[0] / np.sqrt(2.0)
    z = s * (rng.standard_normal(args.n_z) + 1j * rng.standard_normal(args.n_z))
    report(f"tool_random (rms |U_tool| = {args.tool_ratio} x {U[0] * 1e6:.2f} g mm)", X,
           peaks(U[1] * np.ones(args.n_z), z), args.delta_lim_um)
    phi = np.linspace(0.0, 2 * np.pi, args.n_z, endpoint=False)
    report("tool_angle", X, peaks(U[1] * np.ones(args.n_z), U[0] * np.exp(1j * phi)),
           args.delta_lim_um)
    if not args.skip_damping:
        t = time.time()
        c = np.exp(args.damping_cov * rng.standard_normal((args.n_k, 2)))
        y = np.array(Parallel(n_jobs=args.n_jobs)(delayed(damping_samples)(sp, x, k, c) for x in X))
        report(f"bearing_damping (CoV {args.damping_cov})", X, y * 1e6, args.delta_lim_um)
        print(f"  ({time.time() - t:.0f} s)")


if __name__ == "__main__":
    main()
