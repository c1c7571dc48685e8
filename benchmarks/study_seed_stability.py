"""Stability of a study's results over seeds: the compromise (ASF) designs, the fronts, the
front-end MBR and the FE verification, from the run folders of ``rbrdo run … --seed a b c``.

Run:  python benchmarks/study_seed_stability.py results/paper/sweep-seed2024 \
          results/paper/sweep-seed2025 results/paper/sweep-seed2026

Prints, per run of the study (``rbrdo 10%`` …):

1. each seed's compromise design, its μ/σ/P_f on the optimiser's common θ sample and with the
   FE model on fresh θ, its first critical speed (FE Campbell) and front size;
2. the spread over seeds: range of each design variable in % of the design box, of μ_FE and
   σ_FE in % of their mean;
3. the fronts checked by the FE model (``front_verification.csv``): verified designs,
   FE-non-dominated ones and how far apart they are (largest distance in % of the box);
4. the reliability constraint's activity (front designs with CRN P_f > 0.9 P_target, chosen
   designs with an FE failure) and the MBR rows (``mbr.csv``) of every seed;
5. each MBR step over the seeds: mean and [min, max], and whether the constraint acted at
   either level in any seed (an MBR between two levels where it acts at neither is noise);
6. with ``--common-theta N`` (runs of the credible problem, ``study.credible_problem()``):
   every seed's compromise designs on ONE fresh sample of N θ through the exact fast path, so
   the spread over seeds is the designs' own, free of the per-seed verification samples'
   sampling error (which section 2 contains).
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import numpy as np

from surrogate_rbrdo.study import credible_problem

NAMES = ("preload_N", "span_mm", "diameter_mm")


def rows(path: Path) -> list[dict[str, str]]:
    return list(csv.DictReader(path.open())) if path.is_file() else []


def fnum(r: dict[str, str], k: str) -> float:
    v = r.get(k, "")
    return float(v) if v not in ("", None) else float("nan")


def common(per: dict[str, list[dict]], n: int) -> None:
    """Section 6: every compromise on one common θ sample (the exact fast path)."""
    pr = credible_problem()
    theta = pr.inputs.sample(n, rng=np.random.default_rng(20261124))
    resp = pr.fe_response("condensed")
    print(f"\n6. compromises on one common sample of {n} θ (exact fast path): μ, σ (µm), "
          "spread over seeds in % of the mean (SE of μ ≈ σ/√N)")
    for lab, lst in per.items():
        y = resp(np.array([e["x"] for e in lst]), theta) * 1e6
        mu, sd = y.mean(1), y.std(1, ddof=1)
        print(f"  {lab:18s} μ {np.round(mu, 4).tolist()} σ {np.round(sd, 4).tolist()}; spread "
              f"μ {np.ptp(mu) / mu.mean() * 100:.2f} %, σ {np.ptp(sd) / sd.mean() * 100:.2f} %"
              f" (SE of μ {sd.mean() / np.sqrt(n):.5f}); max y {y.max():.3f}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("runs", nargs="+", type=Path, help="run folders (one per seed)")
    ap.add_argument("--common-theta", type=int, default=0,
                    help="evaluate every compromise on one common θ sample of this size")
    args = ap.parse_args()
    folders = [p for p in args.runs if (p / "compromises.csv").is_file()]
    box = None
    per: dict[str, list[dict]] = {}
    for f in folders:
        cfg = json.loads((f / "config.json").read_text())
        seed = cfg["experiment"]["seed"]
        meta = json.loads((f / "meta.json").read_text())
        if box is None:
            box = np.array(json.loads((f / "study_meta.json").read_text())["design_box"])
        ver = {r["design"]: r for r in rows(f / "verification.csv")}
        for r in rows(f / "compromises.csv"):
            if r.get("feasible") == "False":
                continue
            v = ver.get(r["run"], {})
            per.setdefault(r["run"], []).append({
                "seed": seed, "x": np.array([fnum(r, n) for n in NAMES]),
                "mu": fnum(r, "mean_um"), "sd": fnum(r, "std_um"), "pf": fnum(r, "pf_pct"),
                "mu_fe": fnum(v, "mean_um_fe"), "sd_fe": fnum(v, "std_um_fe"),
                "pf_fe": fnum(v, "pf_pct_fe"), "crit": fnum(v, "first_critical_rpm_fe"),
                "in_range": v.get("criticals_in_range_fe", ""),
                "front": r.get("front_size", ""), "active": r.get("front_active_1pct", ""),
                "wall": meta.get("wall_time_s")})
    print(f"{len(folders)} run folders")
    width = box[:, 1] - box[:, 0]
    print("\n1. compromise (ASF 0.5/0.5) designs per seed")
    for lab, lst in per.items():
        for e in lst:
            print(f"  {lab:18s} seed {e['seed']}: x = {np.round(e['x'], 1).tolist()}, "
                  f"CRN μ {e['mu']:.4f} σ {e['sd']:.4f} P_f {e['pf']:.2f} %; FE μ "
                  f"{e['mu_fe']:.4f} σ {e['sd_fe']:.4f} P_f {e['pf_fe']:.2f} %; first critical "
                  f"{e['crit']:.0f} rpm (in range: {e['in_range']}); front {e['front']}, "
                  f"active {e['active'] or '-'}")
    print("\n2. spread over seeds (max − min; in % of the box, and of μ_FE's mean)")
    for lab, lst in per.items():
        X = np.array([e["x"] for e in lst])
        mu = np.array([e["mu_fe"] for e in lst])
        sd = np.array([e["sd_fe"] for e in lst])
        spread = (X.max(0) - X.min(0)) / width * 100
        print(f"  {lab:18s} x: {np.round(spread, 2).tolist()} % of the box; μ_FE "
              f"{mu.mean():.4f} ± {np.ptp(mu) / 2:.4f} µm ({np.ptp(mu) / mu.mean() * 100:.1f} %)"
              f"; σ_FE {sd.mean():.4f} ± {np.ptp(sd) / 2:.4f} µm")
    print("\n3. fronts checked by the FE model")
    for f in folders:
        fv = rows(f / "front_verification.csv")
        by: dict[str, list] = {}
        for r in fv:
            by.setdefault(r["run"], []).append(r)
        for lab, lst in by.items():
            X = np.array([[fnum(r, n) for n in NAMES] for r in lst])
            nd = [r for r in lst if r["fe_nondominated"] == "True"]
            Xn = np.array([[fnum(r, n) for n in NAMES] for r in nd])
            dist = 0.0 if len(Xn) < 2 else float(np.max(np.linalg.norm(
                (Xn[:, None] - Xn[None]) / width, axis=-1)) * 100)
            print(f"  {f.name} {lab:10s}: archive front {lst[0]['front_size']}, verified "
                  f"{len(X)}, FE-non-dominated {len(nd)} (largest distance {dist:.1f} % of the "
                  f"box); FE μ {min(fnum(r, 'mean_um_fe') for r in lst):.4f}–"
                  f"{max(fnum(r, 'mean_um_fe') for r in lst):.4f} µm")
    print("\n4. MBR (mbr.csv) per seed")
    by_step: dict[tuple[str, str, str], list[dict[str, str]]] = {}
    for f in folders:
        for r in rows(f / "mbr.csv"):
            step = (r["source"], r.get("from_pct", ""), r.get("to_pct", ""))
            by_step.setdefault(step, []).append(r)
            print(f"  {f.name} {r['source']:16s} {step[1]}→{step[2]}: MBR "
                  f"{fnum(r, 'mbr_um_per_pp'):.2e} µm/pp, Δμ {fnum(r, 'delta_mean_um'):+.2e}, "
                  f"Δσ {fnum(r, 'delta_std_um'):+.2e}; constraint "
                  f"{r.get('constraint', '?')} ({r.get('active_from', '?')}/"
                  f"{r.get('active_to', '?')} front designs near P_target)")
    print("\n5. MBR over the seeds: mean, [min, max] (µm/pp); Δσ [min, max] (µm)")
    for (src, a, b), lst in by_step.items():
        m = np.array([fnum(r, "mbr_um_per_pp") for r in lst])
        ds = np.array([fnum(r, "delta_std_um") for r in lst])
        states = sorted({r.get("constraint", "?") for r in lst})
        noise = " — pure noise: no constraint active" if states == [
            "inactive at both levels"] else ""
        print(f"  {src:16s} {a}→{b}: {m.mean():.2e} [{m.min():.2e}, {m.max():.2e}]; Δσ "
              f"[{ds.min():+.2e}, {ds.max():+.2e}] ({len(lst)} seeds; constraint "
              f"{', '.join(states)}){noise}")
    if args.common_theta:
        common(per, args.common_theta)
    walls = [e["wall"] for lst in per.values() for e in lst if e["wall"]]
    if walls:
        print(f"\nwall time per run: {min(walls):.0f}–{max(walls):.0f} s")


if __name__ == "__main__":
    main()
