"""A recording wrapper around ``Formulation.evaluate`` shared by every optimiser backend.

Each call evaluates one batch (one generation for NSGA-II), appends it to the archive (the
arrays are kept by reference, concatenated once at the end), sums the surrogate and model calls
and writes a one-line history entry. Optionally advances a tqdm progress bar.
"""

from __future__ import annotations

import numpy as np
from tqdm.auto import tqdm

from surrogate_rbrdo.optimization.pareto import feasible_pareto
from surrogate_rbrdo.optimization.result import (
    Archive,
    ArchiveRecorder,
    OptimizationResult,
    batch_history,
)


class RecordingEvaluator:
    """``X (P, d) -> (F, G)`` that records every design it sees.

    Parameters
    ----------
    formulation : Formulation
        Anything with ``evaluate(x) -> Evaluation``, ``n_obj`` and ``n_con``.
    progress : bool
        Show a tqdm bar with ``total`` batches.
    total : int or None
        Expected number of batches (for the progress bar).
    desc : str
        Progress-bar label.
    """

    def __init__(self, formulation, *, progress: bool = False, total: int | None = None,
                 desc: str = "optimising") -> None:
        self.formulation = formulation
        self.recorder = ArchiveRecorder()
        self.n_surrogate_calls = 0
        self.n_model_calls = 0
        self.history: list[dict] = []
        self._bar = None
        if progress:
            self._bar = tqdm(total=total, desc=desc, unit="gen", leave=False)

    def __call__(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        X = np.array(X, dtype=float)  # own copy: the optimiser may reuse its buffer
        ev = self.formulation.evaluate(X)
        F = np.asarray(ev.F, dtype=float)
        G = np.asarray(ev.G, dtype=float).reshape(X.shape[0], -1)
        est = ev.estimate
        self.recorder.add(X, F, G, np.asarray(est.mean, dtype=float),
                          np.asarray(est.std, dtype=float), np.asarray(est.pf, dtype=float))
        self.n_surrogate_calls += int(ev.n_surrogate_calls)
        self.n_model_calls += int(ev.n_model_calls)
        self.history.append(batch_history(self.recorder.n_batches - 1, F, G))
        if self._bar is not None:
            self._bar.update(1)
        return F, G

    def close_progress(self) -> None:
        """Close the progress bar (safe to call in a ``finally``: never raises)."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def freeze(self) -> Archive:
        """The frozen archive; ``ValueError`` if no design was evaluated."""
        return self.recorder.freeze()

    def close(self) -> Archive:
        """Close the progress bar and return the frozen archive.

        Optimisers call :meth:`close_progress` in their ``finally`` and :meth:`freeze` after a
        successful run, so that an error raised while evaluating (e.g. in generation 0) is not
        replaced by the empty-archive error of :meth:`freeze`.
        """
        self.close_progress()
        return self.freeze()

    def result(self, archive: Archive, X: np.ndarray, F: np.ndarray, G: np.ndarray,
               wall_time_s: float, optimizer: dict) -> OptimizationResult:
        """The :class:`OptimizationResult` of a finished run (final population ``X, F, G``,
        Pareto mask, archive, call counts, history, formulation and ``optimizer`` info)."""
        return OptimizationResult(
            X=X, F=F, G=G, pareto_mask=feasible_pareto(F, G), archive=archive,
            n_surrogate_calls=self.n_surrogate_calls, n_model_calls=self.n_model_calls,
            history=tuple(self.history), wall_time_s=wall_time_s,
            formulation=self.formulation.describe(), optimizer=optimizer,
        )
