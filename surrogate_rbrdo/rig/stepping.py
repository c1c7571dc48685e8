"""Exact stepping of a first-order system frozen over a segment, with a time-varying correction.

In modal coordinates ``η = W z`` of ``A_m = V Λ W`` (the matrices at the segment's middle) each
mode obeys ``η' = λ η + p(t)``, whose step over ``[t, t + h]`` is *exact* for an input
``e^{ντ} (c₀ + c₁ τ/h)``:

    η(t + h) = e^{λh} η(t) + h e^{λh} [φ₁(μh) c₀ + (φ₁(μh) − φ₂(μh)) c₁],   μ = ν − λ,

``φ₁(x) = (eˣ − 1)/x``, ``φ₂(x) = (eˣ − 1 − x)/x²`` (Hochbruck & Ostermann, *Exponential
integrators*, Acta Numerica 19, 2010, §2). The rotating unbalance ``Re(P (φ'² − iφ'') e^{iφ})``
is such an input with ``ν = ±iΩ`` and its slowly varying envelope linear over a step; a sampled
force is ``ν = 0`` with a first-order hold.

**The correction.** On a speed ramp ``A(t) = A_m + δA(t)``. Freezing ``A_m`` alone leaves a
sawtooth error inside every segment (first order in the segment length; it excites the modes
near ``1x ± k/H``). Here ``δA(τ) ≈ τ A₁ + τ² A₂`` (``τ = t − t_m``, the quadratic through the
segment's ends and middle) is kept as an input ``W δA V η`` to the modal equations (first-order
hold between steps), solved by Picard iteration over the segment, each sweep vectorised, until
the outputs change by less than ``tol``: no sawtooth. Modes are corrected if slow (``|λ| ≤
w_slow``) or if their quasi-static share of the error would exceed ``tol``. The diagonal
recurrence is vectorised over modes and blocks of steps.

**Stretches without input** (constant speed, no unbalance, the force zero: a hammer hit's free
decay, the quiet lead-in before it) need no recurrence: ``η_j = a^j η_0`` and the outputs are
one real matrix product of block powers (:func:`free_outputs`), ``m N n_out`` multiply-adds for
``m`` steps instead of the recurrence's ``m N (L + n_out)``; the same values to round-off
(``tests/rig/test_stepping.py``: ≤ 1e-9 of the record's RMS; measured ≤ 6e-13 on hits at
0–20 000 rpm).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def phi12(lam_h: np.ndarray, nu_h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``e^{λh} φ₁(x)`` and ``e^{λh} (φ₁ − φ₂)(x)`` with ``x = (ν − λ)h``: Taylor series near
    ``x = 0``, else ``(e^{νh} − e^{λh})/x`` and ``(x e^{νh} − e^{νh} + e^{λh})/x²`` (no
    overflow for stiff modes, ``Re λ ≪ 0``).

    >>> p1, p12 = phi12(np.array([-1e-9]), np.array([0.0]))
    >>> np.round([p1[0], p12[0]], 6).tolist()          # ∫₀¹ 1 dτ and ∫₀¹ τ dτ
    [1.0, 0.5]
    """
    x = nu_h - lam_h
    el, en = np.exp(lam_h), np.exp(nu_h)
    small = np.abs(x) < 1e-2
    xs = np.where(small, 1.0, x)
    p1 = np.where(small, el * (1 + x / 2 + x**2 / 6 + x**3 / 24 + x**4 / 120),
                  (en - el) / xs)
    p12 = np.where(small, el * (0.5 + x / 3 + x**2 / 8 + x**3 / 30 + x**4 / 144),
                   (xs * en - en + el) / xs**2)
    return p1, p12


@dataclass(frozen=True)
class Segment:
    """A segment's frozen modal system and what drives it.

    ``lam`` (N,), ``WB`` (N, n): physical force → modal input, ``CV`` (n_out, N): modal state
    → outputs; ``P`` (n,) the unbalance pattern (zeros: none); ``D`` (2N, N) the correction
    ``[W A₁ V; W A₂ V]`` about ``t_mid`` (None: none), applied to the modes with
    ``|λ| ≤ w_slow`` and to any other whose quasi-static share of the outputs' error would
    exceed the tolerance.
    """

    lam: np.ndarray
    WB: np.ndarray
    CV: np.ndarray
    P: np.ndarray
    D: np.ndarray | None = None
    w_slow: float = 0.0
    t_mid: float = 0.0


def advance_constant(eta: np.ndarray, seg: Segment, profile, ta: float, tb: float
                     ) -> np.ndarray:
    """Exact jump over ``[ta, tb]`` at constant speed (unbalance only)."""
    w = float(profile.omega(np.array([ta]))[0])
    hh = tb - ta
    if hh == 0.0:
        return eta
    c = w**2 * np.exp(1j * float(profile.angle(np.array([ta]))[0]))
    acc = np.zeros_like(eta)
    for nu, coef in ((1j * w, 0.5 * c * (seg.WB @ seg.P)),
                     (-1j * w, 0.5 * np.conj(c) * (seg.WB @ seg.P.conj()))):
        p1, _ = phi12(seg.lam * hh, nu * hh)
        acc += hh * p1 * coef
    return np.exp(seg.lam * hh) * eta + acc


def _inputs(seg: Segment, profile, t: np.ndarray, h: float, ws: float, fseg, force_dofs,
            pf: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """Per-step input increments ``r_k`` (K, N) over the steps between the times ``t``."""
    lam = seg.lam
    r = np.zeros((t.size - 1, lam.size), complex)
    if np.any(seg.P != 0):
        ph, w2 = profile.angle(t), profile.omega(t) ** 2
        # the envelope φ'² − iφ'' at each step's start and (left limit) end: φ'' jumps at
        # the profile's breakpoints
        g0 = (w2[:-1] - 1j * profile.alpha(t[:-1])) * np.exp(1j * ph[:-1])
        g1 = (w2[1:] - 1j * profile.alpha(t[1:], "left")) * np.exp(1j * (ph[1:] - ws * h))
        for sgn, b in ((1.0, seg.WB @ seg.P), (-1.0, seg.WB @ seg.P.conj())):
            p1, p12 = phi12(lam * h, np.full_like(lam, sgn * 1j * ws * h))
            G0, G1 = (g0, g1) if sgn > 0 else (g0.conj(), g1.conj())
            r += 0.5 * h * (G0[:, None] * (p1 * b) + (G1 - G0)[:, None] * (p12 * b))
    if fseg is not None and np.any(fseg):
        bF = seg.WB[:, np.asarray(force_dofs)]
        F0, F1 = fseg[:-1] @ bF.T, fseg[1:] @ bF.T
        r += h * (pf[0] * F0 + pf[1] * (F1 - F0))
    return r


def _recur(a: np.ndarray, eta0: np.ndarray, r: np.ndarray, L: int = 8) -> np.ndarray:
    """``η_{k+1} = a η_k + r_k`` for every mode; returns ``η_1 … η_K`` (K, N).

    Vectorised by blocks of ``L`` steps: inside a block ``η_{s+k+1} = a^{k+1} η_s +
    Σ_{j≤k} a^{k−j} r_{s+j}`` (one batched product for all blocks), then the block states in
    sequence; only non-negative powers of ``a`` appear (stable for stiff modes)."""
    K, N = r.shape
    nb = -(-K // L)
    R = np.zeros((nb * L, N), complex)
    R[:K] = r
    k = np.arange(L)
    expo = k[:, None] - k[None, :]
    P = np.where(expo >= 0, a[:, None, None] ** np.maximum(expo, 0), 0.0)   # (N, L, L)
    part = P @ R.reshape(nb, L, N).transpose(2, 1, 0)                       # (N, L, nb)
    apow = a[None, :] ** (k[:, None] + 1)                                   # (L, N)
    E = np.empty((nb, N), complex)
    e = eta0
    last = part[:, -1, :].T                                                  # (nb, N)
    for b in range(nb):
        E[b] = e
        e = apow[-1] * e + last[b]
    out = apow[None] * E[:, None, :] + part.transpose(2, 1, 0)              # (nb, L, N)
    return out.reshape(nb * L, N)[:K]


def _rows(seg: Segment, eta0, eta1, tau0, tau1, scale, tol) -> np.ndarray:
    """Modes to correct dynamically: the slow ones, plus those fast ones whose quasi-static
    error ``|c_j| ‖CV_j‖ / |λ_j|`` (``c`` the correction input at the chunk's ends) adds up to
    more than ``tol`` of the outputs' scale (largest first)."""
    N = seg.lam.size
    slow = np.abs(seg.lam) <= seg.w_slow
    c = np.maximum(*(np.abs(t * (seg.D[:N] @ e) + t * t * (seg.D[N:] @ e))
                     for t, e in ((tau0, eta0), (tau1, eta1))))
    err = np.where(slow, 0.0, c * np.linalg.norm(seg.CV, axis=0) / np.abs(seg.lam))
    order = np.argsort(err)                      # smallest first
    left = np.cumsum(err[order]) > tol * scale  # dropping these would cost too much
    slow[order[left]] = True
    return np.flatnonzero(slow)


def _picard(a, eta0, r, etas, seg: Segment, tau, h, pf, scale, tol, max_iter=12) -> int:
    """Add the correction input ``W δA(τ) V η`` to the frozen solution ``etas`` (in place)
    by Picard iteration over the chunk, each sweep vectorised (first-order hold of the
    correction between steps); returns the sweeps needed, or ``-1`` if the outputs did not
    settle to ``tol`` (relative to ``scale``) — then the segment is too long."""
    rows = _rows(seg, eta0, etas[-1], tau[0], tau[-1], scale, tol)
    if rows.size == 0:
        return 0
    N, R = seg.lam.size, rows.size
    D = np.vstack([seg.D[rows], seg.D[N + rows]])
    p1, p12 = h * pf[0][rows], h * pf[1][rows]
    CVr = seg.CV[:, rows]
    tau = tau[:, None]
    for it in range(1, max_iter + 1):
        v = np.vstack([eta0, etas]) @ D.T                          # (K + 1, 2R)
        c = tau * v[:, :R] + tau**2 * v[:, R:]
        rc = p1 * c[:-1] + p12 * (c[1:] - c[:-1])
        new = _recur(a[rows], eta0[rows], r[:, rows] + rc)
        change = np.abs((new - etas[:, rows]) @ CVr.T).max()
        etas[:, rows] = new
        if change <= 0.1 * tol * scale:
            return it
    return -1


def free_outputs(a: np.ndarray, eta: np.ndarray, CV: np.ndarray, m: int, L: int = 0
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The free response over ``m`` steps without input, in closed form: outputs
    ``Re(CV (a^j ⊙ η))`` for ``j = 1 … m`` (m, n_out) and the final state ``a^m ⊙ η``.

    With ``j − 1 = L b + r`` (``0 ≤ r < L``), ``a^j = (a^L)^b a^{r+1}``: every output is one
    real matrix product ``[Re Aᵦ, −Im Aᵦ] @ [Re M; Im M]`` of the block powers ``Aᵦ`` (nb, N)
    and ``M = η a^{r+1} CVᵀ`` (N, L n_out) — no recurrence, ``m N n_out`` multiply-adds, only
    non-negative powers of ``a`` (stable for stiff modes). ``L = 0``: ``≈ √m``.

    >>> a = np.exp(np.array([-1.0 + 20.0j, -1.0 - 20.0j]) * 1e-3)   # one real mode, h = 1 ms
    >>> y, e = free_outputs(a, np.array([-0.5j, 0.5j]), np.array([[1.0, 1.0]]), 1000)
    >>> t = np.arange(1, 1001) * 1e-3
    >>> bool(np.allclose(y[:, 0], np.exp(-t) * np.sin(20 * t), rtol=0, atol=1e-13))
    True
    """
    N, n_out = a.size, CV.shape[0]
    if m <= 0:
        return np.zeros((0, n_out)), eta
    if not np.any(eta):
        return np.zeros((m, n_out)), eta
    L = L or max(1, int(np.sqrt(m)))
    nb = -(-m // L)
    inner = a[None, :] ** np.arange(1, L + 1)[:, None]                     # (L, N): a^{r+1}
    blocks = np.cumprod(np.vstack([np.ones((1, N), complex),
                                   np.broadcast_to(inner[-1], (nb - 1, N))]), axis=0)
    Mx = (eta[None, :, None] * inner[:, :, None] * CV.T[None]).transpose(1, 0, 2)
    Mx = Mx.reshape(N, L * n_out)                                           # (N, L n_out)
    y = np.hstack([blocks.real, -blocks.imag]) @ np.vstack([Mx.real, Mx.imag])
    r_last, b_last = (m - 1) % L, (m - 1) // L
    return y.reshape(nb * L, n_out)[:m], blocks[b_last] * inner[r_last] * eta


def _pieces(seg: Segment, fseg: np.ndarray | None, n_steps: int, chunk: int
            ) -> list[tuple[int, int, bool]]:
    """``(c0, c1, free)``: the steps ``c0 … c1 − 1`` in order, in runs of at most ``chunk``
    forced steps or of any number of steps without input (``free``: no unbalance, no
    correction, the force zero at both ends of every step)."""
    if seg.D is not None or np.any(seg.P != 0):
        free = np.zeros(n_steps, bool)
    elif fseg is None:
        free = np.ones(n_steps, bool)
    else:
        nz = np.any(fseg != 0, axis=1)
        free = ~(nz[:-1] | nz[1:])
    edges = np.flatnonzero(np.diff(free.astype(np.int8))) + 1
    out = []
    for c0, c1 in zip(np.r_[0, edges], np.r_[edges, n_steps], strict=True):
        if free[c0]:
            out.append((int(c0), int(c1), True))
        else:
            out += [(c, min(c + chunk, int(c1)), False) for c in range(int(c0), int(c1), chunk)]
    return out


def run_segment(eta0: np.ndarray, seg: Segment, profile, grid: np.ndarray,
                fseg: np.ndarray | None, force_dofs, *, tol: float = 1e-7, chunk: int = 4096,
                closed_form: bool = True) -> tuple[np.ndarray, np.ndarray, int]:
    """Outputs ``Re(CV η)`` at every time of ``grid``, the final modal state and the Picard
    sweeps the correction needed (0: none; -1: not converged), in chunks of ``chunk`` steps
    (bounded memory). Stretches without input (at constant speed, e.g. a hammer hit's free
    decay) are :func:`free_outputs`' closed form unless ``closed_form`` is False (then the
    recurrence steps them too: the same values to round-off)."""
    T = grid.size
    out = np.empty((T, seg.CV.shape[0]))
    out[0] = (seg.CV @ eta0).real
    if T == 1:
        return out, eta0, 0
    h = float(grid[1] - grid[0])
    a = np.exp(seg.lam * h)
    ws = float(profile.omega(np.array([0.5 * (grid[0] + grid[-1])]))[0])
    pf = phi12(seg.lam * h, np.zeros_like(seg.lam))
    eta, sweeps, scale = eta0, 0, 0.0
    pieces = (_pieces(seg, fseg, T - 1, chunk) if closed_form else
              [(c, min(c + chunk, T - 1), False) for c in range(0, T - 1, chunk)])
    for c0, c1, free in pieces:
        if free:
            out[c0 + 1:c1 + 1], eta = free_outputs(a, eta, seg.CV, c1 - c0)
            continue
        fs = None if fseg is None else fseg[c0:c1 + 1]
        r = _inputs(seg, profile, grid[c0:c1 + 1], h, ws, fs, force_dofs, pf)
        etas = _recur(a, eta, r)
        if seg.D is not None:
            scale = max(scale, np.abs(etas @ seg.CV.T).max(), 1e-300)
            it = _picard(a, eta, r, etas, seg, grid[c0:c1 + 1] - seg.t_mid, h, pf, scale,
                         tol)
            sweeps = -1 if it < 0 or sweeps < 0 else max(sweeps, it)
        out[c0 + 1:c1 + 1] = (etas @ seg.CV.T).real
        eta = etas[-1]
    return out, eta, sweeps
