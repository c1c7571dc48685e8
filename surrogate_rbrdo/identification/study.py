"""The study's θ from an identification: what ``[uncertainty] from = "<run or file>"`` gives.

:func:`study_uncertainty` loads an identified uncertainty model (a run folder with
``uncertainty.json``, the file itself, or the object) and returns the random vector of the
study's θ — stiffness factors on the bearings named ``theta_bearings`` — at the response's
speed or speeds:

* mean: the identified trend at the speed relative to the nominal stiffness of a reference
  model (the one the records were identified against, stored with the model, or the study's
  own ``reference`` model): ``θ̄_b(Ω) = k̄_b(Ω) / k_ref,b(Ω)``;
* covariance: the scatter at that speed (physical by default; ``scatter="total"`` adds the
  identification error at that speed) plus the trends' own uncertainty (statistical over runs
  and systematic from the measurement chain);
* at several speeds (a response that is a peak over a speed range): one MVN per speed, and
  :attr:`StudyUncertainty.random_vector` — the moment-matched mixture over them (mean of the
  means; mean covariance plus the covariance of the means), since the study's θ is one vector
  for all speeds.

Provenance (the source file and its SHA-256, the identification's own provenance, the speeds,
the choices) goes with it, for ``meta.json``.

>>> import numpy as np
>>> from surrogate_rbrdo.identification.scatter import fit_uncertainty
>>> n = np.repeat(np.linspace(1000, 24000, 24), 20)
>>> rng = np.random.default_rng(0)
>>> k = 3e8 * (1 - 0.1 * (n / 24000) ** 2)[:, None] * (1 + 0.02 * rng.normal(size=(480, 2)))
>>> u = fit_uncertainty(k, n, ("front_k_yy", "front_k_zz"),
...                     reference=([1000.0, 24000.0], [[3e8], [2.7e8]]))
>>> su = study_uncertainty(u, [24000.0], theta_bearings=("front",))
>>> su.names, round(float(su.random_vector.mean[0]), 2)
(('front',), 1.0)
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from surrogate_rbrdo.core.files import read_input
from surrogate_rbrdo.core.validate import check_choice
from surrogate_rbrdo.identification.model import (
    SCATTERS,
    IdentifiedUncertainty,
    model_reference,
)
from surrogate_rbrdo.spindle.assembly import SpindleModel
from surrogate_rbrdo.uncertainty.factors import stiffness_factors
from surrogate_rbrdo.uncertainty.mvn import MultivariateNormal

#: what of an identification run's ``meta.json`` goes into the study's provenance
RUN_META_KEYS = ("experiment", "run_id", "kind", "status", "finished_utc", "git_sha",
                 "source_sha256", "seeds")


@dataclass(frozen=True, eq=False)
class StudyUncertainty:
    """The study's θ at ``speeds_rpm``: ``mean (S, m)``, ``cov (S, m, m)``, with provenance."""

    names: tuple[str, ...]
    speeds_rpm: np.ndarray
    mean: np.ndarray
    cov: np.ndarray
    provenance: dict = field(default_factory=dict)

    def at(self, speed_rpm: float) -> MultivariateNormal:
        """θ at one of the speeds."""
        i = np.flatnonzero(np.isclose(self.speeds_rpm, float(speed_rpm), rtol=1e-9, atol=0))
        if i.size == 0:
            raise ValueError(f"speed_rpm = {speed_rpm!r} is not allowed: θ was evaluated at "
                             f"{self.speeds_rpm.tolist()} rpm")
        return MultivariateNormal(self.mean[i[0]], self.cov[i[0]])

    @property
    def random_vector(self) -> MultivariateNormal:
        """The one θ the study uses: at a single speed its MVN; over several, the
        moment-matched mixture (mean of the means, mean covariance + covariance of the means)."""
        m = self.mean.mean(axis=0)
        d = self.mean - m
        cov = self.cov.mean(axis=0) + d.T @ d / self.mean.shape[0]
        return MultivariateNormal(m, 0.5 * (cov + cov.T))

    def to_dict(self) -> dict:
        rv = self.random_vector
        return {"names": list(self.names), "speeds_rpm": self.speeds_rpm.tolist(),
                "mean": rv.mean.tolist(), "cov": rv.cov.tolist(),
                "by_speed": {"mean": self.mean.tolist(), "cov": self.cov.tolist()},
                "provenance": self.provenance}


def _source(source) -> tuple[IdentifiedUncertainty, dict]:
    if isinstance(source, IdentifiedUncertainty):
        return source, {"source": "in memory"}
    path = Path(source)
    file = path / "uncertainty.json" if path.is_dir() else path
    data = read_input(file, "uncertainty")          # recorded: a resumed run sees changes
    try:
        d = json.loads(data)
    except ValueError as exc:
        raise ValueError(f"source = {str(file)!r} is not allowed: not JSON ({exc})") from None
    if not isinstance(d, dict):
        raise ValueError(f"source = {str(file)!r} is not allowed: not an uncertainty.json")
    u = IdentifiedUncertainty.from_dict(d, source=str(file))
    return u, {"source": str(file), "sha256": hashlib.sha256(data).hexdigest()}


def study_uncertainty(source, speeds_rpm: Sequence[float], *,
                      theta_bearings: Sequence[str] | None = None,
                      reference: SpindleModel | np.ndarray | None = None,
                      scatter: str | None = None,
                      trend_uncertainty: bool = True) -> StudyUncertainty:
    """θ of the study from an identification (module docstring).

    Parameters
    ----------
    source : path or IdentifiedUncertainty
        A run folder holding ``uncertainty.json``, the file, or the model.
    speeds_rpm : sequence of float
        The response's speed(s); inside the identified range (no extrapolation).
    theta_bearings : sequence of str, optional
        The study's θ bearings, in its order (default the identified order); each must be an
        identified θ variable.
    reference : SpindleModel or array (S, m), optional
        Nominal stiffness θ refers to: a model (its nominal bearings at each speed), an array,
        or ``None`` for the one stored with the identification (the tested rotor's model).
    scatter : {"physical", "total"}, optional
        Override the identification's choice.
    trend_uncertainty : bool
        Add the trends' uncertainty (statistical and systematic).
    """
    u, prov = _source(source)
    sp = np.atleast_1d(np.asarray(speeds_rpm, dtype=float))
    if sp.ndim != 1 or sp.size == 0:
        raise ValueError(f"speeds_rpm = {speeds_rpm!r} is not allowed: give one or more speeds")
    if scatter is not None:
        check_choice("scatter", scatter, SCATTERS)
        u = replace(u, scatter=scatter)
    names = tuple(u.names if theta_bearings is None else theta_bearings)
    missing = [b for b in names if b not in u.names]
    if missing:
        raise ValueError(f"theta_bearings = {list(names)} is not allowed: {missing} not "
                         f"identified (identified: {list(u.names)})")
    order = [u.names.index(b) for b in names]
    if isinstance(reference, SpindleModel):
        refs, ref_kind = model_reference(reference, sp, u.names).reshape(sp.size, -1), "model"
    elif reference is None:
        refs, ref_kind = None, "stored" if u.reference is not None else "N/m"
    else:
        refs, ref_kind = np.asarray(reference, float).reshape(sp.size, -1), "given"
    rvs = [u.random_vector(float(s), reference=refs[i] if refs is not None else (
        "stored" if ref_kind == "stored" else None), trend_uncertainty=trend_uncertainty)
        for i, s in enumerate(sp)]
    mean = np.stack([rv.mean[order] for rv in rvs])
    cov = np.stack([rv.cov[np.ix_(order, order)] for rv in rvs])
    prov |= {"identification": u.provenance, "speeds_rpm": sp.tolist(), "scatter": u.scatter,
             "trend_uncertainty": trend_uncertainty, "reference": ref_kind,
             "trend_laws": {c: t.law for c, t in zip(u.coefficients, u.trends, strict=True)},
             "n_records": u.n_records}
    return StudyUncertainty(names, sp, mean, cov, prov)


def _run_meta(source) -> dict:
    """The identification run's ``meta.json`` (beside ``uncertainty.json``), if there is one;
    a run that is not a complete ``identification`` run is refused."""
    path = Path(source)
    folder = path if path.is_dir() else path.parent
    try:
        meta = json.loads((folder / "meta.json").read_text())
    except (OSError, ValueError):
        return {}
    if meta.get("kind") not in (None, "identification") or meta.get("status") != "complete":
        raise ValueError(f"source = {str(source)!r} is not allowed: not a complete "
                         f"identification run (its meta.json: kind {meta.get('kind')!r}, status "
                         f"{meta.get('status')!r})")
    return {"path": str(folder.resolve()), **{k: meta[k] for k in RUN_META_KEYS if k in meta}}


def _grid_in(u: IdentifiedUncertainty, speed_range_rpm, n_speeds: int) -> tuple[np.ndarray, dict]:
    """``n_speeds`` evenly spaced speeds over the part of ``speed_range_rpm`` the model was
    identified in, and what of the range that leaves out."""
    lo, hi = (float(v) for v in speed_range_rpm)
    ilo, ihi = u.speed_range_rpm
    a, b = max(lo, ilo), min(hi, ihi)
    if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi) or a > b:
        raise ValueError(f"speed_range_rpm = [{lo:g}, {hi:g}] is not allowed: the model was "
                         f"identified in [{ilo:g}, {ihi:g}] rpm, which it does not overlap "
                         "(no extrapolation)")
    left_out = [r for r in ([lo, a], [b, hi]) if r[1] > r[0]]
    return np.linspace(a, b, n_speeds if b > a else 1), {
        "speed_range_rpm": [lo, hi], "identified_range_rpm": [ilo, ihi],
        "range_left_out_rpm": left_out}


def stiffness_block_from(source, theta_bearings: Sequence[str],
                         speeds_rpm: Sequence[float] | None = None, *,
                         speed_range_rpm: Sequence[float] | None = None, n_speeds: int = 25,
                         distribution: str = "normal",
                         reference: SpindleModel | np.ndarray | None = None
                         ) -> tuple[object, dict]:
    """The study's stiffness block of θ from an identification run: what ``[uncertainty]
    from = "<run folder or uncertainty.json>"`` gives.

    The moments are :func:`study_uncertainty`'s ``random_vector`` at ``speeds_rpm`` (one
    speed: the identified trend there relative to the stored reference, with the physical
    scatter and the trend's uncertainty; several: their moment-matched mixture) or, for a
    response that is a peak over ``speed_range_rpm``, at ``n_speeds`` evenly spaced speeds over
    the part of that range the model was identified in (the identified trend is not
    extrapolated; what of the range is left out is in the provenance). The block is
    :func:`~surrogate_rbrdo.uncertainty.factors.stiffness_factors` with those moments
    (``distribution = "normal"``: that MVN; ``"lognormal"``: lognormal margins with the same
    means, standard deviations and correlations).

    Returns
    -------
    block : random vector of ``len(theta_bearings)`` positive factors
    provenance : dict
        ``source`` (the file), its ``sha256``, the identification's own provenance, the
        speeds and choices (:attr:`StudyUncertainty.provenance`), ``distribution``, for a
        range ``speed_range_rpm``, ``identified_range_rpm`` and ``range_left_out_rpm``, and
        ``run``: the identification run's ``meta.json`` (experiment, run id, finishing time,
        code) when the file sits in a run folder.

    Raises ``ValueError`` for a source that is not an identification's ``uncertainty.json`` (or
    a run that did not complete), θ bearings that were not identified, a speed outside the
    identified range or a range that does not overlap it.
    """
    if (speeds_rpm is None) == (speed_range_rpm is None):
        raise ValueError("speeds_rpm and speed_range_rpm: give exactly one")
    run = _run_meta(source)
    u, file_prov = _source(source)
    extra: dict = {}
    if speed_range_rpm is not None:
        speeds_rpm, extra = _grid_in(u, speed_range_rpm, n_speeds)
    su = study_uncertainty(u, speeds_rpm, theta_bearings=theta_bearings, reference=reference)
    rv = su.random_vector
    block = stiffness_factors(rv.mean, rv.std, rv.corr, distribution=distribution)
    return block, {**su.provenance, **file_prov, **extra, "distribution": distribution,
                   "run": run}


__all__ = ["StudyUncertainty", "stiffness_block_from", "study_uncertainty"]
