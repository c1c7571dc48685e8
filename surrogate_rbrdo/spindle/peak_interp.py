"""The peak over speed of each sample from exact coupled tables (``peak_coupling``).

:func:`peak_from_tables` takes the determinant ``D`` and the plane numerators ``N_j`` of the
coupled system, exact at the θ nodes and on a geometric speed grid (:class:`CoupledTables`,
``peak_coupling.coupled_tables``), and for each sample (θ basis row, unbalance phasors):

1. contracts θ and combines the planes on a sub-grid (the exact grid interpolated by local
   Lagrange polynomials in ``ln Ω``; ``D`` and ``N`` are smooth there, the resonances being
   zeros of ``D``), in real BLAS products;
2. takes the sub-grid's highest local maxima of the amplitude as candidates;
3. refines each on the local interpolants: samples of its bracket, then Newton steps on
   ``1/A² ∝ |D|²/|N|²`` (rotationally invariant rotors), or zooms and the parabola in
   ``1/A²`` of ``harmonic.peak_search`` (anisotropic bearings, two circular components).

The amplitude is the orbit's semi-major axis ``(|Σ U_j N^a_j| + |Σ U_j N^b_j|) / (2|D|)``.

>>> CoupledPeakOptions().n_grid
48
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.validate import check_int, check_range
from surrogate_rbrdo.spindle.harmonic import PeakResult, _parabola_peak


@dataclass(frozen=True)
class CoupledPeakOptions:
    """How :func:`peak_from_tables` searches the peak over speed.

    ``n_grid`` exact speeds, geometric over the range (uniform spacing ``h`` in ``ln Ω``);
    ``stencil`` grid values per local Lagrange interpolant of ``D`` and ``N``; ``n_sub``
    sub-intervals per grid interval on which candidates (local maxima) are looked for; the
    ``n_candidates`` highest (those sampled above ``prune`` times the row's best) are refined
    on the local interpolants: ``n_refine`` samples of the bracket and Newton steps on
    ``1/A²`` (isotropic bearings), or ``n_zoom`` zooms of ``n_refine`` points and the
    parabola in ``1/A²`` through the last three (anisotropic). Defaults: 48 speeds over
    1 000–24 000 rpm (ratio 1.07), interpolants of degree 7, sub-grid spacing 3.4 %; measured
    ≤ 2.6e-5 from a fine FE peak search at 3 600 random (design, θ, unbalance) samples over
    the reference box (40 speeds: ≤ 9.4e-5; degree 5: ≤ 4.6e-4), and
    ``benchmarks/bench_peak_coupling.py``.
    """

    n_grid: int = 48
    stencil: int = 8
    n_sub: int = 2
    n_candidates: int = 3
    n_refine: int = 17
    n_zoom: int = 3
    prune: float = 0.1

    def __post_init__(self) -> None:
        check_int("n_grid", self.n_grid, minimum=8)
        check_int("stencil", self.stencil, minimum=2)
        if self.stencil > self.n_grid:
            raise ValueError(f"stencil = {self.stencil} is not allowed: must not exceed "
                             f"n_grid = {self.n_grid}")
        check_int("n_sub", self.n_sub, minimum=1)
        check_int("n_candidates", self.n_candidates, minimum=1)
        check_int("n_refine", self.n_refine, minimum=5)
        check_int("n_zoom", self.n_zoom, minimum=1)
        check_range("prune", self.prune, 0.0, 1.0)


@dataclass(frozen=True)
class CoupledTables:
    """Exact coupled quantities of one rotor on a geometric speed grid at θ nodes.

    Attributes
    ----------
    log_speed : ndarray (G,)
        ``ln`` of the grid speeds (rpm), equally spaced.
    nodes : ndarray (K, m)
        θ interpolation nodes (``coupling.theta_grid``), or the θ sample itself when
        ``basis`` is None (row-by-row tables).
    D : ndarray (K, G) complex
        ``det K_c`` scaled by one real constant.
    Na, Nb : ndarray (K, G, P) complex
        ``D`` times the forward (``X + iY``) and backward (``X − iY``) circular component of
        the tool displacement per unit unbalance (1 kg m, phase 0) in plane ``j``; ``Nb`` is
        None where it vanishes (isotropic bearings).
    """

    log_speed: np.ndarray
    nodes: np.ndarray
    D: np.ndarray
    Na: np.ndarray
    Nb: np.ndarray | None

    @property
    def speeds_rpm(self) -> np.ndarray:
        return np.exp(self.log_speed)


@lru_cache(maxsize=8)
def _lagrange_coefficients(n: int) -> np.ndarray:
    """Monomial coefficients of the Lagrange basis on the nodes ``0..n-1`` and of its first
    and second derivatives, ``(n, 3n)``: ``w_i^(o)(x) = Σ_p x^p C[p, o n + i]``."""
    C0 = np.linalg.inv(np.vander(np.arange(n, dtype=float), n, increasing=True))
    q = np.arange(n)[:, None]
    C1 = np.zeros_like(C0)
    C1[:-1] = (q[:-1] + 1) * C0[1:]
    C2 = np.zeros_like(C0)
    C2[:-2] = (q[:-2] + 1) * (q[:-2] + 2) * C0[2:]
    return np.concatenate([C0, C1, C2], axis=1)


def _lagrange(x: np.ndarray, n: int, orders: int = 1) -> np.ndarray:
    """Lagrange weights of the nodes ``0..n-1`` at points ``x``: ``(..., n)`` for the values
    (``orders = 1``), ``(..., 3, n)`` for values, first and second derivatives (``3``)."""
    X = np.asarray(x, dtype=float)[..., None] ** np.arange(n)
    W = X @ _lagrange_coefficients(n)[:, :orders * n]
    return W if orders == 1 else W.reshape(W.shape[:-1] + (3, n))


def _stencil(u: np.ndarray, G: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """First stencil node and local coordinate for grid coordinates ``u`` (0 … G−1)."""
    s = np.clip(np.floor(u).astype(int) - (n // 2 - 1), 0, G - n)
    return s, u - s


@lru_cache(maxsize=8)
def _sub_matrix(G: int, n_sub: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Grid coordinates of the sub-grid (G−1)·n_sub + 1 points and its interpolation matrix."""
    u = np.linspace(0.0, G - 1.0, (G - 1) * n_sub + 1)
    s, x = _stencil(u, G, n)
    M = np.zeros((u.size, G))
    np.put_along_axis(M, s[:, None] + np.arange(n), _lagrange(x, n), axis=1)
    return u, M


def _amplitude(d: np.ndarray, a: np.ndarray, b: np.ndarray | None) -> np.ndarray:
    num = 0.5 * np.abs(a) if b is None else 0.5 * (np.abs(a) + np.abs(b))
    with np.errstate(divide="ignore", invalid="ignore"):
        return num / np.abs(d)


def _contract(B: np.ndarray | None, T: np.ndarray, U: np.ndarray):
    """θ-contract the sub-grid tables ``T (K, F, 1 + c P)`` (``D``, then ``c`` blocks of ``P``
    plane numerators) and combine the planes with the phasors ``U (N, P)``: returns
    ``|D|²``, the lists of real and of imaginary parts of the combined numerators, and the
    real and imaginary part of ``D``, ``(N, F)`` each.

    ``B`` None means one table row per sample (``K = N``). Real BLAS products: with
    ``W = B ⊗ U`` the combined numerator is ``Re = [B⊗Re U, −B⊗Im U] · [Re T; Im T]`` and
    ``Im = [B⊗Im U, B⊗Re U] · [Re T; Im T]``.
    """
    K, F, cols = T.shape
    P = U.shape[1]
    if B is None:                                    # one θ row per sample: weights diagonal
        Dv = T[..., 0]
        out_r, out_i = [], []
        for c in range((cols - 1) // P):
            Tc = T[..., 1 + c * P:1 + (c + 1) * P]                      # (N, F, P)
            v = np.einsum("nfp,np->nf", Tc, U)
            out_r.append(v.real)
            out_i.append(v.imag)
        return np.abs(Dv) ** 2, out_r, out_i, Dv.real, Dv.imag
    N = B.shape[0]
    D2 = np.concatenate([T[..., 0].real, T[..., 0].imag], axis=1)      # (K, 2F)
    Dv = B @ D2
    dr, di = Dv[:, :F], Dv[:, F:]
    Wr = (B[:, :, None] * U.real[:, None, :]).reshape(N, -1)          # (N, K P)
    Wi = (B[:, :, None] * U.imag[:, None, :]).reshape(N, -1)
    out_r, out_i = [], []
    for c in range((cols - 1) // P):
        Tc = T[..., 1 + c * P:1 + (c + 1) * P].transpose(0, 2, 1).reshape(K * P, F)
        Tstack = np.concatenate([Tc.real, Tc.imag], axis=0)            # (2 K P, F)
        out_r.append(np.concatenate([Wr, -Wi], axis=1) @ Tstack)
        out_i.append(np.concatenate([Wi, Wr], axis=1) @ Tstack)
    return dr**2 + di**2, out_r, out_i, dr, di


def peak_from_tables(tables: CoupledTables, basis: np.ndarray | None, unbalance: np.ndarray,
                     options: CoupledPeakOptions = CoupledPeakOptions()
                     ) -> tuple[PeakResult, np.ndarray]:
    """Peak tool amplitude (m) and its speed (rpm) for each row: θ ``basis`` (N, K) and
    unbalance phasors ``unbalance`` (N, P) complex, kg m.

    ``basis`` None means the tables hold one θ row per sample (K = N). Returns the
    :class:`~surrogate_rbrdo.spindle.harmonic.PeakResult` and, per row, the round-off bound of
    the θ interpolation at the peak (``eps · Λ · max node value / value``; see
    ``coupling.coupled_tool_amplitude_theta``).
    """
    U = np.asarray(unbalance, dtype=complex)
    K, G, P = tables.Na.shape
    N = U.shape[0]
    if U.ndim != 2 or U.shape[1] != P:
        raise ValueError(f"unbalance has shape {U.shape}: must be (N, {P}) complex (kg m)")
    B = None if basis is None else np.asarray(basis, dtype=float)
    if B is None and K != N:
        raise ValueError(f"row-by-row tables hold {K} rows, unbalance has {N}")
    u_sub, Msub = _sub_matrix(G, options.n_sub, options.stencil)
    # every quantity on the sub-grid (local interpolation of the exact grid)
    quants = [tables.D[..., None], tables.Na] + ([] if tables.Nb is None else [tables.Nb])
    Tsub = np.einsum("fg,kgc->kfc", Msub, np.concatenate(quants, axis=-1))
    amp, speed, bound = np.empty(N), np.empty(N), np.empty(N)
    for s in range(0, N, _ROWS):                # blocks of rows: their arrays stay in cache
        rows = slice(s, s + _ROWS)
        res = (_peak_rows(tables, None, Tsub[rows], U[rows], u_sub, options) if B is None
               else _peak_rows(tables, B[rows], Tsub, U[rows], u_sub, options))
        amp[rows], speed[rows], bound[rows] = res
    return PeakResult(amp, speed), bound


#: rows per block in :func:`peak_from_tables`: bounds the memory of large samples (1 024 rows
#: of the default 95 sub-grid points hold ~5 MB)
_ROWS = 1024


def _peak_rows(tables, B, Tsub, U, u_sub, options):
    """:func:`peak_from_tables` for one block of rows: basis ``B`` (or None with one table row
    per sample in ``Tsub``), phasors ``U``; returns amplitudes, speeds and round-off bounds."""
    N = U.shape[0]
    d2, nr, ni, dr, di = _contract(B, Tsub, U)
    with np.errstate(divide="ignore", invalid="ignore"):
        if tables.Nb is None:
            rank = (nr[0] ** 2 + ni[0] ** 2) / d2                        # ∝ A², same peaks
        else:
            rank = (np.hypot(nr[0], ni[0]) + np.hypot(nr[1], ni[1])) / np.sqrt(d2)
    cand, valid = _candidates(rank, options.n_candidates)
    rows = np.arange(N)[:, None]
    sampled = 0.5 * (np.sqrt(rank[rows, cand]) if tables.Nb is None else rank[rows, cand])
    g = slice(None, None, options.n_sub)                               # the exact grid
    grid = [dr[:, g] + 1j * di[:, g]] + [a[:, g] + 1j * b[:, g] for a, b in zip(nr, ni,
                                                                                 strict=True)]
    amp, pos = _refine(u_sub, cand, valid, sampled, grid, options)
    h = tables.log_speed[1] - tables.log_speed[0]
    speed = np.exp(tables.log_speed[0] + h * pos)
    if B is None:
        return amp, speed, np.zeros(N)
    lam = np.abs(B).sum(axis=1)                          # Lebesgue sum of each row's basis
    sel = np.round(pos * options.n_sub).astype(int)                    # nearest sub-grid point
    r = np.arange(N)
    dmax = np.abs(tables.D).max()
    nmax = np.abs(tables.Na).max(axis=(0, 1)) @ np.abs(U).T
    with np.errstate(divide="ignore"):
        bound = np.finfo(float).eps * lam * (dmax / np.sqrt(d2[r, sel])
                                             + nmax / np.hypot(nr[0][r, sel], ni[0][r, sel]))
    return amp, speed, bound


def _candidates(A: np.ndarray, n_cand: int) -> tuple[np.ndarray, np.ndarray]:
    """Sub-grid indices ``(N, k)`` of each row's ``k`` highest local maxima, and whether each
    is one (rows with fewer maxima are padded)."""
    N, F = A.shape
    score = A.copy()
    score[:, 1:][A[:, 1:] < A[:, :-1]] = -np.inf
    score[:, :-1][A[:, :-1] < A[:, 1:]] = -np.inf
    rows = np.arange(N)
    cand = np.empty((N, min(n_cand, F)), dtype=int)
    valid = np.empty(cand.shape, dtype=bool)
    for k in range(cand.shape[1]):
        cand[:, k] = j = np.argmax(score, axis=1)
        valid[:, k] = score[rows, j] > -np.inf
        score[rows, j] = -np.inf
    return cand, valid


def _refine(u_sub, cand, valid, sampled, grid, opt: CoupledPeakOptions):
    """Peak of each row from its sub-grid candidates ``cand (N, k)``: Newton steps on
    ``1/A² = 4|D|²/|N|²`` (isotropic: ``grid = [D, Na]``) or zooms (``[D, Na, Nb]``) on the
    local interpolants of the exact grid values, never below the ``sampled`` amplitude.
    Candidates sampled below ``opt.prune`` times the row's best are not refined."""
    N = cand.shape[0]
    F = u_sub.size
    best = np.where(valid, sampled, -np.inf).max(axis=1, keepdims=True)
    r, k = np.nonzero(valid & (sampled >= opt.prune * best))
    c = cand[r, k]
    lo, hi = u_sub[np.maximum(c - 1, 0)], u_sub[np.minimum(c + 1, F - 1)]
    if len(grid) == 2:
        pos_rk, amp_rk = _newton(grid[0], grid[1], r, u_sub[c], lo, hi, opt)
    else:
        pos_rk, amp_rk = _zoom(grid, r, lo, hi, opt)
    amp = np.where(valid, sampled, -np.inf)
    pos = u_sub[cand]
    better = amp_rk >= amp[r, k]
    amp[r[better], k[better]] = amp_rk[better]
    pos[r[better], k[better]] = pos_rk[better]
    j = np.argmax(amp, axis=1)
    rows = np.arange(N)
    out_amp, out_pos = amp[rows, j], pos[rows, j]
    if not np.all(np.isfinite(out_amp)):
        raise ModelError("peak_from_tables: non-finite peak amplitude")
    return out_amp, out_pos


def _at(V: np.ndarray, rows: np.ndarray, u: np.ndarray, n: int, orders: int = 1):
    """Local interpolant of ``V[rows]`` (grid values ``(N, G)`` or ``(N, G, c)``) at grid
    coordinates ``u`` (same shape as ``rows``): values ``(..., [c])``, or values and two
    derivatives stacked on a leading axis (``orders = 3``)."""
    s, x = _stencil(u, V.shape[1], n)
    vals = V[rows[..., None], s[..., None] + np.arange(n)]              # (..., n[, c])
    W = _lagrange(x, n, orders)
    if V.ndim == 2:
        vals = vals[..., None]
    out = (np.einsum("...k,...kc->...c", W, vals) if orders == 1
           else np.moveaxis(np.einsum("...ok,...kc->...oc", W, vals), -2, 0))
    return out[..., 0] if V.ndim == 2 else out


def _local_polynomials(V: np.ndarray, rows: np.ndarray, u: np.ndarray, n: int
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Monomial coefficients ``(M, n, c)`` in ``x = u − s`` of the local interpolants of
    ``V[rows]`` (``(N, G, c)`` grid values) on the stencils ``s`` of ``u``; returns ``(s, c)``."""
    s, _ = _stencil(u, V.shape[1], n)
    vals = V[rows[:, None], s[:, None] + np.arange(n)]                  # (M, n, c)
    C0 = _lagrange_coefficients(n)[:, :n]
    return s, (vals.transpose(0, 2, 1) @ C0.T).transpose(0, 2, 1)


def _horner_values(coef: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Values ``(M, R, c)`` of the polynomials ``coef (M, n, c)`` at points ``x (M, R)``."""
    x = x[..., None]
    p = np.broadcast_to(coef[:, None, -1], x.shape[:2] + coef.shape[-1:])
    for k in range(coef.shape[1] - 2, -1, -1):
        p = p * x + coef[:, None, k]
    return p


def _horner(coef: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Value, first and second derivative of the polynomials ``coef (M, n, c)`` at ``x``."""
    x = x[:, None]
    p = coef[:, -1]
    d1 = np.zeros_like(p)
    d2 = np.zeros_like(p)
    for k in range(coef.shape[1] - 2, -1, -1):
        d2 = d2 * x + 2 * d1
        d1 = d1 * x + p
        p = p * x + coef[:, k]
    return p, d1, d2


def _newton(Dg, Ng, rows, u0, lo, hi, opt: CoupledPeakOptions, n_iter: int = 3):
    """Minimise ``g = |D|²/|N|²`` (= 1/(4A²)) on the local interpolants of rows ``rows``
    within ``[lo, hi]`` (flat arrays): ``n_refine`` samples of the bracket, then Newton steps
    from the best within its neighbours (``g`` is nearly quadratic across a resonance, where
    ``D`` is nearly linear and ``N`` nearly constant). Each pair keeps the stencil of its
    start ``u0`` (its interpolant is the same polynomial throughout)."""
    s, coef = _local_polynomials(np.stack([Dg, Ng], axis=-1), rows, u0, opt.stencil)
    # first sample the bracket (two close maxima, e.g. a resonance next to a zero of N, make
    # g far from quadratic), then Newton from the best sample within its neighbours
    t = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, opt.n_refine)
    vals = _horner_values(coef, t - s[:, None])
    j = np.argmax(np.abs(vals[..., 1]) / np.abs(vals[..., 0]), axis=1)
    pick = np.arange(t.shape[0])
    u = t[pick, j]
    lo = t[pick, np.maximum(j - 1, 0)]
    hi = t[pick, np.minimum(j + 1, opt.n_refine - 1)]
    half = (hi - lo) / 2
    for _ in range(n_iter):
        v0, v1, v2 = _horner(coef, u - s)
        D0, D1, D2, N0, N1, N2 = v0[:, 0], v1[:, 0], v2[:, 0], v0[:, 1], v1[:, 1], v2[:, 1]
        p, p1 = np.abs(D0) ** 2, 2 * (D0.conj() * D1).real
        p2 = 2 * (np.abs(D1) ** 2 + (D0.conj() * D2).real)
        q, q1 = np.abs(N0) ** 2, 2 * (N0.conj() * N1).real
        q2 = 2 * (np.abs(N1) ** 2 + (N0.conj() * N2).real)
        with np.errstate(divide="ignore", invalid="ignore"):
            g1 = (p1 * q - p * q1) / q**2
            g2 = (p2 * q - p * q2) / q**2 - 2 * q1 * (p1 * q - p * q1) / q**3
            step = np.where(g2 > 0, -g1 / g2, -np.sign(g1) * half / 2)
        u = np.clip(u + np.clip(np.nan_to_num(step), -half, half), lo, hi)
    v0 = _horner(coef, u - s)[0]
    return u, _amplitude(v0[:, 0], v0[:, 1], None)


def _zoom(grid, rows, lo, hi, opt: CoupledPeakOptions):
    """Zooms of ``n_refine`` points and the parabola in ``1/A²`` (``harmonic.peak_search``)
    on the local interpolants of rows ``rows`` (flat arrays)."""
    t = np.linspace(0.0, 1.0, opt.n_refine)
    n = opt.stencil
    R = np.broadcast_to(rows[:, None], (rows.size, t.size))

    def amp_at(u):
        val = [_at(X, R, u, n) for X in grid]
        return _amplitude(val[0], val[1], val[2] if len(val) > 2 else None)

    for _ in range(opt.n_zoom):
        pts = lo[:, None] + (hi - lo)[:, None] * t                     # (M, R)
        Ar = amp_at(pts)
        j = np.argmax(Ar, axis=-1)
        jl, jh = np.maximum(j - 1, 0), np.minimum(j + 1, opt.n_refine - 1)
        lo = np.take_along_axis(pts, jl[:, None], -1)[:, 0]
        hi = np.take_along_axis(pts, jh[:, None], -1)[:, 0]
    jj = np.clip(j, 1, opt.n_refine - 2)
    x3 = np.stack([np.take_along_axis(pts, (jj + k)[:, None], -1)[:, 0] for k in (-1, 0, 1)])
    y3 = np.stack([np.take_along_axis(Ar, (jj + k)[:, None], -1)[:, 0] for k in (-1, 0, 1)])
    best_x = np.take_along_axis(pts, j[:, None], -1)[:, 0]
    best_y = np.take_along_axis(Ar, j[:, None], -1)[:, 0]
    px, py = _parabola_peak(x3, 1.0 / y3**2)
    inside = (px > x3[0]) & (px < x3[2]) & (py > 0)
    amp_par = 1.0 / np.sqrt(np.where(inside, py, 1.0))
    inside &= amp_par >= best_y
    return np.where(inside, px, best_x), np.where(inside, amp_par, best_y)


__all__ = ["CoupledPeakOptions", "CoupledTables", "peak_from_tables"]
