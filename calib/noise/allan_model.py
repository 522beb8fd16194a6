"""The Allan variance of the inertial-sensor noise model and the covariance of its estimates.

The noise model (IEEE Std 952-1997 Annex C; IEEE Std 1293-2018 Annex; El-Sheimy, Hou & Niu,
IEEE Trans. Instrum. Meas. 57(1), 2008, "Analysis and modeling of inertial sensors using Allan
variance") of a rate-like output ``y`` (an accelerometer in m/s², a gyro in rad/s), sampled every
τ0 = 1/fs s, is a sum of independent processes, each a unit process scaled by one parameter θ:

==================  =====================================  ===============  =======================
process             unit process (per sample k)            θ                Allan variance, m ≫ 1
==================  =====================================  ===============  =======================
white noise N       ``w_k``, var 1                         ``N²·fs``        ``N²/τ``
bias instability B  flicker ``Σ_j f_j w_{k-j}`` (Kasdin's  ``B²``           ``(2 ln2/π)·B²``
                    fractional integration, α = 1)
rate random walk K  ``Σ_{j≤k} w_j`` (a random walk)        ``K²/fs``        ``K²·τ/3``
quantization Q      ``w_k − w_{k−1}`` (the rate of an      ``Q²·fs²``       ``3·Q²/τ²``
                    integrated output quantized by Q)
Gauss–Markov        AR(1) ``x_k = φ x_{k−1} + √(1−φ²) w_k``  ``σ²``         ``(σ²T_c/τ)·[2 − (T_c/τ)
(σ, T_c)            unit variance, ``φ = exp(−τ0/T_c)``                       (3 − 4e^{−τ/T_c} +
                                                                              e^{−2τ/T_c})]``
==================  =====================================  ===============  =======================

with τ = m·τ0 and, for an accelerometer, N in (m/s²)/√Hz, B in m/s², K in m/s²/√s, Q in m/s
(the velocity step of a Δv-integrating output), σ in m/s², T_c in s; for a gyro the same with
rad in place of m/s (ARW rad/√s, B rad/s, RRW rad/s/√s, Q rad). The Gauss–Markov (first-order
Markov, "correlated noise") curve rises as σ·√(τ/T_c)… like a random walk for τ ≪ T_c, peaks
near τ ≈ 1.89·T_c at 0.62·σ·…, and falls as ``σ·√(2T_c/τ)`` like white noise for τ ≫ T_c
(El-Sheimy et al. 2008 eq. 14; the column above is its exact continuous form, the fit uses the
exact discrete one). Flicker: Kasdin's filter ``f_0 = 1, f_j = f_{j-1}·(j - 1/2)/j`` (N. J.
Kasdin, Proc. IEEE 83(5), 1995) turns white noise of variance B² into a process with one-sided
spectrum ``S(f) ≈ B²/(π f)`` for f ≪ fs, i.e. IEEE Std 952's ``h_{-1} = B²/π`` whose Allan
deviation floor is ``√(2 ln2/π)·B = 0.664·B``; its memory is truncated at one record length
(the record cannot tell a longer memory from a mean). The bench simulates exactly these
processes (:class:`bench.terms.BiasInstability`, :mod:`bench.sensor_twin`), so a fit and a
simulation share one definition.

Sample quantization of a rate-like output (each *reading* rounded to a step Δ) is white noise
of variance Δ²/12 (slope −½, part of N). The ``3Q²/τ²`` process above is the quantization of an
*integrated* output (a Δv or Δθ counter differenced to a rate: slope −1); it enters the model
only when the fit's rule asks for it (:mod:`calib.noise.allan`).

**Estimator and its covariance.** The overlapping Allan variance at ``m`` samples is
``s(m) = (1/2M) Σ_k d_k²``, ``M = N_s - 2m + 1``, with ``d_k = ȳ_{k+m..k+2m-1} - ȳ_{k..k+m-1}``
a linear filter ``h_m`` (``-1/m`` m times, ``+1/m`` m times) of the data. Each unit process is
a linear filter ``a`` of white noise, so ``d_k = Σ_s a(s - k)·w_s`` and for Gaussian data
(Isserlis)::

    E s(m)              = Σ_a θ_a · c_a(0)/2
    Cov(s(m_i), s(m_j)) = Σ_{a,b} θ_a θ_b · Σ_D n_ij(D) c_a(D) c_b(D) / (2 M_i M_j)

``c_a(D) = Σ_p a_i(p)·a_j(p - D)`` the cross-correlation of the two filters of process ``a``
and ``n_ij(D)`` the number of index pairs (k, l) with l - k = D. All are exact for the discrete
processes: white, quantization and random walk have finite filters (``h_m``, its first
difference, its tail sums); flicker is ``h_m`` convolved with Kasdin's filter (one FFT per τ,
one inverse FFT per pair of τ); Gauss–Markov is the white correlation convolved with the AR(1)
autocovariance ``φ^|k|`` (two first-order recursions over the lags, cut where ``φ^|k|`` <
e^-40). The diagonal ``Var s(m_i)`` gives the exact equivalent degrees of freedom of each point
for the fitted mixture, ``ν_i = 2 (E s_i)² / Var s_i`` (:func:`edf`), which for a pure power-law
noise is Greenhall's EDF (``allantools.edf_greenhall``; ``tests/test_allan.py`` compares them).

**Segments** (a log with gaps, :func:`pooled_moments`). A log split at its gaps
(:func:`calib.logs.static_log.log_segments`) gives segments of ``n_s`` samples, each evenly
sampled at the one rate. Octave m of the pooled overlapping Allan variance averages every
overlapping difference of every segment that holds one::

    s(m) = Σ_s c_s(m)·s_s(m) / Σ_s c_s(m),   c_s(m) = max(n_s − 2m + 1, 0)

(``s_s`` the segment's own overlapping Allan variance, ``c_s`` its number of differences; no
difference straddles a gap — the gap is never filled). With the weights
``w_s(m) = c_s(m)/Σ_s c_s(m)`` and the segments taken as independent records::

    E s(m_i)              = Σ_s w_s(m_i) · E s_s(m_i)
    Cov(s(m_i), s(m_j))   = Σ_s w_s(m_i) w_s(m_j) · Cov(s_s(m_i), s_s(m_j))

each segment's moments those above for its own length, on the octaves it supports (``n_s ≥
2m``, one difference or more; the others get weight 0). Independence is exact for white
noise, quantization and the random walk (the differences inside a segment see only its own
white draws and walk increments) and for a Gauss–Markov term whose correlation time is short
against the gap; for
flicker (and a longer T_c) the differences of two segments are weakly correlated through the
process's memory, a positive cross term the pooled covariance leaves out (each segment's
flicker is also truncated at its own length, as one record's is at its). This is the
pooling of independent estimates of IEEE Std 952-1997 Annex C and of Greenhall's EDF
(the degrees of freedom of independent records add, here through the exact covariance).
One segment is one record: :func:`record_moments` then returns :func:`moments` itself.

**Cost and cache.** Only the record length ``n`` and the octave grid enter these moments, never
the data, so they are computed once per (n, grid) and kept: in memory, and on disk as one
``.npz`` per key under the user's cache folder (:func:`cache_dir`), written atomically (a
temporary file in the same folder, then ``os.replace``), read back after checking its key,
shapes and finiteness (a damaged file is recomputed and replaced). The Gauss–Markov columns
(one per correlation time of :func:`gm_grid`) are computed only when a fit asks for them and
are cached the same way.
"""

from __future__ import annotations

import contextlib
import hashlib
import math
import os
import tempfile
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
from scipy import fft as sfft

# scipy.signal is imported inside the functions that use it: it costs ≈ 0.7 s at start-up and
# most commands that import this module (the bench's flicker term) never call them.

TERM_NAMES: tuple[str, ...] = ("white_noise_density", "bias_instability", "rate_random_walk")
"""The three core terms, in the order of ``θ`` (every fit holds them)."""
EXTRA_TERM_NAMES: tuple[str, ...] = ("quantization_noise", "gauss_markov")
"""The terms a fit adds by its rule (:mod:`calib.noise.allan`), after the core ones in ``θ``."""
ALL_TERM_NAMES: tuple[str, ...] = TERM_NAMES + EXTRA_TERM_NAMES
"""θ = (N²·fs, B², K²/fs, Q²·fs², σ²_GM): the order of every design column and tensor axis."""
N_PROCESSES = len(ALL_TERM_NAMES)

FLICKER_FLOOR = float(np.sqrt(2.0 * np.log(2.0) / np.pi))
"""ADEV floor of bias instability B: ``σ_floor = 0.664·B`` (IEEE Std 952 C.3)."""

GM_CUT = 40.0
"""The Gauss–Markov correlation ``φ^|k| = e^{-|k|/T_c}`` is taken as 0 beyond |k| = 40·T_c
(e^-40 ≈ 4e-18 of its peak: below float64 resolution of the sums)."""
MOMENTS_VERSION = 4
"""Bumped whenever these formulas change: cache files of another version are not read."""
CACHE_ENV = "TILTBENCH_CACHE_DIR"
"""Environment variable naming the cache folder; ``off`` disables the disk cache."""


def flicker_coefficients(n: int) -> np.ndarray:
    """Kasdin's fractional-integration filter for α = 1 (flicker): ``f_0 = 1``,
    ``f_j = f_{j-1}·(j - 1/2)/j``, j = 1 … n-1 (the coefficients of ``(1 - z⁻¹)^{-1/2}``)."""
    j = np.arange(1, max(int(n), 1), dtype=float)
    return np.concatenate([[1.0], np.cumprod((j - 0.5) / j)])


_SCALES = {"white_noise_density": (1, -1), "bias_instability": (0, 0),
           "rate_random_walk": (-1, 1), "quantization_noise": (2, -2), "gauss_markov": (0, 0)}
"""θ_a = value² · fs^e (first exponent); value = √(θ_a · fs^-e)."""


def theta_from_terms(n_density: float, b: float, k: float, rate: float,
                     q: float = 0.0, gm_sigma: float = 0.0) -> np.ndarray:
    """``θ = (N²·fs, B², K²/fs[, Q²·fs², σ²])`` from the terms (module table); the two extra
    entries only when ``q`` or ``gm_sigma`` is given."""
    core = np.array([n_density ** 2 * rate, b ** 2, k ** 2 / rate])
    if q == 0.0 and gm_sigma == 0.0:
        return core
    return np.concatenate([core, [q ** 2 * rate ** 2, gm_sigma ** 2]])


def terms_from_theta(theta: np.ndarray, rate: float) -> np.ndarray:
    """Inverse of :func:`theta_from_terms` for θ ≥ 0 (negative θ map to 0); 3 or 5 entries."""
    t = np.maximum(np.asarray(theta, dtype=float), 0.0)
    factor = np.array([1.0 / rate, 1.0, rate, 1.0 / rate ** 2, 1.0])[:t.shape[-1]]
    return np.sqrt(t * factor)


def term_value(name: str, theta_a: float, rate: float) -> float:
    """One term's value in its unit from its θ entry (``max(θ, 0)``; module table)."""
    e = _SCALES[name][0]
    return float(math.sqrt(max(float(theta_a), 0.0) * rate ** (-e)))


def gm_avar(tau: np.ndarray, sigma: float, tc: float) -> np.ndarray:
    """Continuous-time Allan variance of a Gauss–Markov process of std σ and correlation
    time T_c (El-Sheimy et al. 2008 eq. 14, with q_c² = 2σ²/T_c)::

        σ²_A(τ) = (σ² T_c/τ)·[2 − (T_c/τ)(3 − 4e^{−τ/T_c} + e^{−2τ/T_c})]

    (its square-root peaks at τ ≈ 1.89·T_c at ≈ 0.62·σ)."""
    tau = np.asarray(tau, dtype=float)
    x = tau / tc
    return sigma ** 2 / x * (2.0 - (3.0 - 4.0 * np.exp(-x) + np.exp(-2.0 * x)) / x)


# ------------------------------------------------------------------ filters and pairs
def _box(m: int) -> np.ndarray:
    return np.concatenate([-np.ones(m), np.ones(m)]) / m


Shaping = tuple[float, ...] | None
"""A log's shaping filter (:mod:`calib.noise.shaping`: the taps ``f`` of an export's low-pass
filter, Σ f = 1), or None for none. Every process reaches the readings through it, so the
Allan difference filter of octave m is ``h_m ∗ f`` instead of ``h_m`` (module docstring:
Shaped logs); a tuple, so that the moments are cached per filter."""


def _shaped(shaping: Shaping) -> tuple:
    """The shaping argument of a cached function: none for an unshaped log, so that
    ``moments(n, ms)`` and the moments a fit asks for are one cache entry."""
    return () if shaping is None else (shaping,)


def difference_filter(m: int, shaping: Shaping = None) -> np.ndarray:
    """The Allan difference filter of octave ``m``: ``h_m``, or ``h_m ∗ f`` for a shaped log."""
    h = _box(m)
    return h if shaping is None else np.convolve(h, np.asarray(shaping, dtype=float))


def _finite_filters(m: int, shaping: Shaping = None
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """White ``h_m`` (``h_m ∗ f`` when shaped), random walk (its tail sums Σ_{t≥u} h_t, finite
    because Σ h = 0) and quantization (``h`` convolved with [1, −1]), each on its process's own
    origin."""
    h = difference_filter(m, shaping)
    return h, np.cumsum(h[::-1])[::-1], np.convolve(h, [1.0, -1.0])


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


def _gm_correlation(cw: np.ndarray, phi: float, pad: int) -> np.ndarray:
    """``(cw ∗ R)(D)`` with ``R(k) = φ^|k|`` on the lags of ``cw`` widened by ``pad`` on each
    side: a causal and an anticausal first-order recursion (scipy.signal.lfilter)."""
    from scipy import signal

    x = np.concatenate([np.zeros(pad), cw, np.zeros(pad)])
    fwd = signal.lfilter([1.0], [1.0, -phi], x)
    bwd = signal.lfilter([0.0, phi], [1.0, -phi], x[::-1])[::-1]
    return fwd + bwd


@dataclass(frozen=True)
class AllanMoments:
    """Exact moments of the overlapping Allan variance for ``n`` samples at octaves ``ms``
    (module docstring), per unit process.

    design : (k, 4) — ``E s(m_i)`` per unit θ of white, flicker, random walk, quantization.
    tensor : (k, k, 4, 4) — ``Cov(s_i, s_j) = θ @ tensor[i, j] @ θ`` (the same four).
    gm_tc : (G,) correlation times of :func:`gm_grid`, in samples.
    gm_design : (G, k) — ``E s(m_i)`` per unit σ² of the Gauss–Markov process of each T_c
        (cheap: the lag-0 values only); its covariance columns come from :func:`gm_columns`
        when a fit asks for one T_c (:meth:`full`).
    """

    n: int
    ms: tuple[int, ...]
    design: np.ndarray
    tensor: np.ndarray
    gm_tc: np.ndarray
    gm_design: np.ndarray
    shaping: Shaping = None

    def full(self, g: int | None) -> tuple[np.ndarray, np.ndarray]:
        """(design (k, 5), tensor (k, k, 5, 5)) with the Gauss–Markov process of T_c
        ``gm_tc[g]`` in the last place (zeros when ``g`` is None)."""
        if g is None:
            return with_gauss_markov(self.design, self.tensor)
        return with_gauss_markov(self.design, self.tensor, self.gm_design[g],
                                 gm_columns(self.n, self.ms, float(self.gm_tc[g]),
                                            *_shaped(self.shaping)))


def with_gauss_markov(design4: np.ndarray, tensor4: np.ndarray,
                      gm_design: np.ndarray | None = None, gm_cols: np.ndarray | None = None
                      ) -> tuple[np.ndarray, np.ndarray]:
    """(design (k, 5), tensor (k, k, 5, 5)) of the four processes' ``design4`` (k, 4) and
    ``tensor4`` (k, k, 4, 4) with a Gauss–Markov process in the last place: its design column
    ``gm_design`` (k,) and covariance products ``gm_cols`` (k, k, 5); zeros when not given."""
    k = design4.shape[0]
    design = np.zeros((k, N_PROCESSES))
    tensor = np.zeros((k, k, N_PROCESSES, N_PROCESSES))
    design[:, :4] = design4
    tensor[:, :, :4, :4] = tensor4
    if gm_cols is not None:
        design[:, 4] = gm_design
        tensor[:, :, 4, :] = gm_cols
        tensor[:, :, :, 4] = gm_cols
    return design, tensor


GM_STEPS_PER_OCTAVE = 8
"""Correlation times tried per octave: a T_c off by half a step (2^{1/8}, 9 %) moves the
bump's Allan variance by at most ≈ 4 % (measured on the design), within the scatter of a few
hundred degrees of freedom."""


def gm_grid(ms: tuple[int, ...]) -> np.ndarray:
    """Gauss–Markov correlation times tried by the fit, in samples: every quarter octave
    (:data:`GM_STEPS_PER_OCTAVE`) from 2 to the last octave's m (``2^{j/4}``): the bump of a
    GM term lies near τ ≈ 1.89·T_c, so these place it anywhere inside the octave grid."""
    top = max(ms[-1], 2)
    steps = GM_STEPS_PER_OCTAVE
    j = np.arange(steps, int(math.floor(steps * math.log2(top))) + 1)
    return 2.0 ** (j / steps)


def _pair_lags(n: int, ms: tuple[int, ...], i: int, j: int):
    """Lags where index pairs exist, D = l - k in [-(M_i - 1), M_j - 1], and their weights
    ``n_ij(D) / (2 M_i M_j)``."""
    lo, hi = -(n - 2 * ms[i]), n - 2 * ms[j]
    lags = np.arange(lo, hi + 1)
    w = _pair_counts(ms[i], ms[j], lags, n) / (2.0 * (n - 2 * ms[i] + 1) * (n - 2 * ms[j] + 1))
    return lo, hi, w


def _flicker_parts(n: int, filters: list) -> tuple[list[int], int, list[np.ndarray]]:
    """The flicker filters of every octave (its difference filter convolved with Kasdin's,
    memory one record): their lengths, the FFT length that holds a full correlation of two
    of them (no wrap) and their FFTs."""
    memory = int(n)
    kern = flicker_coefficients(memory)[::-1]
    flick_len = [f[0].size + memory - 1 for f in filters]
    nfft = sfft.next_fast_len(2 * max(flick_len))
    kernel_fft = sfft.rfft(kern, nfft)
    return flick_len, nfft, [sfft.rfft(f[0], nfft) * kernel_fft for f in filters]


def _compute(n: int, ms: tuple[int, ...], shaping: Shaping = None) -> dict[str, np.ndarray]:
    """The four processes' moments and the GM design of every T_c of :func:`gm_grid`."""
    from scipy import signal

    k = len(ms)
    filters = [_finite_filters(m, shaping) for m in ms]
    flick_len, nfft, flick_fft = _flicker_parts(n, filters)
    tc = gm_grid(ms)
    design = np.empty((k, 4))
    tensor = np.empty((k, k, 4, 4))
    gm_design = np.empty((tc.size, k))
    for i in range(k):
        h, g, q = filters[i]
        design[i, 0], design[i, 2], design[i, 3] = h @ h / 2.0, g @ g / 2.0, q @ q / 2.0
        cw0 = signal.correlate(h, h, mode="full")  # lags -(len h - 1) … len h - 1
        lag = np.arange(-(h.size - 1), h.size)
        gm_design[:, i] = (np.exp(-np.abs(lag)[None, :] / tc[:, None]) @ cw0) / 2.0
        for j in range(i, k):
            lo, hi, w = _pair_lags(n, ms, i, j)
            full = _four_correlations(filters[i], filters[j], flick_fft[i], flick_fft[j],
                                      flick_len[i], flick_len[j], nfft, lo, hi)
            if j == i:
                design[i, 1] = full[1, -lo] / 2.0
            t = np.einsum("d,ad,bd->ab", w, full, full)
            tensor[i, j] = tensor[j, i] = t
    return {"design": design, "tensor": tensor, "gm_tc": tc, "gm_design": gm_design}


def _four_correlations(fi, fj, ffi, ffj, fli, flj, nfft, lo, hi) -> np.ndarray:
    """(4, hi - lo + 1): the cross-correlations c_a(D) of white, flicker, random walk and
    quantization between two octaves, on the lags lo … hi."""
    from scipy import signal

    first = -(fj[0].size - 1)  # scipy: index 0 is lag -(len(b) - 1)
    cw = signal.correlate(fi[0], fj[0], mode="full")
    cr = signal.correlate(fi[1], fj[1], mode="full")
    cq = signal.correlate(fi[2], fj[2], mode="full")
    circ = sfft.irfft(ffi * np.conj(ffj), nfft)  # flicker c(D) at D mod nfft
    cf_first = max(lo, -(flj - 1))
    cf = np.concatenate([circ[nfft + cf_first:], circ[:min(hi, fli - 1) + 1]])
    return np.stack([_on_lags(cw, first, lo, hi), _on_lags(cf, cf_first, lo, hi),
                     _on_lags(cr, first, lo, hi), _on_lags(cq, first - 1, lo, hi)])


def _compute_gm(n: int, ms: tuple[int, ...], tc: float, shaping: Shaping = None
                ) -> np.ndarray:
    """(k, k, 5): covariance products of the Gauss–Markov process of correlation time ``tc``
    samples with white, flicker, random walk, quantization and itself (module docstring)."""
    from scipy import signal

    k = len(ms)
    filters = [_finite_filters(m, shaping) for m in ms]
    flick_len, nfft, flick_fft = _flicker_parts(n, filters)
    phi = math.exp(-1.0 / tc)
    pad = int(min(n, math.ceil(GM_CUT * tc)))
    out = np.empty((k, k, 5))
    for i in range(k):
        for j in range(i, k):
            lo, hi, w = _pair_lags(n, ms, i, j)
            first = -(filters[j][0].size - 1)
            c_first = first - pad  # the lag of cg[0]
            cw = signal.correlate(filters[i][0], filters[j][0], mode="full")
            cg = _gm_correlation(cw, phi, pad)
            # only the lags where the GM correlation is not (yet) below e^-40
            a, b = max(lo, c_first), min(hi, c_first + cg.size - 1)
            full = _four_correlations(filters[i], filters[j], flick_fft[i], flick_fft[j],
                                      flick_len[i], flick_len[j], nfft, a, b)
            seg = cg[a - c_first:b - c_first + 1]
            wg = w[a - lo:b - lo + 1] * seg
            out[i, j] = out[j, i] = np.concatenate([full @ wg, [seg @ wg]])
    return out


# ------------------------------------------------------------------ the cache
def cache_dir() -> Path | None:
    """The moments' disk cache: ``$TILTBENCH_CACHE_DIR`` (``off``: no disk cache), else
    ``$XDG_CACHE_HOME/tiltbench/allan``, else ``~/.cache/tiltbench/allan`` (the XDG base
    directory convention, used on every system)."""
    env = os.environ.get(CACHE_ENV)
    if env is not None:
        return None if env.strip().lower() in ("", "off", "0", "none") else Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "tiltbench" / "allan"


def _key(n: int, ms: tuple[int, ...], part: str, shaping: Shaping = None) -> str:
    text = f"v{MOMENTS_VERSION}|{part}|n={n}|ms={','.join(map(str, ms))}"
    if shaping is not None:  # the taps' exact bits: another filter, another file
        text += "|shaping=" + np.asarray(shaping, dtype="<f8").tobytes().hex()
        part = "shaped-" + part
    return f"{part}-n{n}-k{len(ms)}-{hashlib.sha256(text.encode()).hexdigest()[:16]}"


def _load(path: Path, key: str, shapes: dict[str, tuple[int, ...]]) -> dict | None:
    try:
        with np.load(path, allow_pickle=False) as z:
            if str(z["key"]) != key:
                return None
            out = {name: np.array(z[name]) for name in shapes}
    except (OSError, KeyError, ValueError, EOFError):
        return None
    for name, shape in shapes.items():
        if out[name].shape != shape or not np.all(np.isfinite(out[name])):
            return None
    return out


def _store(path: Path, key: str, arrays: dict[str, np.ndarray]) -> None:
    """Write atomically (temporary file beside it, then ``os.replace``); a cache that cannot
    be written is only a cache: the error is dropped and the next run computes again."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        try:
            with os.fdopen(fd, "wb") as f:
                np.savez(f, key=np.array(key), **arrays)
            os.replace(tmp, path)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
            raise
    except OSError:
        return


@lru_cache(maxsize=16)
def moments(n: int, ms: tuple[int, ...], shaping: Shaping = None) -> AllanMoments:
    """:class:`AllanMoments` for ``n`` samples at octaves ``ms`` — from memory, the disk cache
    (module docstring) or computed. Cost of a computation: the flicker filters are a record
    long; their correlations share one FFT per τ and one inverse FFT per pair of τ (1.4 s at
    2^15 samples, 8 s at 2^17 on one core); a cached copy loads in milliseconds."""
    ms = tuple(int(m) for m in ms)
    k = len(ms)
    tc = gm_grid(ms)
    folder = cache_dir()
    key = _key(n, ms, "base", shaping)
    shapes = {"design": (k, 4), "tensor": (k, k, 4, 4), "gm_tc": (tc.size,),
              "gm_design": (tc.size, k)}
    got = None if folder is None else _load(folder / f"{key}.npz", key, shapes)
    if got is not None and not np.array_equal(got["gm_tc"], tc):
        got = None
    if got is None:
        got = _compute(n, ms, shaping)
        if folder is not None:
            _store(folder / f"{key}.npz", key, got)
    out = AllanMoments(n=int(n), ms=ms, shaping=shaping, **got)
    for a in (out.design, out.tensor, out.gm_tc, out.gm_design):
        a.setflags(write=False)
    return out


@lru_cache(maxsize=64)
def gm_columns(n: int, ms: tuple[int, ...], tc: float, shaping: Shaping = None) -> np.ndarray:
    """(k, k, 5): the covariance products of the Gauss–Markov process of correlation time
    ``tc`` samples with white, flicker, random walk, quantization and itself — from memory,
    the disk cache or computed (about 1 s at 2^15 samples, 3 s at 2^17: one T_c at a time,
    when a fit asks for it)."""
    ms = tuple(int(m) for m in ms)
    k = len(ms)
    folder = cache_dir()
    key = _key(n, ms, f"gm{float(tc)!r}", shaping)
    got = None if folder is None else _load(folder / f"{key}.npz", key, {"cols": (k, k, 5)})
    if got is None:
        got = {"cols": _compute_gm(n, ms, float(tc), shaping)}
        if folder is not None:
            _store(folder / f"{key}.npz", key, got)
    cols = got["cols"]
    cols.setflags(write=False)
    return cols


def segment_counts(lengths: tuple[int, ...], ms: tuple[int, ...]) -> np.ndarray:
    """(S, k) the overlapping differences ``c_s(m) = max(n_s − 2m + 1, 0)`` of each segment at
    each octave (module docstring: Segments)."""
    n = np.asarray(lengths, dtype=float)[:, None]
    m = np.asarray(ms, dtype=float)[None, :]
    return np.maximum(n - 2.0 * m + 1.0, 0.0)


def segment_weights(lengths: tuple[int, ...], ms: tuple[int, ...]) -> np.ndarray:
    """(S, k) the weights ``w_s(m) = c_s(m)/Σ_s c_s(m)`` of the pooled Allan variance (0 at
    an octave no segment holds)."""
    c = segment_counts(lengths, ms)
    total = c.sum(axis=0)
    return c / np.where(total > 0, total, 1.0)


@dataclass(frozen=True)
class PooledMoments:
    """Exact moments (independent segments, module docstring) of the overlapping Allan variance
    pooled over segments of ``lengths`` samples at octaves ``ms``: the interface of
    :class:`AllanMoments` (``design``, ``tensor``, ``gm_tc``, ``gm_design``, ``full``), so the
    fit (:class:`calib.noise.allan_fit.Engine`) uses either unchanged.

    lengths : (S,) samples of each segment (every one holds octave ``ms[0]``: n_s ≥ 2·ms[0]).
    weights : (S, k) ``w_s(m_i)`` (:func:`segment_weights`).
    parts : each segment's :class:`AllanMoments` on the octaves it supports (a prefix of ``ms``).
    design (k, 4), tensor (k, k, 4, 4), gm_design (G, k) : pooled as in the module docstring.
    gm_tc : (G,) the correlation times of :func:`gm_grid` of ``ms``, in samples.
    n : Σ_s n_s, the samples of all segments.
    """

    lengths: tuple[int, ...]
    ms: tuple[int, ...]
    weights: np.ndarray
    parts: tuple[AllanMoments, ...]
    design: np.ndarray
    tensor: np.ndarray
    gm_tc: np.ndarray
    gm_design: np.ndarray
    shaping: Shaping = None

    @property
    def n(self) -> int:
        return int(sum(self.lengths))

    def full(self, g: int | None) -> tuple[np.ndarray, np.ndarray]:
        """(design (k, 5), tensor (k, k, 5, 5)) with the Gauss–Markov process of T_c
        ``gm_tc[g]`` in the last place (zeros when ``g`` is None): each segment's covariance
        columns (:func:`gm_columns` of its length and octaves) pooled with the weights."""
        if g is None:
            return with_gauss_markov(self.design, self.tensor)
        k, tc = len(self.ms), float(self.gm_tc[g])
        cols = np.zeros((k, k, N_PROCESSES))
        for w, part in zip(self.weights, self.parts, strict=True):
            ks = len(part.ms)
            ww = w[:ks]
            cols[:ks, :ks] += (ww[:, None, None] * ww[None, :, None]
                               * gm_columns(part.n, part.ms, tc, *_shaped(self.shaping)))
        return with_gauss_markov(self.design, self.tensor, self.gm_design[g], cols)


def supported_octaves(n: int, ms: tuple[int, ...]) -> tuple[int, ...]:
    """The octaves of ``ms`` a record of ``n`` samples holds a difference at: n ≥ 2m (its
    ``n − 2m + 1`` overlapping differences ``ȳ_{k+m..k+2m-1} − ȳ_{k..k+m-1}``, one or more)."""
    return tuple(int(m) for m in ms if n >= 2 * m)


@lru_cache(maxsize=16)
def pooled_moments(lengths: tuple[int, ...], ms: tuple[int, ...], shaping: Shaping = None
                   ) -> PooledMoments:
    """:class:`PooledMoments` of segments of ``lengths`` samples at octaves ``ms`` (module
    docstring: Segments). Each segment's own moments come from :func:`moments` (cached on disk
    per length and octaves); segments that hold no octave are refused (give only the ones
    that contribute).

    ``gm_design``: the mean of a Gauss–Markov process's Allan variance does not depend on the
    record's length (a finite filter against ``φ^|k|``, no memory truncation), so it is the
    same in every segment and the pooled one (Σ_s w_s = 1) is that of the longest segment,
    which holds every octave of ``ms``."""
    lengths = tuple(int(n) for n in lengths)
    ms = tuple(int(m) for m in ms)
    k = len(ms)
    parts = []
    for n in lengths:
        own = supported_octaves(n, ms)
        if not own or own != ms[:len(own)]:
            raise ValueError(f"a segment of {n} samples holds no octave of {ms}")
        parts.append(moments(n, own, *_shaped(shaping)))
    weights = segment_weights(lengths, ms)
    if np.any(weights.sum(axis=0) <= 0):
        raise ValueError(f"no segment of {lengths} holds every octave of {ms}")
    design = np.zeros((k, 4))
    tensor = np.zeros((k, k, 4, 4))
    for w, part in zip(weights, parts, strict=True):
        ks = len(part.ms)
        ww = w[:ks]
        design[:ks] += ww[:, None] * part.design
        tensor[:ks, :ks] += ww[:, None, None, None] * ww[None, :, None, None] * part.tensor
    longest = parts[int(np.argmax(lengths))]
    if longest.ms != ms:
        raise ValueError(f"the longest segment ({max(lengths)} samples) holds octaves "
                         f"{longest.ms}, not all of {ms}")
    out = PooledMoments(lengths=lengths, ms=ms, weights=weights, parts=tuple(parts),
                        design=design, tensor=tensor, gm_tc=longest.gm_tc,
                        gm_design=longest.gm_design, shaping=shaping)
    for a in (out.weights, out.design, out.tensor):
        a.setflags(write=False)
    return out


def record_moments(lengths: tuple[int, ...], ms: tuple[int, ...], shaping: Shaping = None
                   ) -> AllanMoments | PooledMoments:
    """The moments of the records a fit reads: :func:`moments` of the one record (exactly the
    unsegmented numbers), else :func:`pooled_moments` of the segments; ``shaping`` the log's
    shaping filter (None: none)."""
    lengths = tuple(int(n) for n in lengths)
    if shaping is not None:
        shaping = tuple(float(v) for v in shaping)
    if len(lengths) == 1:
        return moments(lengths[0], tuple(int(m) for m in ms), *_shaped(shaping))
    return pooled_moments(lengths, tuple(int(m) for m in ms), *_shaped(shaping))


def allan_moments(n: int, ms: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Design and covariance tensor of the overlapping Allan variance for ``n`` samples at the
    averaging factors ``ms``, for the three core unit processes (white, flicker, random walk;
    :func:`moments` has all five).

    Returns
    -------
    design : (n_tau, 3) — ``E s(m_i) = design[i] @ θ`` (units of θ: y², per unit process).
    tensor : (n_tau, n_tau, 3, 3) — ``Cov(s_i, s_j) = θ @ tensor[i, j] @ θ``.
    """
    mom = moments(int(n), tuple(int(m) for m in ms))
    return mom.design[:, :3], mom.tensor[:, :, :3, :3]


def avar_covariance(tensor: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """``Cov(s_i, s_j) = θᵀ T_ij θ`` for the given θ (n_tau, n_tau)."""
    return np.einsum("a,ijab,b->ij", theta, tensor, theta)


def edf(design: np.ndarray, tensor: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Equivalent degrees of freedom of each octave's Allan variance for the mixture θ:
    ``ν_i = 2 (E s_i)² / Var s_i`` (the χ²_ν whose mean and variance match; module
    docstring)."""
    mean = design @ theta
    var = np.einsum("a,iiab,b->i", theta, tensor, theta)
    return 2.0 * mean ** 2 / var


__all__ = ["ALL_TERM_NAMES", "CACHE_ENV", "EXTRA_TERM_NAMES", "FLICKER_FLOOR", "GM_CUT",
           "GM_STEPS_PER_OCTAVE",
           "MOMENTS_VERSION", "N_PROCESSES", "TERM_NAMES", "AllanMoments", "PooledMoments",
           "Shaping", "allan_moments", "avar_covariance", "cache_dir", "difference_filter", "edf",
           "flicker_coefficients", "gm_avar", "gm_columns", "gm_grid", "moments",
           "pooled_moments", "record_moments",
           "segment_counts", "segment_weights", "supported_octaves", "term_value",
           "terms_from_theta", "theta_from_terms", "with_gauss_markov"]
