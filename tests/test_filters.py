"""``calib.filters.constant_recursion``: the one-pole filter without ``scipy.signal``.

It replaces ``scipy.signal.lfilter([1], [1, -a], d, axis=0)`` in the lag filter and the
ringing columns (importing ``scipy.signal`` pulls in ``scipy.stats``, ≈ 0.7 s), so it must give
the library's values to rounding: real and complex poles, 1-D and 2-D inputs, lengths around
a few samples and long runs."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from calib.filters import constant_recursion, first_order_recursion, lowpass


@pytest.mark.parametrize("n", [1, 2, 15, 16, 17, 257, 4001, 60001])
def test_constant_recursion_is_the_one_pole_filter(n):
    rng = np.random.default_rng([5, n])
    d = rng.standard_normal((n, 3))
    for a in (0.0, 0.37, 0.999, -0.5):
        ref = signal.lfilter([1.0], [1.0, -a], d, axis=0)
        np.testing.assert_allclose(constant_recursion(a, d), ref, rtol=0.0,
                                   atol=1e-13 * max(1.0, float(np.max(np.abs(ref)))))
    pole = np.exp(complex(-0.02 * 2 * np.pi * 4.0, 2 * np.pi * 4.0) * 0.005)  # a ringing mode
    kicks = np.zeros((n, 2), dtype=complex)
    kicks[:: max(1, n // 7)] = 1.0
    ref = signal.lfilter([1.0], [1.0, -pole], kicks, axis=0)
    out = constant_recursion(pole, kicks)
    assert out.dtype == np.complex128
    np.testing.assert_allclose(out, ref, rtol=0.0, atol=1e-13 * max(1.0, np.max(np.abs(ref))))
    np.testing.assert_allclose(constant_recursion(0.37, d[:, 0]),
                               signal.lfilter([1.0], [1.0, -0.37], d[:, 0]), rtol=0.0,
                               atol=1e-13 * max(1.0, float(np.max(np.abs(d)))))


def test_the_uniform_lowpass_agrees_with_its_general_form():
    """On a uniform grid the lag filter's fast path (one coefficient) and its general path
    (a coefficient per step) are the same recursion."""
    t = np.arange(5001) / 200.0
    u = np.column_stack([np.sin(1.3 * t), np.cos(3.1 * t) ** 3])
    fast = lowpass(u, t, 0.05, h_uniform=1.0 / 200.0)
    general = lowpass(u, t, 0.05)
    np.testing.assert_allclose(fast, general, rtol=0.0, atol=1e-13)


def test_first_order_recursion_is_the_sequential_recursion():
    """A coefficient per step, shared by the columns (one solve) or not (column by column),
    and 1-D, real or complex (a damped rotating pole, complex or real inputs): the loop
    ``x_k = a_k·x_{k-1} + d_k`` from ``x_{-1} = 0``."""
    rng = np.random.default_rng(11)
    n = 3001
    d = rng.standard_normal((n, 3))
    a_step = rng.uniform(0.2, 1.0, n)
    a_cols = rng.uniform(0.2, 1.0, (n, 3))

    def loop(a, d):
        x, acc = np.empty(d.shape, np.result_type(a, d)), np.zeros(d.shape[1:])
        for k in range(d.shape[0]):
            acc = a[k] * acc + d[k]
            x[k] = acc
        return x

    shared = np.broadcast_to(a_step[:, None], d.shape)
    poles = a_step * np.exp(1j * rng.uniform(0.0, 0.3, n))  # a complex pole per step
    kicks = d + 1j * rng.standard_normal(d.shape)
    for a, dd in ((shared, d), (a_cols, d), (a_step, d[:, 0]), (poles, kicks), (poles, d)):
        ref = loop(a, dd)
        np.testing.assert_allclose(first_order_recursion(a, dd), ref, rtol=0.0,
                                   atol=1e-13 * max(1.0, float(np.max(np.abs(ref)))))
    assert first_order_recursion(a_step[:0], d[:0]).shape == (0, 3)
