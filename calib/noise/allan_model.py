"""The Allan variance of the accelerometer noise model and the covariance of its estimates.

The noise model (IEEE Std 952-1997 Annex C, IEEE Std 1293-2018 Annex; rate-like output ``y`` in
m/s², sampled every τ0 = 1/fs s) is a sum of three independent processes, each a unit process
scaled by one parameter ``θ``:

=================  ==================================  ===============  =====================
term               unit process (per sample k)         θ                Allan variance, m ≫ 1
=================  ==================================  ===============  =====================
white noise N      ``w_k``, var 1                      ``N²·fs``        ``N²/τ``
bias instability B flicker: ``Σ_j f_j w_{k-j}`` (Kasdin ``B²``             ``(2 ln2/π)·B²``
                   fractional integration, α = 1)
rate random walk K ``Σ_{j≤k} w_j`` (a random walk)     ``K²/fs``        ``K²·τ/3``
=================  ==================================  ===============  =====================

with N in (m/s²)/√Hz, B in m/s², K in m/s²/√s and τ = m·τ0. Flicker: Kasdin's filter
``f_0 = 1, f_j = f_{j-1}·(j - 1/2)/j`` (N. J. Kasdin, Proc. IEEE 83(5), 1995) turns white
noise of variance B² into a process with one-sided spectrum ``S(f) ≈ B²/(π f)`` for
f ≪ fs, i.e. IEEE Std 952's ``h_{-1} = B²/π`` whose Allan deviation floor is
``√(2 ln2/π)·B = 0.664·B``; its memory is truncated at one record length (the record cannot
tell a longer memory from a mean). The bench simulates exactly these processes
(:class:`bench.terms.BiasInstability`), so a fit and a simulation share one definition.

Sample quantization of a rate-like output (each reading rounded to a step Δ) adds white noise
of variance Δ²/12 to ``y`` (slope −½, absorbed in N); the ``3Q²/τ²`` term of IEEE Std 952
belongs to the quantization of an *integrated* output (angle, velocity), which an
accelerometer's readings are not, so it is not part of the model.

**Estimator and its covariance.** The overlapping Allan variance at ``m`` samples is
``s(m) = (1/2M) Σ_k d_k²``, ``M = N_s - 2m + 1``, with ``d_k = ȳ_{k+m..k+2m-1} - ȳ_{k..k+m-1}``
a linear filter ``h_m`` (``-1/m`` m times, ``+1/m`` m times) of the data. Each unit process
is a linear filter ``a`` of white noise, so ``d_k = Σ_s a(s - k)·w_s`` and for Gaussian data
(Isserlis)::

    E s(m)             = Σ_a θ_a · c_a(0)/2
    Cov(s(m_i), s(m_j)) = Σ_{a,b} θ_a θ_b · Σ_D n_ij(D) c_a(D) c_b(D) / (2 M_i M_j)

``c_a(D) = Σ_p a_i(p)·a_j(p - D)`` the cross-correlation of the two filters of process ``a``
and ``n_ij(D)`` the number of index pairs (k, l) with l - k = D. Both are exact for the
discrete processes (white and random walk: finite filters ``h_m`` and its tail sums; flicker:
``h_m`` convolved with Kasdin's filter), so the fit in :mod:`calib.noise.allan` uses the exact
expected Allan variance at every τ (not only the m ≫ 1 asymptotes of the table) and the full
covariance between the octave points (adjacent octaves of the overlapping estimator are
correlated; treating them as independent would make the intervals too narrow).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy import fft as sfft
from scipy import signal

TERM_NAMES: tuple[str, ...] = ("white_noise_density", "bias_instability", "rate_random_walk")
"""The three terms, in the order of ``θ``."""

FLICKER_FLOOR = float(np.sqrt(2.0 * np.log(2.0) / np.pi))
"""ADEV floor of bias instability B: ``σ_floor = 0.664·B`` (IEEE Std 952 C.3)."""


def flicker_coefficients(n: int) -> np.ndarray:
    """Kasdin's fractional-integration filter for α = 1 (flicker): ``f_0 = 1``,
    ``f_j = f_{j-1}·(j - 1/2)/j``, j = 1 … n-1 (the coefficients of ``(1 - z⁻¹)^{-1/2}``)."""
    j = np.arange(1, max(int(n), 1), dtype=float)
    return np.concatenate([[1.0], np.cumprod((j - 0.5) / j)])


def theta_from_terms(n_density: float, b: float, k: float, rate: float) -> np.ndarray:
    """``θ = (N²·fs, B², K²/fs)`` from the terms (module table)."""
    return np.array([n_density ** 2 * rate, b ** 2, k ** 2 / rate])


def terms_from_theta(theta: np.ndarray, rate: float) -> np.ndarray:
    """Inverse of :func:`theta_from_terms` for θ ≥ 0 (negative θ map to 0)."""
    t = np.maximum(np.asarray(theta, dtype=float), 0.0)
    return np.sqrt(t * np.array([1.0 / rate, 1.0, rate]))


def _box_filters(m: int) -> tuple[np.ndarray, np.ndarray]:
    """The white-noise filter ``h_m`` and the random walk's (its tail sums Σ_{t≥u} h_t,
    finite because Σ h = 0), both on the window's own origin."""
    h = np.concatenate([-np.ones(m), np.ones(m)]) / m
    return h, np.cumsum(h[::-1])[::-1]


def _pair_counts(m_i: int, m_j: int, lags: np.ndarray, n: int) -> np.ndarray:
    """Number of (k, l), 0 ≤ k < M_i, 0 ≤ l < M_j, with l - k = D, for each D in ``lags``."""
    mi, mj = n - 2 * m_i + 1, n - 2 * m_j + 1
    return np.maximum(0, np.minimum(mi, mj - lags) - np.maximum(0, -lags)).astype(float)


def _on_lags(c: np.ndarray, first: int, lo: int, hi: int) -> np.ndarray:
    """``c`` (lags ``first`` …) placed on the lag axis lo … hi (zeros outside its support)."""
    out = np.zeros(hi - lo + 1)
    a, b = max(lo, first), min(hi, first + c.size - 1)
    if a <= b:
        out[a - lo:b - lo + 1] = c[a - first:b - first + 1]
    return out


@lru_cache(maxsize=8)
def allan_moments(n: int, ms: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Design and covariance tensor of the overlapping Allan variance for ``n`` samples at the
    averaging factors ``ms`` (module docstring), for unit processes.

    Returns
    -------
    design : (n_tau, 3) — ``E s(m_i) = design[i] @ θ`` (units of θ: y², per unit process).
    tensor : (n_tau, n_tau, 3, 3) — ``Cov(s_i, s_j) = θ @ tensor[i, j] @ θ``.

    Cost: the flicker filters are a record long; their correlations share one FFT per τ and
    one inverse FFT per pair of τ (about 1 s for 2^17 samples here). Cached, so many logs of
    one length (a Monte Carlo, both axes of a log) pay it once.
    """
    memory = int(n)
    kern = flicker_coefficients(memory)[::-1]
    flick_len = [2 * m + memory - 1 for m in ms]
    nfft = sfft.next_fast_len(2 * max(flick_len))  # room for a full correlation: no wrap
    kernel_fft = sfft.rfft(kern, nfft)
    # flicker: a(u') = Σ_u h_u f_{u-u'} = conv(h, reversed f); origin shared by every τ
    flick_fft = [sfft.rfft(_box_filters(m)[0], nfft) * kernel_fft for m in ms]
    boxes = [_box_filters(m) for m in ms]
    k = len(ms)
    design = np.empty((k, 3))
    tensor = np.empty((k, k, 3, 3))
    for i in range(k):
        h, g = boxes[i]
        design[i, 0], design[i, 2] = h @ h / 2.0, g @ g / 2.0
        for j in range(i, k):
            # only lags where index pairs exist: D = l - k in [-(M_i - 1), M_j - 1]
            lo, hi = -(n - 2 * ms[i]), n - 2 * ms[j]
            lags = np.arange(lo, hi + 1)
            cw = signal.correlate(h, boxes[j][0], mode="full")
            cr = signal.correlate(g, boxes[j][1], mode="full")
            first = -(2 * ms[j] - 1)  # scipy: index 0 is lag -(len(b) - 1)
            circ = sfft.irfft(flick_fft[i] * np.conj(flick_fft[j]), nfft)  # c(D) at D mod nfft
            if j == i:
                design[i, 1] = circ[0] / 2.0
            cf = np.concatenate([circ[nfft + max(lo, -(flick_len[j] - 1)):],
                                 circ[:min(hi, flick_len[i] - 1) + 1]])
            full = np.stack([_on_lags(cw, first, lo, hi),
                             _on_lags(cf, max(lo, -(flick_len[j] - 1)), lo, hi),
                             _on_lags(cr, first, lo, hi)])
            w = _pair_counts(ms[i], ms[j], lags, n) / (2.0 * (n - 2 * ms[i] + 1)
                                                        * (n - 2 * ms[j] + 1))
            t = np.einsum("d,ad,bd->ab", w, full, full)
            tensor[i, j] = tensor[j, i] = t
    design.setflags(write=False)
    tensor.setflags(write=False)
    return design, tensor


def avar_covariance(tensor: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """``Cov(s_i, s_j) = θᵀ T_ij θ`` for the given θ (n_tau, n_tau)."""
    return np.einsum("a,ijab,b->ij", theta, tensor, theta)


__all__ = ["FLICKER_FLOOR", "TERM_NAMES", "allan_moments", "avar_covariance",
           "flicker_coefficients", "terms_from_theta", "theta_from_terms"]
