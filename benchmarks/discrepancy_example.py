"""The worked example of docs/discrepancy.md: the experiment configs run end to end on the
virtual rig (what the runner's kind `discrepancy` will do), with timings.

    PYTHONPATH=$PWD python3 benchmarks/discrepancy_example.py experiments/discrepancy.toml \
        --out /tmp/<you>/discrepancy

Simulates the rig campaign of ``[rig]`` (``rig.campaign.run_campaign``: time-domain records,
demodulated into ``phasors.csv``), reads it back as measured data, runs the workflow, writes the
run folder (findings.json, spindle_updated.toml, tables, figures) and prints the findings and
the seconds of each step (measured under load: the load average is printed).
"""

from __future__ import annotations

import argparse
import json
import os
import time
import tomllib
from pathlib import Path

import numpy as np

from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.discrepancy.experiment import analyse, data_from_folder, options_from_dict
from surrogate_rbrdo.reporting.plots_discrepancy import plot_all
from surrogate_rbrdo.spindle.config import SpindleTable, build_spindle


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("config")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    from surrogate_rbrdo.rig.campaign import run_campaign  # the virtual rig (issue 14)
    from surrogate_rbrdo.rig.config import RigTable

    cfg = tomllib.loads(Path(args.config).read_text())
    out = Path(args.out)
    seed = int(cfg["experiment"].get("seed", 0))
    sp = build_spindle(parse(SpindleTable, cfg["spindle"], "spindle"))
    t0 = time.perf_counter()
    rig = parse(RigTable, cfg["rig"], "rig").config()
    run_campaign(rig.truth, rig.options, out / "rig", rng=np.random.default_rng(seed))
    t1 = time.perf_counter()
    options = options_from_dict(cfg.get("discrepancy", {}))
    data = data_from_folder(out / "rig", impacts=options.use_impacts)
    res, paths = analyse(data, sp.geometry_for(sp.baseline), sp.effects,
                         spindle_section=cfg["spindle"], options=options,
                         rng=np.random.default_rng([seed, 1]), out_dir=out)
    t2 = time.perf_counter()
    paths.update(plot_all(res, out))
    t3 = time.perf_counter()
    f = json.loads(paths["findings"].read_text())
    print(json.dumps({k: f[k] for k in ("verdict", "effects", "confounded_with", "test",
                                        "gap")}, indent=1))
    print(f"rig campaign {t1 - t0:.1f} s, workflow {t2 - t1:.1f} s, figures {t3 - t2:.1f} s; "
          f"load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
