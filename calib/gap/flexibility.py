"""What a flexible effect costs: the effective degrees of freedom of a bias random walk.

A random walk can bend to follow almost any slow residual, so counting it as one parameter (q)
would let it "explain" structured or unknown effects cheaply. It is charged instead for the
degrees of freedom its smoother actually uses: the trace of the smoother's hat matrix.

Equation (one axis, differenced data ``Δz``, the linear parameters aside): the readings are
``z = b + v`` with ``v`` white (σ²) and ``b`` a walk with increment variances ``r_k = q²Δt_k``.
The differenced covariance is ``Σ_Δ = σ² T + diag(r)`` (``T`` tridiagonal 2, -1), the smoothed
noise is ``v̂ = σ² Dᵀ Σ_Δ⁻¹ Δz`` and the hat matrix of the smoothed walk ``S = I - σ² Dᵀ Σ_Δ⁻¹ D``
(D the difference operator). With ``σ² D Dᵀ = Σ_Δ - diag(r)``:

    tr S = N - tr(Σ_Δ⁻¹ (Σ_Δ - diag r)) = 1 + Σ_k r_k (Σ_Δ⁻¹)_kk

The 1 is the level (the bias, already in the nominal model); the walk's effective dof is
``edf = Σ_k r_k (Σ_Δ⁻¹)_kk``, between 0 (q = 0) and N - 1 (q → ∞). For uniform steps and
away from the ends ``(Σ_Δ⁻¹)_kk → 1/sqrt(r (r + 4σ²))``, so ``edf ≈ (N-1)·sqrt(r/(r + 4σ²))``.

The diagonal of the inverse of the symmetric tridiagonal ``Σ_Δ`` comes from the pivots of its
forward and backward LDLᵀ factorisations (O(N), no inverse formed: LAPACK ``dpttrf`` on the
matrix and on its reversal); no library routine returns only this diagonal of a banded
inverse, hence the one line that combines them here.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import lapack


def tridiagonal_inverse_diagonal(diag: np.ndarray, off: float) -> np.ndarray:
    """Diagonal of ``A⁻¹`` for a symmetric positive-definite tridiagonal A.

    Parameters
    ----------
    diag : (m,) the diagonal of A.  off : the constant off-diagonal element.

    Notes
    -----
    Forward pivots ``f_0 = a_0``, ``f_i = a_i - b²/f_{i-1}``; backward ``g_{m-1} = a_{m-1}``,
    ``g_i = a_i - b²/g_{i+1}``; then ``(A⁻¹)_ii = 1 / (f_i + g_i - a_i)`` (Meurant, SIAM J.
    Matrix Anal. Appl. 13, 1992, §2). The pivots are the D of ``A = LDLᵀ`` (LAPACK ``dpttrf``)
    and of the same factorisation of A reversed.
    """
    a = np.asarray(diag, dtype=float)
    m = a.size
    if m == 1:
        return 1.0 / a
    e = np.full(m - 1, float(off))
    f = _pivots(a, e)
    g = _pivots(a[::-1].copy(), e)[::-1]
    return 1.0 / (f + g - a)


def _pivots(a: np.ndarray, e: np.ndarray) -> np.ndarray:
    """The pivots D of ``A = LDLᵀ`` for the tridiagonal (a, e), LAPACK ``dpttrf``."""
    d, _, info = lapack.dpttrf(a, e)
    if info != 0:
        raise np.linalg.LinAlgError(f"tridiagonal matrix not positive definite (dpttrf info "
                                    f"{info})")
    return d


def walk_effective_dof(sigma2: float, q: float, dt_walk: np.ndarray) -> float:
    """Effective degrees of freedom of a bias random walk, ``Σ_k r_k (Σ_Δ⁻¹)_kk``.

    Parameters
    ----------
    sigma2 : white-noise variance of the axis, (m/s²)².  q : walk intensity (m/s²/√s, or per
    √sample).  dt_walk : (N-1,) the walk's time steps (s, or 1 per sample).

    Returns
    -------
    float : the trace of the smoother's hat matrix minus the level (module docstring).
    """
    r = float(q) ** 2 * np.asarray(dt_walk, dtype=float)
    if q <= 0 or r.size == 0:
        return 0.0
    d = tridiagonal_inverse_diagonal(2.0 * sigma2 + r, -sigma2)
    return float(np.sum(r * d))
