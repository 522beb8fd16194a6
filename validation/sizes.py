"""Effect sizes in σ, defined once.

Every case states how large its effect is in units of the noise, so that "8-20 σ" means the
same thing for a misalignment, a random walk or a lattice. Per axis with noise std σ:

* **Deterministic effect** (signal ``s`` (N,) = reading with the effect minus reading without,
  noise-free)::

      size = ||(I - P) s|| / σ

  ``P`` projects on the nominal per-axis design ``[1, A_r]`` (:func:`nominal_basis`): the part
  the nominal calibration (bias + scale) cannot absorb. Under the nominal model the squared
  size is the non-centrality of the χ² of the residuals, so size 8 is far beyond any
  detection threshold at α = 0.005 (≈ 3-4 σ for one parameter).
* **Out-of-catalog deterministic effect**: the same norm with ``P`` projecting on every
  *linear* column of the catalog that this θ design allows (:func:`catalog_basis`): bias,
  scale, misalignment ``A_p``, K2 ``A_r²``, cross-axis ``A_r·A_p``, drift ``t``, and with
  timing the first-order lag ``dA_r/dt`` and the lever arm ``ω²``, ``α``. That is the part no
  catalog effect can take: "detectable in principle" as something outside the catalog.
* **noise_level** (and the variance a lattice adds): the z of the χ² excess,
  ``(σ_true²/σ² - 1)·sqrt(N/2)`` (:func:`variance_z`) — E[χ²/N] - 1 over its std sqrt(2/N).
* **quantization**: ``lsb`` with ``(lsb²/12)/σ²·sqrt(N/2)`` in the range (:func:`lsb_for_z`):
  the uniform rounding variance counted like a noise excess; for N ≤ 6000 and z ∈ [8, 20]
  this gives lsb ≈ 1.3-4 σ, undithered enough that the readings sit on a visible lattice.
* **bias_random_walk**: ``sqrt(E[LR])``, the expected likelihood ratio of the walk against
  white noise on the differenced series ``d = Δy`` (free of the bias) (:func:`walk_lr`)::

      E[LR] = Σ_j [r_j - log(1 + r_j)],   r_j = q²Δt / (σ²·(2 - 2 cos ω_j)),
      ω_j = πj/(M+1), j = 1 … M, M = N - 1.

  This is Whittle's form evaluated at the eigenfrequencies of the differencing: under white
  noise ``Cov(d) = σ² DDᵀ`` (tridiagonal 2, -1, eigenvalues ``2 - 2cos ω_j``, eigenvectors
  the type-I sine transform), the walk adds ``q²Δt·I``, so each sine coefficient is Gaussian
  with variance ratio ``1 + r_j`` and ``E[LR] = 2 KL`` exactly. (The circular frequencies
  2πj/M of Whittle's approximation understate it by ≈ 40 % here: the lowest frequencies,
  which carry most of a walk, are placed twice as high.)
* **flicker (1/f) noise** (outside the catalog): ``sqrt(min E[LR])`` of the true spectrum
  ``σ² + h/ω`` against the best catalog alternative, white noise of any level plus a random
  walk of any q, in the same differenced basis (:func:`flicker_lr`): what remains after the
  flexible catalog effects. Both spectra grow without bound at low frequency, so this
  separation saturates as h grows (≈ 16 σ at h = 1, N = 6000): flicker targets are [8, 14].
* **effects on both axes** (tilt offset, a clock drift): ``sqrt(size_x² + size_y²)``.
"""

from __future__ import annotations

import numpy as np
from scipy import optimize

TARGET_RANGE: tuple[float, float] = (8.0, 20.0)
"""Every scaled effect size is drawn uniformly in this range (σ)."""


def nominal_basis(a_ref: np.ndarray) -> np.ndarray:
    """(N, 2) columns ``[1, A_r]`` of one axis' nominal model (bias, scale)."""
    a_ref = np.asarray(a_ref, dtype=float)
    return np.column_stack([np.ones_like(a_ref), a_ref])


def catalog_basis(ref: np.ndarray, axis: int, tcol: np.ndarray,
                  omega: np.ndarray | None = None, alpha: np.ndarray | None = None
                  ) -> np.ndarray:
    """Linear columns of the catalog on ``axis`` (0 = x, 1 = y) for an out-of-catalog size.

    Parameters
    ----------
    ref : (N, 2) nominal reference ``[-g sin θ, -g cos θ]``, m/s².
    tcol : (N,) time since the first sample, s (or the sample index without timing).
    omega, alpha : (N,) dθ/dt, d²θ/dt² (rad/s, rad/s²) for a timed run, else None.

    Notes
    -----
    ``dA_x/dθ = -g cos θ = A_y`` and ``dA_y/dθ = g sin θ = -A_x``, so the first-order lag
    column ``-τ dA/dt`` is ``ω·A_y`` on x and ``-ω·A_x`` on y.
    """
    a, p = ref[:, axis], ref[:, 1 - axis]
    cols = [np.ones_like(a), a, p, a * a, a * p, tcol]
    if omega is not None:
        cols += [omega * (p if axis == 0 else -p), omega**2, alpha]
    return np.column_stack(cols)


def residual_size(signal: np.ndarray, basis: np.ndarray, sigma: float) -> float:
    """``||(I - P) s|| / σ`` with P the orthogonal projector on the columns of ``basis``."""
    s = np.asarray(signal, dtype=float)
    q, r = np.linalg.qr(basis)
    keep = np.abs(np.diag(r)) > 1e-10 * np.abs(np.diag(r)).max()  # drop collinear columns
    q = q[:, keep]
    return float(np.linalg.norm(s - q @ (q.T @ s)) / sigma)


def variance_z(sigma2_true: float, sigma2: float, n: int) -> float:
    """z of the χ² excess, ``(σ_true²/σ² - 1)·sqrt(N/2)``."""
    return (sigma2_true / sigma2 - 1.0) * np.sqrt(n / 2.0)


def sigma2_for_z(z: float, sigma2: float, n: int) -> float:
    """Inverse of :func:`variance_z`: the true variance that gives the excess ``z``."""
    return sigma2 * (1.0 + z * np.sqrt(2.0 / n))


def lsb_for_z(z: float, sigma2: float, n: int) -> float:
    """lsb whose rounding variance ``lsb²/12`` gives the χ² excess ``z``."""
    return float(np.sqrt(12.0 * sigma2 * z * np.sqrt(2.0 / n)))


def walk_frequencies(n: int) -> np.ndarray:
    """ω_j = πj/(M+1), j = 1 … M = N-1: ``2 - 2cos ω_j`` are the eigenvalues of ``DDᵀ``."""
    m = n - 1
    return np.pi * np.arange(1, m + 1) / (m + 1)


def walk_lr(q: float, dt: float, sigma2: float, n: int) -> float:
    """Expected likelihood ratio of a random walk of ``q`` on the differenced series (exact,
    see the module doc); ``dt`` the sample interval, s (1 per sample without timing)."""
    w = walk_frequencies(n)
    r = q * q * dt / (sigma2 * (2.0 - 2.0 * np.cos(w)))
    return float(np.sum(r - np.log1p(r)))


def _kl_sum(f_true: np.ndarray, f_alt: np.ndarray) -> float:
    ratio = f_true / f_alt
    return float(np.sum(ratio - 1.0 - np.log(ratio)))


def flicker_lr(h: float, sigma2: float, n: int, dt: float) -> float:
    """Expected LR of flicker noise ``h/ω`` over white noise σ², against the best white noise
    + random walk alternative (level and q free), on the differenced series in the basis of
    :func:`walk_lr`: ``min Σ_j [f/f_a - 1 - log(f/f_a)]`` with ``f = (2 - 2cos ω)(σ² + h/ω)``,
    ``f_a = (2 - 2cos ω)·σ_a² + q²Δt`` (a stationary spectrum placed at the eigenfrequencies
    of the differencing: an approximation for the flicker, exact for the alternative)."""
    w = walk_frequencies(n)
    d = 2.0 - 2.0 * np.cos(w)
    f_true = d * (sigma2 + h / w)

    def cost(p):
        return _kl_sum(f_true, d * np.exp(p[0]) + np.exp(p[1]) * dt)

    best = np.inf
    for q2 in (1e-8, 1e-4, 1e-2, 1.0):
        res = optimize.minimize(cost, [np.log(sigma2), np.log(q2)], method="Nelder-Mead",
                                options={"xatol": 1e-6, "fatol": 1e-6, "maxiter": 2000})
        best = min(best, res.fun)
    return float(best)


def solve_for_size(size_of, target: float, lo: float, hi: float) -> float:
    """The parameter p in [lo, hi] with ``size_of(p) == target`` (size monotone in p).

    The bracket is widened by factors of 10 (up to 6 times) when the target is outside it.
    """
    f_lo, f_hi = size_of(lo) - target, size_of(hi) - target
    for _ in range(6):
        if f_lo * f_hi <= 0:
            break
        if abs(f_lo) < abs(f_hi):
            lo = lo / 10.0 if lo > 0 else lo - 10.0 * (hi - lo)
            f_lo = size_of(lo) - target
        else:
            hi = hi * 10.0
            f_hi = size_of(hi) - target
    else:
        raise ValueError(f"size {target} not reachable in [{lo}, {hi}]")
    return float(optimize.brentq(lambda p: size_of(p) - target, lo, hi, xtol=1e-14, rtol=1e-10))
