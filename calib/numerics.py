"""Small numerical helpers, written once: the R factor of a Householder QR and the condition
number of a design with equilibrated (unit-norm) columns (the least-squares fits), and the
lagged products of a record by FFT (the autocovariance sums of the static check's
correlation time and of the held poses' integrated autocorrelation time).

Why by hand: ``numpy.linalg.qr(mode="r")`` computes the same factor, but its wrapper's copies
cost 7× the factorisation on a 20001 × 3 design, so LAPACK ``dgeqrf`` (scipy) is called
directly; numpy has no equilibrated condition number; numpy's ``correlate`` is O(n²) and one
column at a time.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import lapack


def r_factor(a: np.ndarray, overwrite: bool = False) -> np.ndarray:
    """Upper triangle R (c × c) of the Householder QR of ``a`` (n × c, n ≥ c), without Q.

    ``overwrite=True`` lets LAPACK work in ``a`` itself when it is already a Fortran-ordered
    float array (its content is then lost); the factor is the same either way.
    """
    qr, _, _, info = lapack.dgeqrf(np.asfortranarray(a, dtype=float),
                                   overwrite_a=int(overwrite))
    if info != 0:
        raise np.linalg.LinAlgError(f"dgeqrf failed (info = {info})")
    c = a.shape[1]
    return np.triu(qr[:c, :c])


def equilibrated_cond(r: np.ndarray) -> float:
    """2-norm condition number of a design with unit-norm columns, from the design itself or
    any matrix with its Gram matrix (its R factor): the column norms and the singular values
    are the same. ``inf`` for an empty, singular, zero-column or non-finite input."""
    r = np.asarray(r, dtype=float)
    norms = np.linalg.norm(r, axis=0)
    if r.size == 0 or np.any(norms == 0) or not np.all(np.isfinite(r)):
        return float("inf")
    s = np.linalg.svd(r / norms, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else float("inf")


def design_cond(h: np.ndarray) -> float:
    """:func:`equilibrated_cond` of a tall design ``h`` (n × c): its columns scaled to unit
    norm (a zero column kept as is), then the SVD of the c × c R factor instead of n × c."""
    h = np.asarray(h, dtype=float)
    norms = np.linalg.norm(h, axis=0)
    norms[norms == 0] = 1.0
    s = np.linalg.svd(r_factor(h / norms), compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else float("inf")


def lagged_sums(x: np.ndarray, lags: int) -> np.ndarray:
    """(min(lags + 1, n), k): ``S_j = Σ_{i=0}^{n−1−j} x_i·x_{i+j}``, j = 0 … lags, of each
    column of ``x`` (n,) or (n, k) — the inverse FFT of |FFT(x)|² zero-padded to at least 2n
    (no circular wrap)."""
    x = np.asarray(x, dtype=float)
    if x.ndim == 1:
        x = x[:, None]
    n = x.shape[0]
    size = 1 << int(np.ceil(np.log2(max(2 * n, 2))))
    f = np.fft.rfft(x, size, axis=0)
    return np.fft.irfft(f * np.conj(f), size, axis=0)[:min(lags + 1, n)]


__all__ = ["design_cond", "equilibrated_cond", "lagged_sums", "r_factor"]
