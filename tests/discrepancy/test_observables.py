"""Observables from repeats: mean, covariance of the mean, whitening, validation."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy.observables import ComplexBlock, MeasuredData, RealBlock
from surrogate_rbrdo.discrepancy.sweeps import Channel, Sweep

CH = (Channel("a", 0.0, "x"), Channel("b", 100.0, "y"))


def _records(R=20, X=4, seed=0):
    rng = np.random.default_rng(seed)
    return 1.0 + 0.1 * (rng.normal(size=(R, X, 2)) + 2j * rng.normal(size=(R, X, 2)))


def test_covariance_of_the_mean_is_numpys_over_r():
    rec = _records()
    b = ComplexBlock.from_repeats("u", Sweep.unbalance([1e3, 2e3, 3e3, 4e3]), CH, rec)
    x = np.stack([rec[:, 2, 1].real, rec[:, 2, 1].imag])
    assert np.allclose(b.cov[2, 1], np.cov(x) / 20)
    assert np.allclose(b.mean, rec.mean(axis=0))
    assert b.dof == 19 and b.runs.shape == rec.shape


@pytest.mark.known_answer
def test_unbiased_precision_gives_unit_chi2_per_component():
    """E[r' W'W r] = 2 per cell for Gaussian noise with the precision estimated from R = 10
    repeats (Wishart inverse mean ν/(ν − p − 1) corrected; Anderson 2003, §7.2)."""
    rng = np.random.default_rng(1)
    L = np.array([[1.0, 0.0], [0.8, 0.5]])
    R, n = 10, 20000
    z = rng.normal(size=(n, R, 2)) @ L.T
    rec = (z[..., 0] + 1j * z[..., 1]).T[:, :, None]            # (R, n, 1)
    b = ComplexBlock.from_repeats("u", Sweep.unbalance(np.arange(1, n + 1) * 10.0), CH[:1],
                                  rec)
    W = b.whitening()
    m = np.stack([b.mean.real, b.mean.imag], -1)               # true mean 0
    q = np.einsum("xcij,xcj->xci", W, m)
    assert abs(np.mean(np.sum(q**2, axis=-1)) - 2.0) < 0.05


def test_subset_keeps_runs_consistent():
    rec = _records()
    b = ComplexBlock.from_repeats("u", Sweep.unbalance([1e3, 2e3, 3e3, 4e3]), CH, rec)
    s = b.subset(np.array([True, False, True, False]))
    assert np.allclose(s.runs.mean(axis=0), s.mean)
    assert s.sweep.spin_rad_s.size == 2


def test_bad_input_names_the_block():
    rec = _records(R=4)
    with pytest.raises(ValueError, match="R >= 5"):
        ComplexBlock.from_repeats("u", Sweep.unbalance([1e3, 2e3, 3e3, 4e3]), CH, rec)
    with pytest.raises(ValueError, match="positive definite"):
        ComplexBlock("u", Sweep.unbalance([1e3]), CH[:1], np.ones((1, 1)),
                     np.zeros((1, 1, 2, 2)), 9)
    with pytest.raises(ValueError, match="speeds x bearings"):
        RealBlock("k", np.array([1e3]), ("front",), np.ones((1, 2, 2)), np.ones((1, 1, 2)))
    with pytest.raises(ValueError, match="at least one test"):
        MeasuredData(())


def test_held_out_split_interleaves_frf_lines_and_speeds():
    """Every 5th speed (from the middle of the first stride) and every 5th FRF line are held
    out for interpolation, the top speeds for extrapolation; impact lines never extrapolate."""
    from surrogate_rbrdo.discrepancy.holdout import masks_for, split_speeds

    rng = np.random.default_rng(0)
    ch = (Channel("p", 0.0, "x"),)

    def rec(n):
        return 1 + 0.1 * (rng.normal(size=(6, n, 1)) + 1j * rng.normal(size=(6, n, 1)))

    one = ComplexBlock.from_repeats("unbalance_1x", Sweep.unbalance(np.arange(1, 21) * 1e3),
                                    ch, rec(20))
    hit = ComplexBlock.from_repeats("hit", Sweep.impact(np.arange(1, 13) * 50.0, ch, 9e3), ch,
                                    rec(12), runs=False)
    data = MeasuredData((one, hit))
    split = split_speeds(20)
    inter = masks_for(data, split, "interleaved")
    assert np.flatnonzero(inter["hit"]).tolist() == [2, 7]
    assert np.flatnonzero(inter["unbalance_1x"]).tolist() == [2, 7, 12, 17]
    assert not masks_for(data, split, "extrapolated")["hit"].any()
    train = masks_for(data, split, "train")
    assert np.array_equal(train["hit"], ~inter["hit"])
