"""Where the condensation route for the flexible FE rotor breaks: prints the figures.

Reference spindle, baseline design, Table-3 softening. For each speed:

* noise gain: relative standard error of ``k`` and ``c`` (front, rear; ``yy``) per 1 % of the
  mean journal amplitude as circular phasor noise — probes on the bearings vs 167 mm inboard;
* the condition of ``A_II`` (distance from a pole of the condensed rotor);
* an unknown unbalance: the residual unbalance 10 % larger and 10° off the one assumed;
* cross-coupling ``κ = 0.002`` ignored by the diagonal model.

    PYTHONPATH=$PWD python3 benchmarks/bench_identification_assumptions.py
"""

from __future__ import annotations

import os
from dataclasses import replace

import numpy as np

from surrogate_rbrdo.identification import (
    catalog_coefficients,
    condense_reactions,
    identify_phasors,
    node_at,
)
from surrogate_rbrdo.spindle import reference_spindle, unbalance_response
from surrogate_rbrdo.spindle.effects import CrossCoupling

SPEEDS = np.array([1000.0, 5000.0, 10000.0, 15000.0, 20000.0, 21500.0, 22400.0, 23000.0,
                   24000.0])


def _ph(m, nodes, speeds=SPEEDS):
    return unbalance_response(m, speeds)[0][:, list(nodes), :2].reshape(len(speeds), -1)


def main() -> None:
    sp = reference_spindle()
    m = sp.model(sp.baseline)
    truth = catalog_coefficients(m, SPEEDS)
    on = list(m.bearing_nodes)
    inboard = [node_at(m, 266.667), node_at(m, 433.333)]
    q_on = _ph(m, on)
    # complex noise of RMS 1 % of the mean journal amplitude: 1 %/√2 on each part
    sigma = 0.01 / np.sqrt(2.0) * np.abs(q_on).mean(axis=1, keepdims=True)
    cr_on = condense_reactions(m, SPEEDS)
    cr_in = condense_reactions(m, SPEEDS, probe_nodes=inboard)
    r_on = identify_phasors(cr_on, q_on, SPEEDS, phasor_sd=sigma)
    r_in = identify_phasors(cr_in, _ph(m, inboard), SPEEDS, phasor_sd=sigma)
    # unknown unbalance: truth 10 % larger and 10° off the assumed one
    m_u = replace(m, unbalance=m.unbalance * 1.1 * np.exp(1j * np.deg2rad(10.0)))
    r_u = identify_phasors(cr_on, _ph(m_u, on), SPEEDS)
    m_x = sp.model(sp.baseline, effects=sp.effects + (CrossCoupling(kappa=0.002),))
    r_x = identify_phasors(condense_reactions(m_x, SPEEDS), _ph(m_x, on), SPEEDS)
    print("| speed (rpm) | |x| front/rear (nm) | k_f, c_f SE per 1 % noise (probes on "
          "bearings) | same, probes 167 mm inboard | cond(A_II) | unbalance +10 %, 10°: "
          "k_f, c_f error | κ = 0.002: c_f, c_r error |")
    print("|---|---|---|---|---|---|---|")
    for i, s in enumerate(SPEEDS):
        amp = np.abs(q_on[i, [0, 2]]) * 1e9
        rel_on = r_on.std[i] / truth[i]
        rel_in = r_in.std[i] / truth[i]
        eu = r_u.estimate[i] / truth[i] - 1
        ex = r_x.estimate[i] / catalog_coefficients(m_x, SPEEDS)[i] - 1
        print(f"| {s:.0f} | {amp[0]:.2f} / {amp[1]:.2f} | {100 * rel_on[0]:.2f} %, "
              f"{100 * rel_on[2]:.0f} % | {100 * rel_in[0]:.2f} %, {100 * rel_in[2]:.0f} % | "
              f"{cr_on.interior_condition[i]:.1e} | {100 * eu[0]:+.1f} %, {100 * eu[2]:+.0f} % "
              f"| {100 * ex[2]:+.0f} %, {100 * ex[6]:+.0f} % |")
    grid = np.linspace(1000.0, 24000.0, 400)
    cond = condense_reactions(m, grid).interior_condition
    R = cr_on.probe_nodes
    keep = np.setdiff1d(np.arange(m.n_dof), [4 * n + d for n in R for d in (0, 1)])
    lam = np.linalg.eigvals(np.linalg.solve(m.M[np.ix_(keep, keep)], m.K[np.ix_(keep, keep)]))
    poles = np.sort(np.sqrt(np.abs(lam.real))) * 60 / (2 * np.pi)
    print(f"cond(A_II) over 1 000-24 000 rpm: max {cond.max():.2e} at "
          f"{grid[cond.argmax()]:.0f} rpm; poles of S (journals pinned, non-rotating): "
          f"{np.round(poles[poles < 60000]).tolist()} rpm")
    print(f"load average {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
