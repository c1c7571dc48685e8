"""The bootstrap's noise model: closed-form whitening, the run decomposition."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy.noise import _run_structure, _whitening_2x2
from surrogate_rbrdo.discrepancy.observables import ComplexBlock
from surrogate_rbrdo.discrepancy.sweeps import Channel, Sweep


def test_closed_form_whitening_matches_linear_algebra():
    rng = np.random.default_rng(0)
    A = rng.normal(size=(50, 2, 2))
    S = A @ np.swapaxes(A, -1, -2) + 0.1 * np.eye(2)
    W = _whitening_2x2(S, 0.7)
    assert np.allclose(np.swapaxes(W, -1, -2) @ W, 0.7 * np.linalg.inv(S))
    assert np.allclose(np.tril(W, -1), 0.0)


@pytest.mark.known_answer
def test_run_decomposition_recovers_the_run_scatter_and_the_white_noise():
    """Runs built as J a_r + white noise: the decomposition returns SD(a) and the white part's
    variance within their sampling error."""
    rng = np.random.default_rng(3)
    R, X, C = 200, 30, 2
    J = rng.normal(size=(X * C * 2, 1)) * 5.0
    a = 0.4 * rng.normal(size=(R, 1))
    white = 0.1 * rng.normal(size=(R, X * C * 2))
    y = (a @ J.T + white).reshape(R, X, C, 2)
    rec = 3.0 + y[..., 0] + 1j * y[..., 1]
    b = ComplexBlock.from_repeats("u", Sweep.unbalance(np.arange(1, X + 1) * 100.0),
                                  (Channel("p", 0.0, "x"), Channel("q", 0.0, "y")), rec)
    rs = _run_structure(b, slice(0, X * C), J, np.broadcast_to(np.eye(2), (X * C, 2, 2)))
    assert abs(float(rs.La[0, 0]) - 0.4) < 0.06
    assert abs(float(np.sqrt(np.mean(np.einsum("nij,nij->n", rs.Le, rs.Le) / 2))) - 0.1) < 0.01
    assert np.corrcoef(rs.a[:, 0], a[:, 0])[0, 1] > 0.99
