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

import functools

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
    r = qr[:c, :c].copy()  # a copy: a view would keep the whole n × c array alive
    r[_strictly_lower(c)] = 0.0  # np.triu's generic path costs more than the QR at small n
    return r


@functools.lru_cache(maxsize=64)
def _strictly_lower(c: int) -> np.ndarray:
    """Boolean mask of the entries below the diagonal of a c × c matrix (read-only)."""
    mask = np.tri(c, c, -1, dtype=bool)
    mask.flags.writeable = False
    return mask


def _unit_columns(r: np.ndarray) -> np.ndarray | None:
    """``r`` with each column scaled to unit norm; None for an empty, zero-column or
    non-finite input (its condition number is infinite)."""
    norms = np.sqrt(np.add.reduce(r * r, axis=0))  # np.linalg.norm(r, axis=0), its operations
    if r.size == 0 or (norms == 0).any() or not np.isfinite(r).all():
        return None
    return r / norms


def _svd_cond(u: np.ndarray | None) -> float:
    if u is None:
        return float("inf")
    s = np.linalg.svd(u, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else float("inf")


def equilibrated_cond(r: np.ndarray) -> float:
    """2-norm condition number of a design with unit-norm columns, from the design itself or
    any matrix with its Gram matrix (its R factor): the column norms and the singular values
    are the same. ``inf`` for an empty, singular, zero-column or non-finite input."""
    return _svd_cond(_unit_columns(np.asarray(r, dtype=float)))


def equilibrated_cond_within(r: np.ndarray, limit: float) -> float:
    """:func:`equilibrated_cond` of a square upper-triangular ``r`` (c × c) where it may
    exceed ``limit``; below, possibly an upper bound of it that is itself ≤ ``limit``.

    For unit-norm columns ``κ₂(R) = ‖R‖₂‖R⁻¹‖₂ ≤ √c·‖R⁻¹‖_F`` (‖R‖₂ ≤ ‖R‖_F = √c; Golub &
    Van Loan, *Matrix Computations*, 4th ed., §2.3 and §2.6). The triangular inverse (LAPACK
    ``dtrtri``) costs less than the SVD, and a design well inside the limit — nearly every
    design a profile search visits — needs no more; the SVD runs only where the bound does
    not clear the limit, so "exceeds ``limit``" is decided exactly as with the SVD alone."""
    r = np.asarray(r, dtype=float)
    u = _unit_columns(r)
    if u is not None and r.ndim == 2 and r.shape[0] == r.shape[1]:
        inv, info = lapack.dtrtri(u, lower=0)
        if info == 0:
            bound = float(np.sqrt(r.shape[1] * np.add.reduce((inv * inv).ravel())))
            if np.isfinite(bound) and bound <= limit:
                return bound
    return _svd_cond(u)


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


__all__ = ["design_cond", "equilibrated_cond", "equilibrated_cond_within", "lagged_sums",
           "r_factor"]
