"""A lean, array-based NSGA-II loop built from pymoo's own operators (``engine="lean"``).

pymoo's generic ``minimize`` loop keeps one Python object per individual; with a vectorised
surrogate the per-generation bookkeeping (``Population.get``/``set``, the per-pair tournament
loop, the feasibility split) costs ~10–15 ms per generation, ~80 % of a paper-scale run. This
loop keeps the population as arrays and calls the same numerical kernels:

* initial population: ``pymoo.operators.sampling.lhs.sampling_lhs`` (maximin LHS);
* mating: binary tournament (pymoo's ``binary_tournament`` rule, vectorised: if either design is
  infeasible the smaller total violation CV wins, else Pareto dominance, else the larger
  crowding distance; ties at random), then ``SBX._do`` applied with probability ``prob`` per
  mating, then ``PM._do`` applied with probability ``prob`` per child;
* duplicate elimination as pymoo's default (exact duplicates of the population or of other
  children are dropped and the mating repeated, up to 100 times);
* survival: feasibility first (pymoo's ``split_by_feasibility``), feasible designs by
  non-dominated rank and crowding distance (``NonDominatedSorting``, ``calc_crowding_distance``,
  ``randomized_argsort`` to break the last front), infeasible ones by CV.

The random stream differs from pymoo's (so the designs differ in detail), but the algorithm is
the same and every random number comes from one ``default_rng(seed)``: runs are bit-reproducible.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from surrogate_rbrdo.optimization.pareto import total_violation


def _rank_crowding(F: np.ndarray, n_survive: int, rng: np.random.Generator, nds, crowd
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Survivor indices of feasible ``F`` plus their rank and crowding (pymoo's rule)."""
    from pymoo.util.randomized_argsort import randomized_argsort  # heavy: see lean_nsga2

    fronts = nds.do(F, n_stop_if_ranked=n_survive)
    surv, rank, cd = [], [], []
    n = 0
    for k, front in enumerate(fronts):
        if n + len(front) > n_survive:
            n_remove = n + len(front) - n_survive
            c = crowd.do(F[front, :], n_remove=n_remove)
            order = randomized_argsort(c, order="descending", method="numpy", random_state=rng)
            order = order[:-n_remove]
        else:
            c = crowd.do(F[front, :], n_remove=0)
            order = np.arange(len(front))
        surv.append(front[order])
        rank.append(np.full(len(order), k))
        cd.append(c[order])
        n += len(order)
        if n >= n_survive:
            break
    return np.concatenate(surv), np.concatenate(rank), np.concatenate(cd)


def _survive(F, G, n_survive, rng, nds, crowd):
    cv = total_violation(G)
    feas = np.flatnonzero(cv <= 0.0)
    infeas = np.flatnonzero(cv > 0.0)
    rank = np.full(F.shape[0], np.inf)
    cd = np.zeros(F.shape[0])
    keep = np.empty(0, dtype=int)
    if feas.size:
        s, r, c = _rank_crowding(F[feas], min(n_survive, feas.size), rng, nds, crowd)
        keep = feas[s]
        rank[keep], cd[keep] = r, c
    if keep.size < n_survive:
        order = infeas[np.argsort(cv[infeas], kind="stable")]
        keep = np.concatenate([keep, order[:n_survive - keep.size]])
    return keep, rank[keep], cd[keep], cv[keep]


def _tournament(n_select: int, F, cv, cd, rng) -> np.ndarray:
    """pymoo's ``binary_tournament`` ("comp_by_dom_and_crowding"), vectorised; returns winners
    of ``n_select`` tournaments (indices into the population)."""
    n = F.shape[0]
    n_perms = int(np.ceil(2 * n_select / n))
    P = np.concatenate([rng.permutation(n) for _ in range(n_perms)])[:2 * n_select]
    a, b = P[0::2], P[1::2]
    coin = rng.random(n_select) < 0.5
    win = np.where(coin, a, b)
    infeas = (cv[a] > 0) | (cv[b] > 0)
    by_cv = np.where(cv[a] < cv[b], a, np.where(cv[b] < cv[a], b, win))
    Fa, Fb = F[a], F[b]
    a_dom = np.all(Fa <= Fb, axis=1) & np.any(Fa < Fb, axis=1)
    b_dom = np.all(Fb <= Fa, axis=1) & np.any(Fb < Fa, axis=1)
    by_cd = np.where(cd[a] > cd[b], a, np.where(cd[b] > cd[a], b, win))
    feas_win = np.where(a_dom, a, np.where(b_dom, b, by_cd))
    return np.where(infeas, by_cv, feas_win)


def _unique_rows(Q: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Mask of rows of ``Q`` that duplicate neither ``X`` nor an earlier row of ``Q``
    (exact duplicates, as pymoo's default elimination at ε = 1e-16 on these scales)."""
    seen = {r.tobytes() for r in np.ascontiguousarray(X)}
    ok = np.ones(Q.shape[0], dtype=bool)
    for i, r in enumerate(np.ascontiguousarray(Q)):
        key = r.tobytes()
        if key in seen:
            ok[i] = False
        else:
            seen.add(key)
    return ok


def lean_nsga2(evaluate, lo: np.ndarray, hi: np.ndarray, *, pop_size: int, n_gen: int,
               crossover_prob: float, crossover_eta: float, mutation_prob: float,
               mutation_prob_var: float, mutation_eta: float, eliminate_duplicates: bool,
               seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Run NSGA-II; ``evaluate(X) -> (F, G)``. Returns the final population ``(X, F, G)``."""
    # pymoo (~1.5 s of imports) only when NSGA-II runs, not on `import surrogate_rbrdo`
    from pymoo.operators.crossover.sbx import SBX
    from pymoo.operators.mutation.pm import PM
    from pymoo.operators.sampling.lhs import sampling_lhs
    from pymoo.operators.survival.rank_and_crowding.metrics import get_crowding_function
    from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

    rng = np.random.default_rng(seed)
    problem = SimpleNamespace(n_var=lo.size, xl=lo, xu=hi)
    sbx = SBX(eta=crossover_eta)
    pm = PM(prob=1.0, prob_var=mutation_prob_var, eta=mutation_eta)
    nds, crowd = NonDominatedSorting(), get_crowding_function("cd")

    X = sampling_lhs(pop_size, lo.size, lo, hi, random_state=rng)
    F, G = evaluate(X)
    keep, rank, cd, cv = _survive(F, G, pop_size, rng, nds, crowd)
    X, F, G = X[keep], F[keep], G[keep]
    n_mat = int(np.ceil(pop_size / 2))
    for _ in range(1, n_gen):
        children = np.empty((0, lo.size))
        for _attempt in range(100):
            par = _tournament(2 * n_mat, F, cv, cd, rng).reshape(n_mat, 2)
            P = np.stack([X[par[:, 0]], X[par[:, 1]]])       # (2, n_mat, d)
            Q = P.copy()
            cross = rng.random(n_mat) < crossover_prob
            if cross.any():
                Q[:, cross] = sbx._do(problem, P[:, cross], random_state=rng)
            Q = Q.reshape(-1, lo.size)
            mut = rng.random(Q.shape[0]) < mutation_prob
            if mut.any():
                Q[mut] = pm._do(problem, Q[mut], random_state=rng)
            Q = np.clip(Q, lo, hi)
            if eliminate_duplicates:
                Q = Q[_unique_rows(Q, np.vstack([X, children]))]
            children = np.vstack([children, Q])
            if children.shape[0] >= pop_size:
                break
        children = children[:pop_size]
        if children.shape[0] == 0:
            break
        Fc, Gc = evaluate(children)
        Xa, Fa, Ga = np.vstack([X, children]), np.vstack([F, Fc]), np.vstack([G, Gc])
        keep, rank, cd, cv = _survive(Fa, Ga, pop_size, rng, nds, crowd)
        X, F, G = Xa[keep], Fa[keep], Ga[keep]
    return X, F, G
