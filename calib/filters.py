"""Linear filters of the sensor model, one home each: the first-order low-pass and the
random-walk (local-level) Kalman filter with its Rauch-Tung-Striebel smoother.

The bench simulates with them and the estimation side fits with them, so the simulated effect
and the model of it cannot drift apart.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import lapack


def uniform_step(t: np.ndarray) -> float | None:
    """The sampling period, s, when the sample times ``t`` (N,) are uniform (every step within
    1e-9 of the mean step), else None. :func:`lowpass` runs its vectorised filter with it."""
    dt = np.diff(np.asarray(t, dtype=float))
    if dt.size == 0:
        return None
    h = float(dt.mean())
    return h if np.max(np.abs(dt - h)) <= 1e-9 * h else None


def lowpass(u: np.ndarray, t: np.ndarray, tau: float, h_uniform: float | None = None
            ) -> np.ndarray:
    """First-order low-pass ``τ·dy/dt + y = u`` of sampled inputs (the bench's filter).

    Parameters
    ----------
    u : (N,) or (N, m) inputs at times ``t`` (N,), s.  tau : time constant, s (0: identity).
    h_uniform : the sampling period when ``t`` is uniform (enables a vectorised filter).

    Notes
    -----
    Exact for an input linear between samples: with the lag error ``e = y - u``,
    ``e_0 = 0``, ``e_k = a_k e_{k-1} - τ c_k (1 - a_k)``, ``a_k = e^{-h_k/τ}``,
    ``c_k = (u_k - u_{k-1})/h_k``. A ramp of slope c lags by τ: ``y = u - τc``.
    """
    u = np.asarray(u, dtype=float)
    if tau <= 0 or u.shape[0] < 2:
        return u.copy()
    t = np.asarray(t, dtype=float)
    h = np.diff(t)
    shape = (-1,) + (1,) * (u.ndim - 1)
    c = np.diff(u, axis=0) / h.reshape(shape)
    if h_uniform is not None:  # y = u + e, e_0 = 0 (y_0 = u_0 + 0.0: -0.0 becomes 0.0)
        a = float(np.exp(-h_uniform / tau))
        y = u.copy()
        y[0] += 0.0
        y[1:] += constant_recursion(a, -tau * (1.0 - a) * c)
        return y
    e = np.zeros_like(u)
    a = np.exp(-h / tau)
    e[1:] = first_order_recursion(a, -tau * (1.0 - a.reshape(shape)) * c)
    return u + e


def _bidiagonal_solve(sub: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``x_k = -sub_{k-1}·x_{k-1} + d_k`` (``x_{-1} = 0``) for every column of ``d`` (n, m):
    forward substitution with the unit lower bidiagonal matrix whose subdiagonal is ``sub``
    (n-1,), LAPACK ``?tbtrs`` (the sequential recursion, in one compiled call)."""
    n = d.shape[0]
    band = np.ones((2, n), dtype=d.dtype, order="F")  # LAPACK's layout: no copy
    band[1, :n - 1] = sub
    solve = lapack.ztbtrs if np.iscomplexobj(d) else lapack.dtbtrs
    x, info = solve(band, d, uplo="L", diag="U", overwrite_b=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"tbtrs failed (info = {info})")
    return x


def constant_recursion(a: float | complex, d: np.ndarray) -> np.ndarray:
    """``x_k = a·x_{k-1} + d_k`` (``x_{-1} = 0``) along axis 0 for one coefficient ``a`` (real
    or complex, |a| ≤ 1): the one-pole filter ``scipy.signal.lfilter([1], [1, -a], d, axis=0)``
    without importing ``scipy.signal`` (≈ 0.7 s with the ``scipy.stats`` it pulls in).

    Why by hand: numpy has no recursive filter. The recursion is forward substitution with
    a unit lower bidiagonal matrix (``-a`` below the diagonal), which LAPACK's banded
    triangular solve (``dtbtrs``/``ztbtrs``, already loaded with ``scipy.linalg``) runs in
    the filter's own order: the same operations as the sequential filter.
    """
    d = np.asarray(d)
    dtype = np.result_type(d.dtype, np.asarray(a).dtype, float)
    n, rest = d.shape[0], d.shape[1:]
    if n == 0:
        return d.astype(dtype, copy=True)
    rhs = np.array(d.reshape(n, -1), dtype=dtype, order="F", copy=True)
    sub = np.full(max(n - 1, 0), -a, dtype=dtype)
    return _bidiagonal_solve(sub, rhs).reshape(n, *rest)


def first_order_recursion(a: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``x_k = a_k x_{k-1} + d_k`` (``x_{-1} = 0``) along axis 0, for coefficients that change
    at every step (:func:`constant_recursion` for one coefficient).

    Parameters
    ----------
    a, d : (n, …) coefficients (|a_k| ≤ 1 here: ``e^{-h_k/τ}``, or a complex pole
        ``e^{λ h_k}``) and inputs, real or complex; ``a`` may be (n,) or broadcast along the
        other axes (one coefficient per step for every column); ``a_0`` is not used.

    Notes
    -----
    Forward substitution with the unit lower bidiagonal matrix ``-a_k`` below the diagonal
    (LAPACK ``dtbtrs``, as :func:`constant_recursion`): the sequential recursion's operations.
    A 1-D ``a`` (the callers' case) is one solve for every column; a broadcast ``a`` is solved
    column by column.
    """
    a = np.asarray(a)
    dtype = np.result_type(a.dtype, np.asarray(d).dtype, float)
    d = np.asarray(d, dtype=dtype)
    n, rest = d.shape[0], d.shape[1:]
    if n == 0:
        return d.copy()
    rhs = np.array(d.reshape(n, -1), dtype=dtype, order="F", copy=True)
    if a.ndim == 1:  # one coefficient per step for every column: one solve
        return _bidiagonal_solve(-a.astype(dtype)[1:], rhs).reshape(n, *rest)
    coef = np.broadcast_to(a.astype(dtype), d.shape).reshape(n, -1)
    out = np.empty_like(rhs)
    for j in range(rhs.shape[1]):
        out[:, j] = _bidiagonal_solve(-coef[1:, j], rhs[:, j:j + 1])[:, 0]
    return out.reshape(n, *rest)


def walk_filter(z: np.ndarray, sigma2: float, qk: np.ndarray
                ) -> tuple[np.ndarray, float, float]:
    """Kalman filter + smoother of ``z_k = b_k + v_k``, b a random walk, diffuse b_0.

    Parameters
    ----------
    z : (N,) reading minus the model's mean without its bias, m/s².
    sigma2 : white-noise variance.  qk : (N-1,) walk increment variances q²Δt_k.

    Returns
    -------
    (innovations, b0, var_b0): normalised innovations (N,) (the first, which only fixes the
    diffuse level, set to 0), and the smoothed bias at the first sample with its variance.
    """
    # Plain Python floats (IEEE doubles, the same operations in the same order as numpy
    # scalars, so the same bits) run the scalar recursion ~5× faster than indexing arrays.
    zl = np.asarray(z, dtype=float).tolist()
    ql = np.asarray(qk, dtype=float).tolist()
    sigma2 = float(sigma2)
    n = len(zl)
    m = [0.0] * n
    p = [0.0] * n
    innov = [0.0] * n
    m[0], p[0] = zl[0], sigma2  # diffuse prior updated with z_0
    for k in range(1, n):
        pp = p[k - 1] + ql[k - 1]
        f = pp + sigma2
        e = zl[k] - m[k - 1]
        innov[k] = e / math.sqrt(f)
        gain = pp / f
        m[k] = m[k - 1] + gain * e
        p[k] = (1.0 - gain) * pp
    ms, ps = m[-1], p[-1]
    for k in range(n - 2, -1, -1):  # Rauch-Tung-Striebel
        pp = p[k] + ql[k]
        c = p[k] / pp
        ms = m[k] + c * (ms - m[k])
        ps = p[k] + c * c * (ps - pp)
    return np.array(innov), float(ms), float(ps)
