"""Linear filters of the sensor model, one home each: the first-order low-pass and the
random-walk (local-level) Kalman filter with its Rauch-Tung-Striebel smoother.

The bench simulates with them and the estimation side fits with them, so the simulated effect
and the model of it cannot drift apart.
"""

from __future__ import annotations

import math

import numpy as np


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
    a = np.exp(-h / tau).reshape(shape)
    e[1:] = first_order_recursion(np.broadcast_to(a, c.shape), -tau * (1.0 - a) * c)
    return u + e


RECURSION_BLOCK = 16
"""Block length of :func:`constant_recursion` (each level runs this many vector steps)."""


def constant_recursion(a: float | complex, d: np.ndarray) -> np.ndarray:
    """``x_k = a·x_{k-1} + d_k`` (``x_{-1} = 0``) along axis 0 for one coefficient ``a`` (real
    or complex, |a| ≤ 1): the one-pole filter ``scipy.signal.lfilter([1], [1, -a], d, axis=0)``
    without importing ``scipy.signal`` (≈ 0.7 s with the ``scipy.stats`` it pulls in).

    Notes
    -----
    Blocks of B = :data:`RECURSION_BLOCK`: each block's recursion from zero, all blocks at
    once (B vector steps); the values at the blocks' ends obey the same recursion with
    coefficient ``a^B`` (solved the same way, one level down), and
    ``x = local + a^{j+1}·x_end(previous block)``. About B·log_B(n) vector steps; the same
    terms as the sequential filter summed in another order (differences of a few ulps of the
    largest term).
    """
    d = np.asarray(d)
    dtype = np.result_type(d.dtype, np.asarray(a).dtype, float)
    d = d.astype(dtype, copy=False)
    n, b = d.shape[0], RECURSION_BLOCK
    if n <= b:
        x = np.empty_like(d)
        acc = np.zeros(d.shape[1:], dtype=dtype)
        for k in range(n):
            acc = a * acc + d[k]
            x[k] = acc
        return x
    nb = -(-n // b)
    rest = d.shape[1:]
    dd = np.zeros((nb * b, *rest), dtype=dtype)
    dd[:n] = d
    dd = dd.reshape(nb, b, *rest)
    loc = np.empty_like(dd)
    loc[:, 0] = dd[:, 0]
    for j in range(1, b):
        loc[:, j] = a * loc[:, j - 1] + dd[:, j]
    ends = constant_recursion(a**b, loc[:, -1])  # x at the end of each block
    carry = np.zeros((nb, *rest), dtype=dtype)
    carry[1:] = ends[:-1]
    powers = np.asarray(a, dtype=dtype) ** np.arange(1, b + 1)
    powers = powers.reshape((1, b) + (1,) * len(rest))
    return (loc + powers * carry[:, None]).reshape(nb * b, *rest)[:n]


def first_order_recursion(a: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``x_k = a_k x_{k-1} + d_k`` (``x_{-1} = 0``) along axis 0, for coefficients that change
    at every step (:func:`constant_recursion` for one coefficient).

    Parameters
    ----------
    a, d : (n, …) coefficients (|a_k| ≤ 1 here: ``e^{-h_k/τ}``) and inputs.

    Notes
    -----
    Blocks of B ≈ √n steps: every block runs its own recursion from zero, all blocks at once
    (B vector steps), with the product ``P_k = Π a`` since the block start; then the value at
    each block's end is carried to the next (n/B steps) and ``x = local + P·carry``. About
    2√n numpy steps instead of n Python steps; the same terms summed in another order
    (differences of a few ulps of the largest term).
    """
    a = np.asarray(a, dtype=float)
    d = np.asarray(d, dtype=float)
    n = d.shape[0]
    if n == 0:
        return d.copy()
    b = max(1, int(np.sqrt(n)))
    nb = -(-n // b)
    rest = d.shape[1:]
    aa = np.ones((nb * b, *rest))
    dd = np.zeros((nb * b, *rest))
    aa[:n], dd[:n] = a, d
    aa = aa.reshape(nb, b, *rest)
    dd = dd.reshape(nb, b, *rest)
    loc = np.empty_like(dd)
    prod = np.empty_like(aa)
    loc[:, 0], prod[:, 0] = dd[:, 0], aa[:, 0]
    for j in range(1, b):
        loc[:, j] = aa[:, j] * loc[:, j - 1] + dd[:, j]
        prod[:, j] = aa[:, j] * prod[:, j - 1]
    carry = np.zeros((nb, *rest))
    for i in range(1, nb):
        carry[i] = loc[i - 1, -1] + prod[i - 1, -1] * carry[i - 1]
    x = loc + prod * carry[:, None]
    return x.reshape(nb * b, *rest)[:n]


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
